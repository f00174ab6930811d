//! The default run (`cargo run --release`, `lash` without a command): the paper's press at
//! 150 rpm with 0.1 mm clearance, ideal vs dry vs lubricated, the paper's RK4 against the best
//! adaptive method.
//!
//! ```text
//! for case in ideal_150rpm, dry_150rpm_c0.1, lubricated_150rpm_c0.1 (cases/press/):
//!   reference  compare::Reference (dop853 | bdf at rtol 1e-12, checked by a second method)
//!   rk4        the paper's method at its largest stable step, no event location
//!                (ideal 1e-3 s, dry 2e-4 s, lubricated 2e-6 s: the largest steps of the
//!                1–2–5 series that run the whole case with ‖Φ‖ < 1e-8; crates/model
//!                tests/press_cases.rs and examples/rk4_scan.rs)
//!   adaptive   the case's best method by `lash work-precision` (ideal dop853, dry tsit54,
//!                lubricated bdf) at the loosest rtol in 1e-3, 1e-4, …, 1e-11 whose error is
//!                at most RK4's: the same accuracy, so the costs compare directly
//!   error      compare::ErrorNorms::headline: relative RMS error of the slider acceleration
//!                over the first half revolution (dry: chaotic, docs/model.md §9) or the last
//!                revolution (ideal, lubricated)
//! returns the table (`lash` prints it); writes ./lash-default/ (or the directory given):
//! README.md (the tables), default.json, slider_acceleration.{svg,png} (last revolution, the
//! three cases and the closed form), orbits.{svg,png} (dry and lubricated journal orbits), and
//! per case the reference run's summary.json, trajectory.csv and figures
//! ```
//!
//! Source: docs/outputs.md ("`lash` (no command): the default run"); README.md ("What the
//! default run shows"); docs/model.md §5–§9.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::time::Instant;

use lash_solver::Method;

use crate::compare::reference::{self as compare, Compared, ErrorNorms, ErrorWindow, Reference};
use crate::compare::workprecision::fmt_num;
use crate::error::Error;
use crate::progress::Progress;
use crate::report::metrics::{Metrics, Sample};
use crate::report::plot::{self, Axes, Series, SeriesStyle};
use crate::run::prepare::Prepared;
use crate::run::press::PressCase;
use crate::run::result::RunResult;
use crate::store::io::{self, OutDir, Written};

/// One case of the default run.
///
/// ```text
/// (press case: file stem in cases/press and the paper's RK4 step, label, the best adaptive
/// method)
/// ```
///
/// Source: module doc (RK4 steps: `PressCase::rk4_step`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct HeadlineCase {
    /// The press case (its file in `cases/press/`, its RK4 step: the largest stable one).
    pub case: PressCase,
    /// Short label.
    pub label: &'static str,
    /// The best adaptive method for this case (lash work-precision).
    pub method: Method,
}

/// The three cases.
pub(crate) const CASES: [HeadlineCase; 3] = [
    HeadlineCase {
        case: PressCase::ideal(150),
        label: "ideal",
        method: Method::Dop853,
    },
    HeadlineCase {
        case: PressCase::dry(150, 100),
        label: "dry",
        method: Method::Tsit54,
    },
    HeadlineCase {
        case: PressCase::lubricated(150, 100),
        label: "lubricated",
        method: Method::Bdf,
    },
];

/// Where the default run writes without `--out`: relative to the working directory, never into
/// the source tree the binary was built from.
pub(crate) const DEFAULT_RUN_DIR: &str = "lash-default";

/// Tolerances tried, loosest first, to match RK4's accuracy.
pub(crate) const MATCH_TOLERANCES: [f64; 9] =
    [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11];

/// The workspace root: the working directory if it holds `cases/press`, else the source tree
/// this binary was built from (two levels above the validation crate), else the working
/// directory.
pub(crate) fn workspace_root() -> PathBuf {
    let cwd = PathBuf::from(".");
    if cwd.join("cases/press").is_dir() {
        return cwd;
    }
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    if built.join("cases/press").is_dir() {
        return built.canonicalize().unwrap_or(built);
    }
    cwd
}

