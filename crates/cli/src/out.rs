//! Standard output and standard error without panics: `print!` and `eprintln!` panic when the
//! stream is closed (`lash run … | head -1`) or full (`> /dev/full`); these do not.
//!
//! ```text
//! out(text)   standard output; a broken pipe (the reader is gone) silences the rest of the
//!             output; any other error (a full disk) is kept for stdout_error()
//! err(text)   standard error; errors are ignored (there is nowhere left to report them)
//! exit code   a broken pipe changes nothing (the command's own code: 0 after a successful run,
//!             whose files are written); another error writing standard output is exit 2 with
//!             one line on standard error, after the command's own work
//! ```
//!
//! Rust ignores SIGPIPE, so a closed pipe is the write error `BrokenPipe`, not a signal.
//!
//! Source: docs/outputs.md ("Exit codes of `lash`").

use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// Standard output was closed by its reader: nothing more is written to it.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);
/// The first error other than a broken pipe while writing standard output.
static STDOUT_ERROR: Mutex<Option<String>> = Mutex::new(None);

fn record(e: io::Error) {
    if e.kind() == io::ErrorKind::BrokenPipe {
        STDOUT_CLOSED.store(true, Ordering::Relaxed);
    } else if let Ok(mut slot) = STDOUT_ERROR.lock() {
        if slot.is_none() {
            *slot = Some(e.to_string());
        }
        STDOUT_CLOSED.store(true, Ordering::Relaxed);
    }
}

/// Writes `text` to standard output (module doc).
pub fn out(text: &str) {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut o = io::stdout().lock();
    if let Err(e) = o.write_all(text.as_bytes()).and_then(|()| o.flush()) {
        record(e);
    }
}

/// Writes `text` and a line break to standard output (module doc).
pub fn outln(text: &str) {
    let mut s = String::with_capacity(text.len() + 1);
    s.push_str(text);
    s.push('\n');
    out(&s);
}

/// Writes `text` and a line break to standard error; errors are ignored.
pub fn errln(text: &str) {
    let mut e = io::stderr().lock();
    let _ = e
        .write_all(text.as_bytes())
        .and_then(|()| e.write_all(b"\n"))
        .and_then(|()| e.flush());
}

/// The first error other than a broken pipe while writing standard output, after a final
/// flush.
pub fn stdout_error() -> Option<String> {
    if !STDOUT_CLOSED.load(Ordering::Relaxed) {
        if let Err(e) = io::stdout().lock().flush() {
            record(e);
        }
    }
    STDOUT_ERROR.lock().ok().and_then(|s| s.clone())
}

/// Whether the reader of standard output is gone.
pub fn stdout_closed() -> bool {
    STDOUT_CLOSED.load(Ordering::Relaxed)
}
