//! summary.json: what one run did, in the fields scripts rely on.
//!
//! ```text
//! fixed-step method: controller = rtol = atol = null, step = h
//! adaptive method:   step = null, rtol, atol as given (atol a number or an array),
//!                    controller = the one used (the method's default if none was chosen;
//!                    null for diffsol's methods, which use their own step control)
//! file case:         case = file stem, scene_sha256 = sha256 of its bytes
//! built-in case:     case = "testset:NAME", scene_sha256 = null
//! metrics            object for mechanism cases, else null
//! final_state, reference_error   built-in test problems, else null
//! ```
//!
//! Every key is always present (null when it does not apply). Source: docs/outputs.md
//! (`summary.json`).

use std::path::{Path, PathBuf};

use lash_solver::{Atol, ControllerKind, Method, SolverOptions, Stats};

use crate::error::Error;
use crate::report::metrics::Metrics;
use crate::run::case::Case;
use crate::store::io;

/// File name of the summary in an output directory.
pub(crate) const SUMMARY_FILE: &str = "summary.json";

/// Which case ran with which settings: the header the diagnostic reports (`stiffness.json`,
/// `poincare.json`) share with summary.json, flattened into their JSON objects.
///
/// ```text
/// { version, case, scene_sha256, method, controller, rtol, step }
/// fixed-step: controller = rtol = null, step = h;  adaptive: step = null
/// ```
///
/// Source: docs/outputs.md (`summary.json`, the same keys and meanings).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub(crate) struct RunHeader {
    /// lash version.
    pub version: String,
    /// Case name.
    pub case: String,
    /// sha256 of the scene file (null for built-ins).
    pub scene_sha256: Option<String>,
    /// Method.
    pub method: Method,
    /// Controller in use (`SolverOptions::controller_in_use`: the chosen one, else the
    /// method's default; null for fixed-step and diffsol's methods).
    pub controller: Option<ControllerKind>,
    /// Relative tolerance (null for fixed-step methods).
    pub rtol: Option<f64>,
    /// Fixed step (null for adaptive methods), s.
    pub step: Option<f64>,
}

impl RunHeader {
    /// The header of a run of `case` with `opts`.
    pub(crate) fn new(case: &Case, opts: &SolverOptions) -> RunHeader {
        let fixed = opts.method.is_fixed_step();
        RunHeader {
            version: env!("CARGO_PKG_VERSION").to_string(),
            case: case.name.clone(),
            scene_sha256: case.sha256().map(str::to_string),
            method: opts.method,
            controller: opts.controller_in_use(),
            rtol: (!fixed).then_some(opts.rtol),
            step: if fixed { opts.step } else { None },
        }
    }

    /// `rtol R` (adaptive) or `step H s` (fixed-step).
    pub(crate) fn accuracy(&self) -> String {
        match (self.rtol, self.step) {
            (Some(t), _) => format!("rtol {t:e}"),
            (None, Some(h)) => format!("step {h:e} s"),
            _ => String::new(),
        }
    }
}

