//! The `afford` command line; everything it does is in [`afford_cli::cli`].

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(afford_cli::cli::main(std::env::args_os()))
}
