//! The press metrics of summary.json, computed from samples on the last crank revolution.
//!
//! ```text
//! window  [t_end − T, t_end],  T = 60 / rpm
//! grid    t_i = t_end − T + i T / 2000,  i = 0..2000   (2001 points, both ends; t_2000 = t_end)
//! slider_acc_max, _min        max, min of a_i
//! slider_acc_rms_dev_ideal    sqrt( Σ_i (a_i − a_ideal,i)² / 2001 )
//! eps_max                     max ε_i
//! contact_onsets              #{ located rising crossings of δ with t_end − T ≤ t ≤ t_end }
//! contact_force_max           max F_N,i
//! penetration_max             max(0, max δ_i)
//! film_force_max              max |F_film,i|               (0 when dry)
//! film_thickness_min          c (1 − min(eps_max, 1))      (lubricated; null when dry)
//! slider_x_end                x at t_end
//! constraint_violation_max    max ‖Φ(q, t_i)‖
//! energy.balance_error        W_driver − (ΔT + ΔV + D_damping + D_friction + D_film)
//! energy.quadrature_error     estimated error of the integrals W_driver, D_* (Richardson)
//! ```
//!
//! A metric whose role (slider, crank driver, clearance joint) the scene does not declare is
//! `None` (null). Source: docs/outputs.md (`summary.json`, `metrics`).

use crate::error::Error;

/// Number of grid points over the last revolution.
pub const GRID_POINTS: usize = 2001;

/// The crank period T = 60 / rpm, s.
pub fn period_from_rpm(rpm: f64) -> f64 {
    60.0 / rpm
}

/// The 2001-point grid over [t_end − period, t_end], both ends included, the last point
/// exactly `t_end`.
pub fn grid(t_end: f64, period: f64) -> Vec<f64> {
    let n = GRID_POINTS - 1;
    let t0 = t_end - period;
    (0..GRID_POINTS)
        .map(|i| {
            if i == n {
                t_end
            } else {
                t0 + period * (i as f64) / (n as f64)
            }
        })
        .collect()
}

/// The mechanism's state of interest at one time, model-independent. A field is `None` when
/// the scene does not declare the role it needs (slider; crank driver; clearance joint).
///
/// ```text
/// ε = |e|/c,  δ = |e| − c,  F_N ≥ 0 normal contact force,  F_T friction,  |F_film| film force
/// ```
///
/// Source: docs/outputs.md (`trajectory.csv` columns and `metrics`); docs/model.md §2–§4.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sample {
    /// Time, s.
    pub t: f64,
    /// Crank angle θ, rad (crank driver).
    pub crank_angle: Option<f64>,
    /// Slider x position, m (slider).
    pub slider_x: Option<f64>,
    /// Slider x velocity, m/s (slider).
    pub slider_v: Option<f64>,
    /// Slider x acceleration, m/s² (slider).
    pub slider_a: Option<f64>,
    /// e_x / c (clearance joint).
    pub ex_over_c: Option<f64>,
    /// e_y / c (clearance joint).
    pub ey_over_c: Option<f64>,
    /// Eccentricity ratio ε = |e|/c (clearance joint).
    pub eps: Option<f64>,
    /// Penetration δ = |e| − c, m; negative when apart (clearance joint).
    pub delta: Option<f64>,
    /// Normal contact force F_N, N (clearance joint; film force excluded).
    pub contact_force: Option<f64>,
    /// Friction force F_T, N (clearance joint).
    pub friction_force: Option<f64>,
    /// Film force magnitude, N (clearance joint; 0 when dry).
    pub film_force: Option<f64>,
    /// Euclidean norm of the position constraints Φ(q, t).
    pub constraint_violation: f64,
    /// Driving torque (the driver's λ), N·m (crank driver).
    pub driver_torque: Option<f64>,
    /// Closed-form ideal slider acceleration at this crank angle, m/s² (slider and crank
    /// driver).
    pub ideal_slider_a: Option<f64>,
}

impl Sample {
    /// A sample at time `t` with no role (every optional field None, Φ = 0).
    pub fn at(t: f64) -> Sample {
        Sample {
            t,
            ..Default::default()
        }
    }
}

