//! The statistics of one run of the study: the metrics of the last revolution and the
//! deviations from the ideal mechanism, the realisations of a case together, and the curves
//! the figures draw.
//!
//! Source: the paper's §4 (which claim reads which statistic: `claims`); docs/model.md §5.

use std::f64::consts::PI;

use lash_model::IdealSliderCrank;

use crate::error::Error;
use crate::report::metrics::{Metrics, Sample};
use crate::studies::paper::plan::DEAD_CENTRE_WINDOW_DEG;

/// A 45° sector "fluctuates" when its max deviation exceeds this fraction of the ideal peak.
pub(crate) const SECTOR_FLUCTUATION: f64 = 0.1;

/// Deviations of one run from the ideal mechanism and the journal's motion, over the last
/// revolution (the 2001-point grid), at the same crank angle θ.
///
/// ```text
/// stroke        = max x_id − min x_id                      (≈ 2r)
/// q_dev_max     = max |q − q_id|,  q ∈ {x, ẋ, ẍ};  a_ideal_peak = max |ẍ_id|
/// x_dev_bdc     = max |x − x_id| over |θ mod 2π| ≤ 15°      (bottom dead centre: x = r + l)
/// a_dev_dead_centres = max |ẍ − ẍ_id| over |θ mod π| ≤ 15°
/// q_dev_rel     = RMS(q − q_id) / RMS(q_id − mean q_id)
/// fluctuation_sectors = #{ 45° sectors s : max_s |ẍ − ẍ_id| > 0.1 a_ideal_peak }
/// contact_fraction = #{ i : δ_i > 0 } / 2001;  orbit_closure = max_i |e(t_i) − e(t_i − T)| / c
/// ```
///
/// Source: this study's reading of the paper's §4 (the claims module says which claim uses
/// which); docs/model.md §5 for the ideal mechanism.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Deviations {
    /// max x_ideal − min x_ideal, m.
    pub stroke: f64,
    /// max |x − x_ideal|, m.
    pub x_dev_max: f64,
    /// max |ẋ − ẋ_ideal|, m/s.
    pub v_dev_max: f64,
    /// max |ẍ − ẍ_ideal|, m/s².
    pub a_dev_max: f64,
    /// max |ẍ_ideal|, m/s².
    pub a_ideal_peak: f64,
    /// max |x − x_ideal| within ±15° of θ ≡ 0, m.
    pub x_dev_bdc: f64,
    /// max |ẍ − ẍ_ideal| within ±15° of θ ≡ 0 or π, m/s².
    pub a_dev_dead_centres: f64,
    /// RMS(x − x_ideal) / RMS(x_ideal − mean).
    pub x_dev_rel: f64,
    /// RMS(ẋ − ẋ_ideal) / RMS(ẋ_ideal − mean).
    pub v_dev_rel: f64,
    /// RMS(ẍ − ẍ_ideal) / RMS(ẍ_ideal − mean).
    pub a_dev_rel: f64,
    /// 45° sectors whose max |ẍ − ẍ_ideal| exceeds 10 % of the ideal peak (0..=8).
    pub fluctuation_sectors: usize,
    /// Fraction of the grid in contact, δ > 0 (clearance joint).
    pub contact_fraction: Option<f64>,
    /// max |e(t) − e(t − T)| / c over the last revolution (clearance joint).
    pub orbit_closure: Option<f64>,
}

/// The statistics of one realisation of one case.
///
/// ```text
/// metrics (docs/outputs.md, "`metrics`": last revolution) + deviations from the ideal mechanism
/// ```
///
/// Source: docs/outputs.md (`metrics`); [`Deviations`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaseStats {
    /// The metrics of docs/outputs.md ("`metrics`"; energy null: the study does not account
    /// energy).
    pub metrics: Metrics,
    /// Deviations from the ideal mechanism.
    pub dev: Deviations,
}

