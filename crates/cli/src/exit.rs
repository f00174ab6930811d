//! Exit codes of `lash`, and the one line (two for a solver failure) it prints for an error.
//!
//! ```text
//! exit code = 0  success
//!             2  bad input or usage      (ErrorKind::BadInput: Usage, Option, Input, Scene,
//!                                         Io)
//!             3  the solver failed       (ErrorKind::Solver)
//!             1  a bug                   (ErrorKind::Bug: Internal; a panic)
//!           130  interrupted             (ErrorKind::Interrupted: SIGINT or SIGTERM; the item
//!                                         in flight abandoned, what had finished kept)
//! ```
//!
//! The engine names options by its own names (`rtol`, `t_end`); `lash` spells them as its
//! flags (`--rtol`, `--t-end`: [`flag`]).
//!
//! Source: the exit-code contract of docs/outputs.md ("Exit codes of `lash`").

use lash_validation::{Error, ErrorKind};

/// Exit code of a successful run.
pub const EXIT_OK: u8 = 0;
/// Exit code of a bug (an internal inconsistency, or a command whose engine is not built yet).
pub const EXIT_BUG: u8 = 1;
/// Exit code of bad input or usage.
pub const EXIT_USAGE: u8 = 2;
/// Exit code of a solver failure.
pub const EXIT_SOLVER: u8 = 3;
/// Exit code of an interrupted command (SIGINT or SIGTERM): 128 + 2, the shell's convention
/// for SIGINT, for both signals.
pub const EXIT_INTERRUPTED: u8 = 130;

/// The flag of an engine option: `t_end` → `--t-end`.
pub fn flag(option: &str) -> String {
    format!("--{}", option.replace('_', "-"))
}

/// The error with the options in its message spelled as flags: an [`Error::Option`] becomes
/// the [`Error::Usage`] `lash` reports; every other error stays as it is.
pub fn flagged(e: Error) -> Error {
    match e {
        Error::Option(o) => Error::Usage(o.render(&flag)),
        other => other,
    }
}

/// What `lash` makes of an engine error: its exit code and what it prints.
///
/// Source: docs/outputs.md ("Exit codes of `lash`").
pub trait ExitStatus {
    /// The exit code (docs/outputs.md, "Exit codes of `lash`").
    fn exit_code(&self) -> u8;

    /// What `lash` prints on standard error: `error: MESSAGE` on one line (options spelled as
    /// flags); for a solver failure a second line with the time and the state at the failure.
    fn report(&self) -> String;
}

/// Longest state printed whole on standard error; a longer one shows its first
/// [`STATE_HEAD`] and last [`STATE_TAIL`] components and its length (a 1 000-body state has
/// 6 000: failure.json keeps them all).
const STATE_SHOWN: usize = 16;
/// Components shown from the start of a long state.
const STATE_HEAD: usize = 8;
/// Components shown from the end of a long state.
const STATE_TAIL: usize = 4;

/// `[y0, y1, …]`, shortened past [`STATE_SHOWN`] components.
fn state_text(y: &[f64]) -> String {
    let f = |v: &f64| format!("{v:e}");
    if y.len() <= STATE_SHOWN {
        let ys: Vec<String> = y.iter().map(f).collect();
        return format!("[{}]", ys.join(", "));
    }
    let head: Vec<String> = y[..STATE_HEAD].iter().map(f).collect();
    let tail: Vec<String> = y[y.len() - STATE_TAIL..].iter().map(f).collect();
    format!(
        "[{}, …, {}] ({} components)",
        head.join(", "),
        tail.join(", "),
        y.len()
    )
}

impl ExitStatus for Error {
    fn exit_code(&self) -> u8 {
        match self.kind() {
            ErrorKind::BadInput => EXIT_USAGE,
            ErrorKind::Solver => EXIT_SOLVER,
            ErrorKind::Bug => EXIT_BUG,
            ErrorKind::Interrupted => EXIT_INTERRUPTED,
        }
    }

    fn report(&self) -> String {
        let mut s = format!("error: {}", self.message_with(&flag));
        if let Error::Solver(e) = self {
            match (e.time(), e.state()) {
                (Some(t), Some(y)) if !y.is_empty() => {
                    s.push_str(&format!("\n  at t = {t:e}, state = {}", state_text(y)));
                }
                (Some(t), _) => s.push_str(&format!(
                    "\n  at t = {t:e} (no state yet: the run stopped during its set-up)"
                )),
                _ => {}
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lash_solver::SolveError;
    use lash_validation::OptionError;

    #[test]
    fn exit_codes_follow_interfaces() {
        assert_eq!(Error::Usage("x".into()).exit_code(), 2);
        assert_eq!(Error::Input("x".into()).exit_code(), 2);
        let io = Error::Io {
            path: "a/b".into(),
            source: std::io::Error::from(std::io::ErrorKind::NotFound),
        };
        assert_eq!(io.exit_code(), 2);
        assert!(io.to_string().starts_with("a/b: "));
        let s = Error::Solver(SolveError::InvalidOptions(
            lash_solver::Rule::RTOL.check(0.0).unwrap_err(),
        ));
        assert_eq!(s.exit_code(), 3);
        assert_eq!(Error::Internal("x".into()).exit_code(), 1);
        let i = Error::from(SolveError::Interrupted {
            t: 0.5,
            y: vec![1.0],
        });
        assert_eq!(i.exit_code(), 130);
        assert_eq!(
            i.report(),
            "error: interrupted: stop requested; the run in flight stopped at t = 5e-1"
        );
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
        // A long state: its first 8 and last 4 components and its length, on one line.
        let long = Error::Solver(SolveError::NonFiniteState {
            t: 0.0,
            y: (0..6000).map(f64::from).collect(),
        });
        assert_eq!(
            long.report().lines().nth(1).unwrap(),
            "  at t = 0e0, state = [0e0, 1e0, 2e0, 3e0, 4e0, 5e0, 6e0, 7e0, …, 5.996e3, 5.997e3, \
             5.998e3, 5.999e3] (6000 components)"
        );
        // Usage errors stay on one line.
        assert_eq!(
            Error::Usage("--rtol must be > 0".into()).report(),
            "error: --rtol must be > 0"
        );
    }

    #[test]
    fn option_errors_are_reported_with_flags() {
        let e = Error::from(OptionError::leading("t_end", " must be > 0"));
        assert_eq!(e.exit_code(), 2);
        assert_eq!(e.report(), "error: --t-end must be > 0");
        let u = flagged(e);
        assert!(matches!(&u, Error::Usage(m) if m == "--t-end must be > 0"));
        assert_eq!(flag("renorm_per_rev"), "--renorm-per-rev");
    }
}
