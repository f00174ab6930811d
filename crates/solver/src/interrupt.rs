//! A process-wide stop request: raised by a signal handler (or any thread), checked by every
//! integration before each step attempt.
//!
//! ```text
//! request_stop()     raise the request (an atomic store: safe from a signal handler's thread)
//! stop_requested()   whether it is raised
//! clear_stop()       lower it again (a front end that goes on after an interruption)
//! Budget::check      stop_requested() → SolveError::Interrupted { t, y } of the last
//!                    accepted step, before the next attempt (crate::stepper)
//! ```
//!
//! The request is one flag for the whole process, like the signal (SIGINT, SIGTERM) that
//! usually raises it: every integration in flight, on every thread, ends at its next step
//! boundary, so a long batch of runs can be abandoned cleanly and what had finished kept.
//! Checking it costs one relaxed atomic load per step attempt.
//!
//! Source: this module; the step loops of crate::onestep, crate::rk4 and
//! crate::diffsol_backend check it through crate::stepper::Budget.

use std::sync::atomic::{AtomicBool, Ordering};

/// The request.
static STOP: AtomicBool = AtomicBool::new(false);

/// Raises the stop request: every integration ends at its next step boundary with
/// [`crate::SolveError::Interrupted`].
pub fn request_stop() {
    STOP.store(true, Ordering::SeqCst);
}

/// Whether a stop has been requested.
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// Lowers the stop request.
pub fn clear_stop() {
    STOP.store(false, Ordering::SeqCst);
}
