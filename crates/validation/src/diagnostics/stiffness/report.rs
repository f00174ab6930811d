//! What `lash stiffness` reports: the two limits and where they occur, the stiffness ratio,
//! the verdict; stiffness.csv, .md, .json and the figure.
//!
//! Source: docs/outputs.md ("`lash stiffness CASE`").

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use lash_solver::analysis::stiffness::{verdict, Eigenvalue, MeasuredLimit, Verdict};
use lash_solver::{SolverOptions, Stats};

use crate::diagnostics::stiffness::sample::analysis_error;
use crate::diagnostics::stiffness::sample::criterion_text;
use crate::diagnostics::stiffness::sample::percentile;
use crate::diagnostics::stiffness::sample::phi_max;
use crate::diagnostics::stiffness::sample::Measurement;
use crate::diagnostics::stiffness::sample::Sampled;
use crate::diagnostics::stiffness::sample::StiffnessPoint;
use crate::diagnostics::stiffness::sample::StiffnessSettings;
use crate::error::Error;
use crate::report::plot::{self, Axes, Panel, Series, SeriesStyle};
use crate::report::summary::RunHeader;
use crate::report::trajectory::fmt_num;
use crate::run::prepare::Prepared;
use crate::store::io;

/// A value and where along the run it occurs.
///
/// ```text
/// (value, t, crank angle θ in rad when the case has a crank)
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub(crate) struct At {
    /// The value.
    pub value: f64,
    /// Time, s.
    pub t: f64,
    /// Crank angle, rad.
    pub crank_angle: Option<f64>,
    /// The eigenvalue behind it.
    pub eigenvalue: Eigenvalue,
}

/// Everything `lash stiffness` reports (stiffness.json).
///
/// ```text
/// h_pred = min_k h_k,  h_meas ∈ [h_stable, h_unstable],  ratio = h_stable / h_pred,
/// q = h_acc / h_stab,  verdict(q)
/// ```
///
/// HNW II §IV.1–IV.2.
#[derive(Clone, Debug, serde::Serialize)]
pub(crate) struct StiffnessReport {
    /// Case and settings (the keys of summary.json).
    #[serde(flatten)]
    pub run: RunHeader,
    /// The formulation analysed (a mechanism case; null for a test problem): the one
    /// `lash run --method rk4` integrates, so `lagrange_baumgarte` on a scene whose
    /// formulation is `auto`.
    pub formulation: Option<String>,
    /// Start of the run, s.
    pub t_start: f64,
    /// End of the run, s.
    pub t_end: f64,
    /// Sample points analysed.
    pub samples: usize,
    /// `analytic` or `central differences`.
    pub jacobian: String,
    /// Largest spectral radius over the samples, 1/s, and where.
    pub spectral_radius_max: At,
    /// Smallest predicted RK4 limit over the samples, s, and where (null when no mode limits).
    pub rk4_limit_predicted: Option<At>,
    /// The 5th percentile of the per-sample predicted limits, s: the limit on 95 % of the
    /// run, which a brief spike (one deep impact between flights) does not set.
    pub rk4_limit_predicted_p05: Option<f64>,
    /// The measured limit (null when not measured; see `measurement_note`).
    pub rk4_limit_measured: Option<MeasuredLimit>,
    /// Why the limit was not measured.
    pub measurement_note: Option<String>,
    /// h_stable / h_pred.
    pub measured_over_predicted: Option<f64>,
    /// h_stable / (the 5th percentile of the predicted limits).
    pub measured_over_predicted_p05: Option<f64>,
    /// The stability criterion of the measurement, in words.
    pub stability_criterion: String,
    /// The accuracy step h_acc, s: the reference run's median accepted step.
    pub accuracy_step: f64,
    /// Largest stiffness ratio over the samples.
    pub stiffness_ratio_max: Option<f64>,
    /// Most growing modes at one sample.
    pub growing_modes_max: usize,
    /// Samples with at least one growing mode.
    pub samples_with_growing_modes: usize,
    /// Which family should win, and why.
    pub verdict: Verdict,
    /// The reference run's counters.
    pub stats: Stats,
    /// Wall time of the reference run with the analyses, s.
    pub wall_time_analysis_s: f64,
    /// Wall time of the RK4 measurement, s.
    pub wall_time_measurement_s: f64,
}

