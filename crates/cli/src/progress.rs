//! The engine's progress on standard error: notes as lines, a batch (the points of a sweep) as
//! a progress bar when standard error is a terminal.
//!
//! ```text
//! started(n)    → a bar of n items (terminal only; drawn from then on)
//! finished(..)  → the bar advances by one
//! note(line)    → the line on standard error, options spelled as flags (above the bar)
//! clear()       → the bar disappears (before the command's closing line)
//! ```
//!
//! Source: ARCHITECTURE.md ("Invariants": the engine prints nothing; the CLI draws what it
//! reports).

use std::io::IsTerminal;
use std::sync::OnceLock;

use indicatif::{ProgressBar, ProgressStyle};
use lash_validation::error::Message;
use lash_validation::Progress;

use crate::exit::flag;

/// Template of the progress bar.
const BAR_TEMPLATE: &str = "{bar:40} {pos}/{len} points  {elapsed_precise} elapsed, ~{eta} left";

/// [`Progress`] on standard error.
///
/// Source: this module.
#[derive(Debug)]
pub struct StderrProgress {
    /// Whether to draw a bar for a batch.
    draw: bool,
    /// The bar, from the first batch on.
    bar: OnceLock<ProgressBar>,
}

impl StderrProgress {
    /// Notes on standard error, and a bar for a batch when standard error is a terminal.
    pub fn new() -> Self {
        Self::with_bar(std::io::stderr().is_terminal())
    }

    /// Notes on standard error, and a bar for a batch if `draw`.
    pub fn with_bar(draw: bool) -> Self {
        StderrProgress {
            draw,
            bar: OnceLock::new(),
        }
    }

    /// Removes the bar, if one was drawn.
    pub fn clear(&self) {
        if let Some(b) = self.bar.get() {
            b.finish_and_clear();
        }
    }
}

impl Default for StderrProgress {
    fn default() -> Self {
        Self::new()
    }
}

impl Progress for StderrProgress {
    fn started(&self, total: usize) {
        if !self.draw {
            return;
        }
        let b = self.bar.get_or_init(|| {
            let b = ProgressBar::new(total as u64);
            if let Ok(style) = ProgressStyle::with_template(BAR_TEMPLATE) {
                b.set_style(style);
            }
            b
        });
        b.set_length(total as u64);
    }

    fn finished(&self, _what: &str, _secs: f64) {
        if let Some(b) = self.bar.get() {
            b.inc(1);
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

    #[test]
    fn without_a_terminal_there_is_no_bar() {
        let p = StderrProgress::with_bar(false);
        p.started(3);
        p.finished("a", 0.1);
        assert!(p.bar.get().is_none());
        p.clear();
        let p = StderrProgress::with_bar(true);
        p.started(3);
        p.finished("a", 0.1);
        assert_eq!(p.bar.get().map(|b| b.position()), Some(1));
        p.clear();
    }
}