/// One case's outcome.
///
/// ```text
/// rows = [rk4, adaptive at matched accuracy, reference check]; reference metrics
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct CaseReport {
    /// Case name.
    pub case: String,
    /// Label (ideal, dry, lubricated).
    pub label: String,
    /// How the reference was obtained.
    pub reference: String,
    /// The reference check's agreement.
    pub reference_agreement: Option<ErrorNorms>,
    /// Where errors were measured.
    pub window: ErrorWindow,
    /// Wall time of the reference and its check, s.
    pub reference_wall_time_s: f64,
    /// The paper's RK4 run.
    pub rk4: Compared,
    /// The best adaptive method at RK4's accuracy (or its tightest tolerance).
    pub adaptive: Compared,
    /// Whether `adaptive` reached RK4's error.
    pub matched: bool,
    /// Metrics of the reference run (last revolution).
    pub metrics: Option<Metrics>,
}

/// Everything the default run found.
///
/// ```text
/// { cases: [CaseReport], total_wall_time_s }
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Headline {
    /// The three cases.
    pub cases: Vec<CaseReport>,
    /// Wall time of the whole default run (all runs, figures, files), s.
    pub total_wall_time_s: f64,
}

fn run_case(root: &Path, c: &HeadlineCase) -> Result<(CaseReport, RunResult, Prepared), Error> {
    let path = root.join("cases/press").join(format!("{}.json", c.case));
    let p = Prepared::load_spec(&path.to_string_lossy(), None)?;
    let reference = Reference::compute(&p, None)?;
    let (rk4, _) = compare::compare_one(
        &p,
        &reference,
        Method::Rk4,
        None,
        Some(c.case.rk4_step()),
        None,
    )?;
    let target = rk4.error.unwrap_or(f64::INFINITY);
    let mut best: Option<Compared> = None;
    let mut matched = false;
    for &tol in &MATCH_TOLERANCES {
        let (a, _) = compare::compare_one(&p, &reference, c.method, Some(tol), None, None)?;
        let ok = a.error.is_some_and(|e| e <= target);
        best = Some(a);
        if ok {
            matched = true;
            break;
        }
    }
    let adaptive = best.ok_or_else(|| Error::Internal("no tolerance tried".into()))?;
    let run = reference
        .run
        .clone()
        .ok_or_else(|| Error::Internal("a press case without a reference run".into()))?;
    let report = CaseReport {
        case: p.case.name.clone(),
        label: c.label.into(),
        reference: reference.how.clone(),
        reference_agreement: reference.agreement.clone(),
        window: reference.window.clone(),
        reference_wall_time_s: reference.wall_time_s,
        rk4,
        adaptive,
        matched,
        metrics: run.summary.metrics.clone(),
    };
    Ok((report, run, p))
}

fn row(label: &str, c: &Compared) -> String {
    let err = match (&c.error, &c.failure) {
        (Some(e), _) => format!("{e:.2e}"),
        (None, Some(f)) => format!("failed: {f}"),
        _ => "–".into(),
    };
    format!(
        "| {label} | {} | {} | {err} | {:.4} | {} | {} | {} |\n",
        c.label(),
        c.setting(),
        c.wall_time_s,
        c.rhs_evals,
        c.events,
        c.contact_onsets.map_or("–".into(), |n| n.to_string()),
    )
}

