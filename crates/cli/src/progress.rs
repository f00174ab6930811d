//! The engine's progress on standard error: notes as lines; a batch (a sweep's points, a
//! study's runs, …) as a progress bar when standard error is a terminal, else as one log line
//! per finished item, so that a batch job's log fills as the work goes on.
//!
//! ```text
//! started(what, n) → terminal: a bar of n items;  otherwise: "lash: N WHAT to run"
//! finished(w, s)   → terminal: the bar advances, its message is w;
//!                    otherwise: "[k/n] w (s s); m left, ~T to go"   (T = elapsed/k · m)
//! note(line)       → the line on standard error, options spelled as flags (above the bar)
//! clear()          → the bar disappears (before the command's closing line)
//! ```
//!
//! Standard output stays for results.
//!
//! Source: ARCHITECTURE.md ("Invariants": the engine prints nothing; the CLI draws what it
//! reports).

use std::io::IsTerminal;
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use lash_validation::Message;
use lash_validation::Progress;

use crate::exit::flag;

/// Template of the progress bar.
const BAR_TEMPLATE: &str =
    "{bar:30} {pos}/{len} {prefix}  {elapsed_precise} elapsed, ~{eta} left  {wide_msg}";

/// The batch in progress.
#[derive(Debug)]
struct Batch {
    what: String,
    total: usize,
    done: usize,
    start: Instant,
}

/// [`Progress`] on standard error.
///
/// Source: this module.
#[derive(Debug)]
pub struct StderrProgress {
    /// Whether to draw a bar for a batch (else one line per finished item).
    draw: bool,
    /// The bar, from the first batch on.
    bar: OnceLock<ProgressBar>,
    /// The current batch.
    batch: Mutex<Option<Batch>>,
}

impl StderrProgress {
    /// Notes on standard error; a bar for a batch when standard error is a terminal, else a
    /// line per finished item.
    pub fn new() -> Self {
        Self::with_bar(std::io::stderr().is_terminal())
    }

    /// Notes on standard error, and a bar for a batch if `draw` (else a line per item).
    pub fn with_bar(draw: bool) -> Self {
        StderrProgress {
            draw,
            bar: OnceLock::new(),
            batch: Mutex::new(None),
        }
    }

    /// Removes the bar, if one was drawn.
    pub fn clear(&self) {
        if let Some(b) = self.bar.get() {
            b.finish_and_clear();
        }
    }

    /// Counts a finished item and, when no bar is drawn, hands its log line to `emit` while
    /// the count is still held: the lines of items that finish together on several threads
    /// come out in the order of their numbers ("[2/4]" before "[3/4]").
    fn count_then(&self, what: &str, secs: f64, emit: impl FnOnce(String)) {
        let mut g = self.batch.lock().unwrap_or_else(|e| e.into_inner());
        let Some(b) = g.as_mut() else {
            return;
        };
        b.done += 1;
        if !self.draw {
            emit(log_line(b, what, secs));
        }
    }

    /// Counts a finished item; the log line for it when no bar is drawn.
    #[cfg(test)]
    fn count(&self, what: &str, secs: f64) -> Option<String> {
        let mut line = None;
        self.count_then(what, secs, |l| line = Some(l));
        line
    }
}

/// "[k/n] WHAT (S s); M left, ~T to go" (no estimate before the first item ends).
fn log_line(b: &Batch, what: &str, secs: f64) -> String {
    let left = b.total.saturating_sub(b.done);
    let mut s = format!("[{}/{}] {what} ({}); ", b.done, b.total, duration(secs));
    if left == 0 {
        s.push_str(&format!("all {} done", b.what));
    } else {
        let per = b.start.elapsed().as_secs_f64() / b.done.max(1) as f64;
        s.push_str(&format!(
            "{left} {} left, ~{} to go",
            b.what,
            duration(per * left as f64)
        ));
    }
    s
}

