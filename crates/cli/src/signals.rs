//! SIGINT and SIGTERM: the first raises the engine's stop request, the second ends the
//! process at once.
//!
//! ```text
//! 1st signal → lash_solver::interrupt::request_stop(); a line on standard error; every run
//!              in flight ends at its next step boundary (SolveError::Interrupted), no new
//!              item starts, partial files are removed, finished items stay; the command
//!              exits 130 (crate::exit::EXIT_INTERRUPTED)
//! 2nd signal → exit 130 at once (temporary files may stay; the next run clears them)
//! ```
//!
//! The handler is the `ctrlc` crate's (its `termination` feature adds SIGTERM, which batch
//! schedulers send before they kill a job): it runs on its own thread, so printing and
//! exiting there is safe.
//!
//! Source: docs/outputs.md ("Exit codes of `lash`", "Progress and interrupting a command").

use std::sync::atomic::{AtomicUsize, Ordering};

use crate::exit::EXIT_INTERRUPTED;

/// Signals received so far.
static RECEIVED: AtomicUsize = AtomicUsize::new(0);

/// Installs the handler (once per process; a second call does nothing).
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        if RECEIVED.fetch_add(1, Ordering::SeqCst) == 0 {
            lash_solver::interrupt::request_stop();
            eprintln!(
                "lash: stopping: the run in flight is abandoned at its next step, finished work \
                 is kept (signal again to quit at once)"
            );
        } else {
            std::process::exit(i32::from(EXIT_INTERRUPTED));
        }
    });
}
