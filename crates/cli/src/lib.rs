//! # lash-cli
//!
//! The `lash` command line over the engine (`lash-validation`): clap arguments, their
//! conversion into the engine's options, what each command prints, exit codes, and the
//! progress display.
//!
//! ```text
//! argv ──args::parse──▶ Command ──args: .options()──▶ lash_validation::{run, compare, …}
//!      ──Written<result> | Error──▶ app: print (stdout), exit: report (stderr) + exit code
//! engine notes, progress ──Progress──▶ progress::StderrProgress (bar on a terminal, else lines)
//! SIGINT, SIGTERM ──signals──▶ lash_solver::interrupt::request_stop() → exit code 130
//! ```
//!
//! Modules: [`args`] (clap derive types and value parsers), [`app`] (dispatch and printing),
//! [`exit`] (exit codes, error reports, engine option names spelled as flags), [`out`]
//! (standard output and error without panics), [`progress`] (notes, the progress bar or
//! per-item log lines on standard error), [`signals`] (SIGINT and SIGTERM stop the work
//! cleanly), [`viz`] (`lash animate`, `lash plot`, `lash run --animate`).

#![warn(missing_docs)]

pub mod app;
pub mod args;
pub mod exit;
pub mod out;
pub mod progress;
pub mod signals;
pub mod viz;
