//! Work–precision tables: error against cost for every run, and the cheapest run for each
//! accuracy target.
//!
//! ```text
//! run k: (method, controller, rtol | step) → error e_k (None if it failed), cost c_k
//!        cost = RHS evaluations, or wall time
//! cheapest(target, cost) = argmin { c_k : e_k ≤ target }   (ties: smaller error, then order)
//! files: work_precision.md, work_precision.json,
//!        wp_rhs.{svg,png} (error vs RHS evaluations), wp_time.{svg,png} (error vs wall time)
//! ```
//!
//! Source: docs/outputs.md ("`lash work-precision CASE`"); work–precision diagrams as in
//! Hairer & Wanner, Solving ODEs II, §IV.10, and DiffEqDevTools' WorkPrecisionSet.

use std::path::{Path, PathBuf};

use lash_solver::{ControllerKind, Method};

use crate::error::{Error, OptionError};
use crate::options::no_duplicates;
use crate::report::plot::{self, Axes, Series, SeriesStyle};
use crate::store::io;

/// A number for a table: plain for 0.01 ≤ |x| < 1e5 (at most 4 decimals), else scientific
/// with at most 4 significant digits (`1e-6`, `3.25e-7`).
pub(crate) fn fmt_num(x: f64) -> String {
    let a = x.abs();
    let trim = |s: String| s.trim_end_matches('0').trim_end_matches('.').to_string();
    if x == 0.0 {
        "0".into()
    } else if (1e-2..1e5).contains(&a) {
        trim(format!("{x:.4}"))
    } else {
        let s = format!("{x:.3e}");
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", trim(m.to_string())),
            None => s,
        }
    }
}

/// Default accuracy targets.
pub(crate) const DEFAULT_TARGETS: [f64; 5] = [1e-2, 1e-4, 1e-6, 1e-8, 1e-10];

/// Default tolerances of a work–precision set.
pub(crate) const DEFAULT_TOLERANCES: [f64; 3] = [1e-4, 1e-6, 1e-8];

/// The method the controllers are compared on when it is listed: the highest-order pair,
/// whose steps are longest and so most sensitive to the controller.
pub(crate) const CONTROLLER_METHOD: Method = Method::Dop853;

/// A checked work–precision request.
///
/// ```text
/// runs = {adaptive m} × tolerances  ∪  {fixed-step m} × steps  ∪  controllers × tolerances
///        (the controllers on one adaptive method of ours)
/// ```
///
/// Source: docs/outputs.md ("`lash work-precision CASE`").
#[derive(Debug, Clone, PartialEq)]
pub struct WorkPrecisionPlan {
    /// Methods, in the order given, no duplicates.
    pub methods: Vec<Method>,
    /// Tolerances of the adaptive methods (empty when there are none).
    pub tolerances: Vec<f64>,
    /// Steps of the fixed-step methods; None = derive from the case.
    pub steps: Option<Vec<f64>>,
    /// Controllers to compare (empty when no method in the list takes one).
    pub controllers: Vec<ControllerKind>,
}