impl Headline {
    /// The comparison table and the physics table, markdown.
    pub fn to_markdown(&self) -> String {
        let mut s = String::from(
            "# lash: the 150 rpm press, 0.1 mm clearance — RK4 (the paper) against adaptive methods\n\n",
        );
        s.push_str("| case | method | setting | error | wall time, s | RHS evals | events | contact onsets |\n");
        s.push_str("|---|---|---|---|---|---|---|---|\n");
        for c in &self.cases {
            s.push_str(&row(c.label.as_str(), &c.rk4));
            s.push_str(&row(c.label.as_str(), &c.adaptive));
        }
        s.push_str("\n| case | RK4 / adaptive: wall time | RHS evals | error window | reference (agreement of its check) |\n");
        s.push_str("|---|---|---|---|---|\n");
        for c in &self.cases {
            let ratio = |a: f64, b: f64| {
                if b > 0.0 {
                    format!("{:.0}×", a / b)
                } else {
                    "–".into()
                }
            };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} |\n",
                c.label,
                ratio(c.rk4.wall_time_s, c.adaptive.wall_time_s),
                ratio(c.rk4.rhs_evals as f64, c.adaptive.rhs_evals as f64),
                c.window.label,
                c.reference_agreement
                    .as_ref()
                    .map_or("–".into(), |a| format!("{:.1e}", a.headline())),
            ));
        }
        s.push_str("\nPhysics over the last revolution (reference runs):\n\n");
        s.push_str("| case | slider ẍ min, max (m/s²) | RMS(ẍ − ẍ_ideal), m/s² | ε_max | contact onsets | F_N max, N | film force max, N | energy balance error, J |\n");
        s.push_str("|---|---|---|---|---|---|---|---|\n");
        for c in &self.cases {
            let Some(m) = &c.metrics else { continue };
            let f = |v: Option<f64>| v.map_or("–".into(), fmt_num);
            s.push_str(&format!(
                "| {} | {}, {} | {} | {} | {} | {} | {} | {} |\n",
                c.label,
                f(m.slider_acc_min),
                f(m.slider_acc_max),
                f(m.slider_acc_rms_dev_ideal),
                f(m.eps_max),
                m.contact_onsets.map_or("–".into(), |n| n.to_string()),
                f(m.contact_force_max),
                f(m.film_force_max),
                m.energy.map_or("–".into(), |e| format!(
                    "{:.1e} (quadrature {:.0e})",
                    e.balance_error, e.quadrature_error
                )),
            ));
        }
        s.push_str(
            "\nerror: relative RMS error of the slider acceleration against the reference on \
             2001 points of the error window (the dry case is chaotic, so it is measured over \
             the first half revolution; docs/model.md §9). RK4 runs at the largest stable step \
             (ideal 1e-3 s, dry 2e-4 s, lubricated 2e-6 s) without event location, its contact \
             onsets counted at the step ends; the adaptive method runs at the loosest rtol \
             (decades from 1e-3) that matches RK4's error, with event location. Wall times are \
             of the integration alone.\n\nReferences:\n",
        );
        for c in &self.cases {
            s.push_str(&format!("- {}: {}.\n", c.case, c.reference));
        }
        s.push_str(&format!(
            "\nTotal wall time of the default run: {:.1} s.\n",
            self.total_wall_time_s
        ));
        s
    }
}

fn crank_degrees(w: &[Sample]) -> Option<Vec<f64>> {
    let th: Vec<f64> = w.iter().map(|s| s.crank_angle).collect::<Option<_>>()?;
    let turns = (th.first()? / (2.0 * PI) + 1e-9).floor();
    Some(
        th.iter()
            .map(|t| (t - 2.0 * PI * turns).to_degrees())
            .collect(),
    )
}

