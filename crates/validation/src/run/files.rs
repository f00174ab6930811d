//! The files of one `lash run`: figures, trajectory.csv, summary.json; failure.json when the
//! solver failed.
//!
//! ```text
//! check:   summary numbers finite                                   (else nothing is written)
//! write:   figures (SVG + PNG) → trajectory.csv (rows kept in memory; a streamed run wrote
//!          it as it went) → summary.json                            (each atomically; the
//!          summary last, so its presence means the run's files are complete)
//! failure: failure.json (the typed error, time, state by component name) beside the rows up
//!          to the failure, partial_trajectory.csv; never summary.json
//! figures over the last revolution, x = crank angle in degrees from the window's start
//!          (time in s when the scene has no crank driver):
//!   slider_x, slider_v, slider_a   lash and the ideal closed form (dashed)     [slider]
//!   orbit                          e/c inside the unit clearance circle        [clearance joint]
//!   joint_forces                   contact force F_N, and film force |F_film|  [clearance joint]
//!                                  when the joint has a film
//! ```
//!
//! Source: docs/outputs.md ("`lash run CASE`": DIR/summary.json, DIR/trajectory.csv and
//! figures).

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use lash_model::IdealSliderCrank;

use lash_solver::SolveError;

use crate::error::Error;
use crate::report::metrics::Sample;
use crate::report::plot::{self, Axes, Series, SeriesStyle};
use crate::report::summary::{RunHeader, Summary, SUMMARY_FILE};
use crate::report::trajectory::{self, Columns, PARTIAL_TRAJECTORY_FILE, TRAJECTORY_FILE};
use crate::store::io;

/// File stems of the figures (each written as .svg and .png).
pub(crate) const FIGURES: [&str; 5] = ["slider_x", "slider_v", "slider_a", "orbit", "joint_forces"];

/// File name of a failed run's account.
pub(crate) const FAILURE_FILE: &str = "failure.json";

/// Whether `name` (`is_dir`: a directory) is a file a run directory holds: what
/// [`io::OutDir`] may replace.
pub(crate) fn run_file(name: &str, is_dir: bool) -> bool {
    if is_dir {
        return false;
    }
    [
        SUMMARY_FILE,
        TRAJECTORY_FILE,
        PARTIAL_TRAJECTORY_FILE,
        FAILURE_FILE,
        crate::animation::SCENE_FILE,
        crate::animation::ANIMATION_FILE,
    ]
    .contains(&name)
        || crate::report::column_plot::is_plot_file(name)
        || FIGURES
            .iter()
            .any(|f| name == format!("{f}.svg") || name == format!("{f}.png"))
}

/// What one run hands over for writing.
///
/// ```text
/// trajectory: rows kept in memory (None: the run streamed them);  window: rows on
/// metrics::grid(t_end, T)
/// ```
///
/// Source: docs/outputs.md (`summary.json`, `trajectory.csv`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RunOutput<'a> {
    /// The summary (metrics filled in for mechanism cases).
    pub summary: &'a Summary,
    /// Rows of trajectory.csv kept in memory; None when the run streamed them into the
    /// directory already.
    pub trajectory: Option<&'a Columns>,
    /// Samples of the last revolution, for the figures (may be empty: no figures).
    pub window: &'a [Sample],
    /// The ideal mechanism drawn beside the slider curves, if the scene has one.
    pub ideal: Option<&'a IdealSliderCrank>,
}

/// The typed error of a failed run, as failure.json holds it.
///
/// ```text
/// { kind, message, t, h, h_limit, steps, reason }   (fields a kind lacks are null)
/// kind: step_size_too_small | too_many_steps | non_finite_state | rk4_unstable
///       | newton_failure | budget_exhausted | invalid_options | event_nan | out_of_memory
///       | law_out_of_range | singular_configuration | constraint_violation
///       | energy_balance
/// ```
///
/// Source: docs/outputs.md ("`failure.json`").
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct FailureError {
    /// The variant of `lash_solver::SolveError`, in snake case.
    pub kind: String,
    /// Its one-line message.
    pub message: String,
    /// The step that failed or the fixed step, s (step_size_too_small, rk4_unstable).
    pub h: Option<f64>,
    /// RK4's estimated stability limit, s (rk4_unstable).
    pub h_limit: Option<f64>,
    /// Steps taken (too_many_steps) or flagged in a row (rk4_unstable).
    pub steps: Option<usize>,
    /// Why (newton_failure, budget_exhausted, invalid_options, out_of_memory,
    /// law_out_of_range, singular_configuration, energy_balance).
    pub reason: Option<String>,
}

