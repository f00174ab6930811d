//! The study's figures, laid out like the paper's Figures 5–16, one file per panel.
//!
//! ```text
//! set (cases)                    displacement/velocity   acceleration      orbits
//! dry, 120–200 rpm, 0.1 mm       fig05a, fig05b, fig05c  fig06a–d          fig07a–d
//! lubricated, 120–200 rpm        fig08a, fig08b, fig08c  fig09a–d          fig10a–d
//! dry, 150 rpm, 0.1–0.5 mm       fig11a, fig11b, fig11c  fig12a–d          fig13a–d
//! lubricated, 150 rpm            fig14a, fig14b, fig14c  fig15a–d          fig16a–d
//! (a) x, (b) ẋ of the four cases with the ideal mechanism dashed; (c) x − x_ideal (added:
//! the curves of (a) coincide at the plot's scale); acceleration: one panel per case with the
//! ideal dashed; orbits: e/c inside the unit clearance circle. x axis: crank angle θ over the
//! last revolution, degrees.
//! ```
//!
//! Source: the paper's figure captions (Figures 5–16).

use std::collections::BTreeMap;
use std::path::Path;

use rayon::prelude::*;

use crate::error::Error;
use crate::report::plot::{self, Axes, Series, SeriesStyle};
use crate::run::press::PressCase;
use crate::studies::paper::plan::{DRY_CLEARANCES, DRY_SPEEDS, LUB_CLEARANCES, LUB_SPEEDS};
use crate::studies::paper::result::FigureRecord;
use crate::studies::paper::stats::Curves;

struct Set {
    first_figure: u32,
    condition: &'static str,
    varies: &'static str,
    cases: [PressCase; 4],
    labels: [&'static str; 4],
    /// All four cases run at one speed (the ideal curves coincide).
    one_speed: bool,
}

impl Set {
    /// The condition the panels of one case share, as a title suffix.
    fn fixed(&self) -> &'static str {
        if self.one_speed {
            ", 150 rpm"
        } else {
            ", c = 0.1 mm"
        }
    }
}

const SETS: [Set; 4] = [
    Set {
        first_figure: 5,
        condition: "dry",
        varies: "c = 0.1 mm, different rotation speeds",
        cases: DRY_SPEEDS,
        labels: ["120 rpm", "150 rpm", "180 rpm", "200 rpm"],
        one_speed: false,
    },
    Set {
        first_figure: 8,
        condition: "lubricated",
        varies: "c = 0.1 mm, different rotation speeds",
        cases: LUB_SPEEDS,
        labels: ["120 rpm", "150 rpm", "180 rpm", "200 rpm"],
        one_speed: false,
    },
    Set {
        first_figure: 11,
        condition: "dry",
        varies: "150 rpm, different clearance sizes",
        cases: DRY_CLEARANCES,
        labels: ["c = 0.1 mm", "c = 0.2 mm", "c = 0.3 mm", "c = 0.5 mm"],
        one_speed: true,
    },
    Set {
        first_figure: 14,
        condition: "lubricated",
        varies: "150 rpm, different clearance sizes",
        cases: LUB_CLEARANCES,
        labels: ["c = 0.1 mm", "c = 0.2 mm", "c = 0.3 mm", "c = 0.5 mm"],
        one_speed: true,
    },
];

const PANELS: [char; 4] = ['a', 'b', 'c', 'd'];
const X_LABEL: &str = "crank angle θ, °";

struct Line {
    name: String,
    x: Vec<f64>,
    y: Vec<f64>,
    style: SeriesStyle,
}

enum Job {
    Lines {
        record: FigureRecord,
        y_label: &'static str,
        lines: Vec<Line>,
    },
    Orbit {
        record: FigureRecord,
        ex: Vec<f64>,
        ey: Vec<f64>,
    },
}

fn get(curves: &BTreeMap<PressCase, Curves>, case: PressCase) -> Result<&Curves, Error> {
    curves
        .get(&case)
        .ok_or_else(|| Error::Internal(format!("study figures: no curves of {case}")))
}

fn record(id: String, title: String, cases: &[PressCase]) -> FigureRecord {
    FigureRecord {
        id,
        title,
        cases: cases.iter().map(|c| c.to_string()).collect(),
    }
}

