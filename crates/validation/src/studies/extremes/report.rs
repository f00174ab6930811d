//! The matrix as files and lines: extremes.md, extremes.json, the summary the command prints
//! and the check that no run failed.
//!
//! Source: docs/outputs.md ("`lash extremes`").

use std::path::{Path, PathBuf};

use lash_solver::Method;

use crate::compare::workprecision::fmt_num;
use crate::error::Error;
use crate::store::io;
use crate::studies::extremes::outcome::Cell;
use crate::studies::extremes::outcome::Matrix;
use crate::studies::extremes::outcome::Outcome;
use crate::studies::extremes::plan::Setting;
use crate::studies::extremes::plan::ADAPTIVE;
use crate::studies::extremes::runner::setting_value;

impl Matrix {
    /// The failures, one line each.
    pub(crate) fn failure_lines(&self) -> Vec<String> {
        self.lines(|o| o.is_failure())
    }

    /// The known findings that occurred, one line each.
    pub(crate) fn known_lines(&self) -> Vec<String> {
        self.lines(|o| matches!(o, Outcome::Known { .. }))
    }

    fn lines(&self, pick: impl Fn(&Outcome) -> bool) -> Vec<String> {
        self.cells
            .iter()
            .filter(|c| pick(&c.outcome))
            .map(|c| {
                format!(
                    "{} {} {}: {:?}",
                    c.scene,
                    c.setting.label(),
                    setting_value(&c.setting),
                    c.outcome
                )
            })
            .collect()
    }

