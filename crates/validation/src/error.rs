//! The errors of the `lash` command and the exit code each maps to.
//!
//! ```text
//! exit code = 0  success
//!             2  bad input or usage      (Usage, Input, Io)
//!             3  the solver failed       (Solver)
//!             1  a bug                   (NotYetAvailable, Internal)
//! ```
//!
//! Source: the exit-code contract of INTERFACES.md ("Exit codes of `lash`").

use std::path::{Path, PathBuf};

use lash_solver::SolveError;

/// Exit code of a successful run.
pub const EXIT_OK: u8 = 0;
/// Exit code of a bug (an internal inconsistency, or a command whose engine is not built yet).
pub const EXIT_BUG: u8 = 1;
/// Exit code of bad input or usage.
pub const EXIT_USAGE: u8 = 2;
/// Exit code of a solver failure.
pub const EXIT_SOLVER: u8 = 3;

/// Everything that can make `lash` fail.
///
/// ```text
/// Error → exit code:  Usage | Input | Io → 2,  Solver → 3,  NotYetAvailable | Internal → 1
/// ```
///
/// Every variant's message is one line that names the problem (the flag, the file, the field);
/// [`Error::report`] adds the time and state of a solver failure.
///
/// Source: INTERFACES.md ("Exit codes of `lash`").
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad command line: a wrong flag combination, an out-of-range number, an unknown name.
    #[error("{0}")]
    Usage(String),
    /// Bad input file: a missing or invalid case, sweep file or result directory.
    #[error("{0}")]
    Input(String),
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The solver failed (typed, with time and state).
    #[error("solver failed: {0}")]
    Solver(#[from] SolveError),
    /// The command exists but its engine (the model, a solver) is not wired in yet.
    #[error("{0} is not yet available in this build")]
    NotYetAvailable(String),
    /// An internal inconsistency: a bug.
    #[error("internal error: {0}")]
    Internal(String),
}

impl Error {
    /// The exit code of this error (INTERFACES.md).
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Usage(_) | Error::Input(_) | Error::Io { .. } => EXIT_USAGE,
            Error::Solver(_) => EXIT_SOLVER,
            Error::NotYetAvailable(_) | Error::Internal(_) => EXIT_BUG,
        }
    }

    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }

    /// What `lash` prints on standard error: `error: MESSAGE` on one line; for a solver failure
    /// a second line with the time and the state at the failure.
    pub fn report(&self) -> String {
        let mut s = format!("error: {self}");
        if let Error::Solver(e) = self {
            if let (Some(t), Some(y)) = (e.time(), e.state()) {
                let ys: Vec<String> = y.iter().map(|v| format!("{v:e}")).collect();
                s.push_str(&format!("\n  at t = {t:e}, state = [{}]", ys.join(", ")));
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_codes_follow_interfaces() {
        assert_eq!(Error::Usage("x".into()).exit_code(), 2);
        assert_eq!(Error::Input("x".into()).exit_code(), 2);
        let io = Error::io("a/b", std::io::Error::from(std::io::ErrorKind::NotFound));
        assert_eq!(io.exit_code(), 2);
        assert!(io.to_string().starts_with("a/b: "));
        let s = Error::Solver(SolveError::InvalidOptions("bad".into()));
        assert_eq!(s.exit_code(), 3);
        assert_eq!(Error::NotYetAvailable("lash run".into()).exit_code(), 1);
        assert_eq!(Error::Internal("x".into()).exit_code(), 1);
    }

    #[test]
    fn solver_report_names_time_and_state() {
        let e = Error::Solver(SolveError::NonFiniteState {
            t: 0.25,
            y: vec![1.0, -2.5],
        });
        let r = e.report();
        let lines: Vec<&str> = r.lines().collect();
        assert_eq!(lines.len(), 2);
        assert_eq!(
            lines[0],
            "error: solver failed: non-finite or diverging state at t = 2.5e-1"
        );
        assert_eq!(lines[1], "  at t = 2.5e-1, state = [1e0, -2.5e0]");
        // Usage errors stay on one line.
        assert_eq!(
            Error::Usage("--rtol must be > 0".into()).report(),
            "error: --rtol must be > 0"
        );
    }
}
