//! The `lash` command. Everything lives in the library; this only sets the exit code.
use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(lash_validation::app::main_with(std::env::args_os()))
}