impl FailureError {
    /// The fields of `e`.
    pub(crate) fn of(e: &SolveError) -> FailureError {
        let mut f = FailureError {
            kind: String::new(),
            message: e.to_string(),
            h: None,
            h_limit: None,
            steps: None,
            reason: None,
        };
        f.kind = match e {
            SolveError::StepSizeTooSmall { h, .. } => {
                f.h = Some(*h);
                "step_size_too_small"
            }
            SolveError::TooManySteps { steps, .. } => {
                f.steps = Some(*steps);
                "too_many_steps"
            }
            SolveError::NonFiniteState { .. } => "non_finite_state",
            SolveError::Rk4Unstable {
                h, h_limit, steps, ..
            } => {
                f.h = Some(*h);
                f.h_limit = Some(*h_limit);
                f.steps = Some(*steps);
                "rk4_unstable"
            }
            SolveError::NewtonFailure { reason, .. } => {
                f.reason = Some(reason.clone());
                "newton_failure"
            }
            SolveError::BudgetExhausted { reason, .. } => {
                f.reason = Some(reason.clone());
                "budget_exhausted"
            }
            SolveError::InvalidOptions(m) => {
                f.reason = Some(m.to_string());
                "invalid_options"
            }
            SolveError::EventNan { .. } => "event_nan",
            SolveError::LawOutOfRange { reason, .. } => {
                f.reason = Some(reason.clone());
                "law_out_of_range"
            }
            SolveError::StateRejected { kind, reason, .. } => {
                f.reason = Some(reason.clone());
                kind
            }
            SolveError::OutOfMemory(m) => {
                f.reason = Some(m.to_string());
                "out_of_memory"
            }
            // `lash run` exits 130 on a stop request and writes nothing; a library caller
            // that records one anyway gets its own kind.
            SolveError::Interrupted { .. } => "interrupted",
        }
        .into();
        f
    }
}

/// failure.json: what a run that failed in the solver leaves (docs/outputs.md,
/// "`failure.json`").
///
/// ```text
/// { version, case, scene_sha256, method, controller, rtol, step,   (as in summary.json)
///   t_end, error: FailureError, t, state: {name: value}, partial_trajectory, rows }
/// ```
///
/// Source: docs/outputs.md ("`failure.json`").
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub(crate) struct Failure {
    /// Which case ran with which settings.
    #[serde(flatten)]
    pub header: RunHeader,
    /// The run's end time, s.
    pub t_end: f64,
    /// The typed error.
    pub error: FailureError,
    /// Time of the failure (the last accepted state), s; null when the error has none.
    pub t: Option<f64>,
    /// The state at the failure, by component name (scene order: `<body>.x`, … then
    /// `<body>.vx`, …; `y0`, … for a test problem); a component that is not finite is a
    /// string (`"NaN"`, `"inf"`).
    pub state: serde_json::Map<String, serde_json::Value>,
    /// The file holding the rows up to the failure, or null.
    pub partial_trajectory: Option<String>,
    /// Its rows.
    pub rows: usize,
}

impl Failure {
    /// The account of `e` for a run with `header`, state components named by `names`.
    pub(crate) fn new(
        header: RunHeader,
        t_end: f64,
        e: &SolveError,
        names: &[String],
        rows: Option<usize>,
    ) -> Failure {
        let mut state = serde_json::Map::new();
        if let Some(y) = e.state() {
            for (i, v) in y.iter().enumerate() {
                let name = names.get(i).cloned().unwrap_or_else(|| format!("y{i}"));
                let value = match serde_json::Number::from_f64(*v) {
                    Some(n) => serde_json::Value::Number(n),
                    None => serde_json::Value::String(v.to_string()),
                };
                state.insert(name, value);
            }
        }
        Failure {
            header,
            t_end,
            error: FailureError::of(e),
            t: e.time(),
            state,
            partial_trajectory: rows.map(|_| PARTIAL_TRAJECTORY_FILE.to_string()),
            rows: rows.unwrap_or(0),
        }
    }