/// The analysis and its samples: what the files are made of.
///
/// ```text
/// report (stiffness.json) + points (stiffness.csv rows)
/// ```
///
/// Source: this module.
#[derive(Clone, Debug)]
pub struct StiffnessResult {
    /// The summary.
    pub(crate) report: StiffnessReport,
    /// One point per sample.
    pub(crate) points: Vec<StiffnessPoint>,
}

/// Index and value of the smallest predicted limit.
pub(crate) fn predicted_min(points: &[StiffnessPoint]) -> Option<(usize, f64)> {
    points
        .iter()
        .enumerate()
        .filter_map(|(k, p)| p.rk4_h_max.map(|h| (k, h)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

pub(crate) fn check(name: &str, v: f64) -> Result<f64, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::Internal(format!("stiffness: {name} is {v}")))
    }
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn build_report(
    p: &Prepared,
    opts: &SolverOptions,
    settings: &StiffnessSettings,
    t_span: (f64, f64),
    sampled: &Sampled,
    measurement: Measurement,
    analytic: bool,
) -> Result<StiffnessReport, Error> {
    let pts = &sampled.points;
    let first = pts
        .first()
        .ok_or_else(|| Error::Internal("stiffness: no sample reached".into()))?;
    for q in pts {
        check("spectral radius", q.spectral_radius)?;
        check("eigenvalue", q.dominant.re)?;
        check("eigenvalue", q.dominant.im)?;
        if let Some(h) = q.rk4_h_max {
            check("rk4_h_max", h)?;
        }
        if let Some(s) = q.stiffness_ratio {
            check("stiffness ratio", s)?;
        }
    }
    let rho = pts
        .iter()
        .max_by(|a, b| a.spectral_radius.total_cmp(&b.spectral_radius))
        .unwrap_or(first);
    let predicted = predicted_min(pts).map(|(k, h)| At {
        value: h,
        t: pts[k].t,
        crank_angle: pts[k].crank_angle,
        eigenvalue: pts[k].limiting.unwrap_or(pts[k].dominant),
    });
    let h_acc = sampled
        .median_step()
        .ok_or_else(|| Error::Internal("stiffness: the reference run took no step".into()))?;
    let h_stab = measurement
        .limit
        .as_ref()
        .map(|m| m.h_stable)
        .or(predicted.as_ref().map(|a| a.value));
    let growing = pts.iter().map(|q| q.n_unstable).max().unwrap_or(0);
    let mut v = verdict(h_acc, h_stab, growing).map_err(analysis_error)?;
    let which = if measurement.limit.is_some() {
        "measured"
    } else {
        "predicted"
    };
    v.reason = format!(
        "{} (accuracy step: the median step of the {} reference run; stability: the {which} \
         RK4 limit)",
        v.reason,
        opts.method.name()
    );
    let ratio = match (&measurement.limit, &predicted) {
        (Some(m), Some(a)) => Some(m.h_stable / a.value),
        _ => None,
    };
    let p05 = percentile(
        &pts.iter().filter_map(|q| q.rk4_h_max).collect::<Vec<_>>(),
        0.05,
    );
    let ratio_p05 = match (&measurement.limit, p05) {
        (Some(m), Some(h)) => Some(m.h_stable / h),
        _ => None,
    };
    Ok(StiffnessReport {
        run: RunHeader::new(&p.case, opts),
        formulation: None,
        t_start: t_span.0,
        t_end: t_span.1,
        samples: pts.len(),
        jacobian: if analytic {
            "analytic".into()
        } else {
            "central differences".into()
        },
        spectral_radius_max: At {
            value: rho.spectral_radius,
            t: rho.t,
            crank_angle: rho.crank_angle,
            eigenvalue: rho.dominant,
        },
        rk4_limit_predicted: predicted,
        rk4_limit_predicted_p05: p05,
        rk4_limit_measured: measurement.limit,
        measurement_note: measurement.note,
        measured_over_predicted: ratio,
        measured_over_predicted_p05: ratio_p05,
        stability_criterion: criterion_text(&settings.probe, p.scene().map(|_| phi_max(p))),
        accuracy_step: h_acc,
        stiffness_ratio_max: pts
            .iter()
            .filter_map(|q| q.stiffness_ratio)
            .max_by(f64::total_cmp),
        growing_modes_max: growing,
        samples_with_growing_modes: pts.iter().filter(|q| q.n_unstable > 0).count(),
        verdict: v,
        stats: sampled.stats,
        wall_time_analysis_s: sampled.wall_time_s,
        wall_time_measurement_s: measurement.wall_time_s,
    })
}

fn opt(v: Option<f64>) -> String {
    v.map(fmt_num).unwrap_or_default()
}

/// stiffness.csv: one row per sample.
///
/// ```text
/// t,crank_angle,lambda_re,lambda_im,lambda_abs,spectral_radius,stiffness_ratio,rk4_h_max,
/// limiting_re,limiting_im,n_unstable
/// ```
/// (λ the eigenvalue of largest modulus, so lambda_abs = spectral_radius; `limiting` the one
/// that sets rk4_h_max; empty fields where a value does not exist).
pub(crate) fn to_csv(points: &[StiffnessPoint]) -> String {
    let mut s = String::from(
        "t,crank_angle,lambda_re,lambda_im,lambda_abs,spectral_radius,stiffness_ratio,\
         rk4_h_max,limiting_re,limiting_im,n_unstable\n",
    );
    for q in points {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{}",
            fmt_num(q.t),
            opt(q.crank_angle),
            fmt_num(q.dominant.re),
            fmt_num(q.dominant.im),
            fmt_num(q.dominant.modulus()),
            fmt_num(q.spectral_radius),
            opt(q.stiffness_ratio),
            opt(q.rk4_h_max),
            opt(q.limiting.map(|l| l.re)),
            opt(q.limiting.map(|l| l.im)),
            q.n_unstable
        );
    }
    s
}