impl WorkPrecisionPlan {
    /// Checks the lists of a request (None = not given) against each other and applies the
    /// defaults: every method, [`DEFAULT_TOLERANCES`], every controller. Errors name the
    /// lists as the options `methods`, `tolerances`, `steps`, `controllers`.
    pub(crate) fn new(
        methods: Option<&[Method]>,
        tolerances: Option<&[f64]>,
        steps: Option<&[f64]>,
        controllers: Option<&[ControllerKind]>,
    ) -> Result<WorkPrecisionPlan, Error> {
        let methods = methods.map_or_else(|| Method::ALL.to_vec(), <[Method]>::to_vec);
        no_duplicates("methods", &methods, |m| m.name().to_string())?;
        let any_fixed = methods.iter().any(|m| m.is_fixed_step());
        let any_adaptive = methods.iter().any(|m| !m.is_fixed_step());
        let any_controlled = methods
            .iter()
            .any(|m| !m.is_fixed_step() && !m.is_diffsol());
        if steps.is_some() && !any_fixed {
            return Err(
                OptionError::leading("steps", " is only for fixed-step methods, and ")
                    .name("methods")
                    .text(" lists none")
                    .into(),
            );
        }
        if tolerances.is_some() && !any_adaptive {
            return Err(
                OptionError::leading("tolerances", " is only for adaptive methods, and ")
                    .name("methods")
                    .text(" lists none")
                    .into(),
            );
        }
        if controllers.is_some() && !any_controlled {
            return Err(OptionError::leading(
                "controllers",
                " needs an adaptive method with our step control in ",
            )
            .name("methods")
            .into());
        }
        let tolerances = match tolerances {
            Some(t) => t.to_vec(),
            None if any_adaptive => DEFAULT_TOLERANCES.to_vec(),
            None => vec![],
        };
        no_duplicates("tolerances", &tolerances, |t| format!("{t:e}"))?;
        if let Some(s) = steps {
            no_duplicates("steps", s, |h| format!("{h:e}"))?;
        }
        let controllers = match controllers {
            Some(c) => c.to_vec(),
            None if any_controlled => ControllerKind::ALL.to_vec(),
            None => vec![],
        };
        no_duplicates("controllers", &controllers, |c| c.name().to_string())?;
        Ok(WorkPrecisionPlan {
            methods,
            tolerances,
            steps: steps.map(<[f64]>::to_vec),
            controllers,
        })
    }

    /// The method of ours the controllers are compared on: [`CONTROLLER_METHOD`] if listed,
    /// else the first adaptive method of ours in the list.
    pub(crate) fn controller_method(&self) -> Option<Method> {
        if self.methods.contains(&CONTROLLER_METHOD) {
            Some(CONTROLLER_METHOD)
        } else {
            self.methods
                .iter()
                .copied()
                .find(|m| !m.is_fixed_step() && !m.is_diffsol())
        }
    }
}

/// One run of a work–precision set.
///
/// ```text
/// (formulation, method, controller, rtol | step) → (error, rhs_evals, wall_time_s)
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct WpRun {
    /// The formulation the run was made with, when formulations are compared
    /// (`--formulations`); None: the case's own (and not written).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formulation: Option<String>,
    /// Method.
    pub method: Method,
    /// Controller (None for fixed-step and diffsol's methods).
    pub controller: Option<ControllerKind>,
    /// Relative tolerance (adaptive methods).
    pub rtol: Option<f64>,
    /// Fixed step, s (fixed-step methods).
    pub step: Option<f64>,
    /// Error against the reference (None when the run failed).
    pub error: Option<f64>,
    /// RHS evaluations.
    pub rhs_evals: usize,
    /// Wall time of the integration, s.
    pub wall_time_s: f64,
    /// The failure, when the run failed.
    pub failure: Option<String>,
}

impl WpRun {
    /// The curve the run belongs to: `method` or `method/controller`, followed by
    /// ` [formulation]` when formulations are compared.
    pub(crate) fn label(&self) -> String {
        let base = match self.controller {
            Some(c) => format!("{}/{}", self.method, c),
            None => self.method.to_string(),
        };
        match &self.formulation {
            Some(f) => format!("{base} [{f}]"),
            None => base,
        }
    }

    /// Its setting: `rtol 1e-6` or `h 1e-4`.
    pub(crate) fn setting(&self) -> String {
        match (self.rtol, self.step) {
            (_, Some(h)) => format!("h {}", fmt_num(h)),
            (Some(r), None) => format!("rtol {}", fmt_num(r)),
            (None, None) => "default".into(),
        }
    }
}

/// What a run's cost is measured in.
///
/// ```text
/// RhsEvals: c = stats.rhs_evals;  WallTime: c = wall_time_s
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Cost {
    /// Right-hand-side evaluations.
    RhsEvals,
    /// Wall time.
    WallTime,
}

fn cost_of(r: &WpRun, cost: Cost) -> f64 {
    match cost {
        Cost::RhsEvals => r.rhs_evals as f64,
        Cost::WallTime => r.wall_time_s,
    }
}