/// A duration for a log line: "0.42 s", "12.3 s", "4 min 05 s", "2 h 03 min".
pub fn duration(secs: f64) -> String {
    if !(secs.is_finite() && secs >= 0.0) {
        return "?".into();
    }
    if secs < 10.0 {
        format!("{secs:.2} s")
    } else if secs < 60.0 {
        format!("{secs:.1} s")
    } else if secs < 3600.0 {
        let s = secs.round() as u64;
        format!("{} min {:02} s", s / 60, s % 60)
    } else {
        let m = (secs / 60.0).round() as u64;
        format!("{} h {:02} min", m / 60, m % 60)
    }
}

impl Default for StderrProgress {
    fn default() -> Self {
        Self::new()
    }
}

impl Progress for StderrProgress {
    fn started(&self, what: &str, total: usize) {
        *self.batch.lock().unwrap_or_else(|e| e.into_inner()) = Some(Batch {
            what: what.to_string(),
            total,
            done: 0,
            start: Instant::now(),
        });
        if !self.draw {
            eprintln!("lash: {total} {what} to run");
            return;
        }
        let b = self.bar.get_or_init(|| {
            let b = ProgressBar::new(total as u64);
            if let Ok(style) = ProgressStyle::with_template(BAR_TEMPLATE) {
                b.set_style(style);
            }
            b
        });
        b.reset();
        b.set_length(total as u64);
        b.set_prefix(what.to_string());
    }

    fn finished(&self, what: &str, secs: f64) {
        self.count_then(what, secs, |line| eprintln!("{line}"));
        if let Some(b) = self.bar.get() {
            b.inc(1);
            b.set_message(what.to_string());
        }
    }

    fn note(&self, line: &Message) {
        let text = line.render(&flag);
        match self.bar.get() {
            Some(b) => b.suspend(|| crate::out::errln(&text)),
            None => crate::out::errln(&text),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Items finishing together on several threads: each line is numbered and emitted in one
    /// step, so the lines come out numbered 1, 2, …, n (the flake of long_work.rs, "[3/4]"
    /// printed before "[2/4]", came from counting and printing in two steps).
    #[test]
    fn lines_of_items_finishing_together_come_out_in_order() {
        let p = StderrProgress::with_bar(false);
        let n = 8 * 200;
        p.started("points", n);
        let out = Mutex::new(Vec::new());
        std::thread::scope(|s| {
            for _ in 0..8 {
                s.spawn(|| {
                    for _ in 0..200 {
                        p.count_then("p", 0.0, |l| out.lock().unwrap().push(l));
                    }
                });
            }
        });
        let out = out.into_inner().unwrap();
        assert_eq!(out.len(), n);
        for (k, l) in out.iter().enumerate() {
            assert!(l.starts_with(&format!("[{}/{n}] p ", k + 1)), "{k}: {l}");
        }
    }

    #[test]
    fn without_a_terminal_each_item_is_a_line_with_what_is_left() {
        let p = StderrProgress::with_bar(false);
        p.started("runs", 3);
        let l = p.count("case a", 1.5).unwrap();
        assert!(
            l.starts_with("[1/3] case a (1.50 s); 2 runs left, ~"),
            "{l}"
        );
        assert!(l.ends_with(" to go"), "{l}");
        p.count("case b", 0.1).unwrap();
        assert_eq!(
            p.count("case c", 75.0).unwrap(),
            "[3/3] case c (1 min 15 s); all runs done"
        );
        assert!(p.bar.get().is_none());
        // A second batch starts counting afresh.
        p.started("points", 1);
        assert_eq!(
            p.count("p", 0.0).unwrap(),
            "[1/1] p (0.00 s); all points done"
        );
    }

    #[test]
    fn on_a_terminal_the_bar_counts() {
        let p = StderrProgress::with_bar(true);
        p.started("points", 3);
        p.finished("a", 0.1);
        assert_eq!(p.bar.get().map(|b| b.position()), Some(1));
        assert!(p.count("b", 0.1).is_none());
        p.clear();
    }

    #[test]
    fn durations_read_at_a_glance() {
        assert_eq!(duration(0.421), "0.42 s");
        assert_eq!(duration(12.34), "12.3 s");
        assert_eq!(duration(245.0), "4 min 05 s");
        assert_eq!(duration(7380.0), "2 h 03 min");
        assert_eq!(duration(f64::NAN), "?");
    }
}