fn where_(a: &At) -> String {
    match a.crank_angle {
        Some(th) => format!("t = {:.6} s, crank angle {:.1}°", a.t, th * 180.0 / PI),
        None => format!("t = {:.6e} s", a.t),
    }
}

fn eig(e: &Eigenvalue) -> String {
    if e.im == 0.0 {
        format!("{:.4e}", e.re)
    } else {
        format!(
            "{:.4e} {} {:.4e}i",
            e.re,
            if e.im < 0.0 { "−" } else { "+" },
            e.im.abs()
        )
    }
}

impl StiffnessReport {
    /// The lines `lash stiffness` prints: the two limits and the verdict.
    pub(crate) fn describe(&self) -> String {
        let mut s = format!(
            "{}{}: {} samples over [{}, {}] s, {} reference run: {} steps, median {:.3e} s\n",
            self.run.case,
            self.formulation
                .as_deref()
                .map(|f| format!(" ({f})"))
                .unwrap_or_default(),
            self.samples,
            self.t_start,
            self.t_end,
            self.run.method.name(),
            self.stats.accepted,
            self.accuracy_step
        );
        let _ = writeln!(
            s,
            "  largest |λ| {:.4e} 1/s (λ = {}) at {}",
            self.spectral_radius_max.value,
            eig(&self.spectral_radius_max.eigenvalue),
            where_(&self.spectral_radius_max)
        );
        match &self.rk4_limit_predicted {
            Some(a) => {
                let _ = writeln!(
                    s,
                    "  predicted RK4 limit {:.4e} s (λ = {}) at {}",
                    a.value,
                    eig(&a.eigenvalue),
                    where_(a)
                );
            }
            None => s.push_str("  predicted RK4 limit: none (no decaying or oscillating mode)\n"),
        }
        if let Some(h) = self.rk4_limit_predicted_p05 {
            let _ = writeln!(
                s,
                "  predicted RK4 limit on 95 % of the samples {h:.4e} s (5th percentile)"
            );
        }
        match (&self.rk4_limit_measured, &self.measurement_note) {
            (Some(m), _) => {
                let _ =
                    writeln!(
                    s,
                    "  measured RK4 limit {:.4e} s (stable) < h* < {:.4e} s (unstable), {} runs{}",
                    m.h_stable,
                    m.h_unstable,
                    m.runs,
                    match (self.measured_over_predicted, self.measured_over_predicted_p05) {
                        (Some(r), Some(q)) => format!(
                            ", measured/predicted {r:.4} (min), {q:.4} (5th percentile)"
                        ),
                        (Some(r), None) => format!(", measured/predicted {r:.4}"),
                        _ => String::new(),
                    }
                );
            }
            (None, Some(n)) => {
                let _ = writeln!(s, "  measured RK4 limit: {n}");
            }
            (None, None) => {}
        }
        let _ = writeln!(
            s,
            "  verdict: {}: {}",
            family_name(&self.verdict),
            self.verdict.reason
        );
        s
    }

