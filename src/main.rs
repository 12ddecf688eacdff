//! The `afford` command line; everything it does is in [`afford::cli`].

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(afford::cli::main(std::env::args_os()))
}