/// The realisations of one case at one setting.
///
/// ```text
/// members[k] = statistics of realisation k;
/// acc_spread = max_i ( max_k ẍ_k(t_i) − min_k ẍ_k(t_i) )  over the last revolution's grid
/// ```
///
/// Source: this module (docs/model.md §9: chaotic cases are compared through statistics).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ensemble {
    /// One entry per realisation (k = 0 is the paper's case).
    pub members: Vec<CaseStats>,
    /// Pointwise spread of the slider acceleration over the realisations, m/s².
    pub acc_spread: f64,
}

// ---------------------------------------------------------------------------------------------
// Statistics of one run
// ---------------------------------------------------------------------------------------------

/// A required column of the samples.
pub(crate) fn need(
    s: &[Sample],
    name: &str,
    f: impl Fn(&Sample) -> Option<f64>,
) -> Result<Vec<f64>, Error> {
    s.iter()
        .map(|x| {
            f(x).filter(|v| v.is_finite()).ok_or_else(|| {
                Error::Internal(format!(
                    "study: {name} missing or not finite at t = {:e}",
                    x.t
                ))
            })
        })
        .collect()
}

pub(crate) fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x * x;
        n += 1;
    }
    (s / n.max(1) as f64).sqrt()
}

pub(crate) fn max_abs(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(0.0, |m: f64, x| m.max(x.abs()))
}

/// RMS(q − q_ideal) / RMS(q_ideal − mean q_ideal).
fn relative_rms(q: &[f64], qi: &[f64]) -> f64 {
    let mean = qi.iter().sum::<f64>() / qi.len() as f64;
    let num = rms(q.iter().zip(qi).map(|(a, b)| a - b));
    let den = rms(qi.iter().map(|b| b - mean));
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// The [`Deviations`] of the last revolution `last` (with `previous`, the revolution before
/// it on the same phases) from the ideal mechanism `ideal`. Errors ([`Error::Internal`]): a
/// missing slider or crank column, different lengths.
pub(crate) fn deviations(
    last: &[Sample],
    previous: &[Sample],
    ideal: &IdealSliderCrank,
) -> Result<Deviations, Error> {
    if last.is_empty() || previous.len() != last.len() {
        return Err(Error::Internal(format!(
            "study: {} and {} samples in the last two revolutions",
            previous.len(),
            last.len()
        )));
    }
    let phi = need(last, "crank_angle", |s| s.crank_angle)?;
    let x = need(last, "slider_x", |s| s.slider_x)?;
    let v = need(last, "slider_v", |s| s.slider_v)?;
    let a = need(last, "slider_a", |s| s.slider_a)?;
    let theta: Vec<f64> = phi.iter().map(|&p| ideal.theta_of_crank_angle(p)).collect();
    let xi: Vec<f64> = theta.iter().map(|&t| ideal.x_at(t)).collect();
    let vi: Vec<f64> = theta.iter().map(|&t| ideal.v_at(t)).collect();
    let ai: Vec<f64> = theta.iter().map(|&t| ideal.a_at(t)).collect();
    let dx: Vec<f64> = x.iter().zip(&xi).map(|(p, q)| (p - q).abs()).collect();
    let da: Vec<f64> = a.iter().zip(&ai).map(|(p, q)| (p - q).abs()).collect();
    let a_ideal_peak = max_abs(ai.iter().copied());
    let w = DEAD_CENTRE_WINDOW_DEG.to_radians();
    let phase: Vec<f64> = theta.iter().map(|t| t.rem_euclid(2.0 * PI)).collect();
    let near_bdc = |p: f64| p.min(2.0 * PI - p) <= w;
    let near_dc = |p: f64| near_bdc(p) || (p - PI).abs() <= w;
    let x_dev_bdc = max_abs((0..x.len()).filter(|&i| near_bdc(phase[i])).map(|i| dx[i]));
    let a_dev_dead_centres = max_abs((0..x.len()).filter(|&i| near_dc(phase[i])).map(|i| da[i]));
    let mut sector_max = [0.0f64; 8];
    for (p, d) in phase.iter().zip(&da) {
        let k = ((p / (PI / 4.0)) as usize).min(7);
        sector_max[k] = sector_max[k].max(*d);
    }
    let fluctuation_sectors = sector_max
        .iter()
        .filter(|&&m| m > SECTOR_FLUCTUATION * a_ideal_peak)
        .count();
    let contact_fraction = if last.iter().all(|s| s.delta.is_some()) {
        let d = need(last, "delta", |s| s.delta)?;
        Some(d.iter().filter(|&&x| x > 0.0).count() as f64 / d.len() as f64)
    } else {
        None
    };
    let has_e = |s: &[Sample]| {
        s.iter()
            .all(|p| p.ex_over_c.is_some() && p.ey_over_c.is_some())
    };
    let orbit_closure = if has_e(last) && has_e(previous) {
        let (ex, ey) = (
            need(last, "ex_over_c", |s| s.ex_over_c)?,
            need(last, "ey_over_c", |s| s.ey_over_c)?,
        );
        let (px, py) = (
            need(previous, "ex_over_c", |s| s.ex_over_c)?,
            need(previous, "ey_over_c", |s| s.ey_over_c)?,
        );
        Some(max_abs(
            (0..ex.len()).map(|i| (ex[i] - px[i]).hypot(ey[i] - py[i])),
        ))
    } else {
        None
    };
    let fold = |v: &[f64], f: fn(f64, f64) -> f64, z: f64| v.iter().copied().fold(z, f);
    Ok(Deviations {
        stroke: fold(&xi, f64::max, f64::NEG_INFINITY) - fold(&xi, f64::min, f64::INFINITY),
        x_dev_max: max_abs(dx.iter().copied()),
        v_dev_max: max_abs(v.iter().zip(&vi).map(|(p, q)| p - q)),
        a_dev_max: max_abs(da.iter().copied()),
        a_ideal_peak,
        x_dev_bdc,
        a_dev_dead_centres,
        x_dev_rel: relative_rms(&x, &xi),
        v_dev_rel: relative_rms(&v, &vi),
        a_dev_rel: relative_rms(&a, &ai),
        fluctuation_sectors,
        contact_fraction,
        orbit_closure,
    })
}

// ---------------------------------------------------------------------------------------------
// The study
// ---------------------------------------------------------------------------------------------

/// Curves of the paper's realisation for the figures (last revolution).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct Curves {
    /// Crank angle θ, degrees, 0..360 over the last revolution.
    pub deg: Vec<f64>,
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    pub x_ideal: Vec<f64>,
    pub v_ideal: Vec<f64>,
    pub a_ideal: Vec<f64>,
    /// e/c of the journal (clearance cases).
    pub orbit: Option<(Vec<f64>, Vec<f64>)>,
}