    /// stiffness.md: the numbers and the verdict.
    pub(crate) fn to_markdown(&self) -> String {
        let mut s = format!("# Stiffness of {}\n\n", self.run.case);
        let _ = writeln!(
            s,
            "Reference run: {} ({}), t ∈ [{}, {}] s, {} accepted steps; Jacobian {}; {} samples.\n",
            self.run.method.name(),
            self.run.accuracy(),
            self.t_start,
            self.t_end,
            self.stats.accepted,
            self.jacobian,
            self.samples
        );
        s.push_str("| quantity | value | where |\n|---|---|---|\n");
        let _ = writeln!(
            s,
            "| largest spectral radius | {:.4e} 1/s (λ = {}) | {} |",
            self.spectral_radius_max.value,
            eig(&self.spectral_radius_max.eigenvalue),
            where_(&self.spectral_radius_max)
        );
        if let Some(a) = &self.rk4_limit_predicted {
            let _ = writeln!(
                s,
                "| predicted RK4 limit (min over samples) | {:.4e} s (λ = {}) | {} |",
                a.value,
                eig(&a.eigenvalue),
                where_(a)
            );
        }
        if let Some(h) = self.rk4_limit_predicted_p05 {
            let _ = writeln!(
                s,
                "| predicted RK4 limit, 5th percentile over samples | {h:.4e} s | 95 % of the run |"
            );
        }
        match &self.rk4_limit_measured {
            Some(m) => {
                let _ = writeln!(
                    s,
                    "| measured RK4 limit | {:.4e} s ≤ h* < {:.4e} s | whole run, {} RK4 runs |",
                    m.h_stable, m.h_unstable, m.runs
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "| measured RK4 limit | – | {} |",
                    self.measurement_note.as_deref().unwrap_or("")
                );
            }
        }
        if let Some(r) = self.measured_over_predicted {
            let _ = writeln!(s, "| measured / predicted (min) | {r:.4} | |");
        }
        if let Some(r) = self.measured_over_predicted_p05 {
            let _ = writeln!(s, "| measured / predicted (5th percentile) | {r:.4} | |");
        }
        let _ = writeln!(
            s,
            "| accuracy step (median step of the reference run) | {:.4e} s | |",
            self.accuracy_step
        );
        if let Some(r) = self.stiffness_ratio_max {
            let _ = writeln!(s, "| largest stiffness ratio | {r:.3e} | |");
        }
        let _ = writeln!(
            s,
            "| samples with a growing mode (Re λ > 0) | {} of {} (at most {} at once) | |",
            self.samples_with_growing_modes, self.samples, self.growing_modes_max
        );
        let reason = &self.verdict.reason;
        let mut chars = reason.chars();
        let reason = match chars.next() {
            Some(c) => c.to_uppercase().chain(chars).collect::<String>(),
            None => String::new(),
        };
        let _ = writeln!(
            s,
            "\n**Verdict: {}.** {reason}.\n\nStability criterion of the measurement: {}.",
            family_name(&self.verdict),
            self.stability_criterion
        );
        s
    }
}

/// The family's name in a sentence.
pub(crate) fn family_name(v: &Verdict) -> &'static str {
    use lash_solver::analysis::stiffness::Family;
    match v.family {
        Family::Explicit => "explicit",
        Family::Either => "either",
        Family::Implicit => "implicit",
    }
}

