//! The files of one `lash run`: figures, trajectory.csv, summary.json.
//!
//! ```text
//! check:   trajectory rows finite, summary numbers finite          (else nothing is written)
//! write:   figures (SVG + PNG) → trajectory.csv → summary.json      (each atomically; the
//!          summary last, so its presence means the run's files are complete)
//! figures over the last revolution, x = crank angle in degrees from the window's start
//!          (time in s when the scene has no crank driver):
//!   slider_x, slider_v, slider_a   lash and the ideal closed form (dashed)     [slider]
//!   orbit                          e/c inside the unit clearance circle        [clearance joint]
//!   joint_forces                   contact force F_N and film force |F_film|   [clearance joint]
//! ```
//!
//! Source: docs/outputs.md ("`lash run CASE`": DIR/summary.json, DIR/trajectory.csv and
//! figures).

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use lash_model::IdealSliderCrank;

use crate::error::Error;
use crate::io;
use crate::metrics::Sample;
use crate::plot::{self, Axes, Series, SeriesStyle};
use crate::summary::Summary;
use crate::trajectory::{self, Extra};

/// File stems of the figures (each written as .svg and .png).
pub const FIGURES: [&str; 5] = ["slider_x", "slider_v", "slider_a", "orbit", "joint_forces"];

/// What one run hands over for writing.
///
/// ```text
/// trajectory: rows at the output times;  window: rows on metrics::grid(t_end, T)
/// ```
///
/// Source: docs/outputs.md (`summary.json`, `trajectory.csv`).
#[derive(Clone, Copy, Debug)]
pub struct RunOutput<'a> {
    /// The summary (metrics filled in for mechanism cases).
    pub summary: &'a Summary,
    /// Rows of trajectory.csv.
    pub trajectory: &'a [Sample],
    /// Extra trajectory columns.
    pub extra: &'a [Extra<'a>],
    /// Samples of the last revolution, for the figures (may be empty: no figures).
    pub window: &'a [Sample],
    /// The ideal mechanism drawn beside the slider curves, if the scene has one.
    pub ideal: Option<&'a IdealSliderCrank>,
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
pub fn write_run(dir: &Path, out: &RunOutput<'_>) -> Result<Vec<PathBuf>, Error> {
    let csv = trajectory::to_csv(out.trajectory, out.extra)?;
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
        let film = col(w, |s| s.film_force.map(f64::abs));
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
    let traj = dir.join(trajectory::TRAJECTORY_FILE);
    io::write_atomic(&traj, csv.as_bytes())?;
    written.push(traj);
    written.push(out.summary.write(dir)?);
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::{Case, CaseSource};
    use crate::metrics::grid;
    use lash_solver::{SolverOptions, Stats};

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
        let files = write_run(
            d.path(),
            &RunOutput {
                summary: &s,
                trajectory: &w,
                extra: &[],
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
        assert_eq!(csv.lines().count(), 2002);
    }

    #[test]
    fn missing_roles_skip_their_figures() {
        let d = tempfile::tempdir().unwrap();
        let w: Vec<Sample> = grid(0.8, 0.4).into_iter().map(Sample::at).collect();
        let s = summary();
        let out = RunOutput {
            summary: &s,
            trajectory: &w,
            extra: &[],
            window: &w,
            ideal: None,
        };
        let files = write_run(d.path(), &out).unwrap();
        assert_eq!(files.len(), 2);
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 2);
    }

    #[test]
    fn a_bad_row_writes_nothing() {
        let d = tempfile::tempdir().unwrap();
        let m = press_ideal();
        let mut w = press_window(&m);
        w[10].delta = Some(f64::INFINITY);
        let s = summary();
        let dir = d.path().join("out");
        let e = write_run(
            &dir,
            &RunOutput {
                summary: &s,
                trajectory: &w,
                extra: &[],
                window: &w,
                ideal: Some(&m),
            },
        )
        .unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Bug);
        assert!(!dir.exists());
    }
}