/// The clearance joint's data the metrics need.
///
/// ```text
/// c = R_B − R_J;  lubricated ⇒ film_thickness_min = c (1 − min(ε_max, 1))
/// ```
///
/// Source: docs/model.md §2, docs/outputs.md (`metrics`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointInfo {
    /// Radial clearance c, m.
    pub clearance: f64,
    /// Whether the joint has an oil film.
    pub lubricated: bool,
}

/// What an event function measures.
///
/// ```text
/// Penetration: g = δ = |e| − c;  FilmCap: g = ε − ε_cap
/// ```
///
/// Source: docs/model.md §7.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventQuantity {
    /// The penetration δ of the clearance joint (rising = contact onset).
    Penetration,
    /// ε − ε_cap of a lubricated joint.
    FilmCap,
    /// Anything else.
    Other,
}

/// A located event.
///
/// ```text
/// contact onset ⇔ quantity = Penetration ∧ rising
/// ```
///
/// Source: docs/outputs.md (`contact_onsets`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EventRecord {
    /// Event time, s.
    pub t: f64,
    /// What crossed zero.
    pub quantity: EventQuantity,
    /// True for a crossing from negative to positive.
    pub rising: bool,
}

/// Energy totals over the whole run, J, as the model accumulates them.
///
/// ```text
/// W_driver = ∫ τ_driver θ̇ dt;  ΔT, ΔV (gravity and contact elastic energy);
/// D_* = ∫ (dissipated power) dt ≥ 0
/// ```
///
/// Source: docs/outputs.md (`energy`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EnergyTotals {
    /// Work done by the crank driver, J.
    pub driver_work: f64,
    /// Change of kinetic energy, J.
    pub kinetic_change: f64,
    /// Change of potential energy (gravity and contact elastic energy), J.
    pub potential_change: f64,
    /// Dissipated by contact damping, J.
    pub dissipated_damping: f64,
    /// Dissipated by friction, J.
    pub dissipated_friction: f64,
    /// Dissipated by the oil film, J.
    pub dissipated_film: f64,
    /// Estimated absolute error of the time integrals above (driver work and the three
    /// dissipations together), J: the sum over quadrature panels of |S₂ − S₁|/15, S₁ and S₂
    /// Simpson's rule on one and two subintervals (Richardson; the value used is Boole's rule
    /// S₂ + (S₂ − S₁)/15, one order higher).
    pub quadrature_error: f64,
}

/// The `energy` object of summary.json.
///
/// ```text
/// balance_error = driver_work − (kinetic_change + potential_change
///                 + dissipated_damping + dissipated_friction + dissipated_film)
/// ```
///
/// Source: docs/outputs.md (`energy`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Energy {
    /// Work done by the crank driver, J.
    pub driver_work: f64,
    /// Change of kinetic energy, J.
    pub kinetic_change: f64,
    /// Change of potential energy, J.
    pub potential_change: f64,
    /// Dissipated by contact damping, J.
    pub dissipated_damping: f64,
    /// Dissipated by friction, J.
    pub dissipated_friction: f64,
    /// Dissipated by the film, J.
    pub dissipated_film: f64,
    /// Estimated error of the time integrals (driver work and dissipations), J.
    pub quadrature_error: f64,
    /// The balance error, J: integration error plus the work of the Baumgarte terms; it is
    /// meaningful where it exceeds `quadrature_error`.
    pub balance_error: f64,
}

impl Energy {
    /// Closes the balance of the totals.
    pub fn from_totals(e: &EnergyTotals) -> Energy {
        Energy {
            driver_work: e.driver_work,
            kinetic_change: e.kinetic_change,
            potential_change: e.potential_change,
            dissipated_damping: e.dissipated_damping,
            dissipated_friction: e.dissipated_friction,
            dissipated_film: e.dissipated_film,
            quadrature_error: e.quadrature_error,
            balance_error: e.driver_work
                - (e.kinetic_change
                    + e.potential_change
                    + e.dissipated_damping
                    + e.dissipated_friction
                    + e.dissipated_film),
        }
    }
}