    /// The markdown report.
    pub(crate) fn to_markdown(&self) -> String {
        let mut s = String::from("# Extremes matrix\n\n");
        s.push_str(&format!(
            "{} scenes × (rk4 inside and beyond its stability limit, {} adaptive methods × \
             rtol {}); every run budgeted at {} step attempts and {} s. {} runs, {} failures; \
             wall time {:.1} s (jobs {}).\n\n",
            self.scenes.len(),
            ADAPTIVE.len(),
            self.plan
                .tolerances
                .iter()
                .map(|t| fmt_num(*t))
                .collect::<Vec<_>>()
                .join(", "),
            self.plan.budget.max_steps,
            fmt_num(self.plan.budget.max_wall_time),
            self.cells.len(),
            self.failures,
            self.wall_time_s,
            self.plan.jobs,
        ));
        s.push_str(&format!(
            "Error e = max(|Δx|/r, |Δv|/max(rω, max|v_ref|)) of the slider on 2001 points of \
             the error window. Promise: adaptive e ≤ C·rtol^α + F·E_ref (C = {} with a dry \
             joint, {} lubricated; α = 1 for \
             bs32, dopri54, tsit54, dop853, rodas5p; 2/3 trbdf2; 3/4 esdirk34; 5/6 bdf), rk4 \
             e(h) ≤ C_rk4·e(h; h/2) + F·E_ref (C_rk4 = {}), F = {}. Cells: `ok R` agrees \
             (R = e/promise), `KIND @t` a typed error at time t (h-min: step size too small, \
             steps: step budget, wall: wall-clock budget, diverged: non-finite or diverging \
             state, newton: Newton failure); *known* breaks the promise in a known finding \
             (listed at the end); **WRONG**, **REJECTED**, **PANIC** are failures.\n\n",
            fmt_num(self.promise_c_dry),
            fmt_num(self.promise_c_lubricated),
            fmt_num(self.promise_c_rk4),
            fmt_num(self.promise_f)
        ));
        s.push_str("## Scenes and references\n\nE_ref is the larger of the two `differ` columns: the reference against the check method at the same rtol, and against itself at 10 × rtol.\n\n");
        s.push_str("| scene | stresses | t_end, s | window | reference | methods differ | tolerances differ | ε_max | rk4 h in / beyond, s | rk4 beyond stopped at |\n");
        s.push_str("|---|---|---|---|---|---|---|---|---|---|\n");
        for r in &self.scenes {
            let stop = self
                .cells
                .iter()
                .find(|c| c.scene == r.stem && matches!(c.setting, Setting::Rk4Beyond { .. }))
                .map_or("–".into(), |c| match &c.outcome {
                    Outcome::Failed { t, .. } => format!("t = {}", fmt_num(*t)),
                    o => o.cell(),
                });
            s.push_str(&format!(
                "| {} | {} | {} | {} [{}, {}] | {} vs {} at {} | {} | {} | {} | {} / {} | {} |\n",
                r.stem,
                r.stresses,
                fmt_num(r.t_end),
                r.window.label,
                fmt_num(r.window.start),
                fmt_num(r.window.end),
                r.reference,
                r.check,
                fmt_num(r.reference_rtol),
                fmt_num(r.agreement_methods),
                fmt_num(r.agreement_tolerance),
                r.eps_max.map_or("–".into(), |e| format!("{e:.5}")),
                fmt_num(r.rk4_steps.0),
                fmt_num(r.rk4_steps.1),
                stop
            ));
        }
        s.push_str("\n## Counts per method\n\n");
        s.push_str("| method | runs | agreed | typed errors | known findings | failures | largest measured C (known findings left out) |\n");
        s.push_str("|---|---|---|---|---|---|---|\n");
        for c in &self.counts {
            let errs = if c.errored.is_empty() {
                "0".to_string()
            } else {
                let n: usize = c.errored.values().sum();
                let parts: Vec<String> =
                    c.errored.iter().map(|(k, v)| format!("{k} {v}")).collect();
                format!("{n} ({})", parts.join(", "))
            };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {} |\n",
                c.label,
                c.runs,
                c.agreed,
                errs,
                c.known,
                c.failures,
                c.measured_c_max.map_or("–".into(), fmt_num)
            ));
        }
        s.push_str("\n## Runs\n\n");
        for r in &self.scenes {
            s.push_str(&format!("### {}\n\n| method |", r.stem));
            for t in &self.plan.tolerances {
                s.push_str(&format!(" {} |", fmt_num(*t)));
            }
            s.push_str("\n|---|");
            s.push_str(&"---|".repeat(self.plan.tolerances.len()));
            s.push('\n');
            let mine: Vec<&Cell> = self.cells.iter().filter(|c| c.scene == r.stem).collect();
            for c in mine.iter().filter(|c| c.setting.method() == Method::Rk4) {
                s.push_str(&format!(
                    "| {} ({}) | {} |{}\n",
                    c.setting.label(),
                    setting_value(&c.setting),
                    c.outcome.cell(),
                    " |".repeat(self.plan.tolerances.len().saturating_sub(1))
                ));
            }
            for m in ADAPTIVE {
                s.push_str(&format!("| {m} |"));
                for t in &self.plan.tolerances {
                    let c = mine.iter().find(|c| {
                        matches!(c.setting, Setting::Adaptive { method, rtol } if method == m && rtol == *t)
                    });
                    s.push_str(&format!(
                        " {} |",
                        c.map_or("–".into(), |c| c.outcome.cell())
                    ));
                }
                s.push('\n');
            }
            s.push('\n');
        }
        let known = self.known_lines();
        if !known.is_empty() {
            s.push_str("## Known findings\n\n");
            for l in known {
                s.push_str(&format!("- {}\n", l.replace('|', "\\|")));
            }
            s.push('\n');
        }
        let bad = self.failure_lines();
        if !bad.is_empty() {
            s.push_str("## Failures\n\n");
            for l in bad {
                s.push_str(&format!("- {}\n", l.replace('|', "\\|")));
            }
        }
        s
    }

    /// Writes extremes.md and extremes.json into `dir` (atomically); returns their paths.
    pub(crate) fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
        io::create_dir(dir)?;
        let md = dir.join("extremes.md");
        let js = dir.join("extremes.json");
        io::write_json_atomic(&js, self)?;
        io::write_atomic(&md, self.to_markdown().as_bytes())?;
        Ok(vec![md, js])
    }
}

impl Matrix {
    /// What `lash extremes` says about a matrix written to `md` and `json`: one line of counts per
    /// method, then the totals and the files.
    pub fn describe(&self, md: &Path, json: &Path) -> String {
        let mut s = String::new();
        for c in &self.counts {
            s.push_str(&format!(
                "{:10} {:3} runs: {:3} agreed, {:3} typed errors, {} known findings, {} failures\n",
                c.label,
                c.runs,
                c.agreed,
                c.errored.values().sum::<usize>(),
                c.known,
                c.failures
            ));
        }
        s.push_str(&format!(
            "{} runs in {:.1} s, {} known findings, {} failures; wrote {} and {}\n",
            self.cells.len(),
            self.wall_time_s,
            self.cells
                .iter()
                .filter(|c| matches!(c.outcome, Outcome::Known { .. }))
                .count(),
            self.failures,
            md.display(),
            json.display()
        ));
        s
    }
}

impl Matrix {
    /// Ok when no run of the matrix failed; else an internal error (a bug, exit code 1) that
    /// counts the failures and points to the report `md`, which lists them.
    pub fn check(&self, md: &Path) -> Result<(), Error> {
        if self.failures > 0 {
            return Err(Error::Internal(format!(
                "extremes: {} of {} runs failed: an outcome that is not allowed (listed in {})",
                self.failures,
                self.cells.len(),
                md.display()
            )));
        }
        Ok(())
    }
}
