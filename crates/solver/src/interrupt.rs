//! A process-wide stop request: raised by a signal handler (or any thread), checked by every
//! integration before each step attempt; and the deadline of the call running on a thread
//! ([`deadline_scope`]), checked by set-up work and every step attempt.
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
#[inline]
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// Lowers the stop request.
pub fn clear_stop() {
    STOP.store(false, Ordering::SeqCst);
}

thread_local! {
    /// The wall-clock deadline of the call running on this thread and its budget in seconds
    /// ([`deadline_scope`]).
    static DEADLINE: std::cell::Cell<Option<(std::time::Instant, f64)>> =
        const { std::cell::Cell::new(None) };
}

/// The deadline of one call (a run, with its set-up) on this thread, with the budget it comes
/// from in seconds, in force until the returned guard drops; nested scopes keep the earlier of
/// the two and restore the outer one.
///
/// ```text
/// deadline_scope(Some((d, w)))  set-up work checks deadline_passed() between and inside its
///                               phases (assembly's iterations, the initial checks) and every
///                               step attempt checks it (crate::stepper::Budget): a budget
///                               that runs out inside set-up ends the call at the next check,
///                               not after the whole set-up
/// deadline_scope(None)          no deadline added (an outer one stays)
/// ```
///
/// Thread-local, not process-wide like the stop request: parallel runs (a sweep's workers)
/// each keep their own budget.
pub fn deadline_scope(deadline: Option<(std::time::Instant, f64)>) -> DeadlineScope {
    let outer = DEADLINE.with(|d| d.get());
    let inner = match (outer, deadline) {
        (Some(a), Some(b)) => Some(if b.0 < a.0 { b } else { a }),
        (a, b) => a.or(b),
    };
    DEADLINE.with(|d| d.set(inner));
    DeadlineScope { outer }
}

/// The budget (s) of the call running on this thread ([`deadline_scope`]) when its deadline
/// has passed; None before it or without one. Costs one clock read when there is one.
pub fn deadline_passed() -> Option<f64> {
    DEADLINE
        .with(|d| d.get())
        .and_then(|(d, w)| (std::time::Instant::now() >= d).then_some(w))
}

/// Whether the call running on this thread has a deadline ([`deadline_scope`]), passed or
/// not; no clock read.
#[inline]
pub(crate) fn deadline_set() -> bool {
    DEADLINE.with(|d| d.get().is_some())
}

/// Restores the deadline that was in force before [`deadline_scope`] when dropped.
#[must_use = "the deadline holds only while the scope is alive"]
#[derive(Debug)]
pub struct DeadlineScope {
    outer: Option<(std::time::Instant, f64)>,
}

impl Drop for DeadlineScope {
    fn drop(&mut self) {
        DEADLINE.with(|d| d.set(self.outer));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    /// Nested scopes keep the earlier deadline and restore the outer one when they end;
    /// another thread never sees this thread's deadline.
    #[test]
    fn scopes_nest_and_stay_on_their_thread() {
        let now = Instant::now();
        let later = now + Duration::from_secs(3600);
        assert_eq!(deadline_passed(), None);
        {
            let _outer = deadline_scope(Some((later, 3600.0)));
            assert_eq!(deadline_passed(), None);
            {
                let _inner = deadline_scope(Some((now, 0.25)));
                assert_eq!(deadline_passed(), Some(0.25));
                assert_eq!(std::thread::spawn(deadline_passed).join().unwrap(), None);
                // A later inner deadline does not extend the earlier one.
                let _none = deadline_scope(Some((later, 7200.0)));
                assert_eq!(deadline_passed(), Some(0.25));
            }
            assert_eq!(deadline_passed(), None);
            let _same = deadline_scope(None);
            assert_eq!(deadline_passed(), None);
        }
        assert_eq!(deadline_passed(), None);
    }
}
