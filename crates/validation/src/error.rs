//! The errors of the engine and the kind of each.
//!
//! ```text
//! kind = BadInput  a wrong request or input file   (Usage, Option, Input, Scene, Io)
//!        Solver    the solver failed               (Solver)
//!        Bug       a broken invariant              (Internal)
//!        Interrupted  a stop was requested (SIGINT, SIGTERM)   (Interrupted)
//! ```
//!
//! Options are named by the engine's names (`rtol`, `t_end`, `max_steps`, …): an
//! [`Error::Option`] keeps the names apart from its text, so that each front end spells them its
//! own way (the `lash` command as `--rtol`, `--t-end`; a Python binding as `rtol`, `t_end`).
//! [`Display`](std::fmt::Display) spells them as the engine names them.
//!
//! Source: the exit-code contract of docs/outputs.md ("Exit codes of `lash`"): the kinds are its
//! classes (exit codes 2, 3 and 1).

use std::fmt;
use std::path::{Path, PathBuf};

use lash_solver::SolveError;

/// Everything that can make the engine fail.
///
/// ```text
/// Error → kind:  Usage | Option | Input | Scene | Io → BadInput,  Solver → Solver,
///                Internal → Bug,  Interrupted → Interrupted
/// SolveError::Interrupted → Error::Interrupted (From), every other SolveError → Error::Solver
/// ```
///
/// Every variant's message is one line that names the problem (the option, the file, the
/// field); a solver failure also carries its time and state ([`SolveError::time`],
/// [`SolveError::state`]).
///
/// Source: docs/outputs.md ("Exit codes of `lash`").
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A request that does not fit: a wrong combination, an out-of-range number, an unknown
    /// name (the message names no option; see [`Error::Option`] for one that does).
    #[error("{0}")]
    Usage(String),
    /// A request whose message names options (a wrong value or combination of options).
    #[error("{0}")]
    Option(OptionError),
    /// Bad input file: a missing or invalid case, sweep file or result directory.
    #[error("{0}")]
    Input(String),
    /// A scene the model rejects, with its JSON path and reason kept apart
    /// ([`lash_model::SceneError`]), so that a front end can show them as fields (the Python
    /// binding's `lash.SceneError`).
    #[error("case {case}: {error}")]
    Scene {
        /// The case as the user named it (the scene file's path, or the case's name).
        case: String,
        /// What the model says.
        error: lash_model::SceneError,
    },
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
    Solver(SolveError),
    /// The work was interrupted (a stop was requested: `lash_solver::interrupt`): the item in
    /// flight was abandoned, what had finished is kept; the message says what and where.
    #[error("interrupted: {0}")]
    Interrupted(String),
    /// A broken invariant of the engine: a bug (never a consequence of the input).
    #[error("internal error: {0}")]
    Internal(String),
}

/// The class of an [`Error`]: whose fault it is.
///
/// ```text
/// BadInput → exit code 2,  Solver → 3,  Bug → 1   (docs/outputs.md, "Exit codes of `lash`")
/// ```
///
/// Source: docs/outputs.md ("Exit codes of `lash`").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The request or an input file is wrong (usage, an option, a case, a file).
    BadInput,
    /// The solver failed.
    Solver,
    /// A bug: a broken invariant of the engine.
    Bug,
    /// A stop was requested (SIGINT, SIGTERM) and the work abandoned.
    Interrupted,
}

impl Error {
    /// The class of this error.
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::Usage(_)
            | Error::Option(_)
            | Error::Input(_)
            | Error::Scene { .. }
            | Error::Io { .. } => ErrorKind::BadInput,
            Error::Solver(_) => ErrorKind::Solver,
            Error::Internal(_) => ErrorKind::Bug,
            Error::Interrupted(_) => ErrorKind::Interrupted,
        }
    }

    /// Whether this is an interruption ([`Error::Interrupted`]).
    pub(crate) fn is_interrupted(&self) -> bool {
        matches!(self, Error::Interrupted(_))
    }

    /// Wraps an I/O error with the path it concerns.
    pub(crate) fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }

    /// The message with the options spelled by `spell` (engine name → the front end's name);
    /// the same as `to_string()` for every error but [`Error::Option`].
    pub fn message_with(&self, spell: &dyn Fn(&str) -> String) -> String {
        match self {
            Error::Option(o) => o.render(spell),
            other => other.to_string(),
        }
    }
}