fn jobs(curves: &BTreeMap<PressCase, Curves>) -> Result<Vec<Job>, Error> {
    let mut jobs = Vec::new();
    for set in &SETS {
        let n = set.first_figure;
        let cs: Vec<&Curves> = set
            .cases
            .iter()
            .map(|&c| get(curves, c))
            .collect::<Result<_, _>>()?;
        let line = |name: String, c: &Curves, y: Vec<f64>, style| Line {
            name,
            x: c.deg.clone(),
            y,
            style,
        };
        // (a) displacement: the ideal x(θ) does not depend on the speed: drawn once.
        let mut lines: Vec<Line> = cs
            .iter()
            .zip(set.labels)
            .map(|(c, l)| line(l.to_string(), c, c.x.clone(), SeriesStyle::Line))
            .collect();
        lines.push(line(
            "ideal mechanism".into(),
            cs[0],
            cs[0].x_ideal.clone(),
            SeriesStyle::Dashed,
        ));
        jobs.push(Job::Lines {
            record: record(
                format!("fig{n:02}a"),
                format!(
                    "Fig. {n}(a) Slider displacement, {}, {}",
                    set.condition, set.varies
                ),
                &set.cases,
            ),
            y_label: "slider displacement x, m",
            lines,
        });
        // (b) velocity, with the ideal of each speed (one when all run at one speed).
        let mut lines: Vec<Line> = cs
            .iter()
            .zip(set.labels)
            .map(|(c, l)| line(l.to_string(), c, c.v.clone(), SeriesStyle::Line))
            .collect();
        if set.one_speed {
            lines.push(line(
                "ideal mechanism".into(),
                cs[0],
                cs[0].v_ideal.clone(),
                SeriesStyle::Dashed,
            ));
        } else {
            for (c, l) in cs.iter().zip(set.labels) {
                lines.push(line(
                    format!("ideal mechanism, {l}"),
                    c,
                    c.v_ideal.clone(),
                    SeriesStyle::Dashed,
                ));
            }
        }
        jobs.push(Job::Lines {
            record: record(
                format!("fig{n:02}b"),
                format!(
                    "Fig. {n}(b) Slider velocity, {}, {}",
                    set.condition, set.varies
                ),
                &set.cases,
            ),
            y_label: "slider velocity ẋ, m/s",
            lines,
        });
        // (c) added: the displacement's deviation from the ideal, mm.
        let lines = cs
            .iter()
            .zip(set.labels)
            .map(|(c, l)| {
                let d =
                    c.x.iter()
                        .zip(&c.x_ideal)
                        .map(|(a, b)| 1e3 * (a - b))
                        .collect();
                line(l.to_string(), c, d, SeriesStyle::Line)
            })
            .collect();
        jobs.push(Job::Lines {
            record: record(
                format!("fig{n:02}c"),
                format!(
                    "Fig. {n}(c) [added] Slider displacement minus the ideal mechanism's, {}, {}",
                    set.condition, set.varies
                ),
                &set.cases,
            ),
            y_label: "x − x of the ideal mechanism, mm",
            lines,
        });
        for (k, ((c, l), case)) in cs.iter().zip(set.labels).zip(set.cases).enumerate() {
            let p = PANELS[k];
            jobs.push(Job::Lines {
                record: record(
                    format!("fig{:02}{p}", n + 1),
                    format!(
                        "Fig. {}({p}) Slider acceleration, {}, {l}{}",
                        n + 1,
                        set.condition,
                        set.fixed()
                    ),
                    &[case],
                ),
                y_label: "slider acceleration ẍ, m/s²",
                lines: vec![
                    line("lash".into(), c, c.a.clone(), SeriesStyle::Line),
                    line(
                        "ideal mechanism".into(),
                        c,
                        c.a_ideal.clone(),
                        SeriesStyle::Dashed,
                    ),
                ],
            });
            let (ex, ey) = c.orbit.clone().ok_or_else(|| {
                Error::Internal(format!("study figures: {case} has no journal orbit"))
            })?;
            jobs.push(Job::Orbit {
                record: record(
                    format!("fig{:02}{p}", n + 2),
                    format!(
                        "Fig. {}({p}) Journal centre, {}, {l}{}",
                        n + 2,
                        set.condition,
                        set.fixed()
                    ),
                    &[case],
                ),
                ex,
                ey,
            });
        }
    }
    Ok(jobs)
}

fn render(dir: &Path, job: &Job) -> Result<FigureRecord, Error> {
    match job {
        Job::Lines {
            record,
            y_label,
            lines,
        } => {
            let series: Vec<Series<'_>> = lines
                .iter()
                .map(|l| Series {
                    name: &l.name,
                    x: &l.x,
                    y: &l.y,
                    style: l.style,
                })
                .collect();
            plot::line_plot(
                &dir.join(&record.id),
                &Axes {
                    title: &record.title,
                    x_label: X_LABEL,
                    y_label,
                },
                &series,
            )?;
            Ok(record.clone())
        }
        Job::Orbit { record, ex, ey } => {
            plot::orbit_plot(&dir.join(&record.id), &record.title, ex, ey)?;
            Ok(record.clone())
        }
    }
}

/// Number of figures [`write`] draws (each an SVG and a PNG).
#[cfg(test)]
pub(crate) fn count() -> usize {
    SETS.len() * (3 + 4 + 4)
}

/// Draws every figure into `dir` (which must exist), in parallel; returns their records in
/// figure order.
pub(super) fn write(
    dir: &Path,
    curves: &BTreeMap<PressCase, Curves>,
) -> Result<Vec<FigureRecord>, Error> {
    let jobs = jobs(curves)?;
    let mut recs: Vec<FigureRecord> = jobs
        .par_iter()
        .map(|j| render(dir, j))
        .collect::<Result<_, _>>()?;
    recs.sort_by(|a, b| a.id.cmp(&b.id));
    Ok(recs)
}