/// Index of the cheapest run whose error is at most `target` (ties: smaller error, then
/// earlier run); None if no run reached it.
pub(crate) fn cheapest(runs: &[WpRun], target: f64, cost: Cost) -> Option<usize> {
    runs.iter()
        .enumerate()
        .filter(|(_, r)| r.error.is_some_and(|e| e <= target))
        .min_by(|(i, a), (j, b)| {
            cost_of(a, cost)
                .total_cmp(&cost_of(b, cost))
                .then(a.error.unwrap_or(0.0).total_cmp(&b.error.unwrap_or(0.0)))
                .then(i.cmp(j))
        })
        .map(|(i, _)| i)
}

/// The cheapest runs for one target (indices into `runs`).
///
/// ```text
/// by_X = argmin { cost_X(run k) : error_k ≤ target }
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Cheapest {
    /// Accuracy target.
    pub target: f64,
    /// Cheapest by RHS evaluations.
    pub by_rhs_evals: Option<usize>,
    /// Cheapest by wall time.
    pub by_wall_time: Option<usize>,
}

/// A work–precision set with its cheapest runs.
///
/// ```text
/// cheapest[j] = (target_j, cheapest(runs, target_j, RhsEvals), cheapest(runs, target_j, WallTime))
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WpTable {
    /// Case name.
    pub(crate) case: String,
    /// The runs, in the order made.
    pub(crate) runs: Vec<WpRun>,
    /// The cheapest runs per target.
    pub(crate) cheapest: Vec<Cheapest>,
    /// What the error measures, in words (the figures' axis label; empty: "error").
    #[serde(default)]
    pub(crate) error_measure: String,
}

