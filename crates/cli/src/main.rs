//! The `lash` command. Everything lives in the library (`lash_cli`); this only sets the exit
//! code.
use std::process::ExitCode;

fn main() -> ExitCode {
    lash_cli::signals::install();
    ExitCode::from(lash_cli::app::main_with(std::env::args_os()))
}