/// The content of summary.json.
///
/// ```text
/// { version, case, scene_sha256, method, controller, rtol, atol, step, t_end, stats,
///   wall_time_s, events, metrics, final_state, reference_error }
/// ```
///
/// Source: docs/outputs.md (`summary.json`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Summary {
    /// lash version string.
    pub version: String,
    /// File stem of the scene or `testset:NAME`.
    pub case: String,
    /// sha256 of the scene file's bytes (null for built-ins).
    pub scene_sha256: Option<String>,
    /// Method name.
    pub method: Method,
    /// Controller name (null for fixed-step and diffsol's methods).
    pub controller: Option<ControllerKind>,
    /// Relative tolerance (null for fixed-step methods).
    pub rtol: Option<f64>,
    /// Absolute tolerance, number or array (null for fixed-step methods).
    pub atol: Option<Atol>,
    /// Fixed step, s (null for adaptive methods).
    pub step: Option<f64>,
    /// End time, s.
    pub t_end: f64,
    /// The solver's counters.
    pub stats: Stats,
    /// Wall time of the integration alone (no I/O), s.
    pub wall_time_s: f64,
    /// Events located during the whole run.
    pub events: usize,
    /// Mechanism metrics (null for built-in test problems).
    pub metrics: Option<Metrics>,
    /// Final state (built-in test problems).
    pub final_state: Option<Vec<f64>>,
    /// Error against the reference solution (built-in test problems).
    pub reference_error: Option<f64>,
    /// How a run until periodic ended (`--until-periodic`; absent otherwise): revolutions,
    /// whether the section settled, its change per revolution (`run::steady`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub until_periodic: Option<Settled>,
    /// The metrics window [from, to], s, of a mechanism case (`--window`;
    /// docs/outputs.md, "The metrics window"); absent for built-in test problems.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics_window: Option<[f64; 2]>,
    /// Turns of the crank over the run, (φ(t_end) − φ(t_start))/2π, signed (counter-clockwise
    /// positive); absent without a crank (`roles.crank`, `roles.crank_driver`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crank_revolutions: Option<f64>,
    /// The formulation of a mechanism case (`lagrange_baumgarte`, `augmented_lagrangian`;
    /// docs/model.md §12); absent for built-in test problems.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formulation: Option<String>,
    /// Whether the run's mechanism had the kink events of its clearance joints' force laws
    /// (the scene's `kink_events`, or the automatic choice: on with a dry revolute clearance
    /// joint whose laws have a kink, off for the paper's RK4; docs/model.md §7); with them an
    /// adaptive one-step method also takes exact event steps. Absent for built-in test
    /// problems.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kink_events: Option<bool>,
    /// The formulation's iteration statistics over the run (the augmented Lagrangian's:
    /// evaluations, iterations, max_iterations, unconverged); absent for one that does not
    /// iterate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formulation_stats: Option<lash_model::FormulationStats>,
    /// What each clearance joint did against the ranges of its laws over the whole run
    /// (deepest penetration, excursions beyond the clearance, films beyond their law's range;
    /// docs/model.md §3.5); absent for a case without clearance joints.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub law_range: Option<Vec<lash_model::LawRangeRecord>>,
}

impl Summary {
    /// A summary of a run of `case` with `opts`, applying the null rules; metrics,
    /// final_state and reference_error start null.
    pub(crate) fn new(
        case: &Case,
        opts: &SolverOptions,
        t_end: f64,
        stats: Stats,
        wall_time_s: f64,
        events: usize,
    ) -> Summary {
        let fixed = opts.method.is_fixed_step();
        Summary {
            version: env!("CARGO_PKG_VERSION").to_string(),
            case: case.name.clone(),
            scene_sha256: case.sha256().map(str::to_string),
            method: opts.method,
            controller: opts.controller_in_use(),
            rtol: (!fixed).then_some(opts.rtol),
            atol: (!fixed).then(|| opts.atol.clone()),
            step: if fixed { opts.step } else { None },
            t_end,
            stats,
            wall_time_s,
            events,
            metrics: None,
            final_state: None,
            reference_error: None,
            until_periodic: None,
            metrics_window: None,
            crank_revolutions: None,
            formulation: None,
            kink_events: None,
            formulation_stats: None,
            law_range: None,
        }
    }

    /// Checks that every number is finite (JSON has no NaN: serde_json would write null).
    pub(crate) fn check_finite(&self) -> Result<(), Error> {
        let mut nums: Vec<(&str, f64)> = vec![
            ("t_end", self.t_end),
            ("wall_time_s", self.wall_time_s),
            ("stats.h_min_used", self.stats.h_min_used),
            ("stats.h_max_used", self.stats.h_max_used),
        ];
        nums.extend(self.rtol.map(|v| ("rtol", v)));
        nums.extend(self.step.map(|v| ("step", v)));
        nums.extend(self.reference_error.map(|v| ("reference_error", v)));
        match &self.atol {
            Some(Atol::Scalar(a)) => nums.push(("atol", *a)),
            Some(Atol::Vector(v)) => nums.extend(v.iter().map(|a| ("atol", *a))),
            None => {}
        }
        if let Some(y) = &self.final_state {
            nums.extend(y.iter().map(|v| ("final_state", *v)));
        }
        if let Some(m) = &self.metrics {
            let opt = [
                m.slider_acc_max,
                m.slider_acc_min,
                m.slider_acc_rms_dev_ideal,
                m.eps_max,
                m.contact_force_max,
                m.penetration_max,
                m.film_force_max,
                m.film_thickness_min,
                m.slider_x_end,
            ];
            nums.extend(opt.into_iter().flatten().map(|v| ("metrics", v)));
            nums.push(("metrics", m.constraint_violation_max));
            if let Some(e) = &m.energy {
                nums.push(("metrics.energy", e.balance_error));
                nums.push(("metrics.energy", e.quadrature_error));
            }
        }
        for r in self.law_range.iter().flatten() {
            nums.push(("law_range.depth_max", r.depth_max));
        }
        match nums.iter().find(|(_, v)| !v.is_finite()) {
            Some((name, v)) => Err(Error::Internal(format!("summary: {name} is {v}"))),
            None => Ok(()),
        }
    }