impl WpTable {
    /// Checks the runs (errors finite and ≥ 0, wall times finite and ≥ 0) and targets (> 0)
    /// and finds the cheapest runs.
    pub(crate) fn new(case: &str, runs: Vec<WpRun>, targets: &[f64]) -> Result<WpTable, Error> {
        for r in &runs {
            if r.error.is_some_and(|e| !(e.is_finite() && e >= 0.0)) {
                return Err(Error::Internal(format!(
                    "work-precision: {} {} has error {:?}",
                    r.label(),
                    r.setting(),
                    r.error
                )));
            }
            if !(r.wall_time_s.is_finite() && r.wall_time_s >= 0.0) {
                return Err(Error::Internal(format!(
                    "work-precision: {} {} has wall time {}",
                    r.label(),
                    r.setting(),
                    r.wall_time_s
                )));
            }
        }
        if let Some(t) = targets.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
            return Err(Error::Internal(format!("work-precision: target {t}")));
        }
        let cheapest = targets
            .iter()
            .map(|&target| Cheapest {
                target,
                by_rhs_evals: cheapest(&runs, target, Cost::RhsEvals),
                by_wall_time: cheapest(&runs, target, Cost::WallTime),
            })
            .collect();
        Ok(WpTable {
            error_measure: String::new(),
            case: case.to_string(),
            runs,
            cheapest,
        })
    }

    fn marks(&self, i: usize, pick: impl Fn(&Cheapest) -> Option<usize>) -> String {
        let t: Vec<String> = self
            .cheapest
            .iter()
            .filter(|c| pick(c) == Some(i))
            .map(|c| fmt_num(c.target))
            .collect();
        t.join(", ")
    }

    fn describe(&self, i: Option<usize>, cost: Cost) -> String {
        match i {
            Some(i) => {
                let r = &self.runs[i];
                let c = match cost {
                    Cost::RhsEvals => format!("{} RHS", r.rhs_evals),
                    Cost::WallTime => format!("{} s", fmt_num(r.wall_time_s)),
                };
                format!("**{} {}** ({c})", r.label(), r.setting())
            }
            None => "none reached it".into(),
        }
    }

    /// The markdown report: every run, and the cheapest run per target.
    pub fn to_markdown(&self) -> String {
        let mut s = format!("# Work–precision: {}\n\n", self.case);
        s.push_str("| method | setting | error | RHS evals | wall time, s | cheapest (RHS) for | cheapest (time) for |\n");
        s.push_str("|---|---|---|---|---|---|---|\n");
        for (i, r) in self.runs.iter().enumerate() {
            let err = match (&r.error, &r.failure) {
                (Some(e), _) => fmt_num(*e),
                (None, Some(f)) => format!("failed: {}", f.replace('|', "\\|")),
                (None, None) => "failed".into(),
            };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {} |\n",
                r.label(),
                r.setting(),
                err,
                r.rhs_evals,
                fmt_num(r.wall_time_s),
                self.marks(i, |c| c.by_rhs_evals),
                self.marks(i, |c| c.by_wall_time),
            ));
        }
        s.push_str("\n## Cheapest run per accuracy target\n\n");
        s.push_str("| error ≤ | by RHS evaluations | by wall time |\n|---|---|---|\n");
        for c in &self.cheapest {
            s.push_str(&format!(
                "| {} | {} | {} |\n",
                fmt_num(c.target),
                self.describe(c.by_rhs_evals, Cost::RhsEvals),
                self.describe(c.by_wall_time, Cost::WallTime),
            ));
        }
        s
    }

    /// One series per curve (label), runs sorted by cost, failed and zero-error runs left out
    /// (a log axis cannot show them).
    fn curves(&self, cost: Cost) -> Vec<(String, Vec<f64>, Vec<f64>)> {
        let mut labels: Vec<String> = Vec::new();
        for r in &self.runs {
            if !labels.contains(&r.label()) {
                labels.push(r.label());
            }
        }
        labels
            .into_iter()
            .filter_map(|l| {
                let mut pts: Vec<(f64, f64)> = self
                    .runs
                    .iter()
                    .filter(|r| r.label() == l)
                    .filter_map(|r| r.error.map(|e| (cost_of(r, cost), e)))
                    .filter(|&(c, e)| c > 0.0 && e > 0.0)
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                (!pts.is_empty()).then(|| {
                    let (x, y) = pts.into_iter().unzip();
                    (l, x, y)
                })
            })
            .collect()
    }

    /// Writes work_precision.md, work_precision.json and the two log–log figures into `dir`
    /// (created if needed); returns the paths.
    pub(crate) fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
        io::create_dir(dir)?;
        let mut out = Vec::new();
        let y_label = if self.error_measure.is_empty() {
            "error".to_string()
        } else {
            format!("error: {}", self.error_measure)
        };
        for (stem, cost, x_label, what) in [
            (
                "wp_rhs",
                Cost::RhsEvals,
                "cost: right-hand-side evaluations",
                "RHS evaluations",
            ),
            ("wp_time", Cost::WallTime, "cost: wall time, s", "wall time"),
        ] {
            let curves = self.curves(cost);
            if curves.is_empty() {
                continue;
            }
            // Line style by family: explicit methods solid, stiff methods dashed; each series
            // its own marker (plot module).
            let series: Vec<Series<'_>> = curves
                .iter()
                .map(|(l, x, y)| Series {
                    name: l,
                    x,
                    y,
                    style: match Method::from_name(l.split('/').next().unwrap_or(l)) {
                        Some(m) if m.is_stiff() => SeriesStyle::DashedPoints,
                        _ => SeriesStyle::LinePoints,
                    },
                })
                .collect();
            let title = format!(
                "Work–precision, {}: error against {what}",
                plot::plain(&self.case)
            );
            let w = plot::loglog_plot(
                &dir.join(stem),
                &Axes {
                    title: &title,
                    x_label,
                    y_label: &y_label,
                },
                &series,
            )?;
            out.push(w.svg);
            out.push(w.png);
        }
        let md = dir.join("work_precision.md");
        io::write_atomic(&md, self.to_markdown().as_bytes())?;
        let js = dir.join("work_precision.json");
        io::write_json_atomic(&js, self)?;
        out.push(md);
        out.push(js);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(
        m: Method,
        c: Option<ControllerKind>,
        rtol: f64,
        err: Option<f64>,
        rhs: usize,
        wall: f64,
    ) -> WpRun {
        WpRun {
            formulation: None,
            method: m,
            controller: c,
            rtol: (!m.is_fixed_step()).then_some(rtol),
            step: m.is_fixed_step().then_some(rtol),
            error: err,
            rhs_evals: rhs,
            wall_time_s: wall,
            failure: err
                .is_none()
                .then(|| "step size too small at t = 1e-1".into()),
        }
    }

    fn set() -> Vec<WpRun> {
        use ControllerKind::*;
        use Method::*;
        vec![
            run(Dopri54, Some(Pi), 1e-3, Some(1e-3), 100, 0.010), // 0
            run(Dopri54, Some(Pi), 1e-6, Some(1e-5), 1000, 0.020), // 1
            run(Bdf, None, 1e-6, Some(1e-5), 800, 0.050),         // 2
            run(Rk4, None, 1e-4, None, 4000, 0.100),              // 3 failed
            run(Dopri54, Some(H211), 1e-6, Some(2e-5), 800, 0.015), // 4
        ]
    }

    #[test]
    fn cheapest_run_per_target() {
        let r = set();
        // 1e-2: every successful run qualifies; run 0 costs least.
        assert_eq!(cheapest(&r, 1e-2, Cost::RhsEvals), Some(0));
        // 1e-4 by RHS: runs 1, 2, 4 qualify; 2 and 4 tie at 800, run 2 has the smaller error.
        assert_eq!(cheapest(&r, 1e-4, Cost::RhsEvals), Some(2));
        // by wall time run 4 (0.015 s) beats 1 (0.020 s) and 2 (0.050 s).
        assert_eq!(cheapest(&r, 1e-4, Cost::WallTime), Some(4));
        // 1e-6: nothing reached it; a failed run never counts.
        assert_eq!(cheapest(&r, 1e-6, Cost::RhsEvals), None);
        assert_eq!(cheapest(&r, 1.0, Cost::WallTime), Some(0));
    }

    #[test]
    fn markdown_marks_the_cheapest() {
        let t = WpTable::new("lub_150rpm_c0.1", set(), &[1e-2, 1e-4, 1e-6]).unwrap();
        let md = t.to_markdown();
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(lines[0], "# Work–precision: lub_150rpm_c0.1");
        assert_eq!(
            lines[4],
            "| dopri54/pi | rtol 1e-3 | 1e-3 | 100 | 0.01 | 0.01 | 0.01 |"
        );
        assert_eq!(
            lines[6],
            "| bdf | rtol 1e-6 | 1e-5 | 800 | 0.05 | 1e-4 |  |"
        );
        assert!(lines[7].starts_with("| rk4 | h 1e-4 | failed: step size too small"));
        assert_eq!(
            lines[8],
            "| dopri54/h211 | rtol 1e-6 | 2e-5 | 800 | 0.015 |  | 1e-4 |"
        );
        assert!(md.contains(
            "| 1e-4 | **bdf rtol 1e-6** (800 RHS) | **dopri54/h211 rtol 1e-6** (0.015 s) |"
        ));
        assert!(md.contains("| 1e-6 | none reached it | none reached it |"));
        assert_eq!(fmt_num(3.25e-7), "3.25e-7");
        assert_eq!(fmt_num(-12345.678), "-12345.678");
        assert_eq!(fmt_num(2.5e5), "2.5e5");
    }

    #[test]
    fn files_and_json_round_trip() {
        let d = tempfile::tempdir().unwrap();
        let t = WpTable::new("c", set(), &DEFAULT_TARGETS).unwrap();
        let files = t.write(d.path()).unwrap();
        assert_eq!(files.len(), 6);
        let back: WpTable =
            serde_json::from_slice(&std::fs::read(d.path().join("work_precision.json")).unwrap())
                .unwrap();
        assert_eq!(back, t);
        let svg = std::fs::read_to_string(d.path().join("wp_rhs.svg")).unwrap();
        for l in ["dopri54/pi", "dopri54/h211", "bdf"] {
            assert!(svg.contains(&format!("\n{l}\n")), "{l}");
        }
        // The failed rk4 run has no point, so no curve.
        assert!(!svg.contains("\nrk4\n"));
        // Curves go by increasing cost.
        let c = t.curves(Cost::RhsEvals);
        assert_eq!(c[0].0, "dopri54/pi");
        assert_eq!(c[0].1, vec![100.0, 1000.0]);
    }

    #[test]
    fn bad_numbers_are_refused() {
        let mut r = set();
        r[0].error = Some(f64::NAN);
        assert!(WpTable::new("c", r, &[1e-3]).is_err());
        assert!(WpTable::new("c", set(), &[0.0]).is_err());
        let mut r = set();
        r[1].wall_time_s = -1.0;
        assert!(WpTable::new("c", r, &[1e-3]).is_err());
    }
}