/// The `metrics` object of summary.json (null fields where a role is missing).
///
/// ```text
/// see the module doc: maxima, minima and RMS over the 2001-point grid of the last revolution
/// ```
///
/// Source: docs/outputs.md (`metrics`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Metrics {
    /// Max slider x acceleration on the grid, m/s².
    pub slider_acc_max: Option<f64>,
    /// Min slider x acceleration on the grid, m/s².
    pub slider_acc_min: Option<f64>,
    /// RMS of (slider acceleration − ideal) on the grid, m/s².
    pub slider_acc_rms_dev_ideal: Option<f64>,
    /// Max ε on the grid.
    pub eps_max: Option<f64>,
    /// Located rising crossings of δ in the window.
    pub contact_onsets: Option<usize>,
    /// Max normal contact force on the grid, N.
    pub contact_force_max: Option<f64>,
    /// max(0, max δ) on the grid, m.
    pub penetration_max: Option<f64>,
    /// Max film force magnitude on the grid, N (0 when dry).
    pub film_force_max: Option<f64>,
    /// c (1 − min(ε_max, 1)), m (lubricated only).
    pub film_thickness_min: Option<f64>,
    /// Slider x at t_end, m.
    pub slider_x_end: Option<f64>,
    /// Max ‖Φ‖ on the grid.
    pub constraint_violation_max: f64,
    /// Energy totals over the whole run and their balance error.
    pub energy: Option<Energy>,
}

/// Where the samples lie: the last revolution before `t_end`.
///
/// ```text
/// [t_end − T, t_end],  T = 60 / rpm
/// ```
///
/// Source: docs/outputs.md (`metrics`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// End time, s.
    pub t_end: f64,
    /// Crank period T, s.
    pub period: f64,
}

/// One column of the samples: all present (`Some`), or all absent (`None`).
fn column(
    samples: &[Sample],
    name: &str,
    get: impl Fn(&Sample) -> Option<f64>,
) -> Result<Option<Vec<f64>>, Error> {
    let vals: Vec<Option<f64>> = samples.iter().map(&get).collect();
    let present = vals.iter().filter(|v| v.is_some()).count();
    if present == 0 {
        return Ok(None);
    }
    if present != vals.len() {
        return Err(Error::Internal(format!(
            "metrics: {name} is given at {present} of {} samples",
            vals.len()
        )));
    }
    let v: Vec<f64> = vals.into_iter().flatten().collect();
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(Error::Internal(format!(
            "metrics: {name} is not finite at t = {:e}",
            samples[i].t
        )));
    }
    Ok(Some(v))
}

fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}