    /// Writes `dir/summary.json` atomically (after [`Summary::check_finite`]); returns its path.
    pub(crate) fn write(&self, dir: &Path) -> Result<PathBuf, Error> {
        self.check_finite()?;
        let p = dir.join(SUMMARY_FILE);
        io::write_json_atomic(&p, self)?;
        Ok(p)
    }
}

/// How a run until periodic ended.
///
/// ```text
/// revolutions = K;  settled ⇔ d_K < tol;  section_changes = [d_1, …, d_K]
/// ```
///
/// Source: docs/outputs.md (`until_periodic` of summary.json); the run until periodic is
/// `run::steady`'s.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settled {
    /// The request.
    pub tol: f64,
    /// The cap of the request.
    pub max_revolutions: usize,
    /// Revolutions run, K.
    pub revolutions: usize,
    /// Whether the section moved by less than tol·c in revolution K.
    pub settled: bool,
    /// d_k = |s_k − s_{k−1}| / c for k = 1..=K.
    pub section_changes: Vec<f64>,
}

impl Settled {
    /// d_K, the change in the last revolution.
    pub(crate) fn last_change(&self) -> f64 {
        self.section_changes.last().copied().unwrap_or(f64::NAN)
    }

    /// One line: "settled after K revolutions (…)" or "not settled within N revolutions (…)".
    pub(crate) fn describe(&self) -> String {
        if self.settled {
            format!(
                "until periodic: settled after {} revolutions (the section moved {:.2e} c in \
                 the last, below {:e} c)",
                self.revolutions,
                self.last_change(),
                self.tol
            )
        } else {
            format!(
                "until periodic: not settled within {} revolutions (the section moved {:.2e} c \
                 in the last, tolerance {:e} c); metrics are those of revolution {}",
                self.max_revolutions,
                self.last_change(),
                self.tol,
                self.revolutions
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::metrics::{compute, grid, Sample, Window};

    fn file_case(d: &Path) -> Case {
        std::fs::write(d.join("dry_150rpm_c0.1.json"), b"{}").unwrap();
        Case::load("dry_150rpm_c0.1.json", Some(d)).unwrap()
    }

    const KEYS: [&str; 15] = [
        "version",
        "case",
        "scene_sha256",
        "method",
        "controller",
        "rtol",
        "atol",
        "step",
        "t_end",
        "stats",
        "wall_time_s",
        "events",
        "metrics",
        "final_state",
        "reference_error",
    ];

    #[test]
    fn fixed_step_run_has_null_tolerances_and_controller() {
        let d = tempfile::tempdir().unwrap();
        let case = file_case(d.path());
        let opts = SolverOptions {
            method: Method::Rk4,
            step: Some(1e-5),
            ..Default::default()
        };
        let s = Summary::new(&case, &opts, 0.8, Stats::default(), 1.5, 3);
        let p = s.write(d.path()).unwrap();
        let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
        let keys: Vec<&String> = j.as_object().unwrap().keys().collect();
        let mut want = KEYS.to_vec();
        want.sort();
        assert_eq!(keys, want);
        assert_eq!(j["case"], "dry_150rpm_c0.1");
        assert_eq!(j["scene_sha256"], crate::run::case::sha256_hex(b"{}"));
        assert_eq!(j["method"], "rk4");
        assert!(j["controller"].is_null() && j["rtol"].is_null() && j["atol"].is_null());
        assert_eq!(j["step"], 1e-5);
        assert_eq!(j["events"], 3);
        assert_eq!(j["stats"]["rhs_evals"], 0);
        assert!(j["metrics"].is_null() && j["final_state"].is_null());
        let back: Summary = serde_json::from_value(j).unwrap();
        assert_eq!(back, s);
    }

    #[test]
    fn adaptive_runs_record_tolerances_and_the_controller_used() {
        let d = tempfile::tempdir().unwrap();
        let case = file_case(d.path());
        let mut opts = SolverOptions::with_method(Method::Dopri54);
        opts.rtol = 1e-8;
        opts.atol = Atol::Vector(vec![1e-10, 1e-6]);
        let j = serde_json::to_value(Summary::new(&case, &opts, 0.8, Stats::default(), 0.1, 0))
            .unwrap();
        assert_eq!(
            (j["rtol"].as_f64(), j["step"].is_null()),
            (Some(1e-8), true)
        );
        assert_eq!(j["atol"], serde_json::json!([1e-10, 1e-6]));
        assert_eq!(j["controller"], "pi");
        opts.controller = Some(ControllerKind::H211);
        opts.atol = Atol::Scalar(1e-9);
        let j = serde_json::to_value(Summary::new(&case, &opts, 0.8, Stats::default(), 0.1, 0))
            .unwrap();
        assert_eq!(
            (j["controller"].as_str(), j["atol"].as_f64()),
            (Some("h211"), Some(1e-9))
        );
        // Rodas5P's default is gustafsson; diffsol's methods record none.
        let ros = SolverOptions::with_method(Method::Rodas5p);
        let j =
            serde_json::to_value(Summary::new(&case, &ros, 0.8, Stats::default(), 0.1, 0)).unwrap();
        assert_eq!(j["controller"], "gustafsson");
        let bdf = SolverOptions::with_method(Method::Bdf);
        let j =
            serde_json::to_value(Summary::new(&case, &bdf, 0.8, Stats::default(), 0.1, 0)).unwrap();
        assert!(j["controller"].is_null());
    }

    #[test]
    fn names_serialise_as_in_interfaces() {
        for m in Method::ALL {
            assert_eq!(serde_json::to_value(m).unwrap(), m.name());
        }
        for c in ControllerKind::ALL {
            assert_eq!(serde_json::to_value(c).unwrap(), c.name());
        }
    }

    #[test]
    fn builtin_has_null_hash_and_nan_is_refused() {
        // A built-in case is built directly (none is registered in this build).
        let case = Case {
            name: "testset:hires".into(),
            source: crate::run::case::CaseSource::BuiltIn("hires".into()),
        };
        let mut s = Summary::new(
            &case,
            &SolverOptions::default(),
            321.8122,
            Stats::default(),
            0.0,
            0,
        );
        s.final_state = Some(vec![1.0, 2.0]);
        s.reference_error = Some(1e-9);
        let j = serde_json::to_value(&s).unwrap();
        assert!(j["scene_sha256"].is_null());
        assert_eq!(j["case"], "testset:hires");
        assert_eq!(j["final_state"], serde_json::json!([1.0, 2.0]));
        s.final_state = Some(vec![f64::NAN]);
        let d = tempfile::tempdir().unwrap();
        assert!(s
            .write(d.path())
            .unwrap_err()
            .to_string()
            .contains("final_state is NaN"));
        assert!(!d.path().join(SUMMARY_FILE).exists());
    }

    #[test]
    fn metrics_nest_as_an_object() {
        let samples: Vec<Sample> = grid(0.8, 0.4).into_iter().map(Sample::at).collect();
        let m = compute(
            &samples,
            Window {
                t_end: 0.8,
                period: 0.4,
            },
            None,
            &[],
            None,
            None,
        )
        .unwrap();
        let case = Case {
            name: "x".into(),
            source: crate::run::case::CaseSource::BuiltIn("x".into()),
        };
        let mut s = Summary::new(
            &case,
            &SolverOptions::default(),
            0.8,
            Stats::default(),
            0.0,
            0,
        );
        s.metrics = Some(m);
        let j = serde_json::to_value(&s).unwrap();
        assert_eq!(j["metrics"]["constraint_violation_max"], 0.0);
        assert!(j["metrics"]["eps_max"].is_null());
    }
}