    /// Writes `dir/failure.json`; returns its path.
    pub(crate) fn write(&self, dir: &Path) -> Result<PathBuf, Error> {
        let p = dir.join(FAILURE_FILE);
        io::write_json_atomic(&p, self)?;
        Ok(p)
    }
}

/// All values of an optional column, if every sample has one.
fn col(s: &[Sample], f: impl Fn(&Sample) -> Option<f64>) -> Option<Vec<f64>> {
    if s.is_empty() {
        return None;
    }
    s.iter().map(f).collect()
}

/// Writes the run's files into `dir` (created if needed); returns their paths in the order
/// written.
pub(crate) fn write_run(dir: &Path, out: &RunOutput<'_>) -> Result<Vec<PathBuf>, Error> {
    out.summary.check_finite()?;
    io::create_dir(dir)?;
    let mut written = Vec::new();
    let mut push = |w: plot::Written| {
        written.push(w.svg);
        written.push(w.png);
    };
    let w = out.window;
    let case = &out.summary.case;
    let theta = col(w, |s| s.crank_angle);
    let (x, x_label): (Vec<f64>, &str) = match &theta {
        Some(th) => {
            // A window starting at a whole number of turns starts at 0° even if θ₀ rounds below it.
            let turns = (th[0] / (2.0 * PI) + 1e-9).floor();
            let x = th
                .iter()
                .map(|t| (t - 2.0 * PI * turns).to_degrees())
                .collect();
            (x, "crank angle θ, °")
        }
        None => (w.iter().map(|s| s.t).collect(), "time t, s"),
    };
    type Get = fn(&Sample) -> Option<f64>;
    type IdealFn = fn(&IdealSliderCrank, f64) -> f64;
    type SliderFigure<'s> = (&'s str, &'s str, &'s str, Get, IdealFn);
    let slider: [SliderFigure<'_>; 3] = [
        (
            "slider_x",
            "Slider position",
            "x, m",
            |s| s.slider_x,
            IdealSliderCrank::x_at,
        ),
        (
            "slider_v",
            "Slider velocity",
            "ẋ, m/s",
            |s| s.slider_v,
            IdealSliderCrank::v_at,
        ),
        (
            "slider_a",
            "Slider acceleration",
            "ẍ, m/s²",
            |s| s.slider_a,
            IdealSliderCrank::a_at,
        ),
    ];
    for (stem, title, y_label, get, ideal_fn) in slider {
        let Some(y) = col(w, get) else { continue };
        let ideal: Option<Vec<f64>> = match (out.ideal, &theta) {
            (Some(m), Some(th)) => Some(
                th.iter()
                    .map(|&phi| ideal_fn(m, m.theta_of_crank_angle(phi)))
                    .collect(),
            ),
            _ if stem == "slider_a" => col(w, |s| s.ideal_slider_a),
            _ => None,
        };
        let mut series = vec![Series {
            name: "lash",
            x: &x,
            y: &y,
            style: SeriesStyle::Line,
        }];
        if let Some(yi) = &ideal {
            series.push(Series {
                name: "ideal mechanism",
                x: &x,
                y: yi,
                style: SeriesStyle::Dashed,
            });
        }
        let t = format!("{title}, {}", plot::plain(case));
        push(plot::line_plot(
            &dir.join(stem),
            &Axes {
                title: &t,
                x_label,
                y_label,
            },
            &series,
        )?);
    }
    if let (Some(ex), Some(ey)) = (col(w, |s| s.ex_over_c), col(w, |s| s.ey_over_c)) {
        let t = format!("Journal centre orbit, {}", plot::plain(case));
        push(plot::orbit_plot(&dir.join("orbit"), &t, &ex, &ey)?);
    }
    if let Some(fn_) = col(w, |s| s.contact_force) {
        let mut series = vec![Series {
            name: "normal contact force",
            x: &x,
            y: &fn_,
            style: SeriesStyle::Line,
        }];
        // The film's force only for a joint with a film (a dry one's is zeros): the scene
        // says so through film_thickness_min (null when dry); without metrics, the data.
        let film =
            col(w, |s| s.film_force.map(f64::abs)).filter(|f| match out.summary.metrics.as_ref() {
                Some(m) => m.film_thickness_min.is_some(),
                None => f.iter().any(|v| *v != 0.0),
            });
        if let Some(f) = &film {
            series.push(Series {
                name: "film force, magnitude",
                x: &x,
                y: f,
                style: SeriesStyle::Line,
            });
        }
        let t = format!("Clearance joint forces, {}", plot::plain(case));
        push(plot::line_plot(
            &dir.join("joint_forces"),
            &Axes {
                title: &t,
                x_label,
                y_label: "force, N",
            },
            &series,
        )?);
    }
    if let Some(rows) = out.trajectory {
        let traj = dir.join(trajectory::TRAJECTORY_FILE);
        rows.write_csv(&traj)?;
        written.push(traj);
    }
    written.push(out.summary.write(dir)?);
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::metrics::grid;
    use crate::report::trajectory::{Header, TrajectorySink};
    use crate::run::case::{Case, CaseSource};
    use lash_solver::{SolverOptions, Stats};

    /// trajectory.csv rows of the window samples: t, slider x, v, a.
    fn rows(w: &[Sample]) -> Columns {
        let mut present = [false; 13];
        for k in [0, 2, 3, 4, 11] {
            present[k] = true;
        }
        let mut c = Columns::new();
        c.start(&Header::new(present, vec!["slider.theta".into()]).unwrap())
            .unwrap();
        for s in w {
            let mut r = vec![f64::NAN; 14];
            r[0] = s.t;
            r[2] = s.slider_x.unwrap_or(0.0);
            r[3] = s.slider_v.unwrap_or(0.0);
            r[4] = s.slider_a.unwrap_or(0.0);
            r[11] = s.constraint_violation;
            r[13] = 0.0;
            TrajectorySink::row(&mut c, &r).unwrap();
        }
        c
    }

    fn summary() -> Summary {
        let case = Case {
            name: "lub_150rpm_c0.1".into(),
            source: CaseSource::BuiltIn("x".into()),
        };
        Summary::new(
            &case,
            &SolverOptions::default(),
            0.8,
            Stats::default(),
            0.5,
            0,
        )
    }

    /// The paper's press at 150 rpm (docs/model.md §5): r = 15 mm, l = 350 mm, θ = φ_crank.
    fn press_ideal() -> IdealSliderCrank {
        IdealSliderCrank {
            r: 0.015,
            l: 0.35,
            omega: 5.0 * PI,
            theta0: 0.0,
            offset: 0.0,
        }
    }

    fn press_window(m: &IdealSliderCrank) -> Vec<Sample> {
        grid(0.8, 0.4)
            .into_iter()
            .map(|t| {
                let th = m.omega * t;
                Sample {
                    crank_angle: Some(th),
                    slider_x: Some(m.x_at(th)),
                    slider_v: Some(m.v_at(th)),
                    slider_a: Some(m.a_at(th) + 0.05 * (7.0 * th).sin()),
                    ex_over_c: Some(0.5 * th.cos()),
                    ey_over_c: Some(-0.7 + 0.1 * th.sin()),
                    eps: Some(0.7),
                    delta: Some(-3e-5),
                    contact_force: Some(0.0),
                    friction_force: Some(0.0),
                    film_force: Some(-900.0 * (1.0 + th.cos())),
                    driver_torque: Some(10.0),
                    ..Sample::at(t)
                }
            })
            .collect()
    }

    #[test]
    fn full_press_run_writes_every_file_and_no_temporary() {
        let d = tempfile::tempdir().unwrap();
        let m = press_ideal();
        let w = press_window(&m);
        let s = summary();
        let c = rows(&w);
        let files = write_run(
            d.path(),
            &RunOutput {
                summary: &s,
                trajectory: Some(&c),
                window: &w,
                ideal: Some(&m),
            },
        )
        .unwrap();
        assert_eq!(files.len(), 2 * FIGURES.len() + 2);
        assert!(files.last().unwrap().ends_with("summary.json"));
        let mut names: Vec<String> = std::fs::read_dir(d.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        let mut want: Vec<String> = FIGURES
            .iter()
            .flat_map(|f| [format!("{f}.png"), format!("{f}.svg")])
            .chain(["summary.json".into(), "trajectory.csv".into()])
            .collect();
        want.sort();
        assert_eq!(names, want);
        let svg = std::fs::read_to_string(d.path().join("slider_a.svg")).unwrap();
        assert!(svg.contains("ideal mechanism") && svg.contains("crank angle θ, °"));
        let csv = std::fs::read_to_string(d.path().join("trajectory.csv")).unwrap();
        assert_eq!(csv, c.to_csv());
        assert_eq!(csv.lines().count(), 2002);
        for f in &files {
            let name = f.file_name().unwrap().to_string_lossy();
            assert!(run_file(&name, false), "{name}");
        }
        assert!(!run_file("notes.txt", false) && !run_file("summary.json", true));
    }

    #[test]
    fn missing_roles_skip_their_figures() {
        let d = tempfile::tempdir().unwrap();
        let w: Vec<Sample> = grid(0.8, 0.4).into_iter().map(Sample::at).collect();
        let s = summary();
        let c = rows(&w);
        let out = RunOutput {
            summary: &s,
            trajectory: Some(&c),
            window: &w,
            ideal: None,
        };
        let files = write_run(d.path(), &out).unwrap();
        assert_eq!(files.len(), 2);
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 2);
        // A streamed run: the summary alone.
        let e = tempfile::tempdir().unwrap();
        let out = RunOutput {
            trajectory: None,
            ..out
        };
        assert_eq!(write_run(e.path(), &out).unwrap().len(), 1);
    }

    #[test]
    fn a_bad_summary_writes_nothing() {
        let d = tempfile::tempdir().unwrap();
        let m = press_ideal();
        let w = press_window(&m);
        let mut s = summary();
        s.wall_time_s = f64::NAN;
        let dir = d.path().join("out");
        let e = write_run(
            &dir,
            &RunOutput {
                summary: &s,
                trajectory: None,
                window: &w,
                ideal: Some(&m),
            },
        )
        .unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Bug);
        assert!(!dir.exists());
    }

    #[test]
    fn failure_json_names_the_error_and_the_state() {
        let d = tempfile::tempdir().unwrap();
        let case = Case {
            name: "lub".into(),
            source: CaseSource::BuiltIn("x".into()),
        };
        let opts = SolverOptions {
            method: lash_solver::Method::Rk4,
            step: Some(1e-4),
            ..Default::default()
        };
        let e = SolveError::Rk4Unstable {
            t: 0.0125,
            y: vec![0.19, f64::NAN],
            h: 1e-4,
            h_limit: 2.2e-6,
            steps: 15,
        };
        let names = vec!["rod.x".to_string(), "rod.y".to_string()];
        let f = Failure::new(RunHeader::new(&case, &opts), 0.8, &e, &names, Some(125));
        let p = f.write(d.path()).unwrap();
        let j: serde_json::Value = serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap();
        assert_eq!(j["method"], "rk4");
        assert_eq!(j["step"], 1e-4);
        assert_eq!(j["error"]["kind"], "rk4_unstable");
        assert_eq!(j["error"]["h_limit"], 2.2e-6);
        assert_eq!(j["error"]["steps"], 15);
        assert!(j["error"]["reason"].is_null());
        assert!(j["error"]["message"]
            .as_str()
            .unwrap()
            .starts_with("RK4 beyond its stability limit at t = 1.25e-2"));
        assert_eq!(j["t"], 0.0125);
        assert_eq!(j["state"]["rod.x"], 0.19);
        assert_eq!(j["state"]["rod.y"], "NaN");
        assert_eq!(j["partial_trajectory"], PARTIAL_TRAJECTORY_FILE);
        assert_eq!(j["rows"], 125);
    }
}
