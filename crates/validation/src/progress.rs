//! How the engine tells a front end what it is doing, without knowing where that goes.
//!
//! ```text
//! started(total)        a batch of `total` items begins (the points of a sweep)
//! finished(what, secs)  one item of the batch ended, after `secs` s of wall time
//! note(line)            one line for the user: what the engine chose or measured
//!                       (the reference of a comparison, a derived RK4 step, a finished run);
//!                       a Message, whose option names the front end spells
//! ```
//!
//! Every method has an empty default, so [`NoProgress`] (and a front end that shows only some
//! of it) implements what it needs. The `lash` command draws a progress bar on a terminal and
//! prints the notes on standard error; a library caller may log them or ignore them.
//!
//! Source: ARCHITECTURE.md ("Invariants": the engine prints nothing; progress goes through a
//! hook).

use crate::error::Message;

/// Receives the engine's progress reports; called from worker threads, so `Sync`.
pub trait Progress: Sync {
    /// A batch of `total` items begins.
    fn started(&self, total: usize) {
        let _ = total;
    }

    /// One item of the batch ended (`what` names it), after `secs` s of wall time.
    fn finished(&self, what: &str, secs: f64) {
        let _ = (what, secs);
    }

    /// One line for the user (no trailing newline); `line.to_string()` spells its option
    /// names as the engine does.
    fn note(&self, line: &Message) {
        let _ = line;
    }
}

/// Reports nothing.
///
/// Source: this module.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {}
