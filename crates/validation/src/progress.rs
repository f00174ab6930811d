//! How the engine tells a front end what it is doing, without knowing where that goes.
//!
//! ```text
//! started(what, total)  a batch of `total` items begins; `what` names them ("points", "runs")
//! finished(what, secs)  one item of the batch ended (`what` names it and how it ended), after
//!                       `secs` s of wall time
//! note(line)            one line for the user: what the engine chose or measured
//!                       (the reference of a comparison, a derived RK4 step, runs reused
//!                       from a cache); a Message, whose option names the front end spells
//! ```
//!
//! Every long command reports its work as batches of items (a sweep's points, a study's runs,
//! the extremes matrix's references and runs, a comparison's runs, the phases of a
//! diagnostic), so that a front end can show a bar, or log one line per finished item when
//! nobody watches a terminal (a batch job's log). Every method has an empty default, so
//! [`NoProgress`] (and a front end that shows only some of it) implements what it needs.
//!
//! Source: ARCHITECTURE.md ("Invariants": the engine prints nothing; progress goes through a
//! hook).

use crate::error::Message;

/// Receives the engine's progress reports; called from worker threads, so `Sync`.
pub trait Progress: Sync {
    /// A batch of `total` items begins; `what` names the items in the plural.
    fn started(&self, what: &str, total: usize) {
        let _ = (what, total);
    }

    /// One item of the batch ended (`what` names it and says how it ended), after `secs` s
    /// of wall time.
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

/// The threads a parallel command uses: the request, capped at the available parallelism
/// (`std::thread::available_parallelism`) with a note; None = the available parallelism.
///
/// ```text
/// jobs = min(requested, available)   (requested > available → note "jobs N is more than …")
/// ```
///
/// More threads than cores only make every run slower (and a per-run wall-clock budget run
/// out sooner), so a larger request is a mistake worth a note, not an error.
pub(crate) fn jobs_within_parallelism(requested: Option<usize>, progress: &dyn Progress) -> usize {
    let available = std::thread::available_parallelism().map_or(1, |n| n.get());
    match requested {
        Some(n) if n > available => {
            progress.note(&Message::default().name("jobs").text(format!(
                " {n} is more than the {available} cores available: using {available}"
            )));
            available
        }
        Some(n) => n.max(1),
        None => available,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[derive(Default)]
    struct Notes(Mutex<Vec<String>>);
    impl Progress for Notes {
        fn note(&self, line: &Message) {
            self.0.lock().unwrap().push(line.to_string());
        }
    }

    #[test]
    fn jobs_are_capped_at_the_available_parallelism_with_a_note() {
        let cores = std::thread::available_parallelism().unwrap().get();
        let n = Notes::default();
        assert_eq!(jobs_within_parallelism(Some(100_000), &n), cores);
        assert_eq!(
            n.0.lock().unwrap().as_slice(),
            [format!(
                "jobs 100000 is more than the {cores} cores available: using {cores}"
            )]
        );
        let n = Notes::default();
        assert_eq!(jobs_within_parallelism(Some(1), &n), 1);
        assert_eq!(jobs_within_parallelism(None, &n), cores);
        assert!(n.0.lock().unwrap().is_empty());
    }
}