impl StiffnessResult {
    /// What the analysis found, in a few lines: the two RK4 limits, the stiffness ratio, the
    /// verdict (what `lash stiffness` prints).
    pub fn describe(&self) -> String {
        self.report.describe()
    }

    /// Writes stiffness.csv, stiffness.{svg,png}, stiffness.md and stiffness.json (last) into
    /// `dir`, each atomically; everything is checked before the first file is written.
    pub(crate) fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, Error> {
        let csv = to_csv(&self.points);
        let md = self.report.to_markdown();
        let json = serde_json::to_string_pretty(&self.report)
            .map_err(|e| Error::Internal(format!("stiffness.json: {e}")))?;
        let (x, x_label): (Vec<f64>, &str) = if self.points.iter().all(|q| q.crank_angle.is_some())
        {
            (
                self.points
                    .iter()
                    .map(|q| q.crank_angle.unwrap_or(0.0).to_degrees())
                    .collect(),
                "crank angle θ, °",
            )
        } else {
            (self.points.iter().map(|q| q.t).collect(), "time t, s")
        };
        io::create_dir(dir)?;
        let mut written = Vec::new();
        let w = self.plot(dir, &x, x_label)?;
        written.push(w.svg);
        written.push(w.png);
        let p = dir.join("stiffness.csv");
        io::write_atomic(&p, csv.as_bytes())?;
        written.push(p);
        let p = dir.join("stiffness.md");
        io::write_atomic(&p, md.as_bytes())?;
        written.push(p);
        let p = dir.join("stiffness.json");
        io::write_atomic(&p, format!("{json}\n").as_bytes())?;
        written.push(p);
        Ok(written)
    }

    fn plot(&self, dir: &Path, x: &[f64], x_label: &str) -> Result<plot::Written, Error> {
        let (xr, rho): (Vec<f64>, Vec<f64>) = x
            .iter()
            .zip(&self.points)
            .filter(|(_, q)| q.spectral_radius > 0.0)
            .map(|(x, q)| (*x, q.spectral_radius))
            .unzip();
        let (xh, h): (Vec<f64>, Vec<f64>) = x
            .iter()
            .zip(&self.points)
            .filter_map(|(x, q)| q.rk4_h_max.map(|h| (*x, h)))
            .unzip();
        let ends = [
            x.first().copied().unwrap_or(0.0),
            x.last().copied().unwrap_or(0.0),
        ];
        let r = &self.report;
        let meas = r.rk4_limit_measured.as_ref().map(|m| [m.h_stable; 2]);
        let acc = [r.accuracy_step; 2];
        let mut s1 = Vec::new();
        if !rho.is_empty() {
            s1.push(Series {
                name: "spectral radius |λ|max",
                x: &xr,
                y: &rho,
                style: SeriesStyle::Line,
            });
        }
        let mut s2 = Vec::new();
        if !h.is_empty() {
            s2.push(Series {
                name: "predicted RK4 limit r(arg λ)/|λ|",
                x: &xh,
                y: &h,
                style: SeriesStyle::Line,
            });
        }
        if let Some(m) = &meas {
            s2.push(Series {
                name: "measured RK4 limit (whole run)",
                x: &ends,
                y: m,
                style: SeriesStyle::Dashed,
            });
        }
        s2.push(Series {
            name: "accuracy step (median step of the reference run)",
            x: &ends,
            y: &acc,
            style: SeriesStyle::Dashed,
        });
        let mut panels = Vec::new();
        if !s1.is_empty() {
            panels.push(Panel {
                axes: Axes {
                    title: "Largest eigenvalue modulus of ∂f/∂y",
                    x_label,
                    y_label: "largest |λ|, 1/s",
                },
                series: &s1,
                log_y: true,
            });
        }
        panels.push(Panel {
            axes: Axes {
                title: "RK4 step limit: predicted along the run, measured over the whole run",
                x_label,
                y_label: "step h, s",
            },
            series: &s2,
            log_y: true,
        });
        let title = format!("Stiffness along the run: {}", plot::plain(&r.run.case));
        plot::panels_plot(&dir.join("stiffness"), &title, &panels)
    }
}