impl From<SolveError> for Error {
    /// [`SolveError::Interrupted`] becomes [`Error::Interrupted`] (not a failure of the
    /// solver); every other failure [`Error::Solver`].
    fn from(e: SolveError) -> Self {
        match e {
            SolveError::Interrupted { t, .. } => Error::Interrupted(format!(
                "stop requested; the run in flight stopped at t = {t:e}"
            )),
            other => Error::Solver(other),
        }
    }
}

/// One piece of a [`Message`].
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Piece {
    /// Text, as is.
    Text(String),
    /// An option, by its engine name (`rtol`, `t_end`, …).
    Option(&'static str),
}

/// A line of text that may name options, kept apart so that each front end spells them its
/// own way; [`Display`](fmt::Display) spells them as the engine names them.
///
/// ```text
/// Message::default().text("rk4 left out (give ").name("steps").text(" to include it)")
///   lash:   "rk4 left out (give --steps to include it)"
///   engine: "rk4 left out (give steps to include it)"
/// ```
///
/// Source: ARCHITECTURE.md ("Invariants": the engine names no command-line flag).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Message {
    /// The pieces, in order.
    pub(crate) pieces: Vec<Piece>,
}

impl Message {
    /// Appends text.
    pub(crate) fn text(mut self, s: impl Into<String>) -> Self {
        self.pieces.push(Piece::Text(s.into()));
        self
    }

    /// Appends an option name.
    pub(crate) fn name(mut self, option: &'static str) -> Self {
        self.pieces.push(Piece::Option(option));
        self
    }

    /// The same message with `text` before it.
    pub(crate) fn prefixed(mut self, text: impl Into<String>) -> Self {
        self.pieces.insert(0, Piece::Text(text.into()));
        self
    }

    /// The line with each option spelled by `spell`.
    pub fn render(&self, spell: &dyn Fn(&str) -> String) -> String {
        self.pieces
            .iter()
            .map(|p| match p {
                Piece::Text(s) => s.clone(),
                Piece::Option(o) => spell(o),
            })
            .collect()
    }
}

impl fmt::Display for Message {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.render(&|o| o.to_string()))
    }
}

impl From<&str> for Message {
    fn from(s: &str) -> Self {
        Message::default().text(s)
    }
}

impl From<String> for Message {
    fn from(s: String) -> Self {
        Message::default().text(s)
    }
}

/// A request whose options are wrong: the option at fault and a [`Message`] that names
/// options apart from its text.
///
/// ```text
/// OptionError::leading("rtol", " is only for adaptive methods, and rk4 is fixed-step")
///   lash:   "--rtol is only for adaptive methods, and rk4 is fixed-step"
///   engine: "rtol is only for adaptive methods, and rk4 is fixed-step"
/// ```
///
/// Source: ARCHITECTURE.md ("Invariants": engine errors name no command-line flag).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OptionError {
    /// The option at fault, by its engine name.
    pub option: &'static str,
    /// What is wrong.
    pub message: Message,
}

impl OptionError {
    /// An empty message about `option`.
    pub(crate) fn new(option: &'static str) -> Self {
        OptionError {
            option,
            message: Message::default(),
        }
    }

    /// The common message: the option at fault, then `rest` (which starts with a space).
    pub fn leading(option: &'static str, rest: impl Into<String>) -> Self {
        OptionError::new(option).name(option).text(rest)
    }

    /// Appends text.
    pub(crate) fn text(mut self, s: impl Into<String>) -> Self {
        self.message = self.message.text(s);
        self
    }

    /// Appends an option name.
    pub(crate) fn name(mut self, option: &'static str) -> Self {
        self.message = self.message.name(option);
        self
    }