fn min(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Computes the metrics from the samples at [`grid`]`(window.t_end, window.period)`, the
/// clearance joint (None when the scene declares none), the events located during the run and
/// the energy totals (None when the model does not account energy).
///
/// Errors ([`Error::Internal`], a bug in the caller): not 2001 samples, a sample off the grid,
/// a non-finite value, a column given at some samples only.
pub fn compute(
    samples: &[Sample],
    window: Window,
    joint: Option<JointInfo>,
    events: &[EventRecord],
    energy: Option<EnergyTotals>,
) -> Result<Metrics, Error> {
    let Window { t_end, period } = window;
    if !(period > 0.0 && period.is_finite() && t_end.is_finite()) {
        return Err(Error::Internal(format!(
            "metrics: bad window t_end = {t_end}, T = {period}"
        )));
    }
    if samples.len() != GRID_POINTS {
        return Err(Error::Internal(format!(
            "metrics: {} samples, the grid has {GRID_POINTS}",
            samples.len()
        )));
    }
    let g = grid(t_end, period);
    let tol = 1e-9 * period.max(t_end.abs());
    if let Some((s, t)) = samples
        .iter()
        .zip(&g)
        .find(|(s, t)| !((s.t - **t).abs() <= tol))
    {
        return Err(Error::Internal(format!(
            "metrics: sample at t = {:e} is off the grid point {t:e}",
            s.t
        )));
    }
    let a = column(samples, "slider_a", |s| s.slider_a)?;
    let a_ideal = column(samples, "ideal_slider_a", |s| s.ideal_slider_a)?;
    let x = column(samples, "slider_x", |s| s.slider_x)?;
    let eps = column(samples, "eps", |s| s.eps)?;
    let delta = column(samples, "delta", |s| s.delta)?;
    let fnorm = column(samples, "contact_force", |s| s.contact_force)?;
    let film = column(samples, "film_force", |s| s.film_force)?;
    let cv = column(samples, "constraint_violation", |s| {
        Some(s.constraint_violation)
    })?
    .unwrap_or_default();

    let rms_dev = match (&a, &a_ideal) {
        (Some(a), Some(ai)) => {
            let ss: f64 = a.iter().zip(ai).map(|(x, y)| (x - y) * (x - y)).sum();
            Some((ss / a.len() as f64).sqrt())
        }
        _ => None,
    };
    let eps_max = eps.as_deref().map(max);
    let (contact_onsets, film_thickness_min) = match joint {
        Some(j) => {
            if !(j.clearance > 0.0 && j.clearance.is_finite()) {
                return Err(Error::Internal(format!(
                    "metrics: clearance must be > 0, got {}",
                    j.clearance
                )));
            }
            let t0 = t_end - period;
            let n = events
                .iter()
                .filter(|e| e.quantity == EventQuantity::Penetration && e.rising)
                .filter(|e| t0 <= e.t && e.t <= t_end)
                .count();
            let h = match (j.lubricated, eps_max) {
                (true, Some(e)) => Some(j.clearance * (1.0 - e.min(1.0))),
                _ => None,
            };
            (Some(n), h)
        }
        None => (None, None),
    };
    let energy = match energy {
        Some(e) => {
            let v = [
                e.driver_work,
                e.kinetic_change,
                e.potential_change,
                e.dissipated_damping,
                e.dissipated_friction,
                e.dissipated_film,
                e.quadrature_error,
            ];
            if v.iter().any(|x| !x.is_finite()) {
                return Err(Error::Internal(format!(
                    "metrics: non-finite energy totals {e:?}"
                )));
            }
            Some(Energy::from_totals(&e))
        }
        None => None,
    };
    Ok(Metrics {
        slider_acc_max: a.as_deref().map(max),
        slider_acc_min: a.as_deref().map(min),
        slider_acc_rms_dev_ideal: rms_dev,
        eps_max,
        contact_onsets,
        contact_force_max: fnorm.as_deref().map(max),
        penetration_max: delta.as_deref().map(|d| max(d).max(0.0)),
        film_force_max: film
            .as_deref()
            .map(|f| f.iter().fold(0.0, |m: f64, x| m.max(x.abs()))),
        film_thickness_min,
        slider_x_end: x.as_deref().and_then(|x| x.last().copied()),
        constraint_violation_max: max(&cv),
        energy,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const T: f64 = 0.4; // 150 rpm
    const T_END: f64 = 2.0 * T;
    const W: Window = Window {
        t_end: T_END,
        period: T,
    };

    fn samples(f: impl Fn(f64) -> Sample) -> Vec<Sample> {
        grid(T_END, T).into_iter().map(f).collect()
    }

    #[test]
    fn grid_has_2001_points_with_both_ends() {
        let g = grid(0.8, 0.4);
        assert_eq!(g.len(), 2001);
        assert_eq!(g[0], 0.4);
        assert_eq!(g[2000], 0.8);
        for w in g.windows(2) {
            assert!((w[1] - w[0] - 0.4 / 2000.0).abs() < 1e-15);
        }
        assert_eq!(period_from_rpm(150.0), 0.4);
    }

    #[test]
    fn cosine_acceleration_closed_forms() {
        // a = A cos(ωt), ω = 2π/T over one full period: max A at i = 0, 2000; min −A at
        // i = 1000; Σ cos² over the 2001 points = 1000 + 1, so RMS(a) = A sqrt(1001/2001).
        // With the ideal = a − B sin(ωt): Σ sin² = 1000, RMS deviation = B sqrt(1000/2001).
        let (amp, b) = (3.86, 0.05);
        let w = 2.0 * PI / T;
        let m = compute(
            &samples(|t| Sample {
                slider_a: Some(amp * (w * t).cos()),
                ideal_slider_a: Some(amp * (w * t).cos() - b * (w * t).sin()),
                slider_x: Some(0.365 * (w * t).cos()),
                crank_angle: Some(w * t),
                ..Sample::at(t)
            }),
            W,
            None,
            &[],
            None,
        )
        .unwrap();
        assert!((m.slider_acc_max.unwrap() - amp).abs() < 1e-12);
        assert!((m.slider_acc_min.unwrap() + amp).abs() < 1e-12);
        let rms = m.slider_acc_rms_dev_ideal.unwrap();
        assert!(
            (rms - b * (1000.0_f64 / 2001.0).sqrt()).abs() < 1e-13,
            "{rms}"
        );
        assert!((m.slider_x_end.unwrap() - 0.365).abs() < 1e-15);
        // The ideal equal to a itself: RMS deviation exactly 0.
        let m0 = compute(
            &samples(|t| Sample {
                slider_a: Some(amp * (w * t).cos()),
                ideal_slider_a: Some(amp * (w * t).cos()),
                ..Sample::at(t)
            }),
            W,
            None,
            &[],
            None,
        )
        .unwrap();
        assert_eq!(m0.slider_acc_rms_dev_ideal, Some(0.0));
    }

    fn journal(t: f64, e0: f64, e1: f64, c: f64) -> Sample {
        // ε = e0 + e1 sin(ωt): max e0 + e1 at ωt = π/2 (grid point i = 500).
        let eps = e0 + e1 * (2.0 * PI * t / T).sin();
        Sample {
            eps: Some(eps),
            ex_over_c: Some(eps),
            ey_over_c: Some(0.0),
            delta: Some(c * (eps - 1.0)),
            contact_force: Some(if eps > 1.0 { 1e4 * (eps - 1.0) } else { 0.0 }),
            friction_force: Some(0.0),
            film_force: Some(-250.0 * eps),
            constraint_violation: 1e-9 * eps,
            ..Sample::at(t)
        }
    }

    #[test]
    fn clearance_metrics_and_film_thickness() {
        let c = 1e-4;
        let lub = Some(JointInfo {
            clearance: c,
            lubricated: true,
        });
        let m = compute(&samples(|t| journal(t, 0.5, 0.3, c)), W, lub, &[], None).unwrap();
        assert!((m.eps_max.unwrap() - 0.8).abs() < 1e-12);
        assert!((m.film_thickness_min.unwrap() - c * 0.2).abs() < 1e-16);
        assert_eq!(m.penetration_max, Some(0.0)); // max δ = −0.2c < 0
        assert_eq!(m.contact_force_max, Some(0.0));
        assert!((m.film_force_max.unwrap() - 200.0).abs() < 1e-9); // |−250 ε| at ε = 0.8
        assert!((m.constraint_violation_max - 0.8e-9).abs() < 1e-20);
        assert_eq!(m.contact_onsets, Some(0));
        // Through the clearance: ε_max = 1.2 → δ_max = 0.2c, film thickness clamps at 0.
        let m = compute(&samples(|t| journal(t, 0.9, 0.3, c)), W, lub, &[], None).unwrap();
        assert!((m.penetration_max.unwrap() - 0.2 * c).abs() < 1e-16);
        assert_eq!(m.film_thickness_min, Some(0.0));
        assert!((m.contact_force_max.unwrap() - 2e3).abs() < 1e-8);
        // Dry: no film thickness.
        let dry = Some(JointInfo {
            clearance: c,
            lubricated: false,
        });
        let m = compute(&samples(|t| journal(t, 0.5, 0.3, c)), W, dry, &[], None).unwrap();
        assert_eq!(m.film_thickness_min, None);
        assert!(m.eps_max.is_some());
    }

    #[test]
    fn contact_onsets_count_rising_penetration_events_in_the_window() {
        let c = 1e-4;
        let joint = Some(JointInfo {
            clearance: c,
            lubricated: false,
        });
        let ev = |t, quantity, rising| EventRecord {
            t,
            quantity,
            rising,
        };
        let events = [
            ev(0.1, EventQuantity::Penetration, true), // before the window
            ev(0.4, EventQuantity::Penetration, true), // at its start: counts
            ev(0.5, EventQuantity::Penetration, true), // counts
            ev(0.55, EventQuantity::Penetration, false), // a loss
            ev(0.6, EventQuantity::FilmCap, true),     // another quantity
            ev(0.7, EventQuantity::Penetration, true), // counts
            ev(0.8, EventQuantity::Penetration, true), // at t_end: counts
            ev(0.81, EventQuantity::Penetration, true), // after
        ];
        let m = compute(
            &samples(|t| journal(t, 0.5, 0.3, c)),
            W,
            joint,
            &events,
            None,
        )
        .unwrap();
        assert_eq!(m.contact_onsets, Some(4));
    }

    #[test]
    fn missing_roles_give_null_metrics() {
        let m = compute(&samples(Sample::at), W, None, &[], None).unwrap();
        assert_eq!(
            (
                m.slider_acc_max,
                m.slider_acc_min,
                m.slider_acc_rms_dev_ideal,
                m.slider_x_end
            ),
            (None, None, None, None)
        );
        assert_eq!(
            (m.eps_max, m.contact_onsets, m.penetration_max),
            (None, None, None)
        );
        assert_eq!(
            (m.film_force_max, m.film_thickness_min, m.contact_force_max),
            (None, None, None)
        );
        assert_eq!(m.constraint_violation_max, 0.0);
        assert_eq!(m.energy, None);
        // A slider without a crank driver: no ideal, so no RMS deviation.
        let m = compute(
            &samples(|t| Sample {
                slider_a: Some(1.0),
                ..Sample::at(t)
            }),
            W,
            None,
            &[],
            None,
        )
        .unwrap();
        assert_eq!(
            (m.slider_acc_max, m.slider_acc_rms_dev_ideal),
            (Some(1.0), None)
        );
        let j = serde_json::to_value(&m).unwrap();
        assert!(j["slider_acc_rms_dev_ideal"].is_null() && j["energy"].is_null());
    }

    #[test]
    fn energy_balance_closes() {
        let e = EnergyTotals {
            driver_work: 100.0,
            kinetic_change: 30.0,
            potential_change: 5.0,
            dissipated_damping: 40.0,
            dissipated_friction: 15.0,
            dissipated_film: 9.5,
            quadrature_error: 1e-9,
        };
        let m = compute(&samples(Sample::at), W, None, &[], Some(e)).unwrap();
        assert_eq!(m.energy.unwrap().balance_error, 0.5);
        let bad = EnergyTotals {
            driver_work: f64::NAN,
            ..e
        };
        assert!(compute(&samples(Sample::at), W, None, &[], Some(bad)).is_err());
    }

    #[test]
    fn bad_samples_are_bugs_not_silent_nans() {
        let s = samples(Sample::at);
        let e = compute(&s[..2000], W, None, &[], None).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Bug);
        let mut off = s.clone();
        off[7].t += 1e-6;
        assert!(compute(&off, W, None, &[], None)
            .unwrap_err()
            .to_string()
            .contains("off the grid"));
        let mut nan = s.clone();
        for x in nan.iter_mut() {
            x.slider_a = Some(0.0);
        }
        nan[3].slider_a = Some(f64::NAN);
        assert!(compute(&nan, W, None, &[], None)
            .unwrap_err()
            .to_string()
            .contains("slider_a is not finite"));
        let mut mixed = s.clone();
        mixed[0].eps = Some(0.1);
        assert!(compute(&mixed, W, None, &[], None)
            .unwrap_err()
            .to_string()
            .contains("eps is given at 1 of 2001"));
        let mut cv = s;
        cv[5].constraint_violation = f64::INFINITY;
        assert!(compute(&cv, W, None, &[], None).is_err());
    }
}