fn figures(dir: &Path, runs: &[(HeadlineCase, RunResult)]) -> Result<Vec<PathBuf>, Error> {
    let mut out = Vec::new();
    // Slider acceleration over the last revolution: the three cases and the closed form.
    let mut xs: Vec<(String, Vec<f64>, Vec<f64>)> = Vec::new();
    let mut ideal: Option<(Vec<f64>, Vec<f64>)> = None;
    for (c, r) in runs {
        let (Some(x), Some(a)) = (
            crank_degrees(&r.window),
            r.window
                .iter()
                .map(|s| s.slider_a)
                .collect::<Option<Vec<f64>>>(),
        ) else {
            continue;
        };
        if ideal.is_none() {
            if let Some(ia) = r
                .window
                .iter()
                .map(|s| s.ideal_slider_a)
                .collect::<Option<Vec<f64>>>()
            {
                ideal = Some((x.clone(), ia));
            }
        }
        xs.push((c.label.to_string(), x, a));
    }
    let mut series: Vec<Series<'_>> = xs
        .iter()
        .map(|(n, x, y)| Series {
            name: n,
            x,
            y,
            style: SeriesStyle::Line,
        })
        .collect();
    if let Some((x, y)) = &ideal {
        series.push(Series {
            name: "closed form (docs/model.md §5)",
            x,
            y,
            style: SeriesStyle::Dashed,
        });
    }
    if !series.is_empty() {
        let w = plot::line_plot(
            &dir.join("slider_acceleration"),
            &Axes {
                title: "Slider acceleration, last revolution, 150 rpm, c = 0.1 mm",
                x_label: "crank angle θ, °",
                y_label: "ẍ, m/s²",
            },
            &series,
        )?;
        out.extend([w.svg, w.png]);
    }
    // Journal orbits of the cases with a clearance joint.
    let orbits: Vec<(String, Vec<f64>, Vec<f64>)> = runs
        .iter()
        .filter_map(|(c, r)| {
            let ex = r
                .window
                .iter()
                .map(|s| s.ex_over_c)
                .collect::<Option<Vec<f64>>>()?;
            let ey = r
                .window
                .iter()
                .map(|s| s.ey_over_c)
                .collect::<Option<Vec<f64>>>()?;
            Some((c.label.to_string(), ex, ey))
        })
        .collect();
    if !orbits.is_empty() {
        let series: Vec<Series<'_>> = orbits
            .iter()
            .map(|(n, x, y)| Series {
                name: n,
                x,
                y,
                style: SeriesStyle::Line,
            })
            .collect();
        let w = plot::orbits_plot(
            &dir.join("orbits"),
            "Journal centre orbit e/c, last revolution, 150 rpm, c = 0.1 mm",
            &series,
        )?;
        out.extend([w.svg, w.png]);
    }
    Ok(out)
}

/// Runs the default comparison, noting each case as it starts (`running STEM …`), and writes
/// `out` (default [`DEFAULT_RUN_DIR`] in the working directory): README.md (the
/// table, [`Headline::to_markdown`]), default.json, the figures and per case the reference
/// run's files. Returns the table, the directory and the files written.
pub(crate) fn run_with_progress(
    out: Option<PathBuf>,
    progress: &dyn Progress,
) -> Result<Written<Headline>, Error> {
    let clock = Instant::now();
    let root = workspace_root();
    let target = out.unwrap_or_else(|| PathBuf::from(DEFAULT_RUN_DIR));
    let mut cases = Vec::new();
    let mut runs = Vec::new();
    for c in &CASES {
        progress.note(&format!("running {} …", c.case).into());
        let (report, run, _) = run_case(&root, c)?;
        cases.push(report);
        runs.push((*c, run));
    }
    // The whole directory is replaced when complete (io::OutDir): never a mix of two runs.
    let out_dir = OutDir::create(&target, &default_run_file)?;
    let dir = out_dir.path().to_path_buf();
    let mut written = figures(&dir, &runs)?;
    for (c, r) in &runs {
        written.extend(r.write(&dir.join(c.case.to_string()))?);
    }
    let mut h = Headline {
        cases,
        total_wall_time_s: 0.0,
    };
    h.total_wall_time_s = clock.elapsed().as_secs_f64();
    let md = h.to_markdown();
    let (readme, json) = (dir.join("README.md"), dir.join("default.json"));
    io::write_atomic(&readme, md.as_bytes())?;
    io::write_json_atomic(&json, &h)?;
    written.extend([readme, json]);
    let files = written.iter().map(|f| out_dir.final_path(f)).collect();
    out_dir.commit()?;
    Ok(Written {
        result: h,
        dir: target,
        files,
    })
}

/// Whether `name` is an entry the default run's directory holds (what its next run may
/// replace): README.md, default.json, the figures, one directory per case.
fn default_run_file(name: &str, is_dir: bool) -> bool {
    if is_dir {
        return CASES.iter().any(|c| c.case.to_string() == name);
    }
    ["README.md", "default.json"].contains(&name)
        || ["slider_acceleration", "orbits"]
            .iter()
            .any(|f| name == format!("{f}.svg") || name == format!("{f}.png"))
}