    /// The same error with `text` before its message.
    pub(crate) fn prefixed(mut self, text: impl Into<String>) -> Self {
        self.message = self.message.prefixed(text);
        self
    }

    /// The message with each option spelled by `spell`.
    pub fn render(&self, spell: &dyn Fn(&str) -> String) -> String {
        self.message.render(spell)
    }
}

impl fmt::Display for OptionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.message.fmt(f)
    }
}

impl From<OptionError> for Error {
    fn from(e: OptionError) -> Self {
        Error::Option(e)
    }
}

impl From<lash_solver::OptionError> for OptionError {
    /// The solver's typed option error with its fields kept apart, so that each front end
    /// spells them (`lash`: `--rtol`).
    fn from(e: lash_solver::OptionError) -> Self {
        use lash_solver::options::Part;
        let pieces = e
            .parts()
            .into_iter()
            .map(|p| match p {
                Part::Text(s) => Piece::Text(s),
                Part::Field(f) => Piece::Option(f.name()),
            })
            .collect();
        OptionError {
            option: e.field.name(),
            message: Message { pieces },
        }
    }
}

impl From<lash_solver::OptionError> for Error {
    fn from(e: lash_solver::OptionError) -> Self {
        Error::Option(e.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_follow_interfaces() {
        assert_eq!(Error::Usage("x".into()).kind(), ErrorKind::BadInput);
        assert_eq!(Error::Input("x".into()).kind(), ErrorKind::BadInput);
        let io = Error::io("a/b", std::io::Error::from(std::io::ErrorKind::NotFound));
        assert_eq!(io.kind(), ErrorKind::BadInput);
        assert!(io.to_string().starts_with("a/b: "));
        let s = Error::Solver(SolveError::InvalidOptions(
            lash_solver::Rule::RTOL.check(0.0).unwrap_err(),
        ));
        assert_eq!(s.kind(), ErrorKind::Solver);
        assert_eq!(Error::Internal("x".into()).kind(), ErrorKind::Bug);
        assert_eq!(
            Error::from(OptionError::leading("t_end", " must be > 0")).kind(),
            ErrorKind::BadInput
        );
    }

    #[test]
    fn option_errors_spell_options_as_asked() {
        let e = Error::from(
            OptionError::new("steps")
                .name("steps")
                .text(" is only for fixed-step methods, and ")
                .name("methods")
                .text(" lists none"),
        );
        assert_eq!(
            e.to_string(),
            "steps is only for fixed-step methods, and methods lists none"
        );
        let flag = |o: &str| format!("--{}", o.replace('_', "-"));
        assert_eq!(
            e.message_with(&flag),
            "--steps is only for fixed-step methods, and --methods lists none"
        );
        let Error::Option(o) = e else { panic!() };
        assert_eq!(o.option, "steps");
        let p = o.prefixed("2 sweep point(s) failed: ");
        assert_eq!(
            p.render(&flag),
            "2 sweep point(s) failed: --steps is only for fixed-step methods, and --methods lists none"
        );
        assert_eq!(
            Error::Input("x".into()).message_with(&flag),
            Error::Input("x".into()).to_string()
        );
    }

    #[test]
    fn solver_option_errors_keep_their_fields() {
        use lash_solver::{Method, OptionField};
        let flag = |o: &str| format!("--{}", o.replace('_', "-"));
        let e = Error::from(lash_solver::Rule::RTOL.check(0.0).unwrap_err());
        assert_eq!(e.kind(), ErrorKind::BadInput);
        assert_eq!(e.to_string(), "rtol must be in [1e-14, 1), got 0");
        assert_eq!(e.message_with(&flag), "--rtol must be in [1e-14, 1), got 0");
        let e = Error::from(lash_solver::OptionError::not_for(
            OptionField::Step,
            Method::Dopri54,
        ));
        assert_eq!(
            e.message_with(&flag),
            "--step is only for fixed-step methods, and dopri54 is adaptive"
        );
        let Error::Option(o) = e else { panic!() };
        assert_eq!(o.option, "step");
    }
}
