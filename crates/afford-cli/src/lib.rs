//! The `afford` command line as a library: flags ([`cli`]) become one validated
//! configuration ([`settings`]), which the commands ([`run`], with [`batch`] runs over many
//! files) hand to the `afford` library and `afford-synth`. The binary (`src/main.rs`) and
//! the Python package's `afford` script both call [`cli::main`].

pub mod batch;
pub mod cli;
pub mod run;
pub mod settings;
mod source_args;