pub(crate) fn curves(last: &[Sample], ideal: &IdealSliderCrank) -> Result<Curves, Error> {
    let phi = need(last, "crank_angle", |s| s.crank_angle)?;
    let theta: Vec<f64> = phi.iter().map(|&p| ideal.theta_of_crank_angle(p)).collect();
    // The window starts at a whole number of turns; start it at 0° even if θ rounds below.
    let turns = (theta[0] / (2.0 * PI) + 1e-9).floor();
    let orbit = match (
        last.iter().map(|s| s.ex_over_c).collect::<Option<Vec<_>>>(),
        last.iter().map(|s| s.ey_over_c).collect::<Option<Vec<_>>>(),
    ) {
        (Some(ex), Some(ey)) => Some((ex, ey)),
        _ => None,
    };
    Ok(Curves {
        deg: theta
            .iter()
            .map(|t| (t - 2.0 * PI * turns).to_degrees())
            .collect(),
        x: need(last, "slider_x", |s| s.slider_x)?,
        v: need(last, "slider_v", |s| s.slider_v)?,
        a: need(last, "slider_a", |s| s.slider_a)?,
        x_ideal: theta.iter().map(|&t| ideal.x_at(t)).collect(),
        v_ideal: theta.iter().map(|&t| ideal.v_at(t)).collect(),
        a_ideal: theta.iter().map(|&t| ideal.a_at(t)).collect(),
        orbit,
    })
}
