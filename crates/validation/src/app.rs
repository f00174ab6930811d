//! Dispatch: parsed command line → work → exit code.
//!
//! ```text
//! main_with(args) = 0 on success; on failure print Error::report() to stderr and return
//!                   Error::exit_code()  (2 usage/input, 3 solver, 1 bug)
//! ```
//!
//! Source: INTERFACES.md ("Exit codes of `lash`"). Commands whose engine (the model, the
//! adaptive and stiff solvers) is not wired in yet check all their input and then fail with
//! [`Error::NotYetAvailable`].

use std::ffi::OsString;
use std::path::PathBuf;

use lash_solver::SolverOptions;

use crate::case::Case;
use crate::cli::{self, Command, Parsed, StudyArgs, StudyName};
use crate::error::{Error, EXIT_OK};
use crate::sweep;

/// Runs `lash` with these arguments (the first is the program name) and returns the exit code.
pub fn main_with<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let result = cli::parse(args).and_then(|p| match p {
        Parsed::Print(s) => {
            print!("{s}");
            Ok(())
        }
        Parsed::Cli(c) => execute(c.command),
    });
    match result {
        Ok(()) => EXIT_OK,
        Err(e) => {
            eprintln!("{}", e.report());
            e.exit_code()
        }
    }
}

/// Executes one command; `None` is the default study (`lash study paper`).
pub fn execute(command: Option<Command>) -> Result<(), Error> {
    let command = command.unwrap_or(Command::Study(StudyArgs {
        study: StudyName::Paper,
        out: None,
    }));
    match command {
        Command::Run(a) => {
            let case = Case::load(&a.case, None)?;
            let _opts = a.solver.apply(&SolverOptions::default())?;
            let _out = a.out.unwrap_or_else(|| default_out("run", &case.name));
            Err(Error::NotYetAvailable(
                "lash run (the model is not wired in)".into(),
            ))
        }
        Command::Study(a) => {
            let StudyName::Paper = a.study;
            Err(Error::NotYetAvailable(
                "lash study paper (the model is not wired in)".into(),
            ))
        }
        Command::Compare(a) => {
            Case::load(&a.case, None)?;
            Err(Error::NotYetAvailable(
                "lash compare (the model is not wired in)".into(),
            ))
        }
        Command::WorkPrecision(a) => {
            Case::load(&a.case, None)?;
            a.plan()?;
            Err(Error::NotYetAvailable(
                "lash work-precision (the model is not wired in)".into(),
            ))
        }
        Command::Sweep(a) => {
            let spec = sweep::SweepSpec::load(&a.file)?;
            let _points = spec.points()?;
            Err(Error::NotYetAvailable(
                "lash sweep (the point runner needs the model)".into(),
            ))
        }
        Command::Merge(a) => {
            let out = a.out.unwrap_or_else(|| a.dirs[0].clone());
            let table = sweep::merge(&a.dirs)?;
            let (csv, md) = table.write(&out)?;
            println!(
                "merged {} points into {} and {}",
                table.rows.len(),
                csv.display(),
                md.display()
            );
            Ok(())
        }
    }
}

/// Default output directory of a command for a case: `out/COMMAND/NAME` (a `:` in a built-in
/// name becomes `_`).
pub fn default_out(command: &str, name: &str) -> PathBuf {
    PathBuf::from("out")
        .join(command)
        .join(name.replace(':', "_"))
}
