//! The press metrics of summary.json, computed on the last crank revolution as the run goes.
//!
//! ```text
//! window  [t_end − T, t_end],  T = 60 / rpm
//! grid    t_i = t_end − T + i T / 2000,  i = 0..2000   (2001 points, both ends; t_2000 = t_end)
//! S       the grid, and every accepted step's dense output inside the window (Peaks):
//!         its ends (located events included), 3 interior points, and the refined extremum
//! slider_acc_max, _min        max, min of a over S
//! slider_acc_rms_dev_ideal    sqrt( Σ_i (a_i − a_ideal,i)² / 2001 )      (grid)
//! eps_max                     max ε over S
//! contact_onsets              #{ located rising crossings of δ with t_end − T ≤ t ≤ t_end }
//! contact_force_max           max F_N over S
//! penetration_max             max(0, max δ over S)
//! film_force_max              max |F_film| over S              (0 when dry)
//! film_thickness_min          c (1 − min(eps_max, 1))      (lubricated; null when dry)
//! slider_x_end                x at t_end
//! constraint_violation_max    max ‖Φ(q, t)‖ over S (no refinement)
//! clearance_joints.NAME       eps_max … film_thickness_min of every clearance joint
//! energy.balance_error        W_driver + W_load + W_motor
//!                             − (ΔT + ΔV + D_damping + D_friction + D_film + D_damper)
//! energy.quadrature_error     estimated error of the integrals W_*, D_* (Richardson)
//! energy.state_tolerance      Σᵢ |∂(T + V)/∂yᵢ| (atolᵢ + rtol |yᵢ|) at the start and end
//! ```
//!
//! Extrema over the dense output ([`Peaks`]): every accepted step [a, b] that reaches into
//! the window is sampled at a + (b − a) j/4, j = 0..4 (a located event ends a step, so it is a
//! sample). A quantity whose largest sample beats its running maximum is refined: at an
//! interior sample j, golden-section search on [t_{j−1}, t_{j+1}]; at the step's end, a probe
//! (b − a)/256 before it decides whether the quantity still rises there (then the next step
//! looks after b) or peaked inside [t_3, b] (then golden-section search there); at the step's
//! start, holding the running maximum with the next sample lower, on [a, t_1]. Golden-section
//! search keeps 0.618 of the bracket per evaluation; after [`REFINE_ITERATIONS`] the bracket
//! W (h/4 or h/2, h the step) is below 1e-6 W. For a maximum unimodal on its bracket,
//! f ≈ A (1 − ((t − t*)/w)²) near it, the value found is within (1e-6 W/w)² of A relative: below
//! 1e-9 for a peak of half-width w ≥ W/30, which an impact is, since the step that resolves it
//! (adaptive methods, event location at its onset) is shorter than the impact. The
//! interpolant is the method's dense output, accurate to its tolerance; the window grid alone
//! misses an impact shorter than its spacing.
//!
//! A metric whose role (slider, crank driver, clearance joint) the scene does not declare is
//! `None` (null). Source: docs/outputs.md (`summary.json`, `metrics`).

use std::collections::BTreeMap;

use crate::error::Error;

/// Number of grid points over the last revolution.
pub(crate) const GRID_POINTS: usize = 2001;

/// Sub-intervals of an accepted step sampled for the extrema (module doc).
pub(crate) const STEP_SAMPLES: usize = 4;

/// Evaluations of one golden-section refinement (module doc): the bracket shrinks to
/// 0.618^30 < 1e-6 of its start.
pub(crate) const REFINE_ITERATIONS: usize = 32;

/// The 2001-point grid over [t_end − period, t_end], both ends included, the last point
/// exactly `t_end`.
pub(crate) fn grid(t_end: f64, period: f64) -> Vec<f64> {
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
pub(crate) struct Sample {
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
    #[cfg(test)]
    pub(crate) fn at(t: f64) -> Sample {
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
pub(crate) struct JointInfo {
    /// Position among the scene's clearance joints (the index of `Outputs::clearance`).
    pub index: usize,
    /// Radial clearance c, m.
    pub clearance: f64,
    /// Whether the joint has an oil film.
    pub lubricated: bool,
}

/// What an event function measures (of any clearance joint: [`EventRecord::joint`] says
/// which).
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
    /// The clearance joint (index among the scene's clearance joints) whose δ or ε crossed;
    /// None when not known (every joint counts as the role's).
    pub joint: Option<usize>,
    /// The event function that crossed (its index in the mechanism's list,
    /// `lash_model::Mechanism::event_name`; `crate::run::simulate::MechanismInfo::event_names`).
    pub index: usize,
}

/// Energy totals over the whole run, J, as the model accumulates them.
///
/// ```text
/// W_driver = ∫ τ_driver θ̇ dt;  W_load = ∫ (Σ F·ṙ^P + Σ τ φ̇) dt;  W_motor = ∫ Σ τ ω dt;
/// ΔT, ΔV (gravity, contact elastic energy and the springs' potential);
/// D_* = ∫ (dissipated power) dt ≥ 0   (contact damping, friction, film, dampers)
/// ```
///
/// Source: docs/outputs.md (`energy`); docs/model.md §1.8, §10.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct EnergyTotals {
    /// Work done by the crank driver, J.
    pub driver_work: f64,
    /// Change of kinetic energy, J.
    pub kinetic_change: f64,
    /// Change of potential energy (gravity, contact elastic energy, springs), J.
    pub potential_change: f64,
    /// Dissipated by contact damping, J.
    pub dissipated_damping: f64,
    /// Dissipated by friction, J.
    pub dissipated_friction: f64,
    /// Dissipated by the oil film, J.
    pub dissipated_film: f64,
    /// Work done by the applied forces and torques, J.
    pub load_work: f64,
    /// Work done by the motors, J.
    pub motor_work: f64,
    /// Dissipated by the dampers of the spring-dampers and bushings, J.
    pub dissipated_damper: f64,
    /// The force elements' share of `potential_change` (springs), J.
    pub element_potential_change: f64,
    /// Estimated absolute error of the time integrals above (the three works and the four
    /// dissipations together), J: the sum over quadrature panels of |S₂ − S₁|/15, S₁ and S₂
    /// Simpson's rule on one and two subintervals (Richardson; the value used is Boole's rule
    /// S₂ + (S₂ − S₁)/15, one order higher).
    pub quadrature_error: f64,
    /// How accurately the tolerances let T + V be known at the start and end states
    /// (crate::run::state_tolerance), J; None for fixed-step methods and large systems.
    pub state_tolerance: Option<f64>,
}

/// The `energy` object of summary.json.
///
/// ```text
/// balance_error = driver_work + load_work + motor_work
///                 − (kinetic_change + potential_change + dissipated_damping
///                    + dissipated_friction + dissipated_film + dissipated_damper)
/// ```
///
/// Source: docs/outputs.md (`energy`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Energy {
    /// Work done by the crank driver, J.
    pub driver_work: f64,
    /// Work done by the applied forces and torques (`force`, `torque` elements), J.
    #[serde(default)]
    pub load_work: f64,
    /// Work done by the motors, J.
    #[serde(default)]
    pub motor_work: f64,
    /// Change of kinetic energy, J.
    pub kinetic_change: f64,
    /// Change of potential energy (gravity, contact elastic energy, springs), J.
    pub potential_change: f64,
    /// The force elements' share of `potential_change` (the springs' potential), J.
    #[serde(default)]
    pub element_potential_change: f64,
    /// Dissipated by contact damping, J.
    pub dissipated_damping: f64,
    /// Dissipated by friction, J.
    pub dissipated_friction: f64,
    /// Dissipated by the film, J.
    pub dissipated_film: f64,
    /// Dissipated by the dampers of the force elements (spring-dampers, bushings), J.
    #[serde(default)]
    pub dissipated_damper: f64,
    /// Estimated error of the time integrals (works and dissipations), J.
    pub quadrature_error: f64,
    /// Σᵢ |∂(T + V)/∂yᵢ| (atolᵢ + rtol |yᵢ|) at the start and end states, J: how accurately
    /// the run's tolerances let the kinetic and potential energies be known (docs/outputs.md);
    /// null for a fixed-step method and above 300 states.
    #[serde(default)]
    pub state_tolerance: Option<f64>,
    /// The balance error, J: integration error plus the work of the Baumgarte terms; it is
    /// meaningful where it exceeds `quadrature_error`.
    pub balance_error: f64,
}

impl Energy {
    /// Closes the balance of the totals.
    pub(crate) fn from_totals(e: &EnergyTotals) -> Energy {
        Energy {
            driver_work: e.driver_work,
            load_work: e.load_work,
            motor_work: e.motor_work,
            kinetic_change: e.kinetic_change,
            potential_change: e.potential_change,
            element_potential_change: e.element_potential_change,
            dissipated_damping: e.dissipated_damping,
            dissipated_friction: e.dissipated_friction,
            dissipated_film: e.dissipated_film,
            dissipated_damper: e.dissipated_damper,
            quadrature_error: e.quadrature_error,
            state_tolerance: e.state_tolerance,
            balance_error: e.driver_work + e.load_work + e.motor_work
                - (e.kinetic_change
                    + e.potential_change
                    + e.dissipated_damping
                    + e.dissipated_friction
                    + e.dissipated_film
                    + e.dissipated_damper),
        }
    }
}

/// The metrics of one clearance joint over the window (`metrics.clearance_joints.NAME`).
///
/// ```text
/// eps_max, penetration_max = max(0, max δ), contact_force_max, film_force_max over S
/// (module doc); contact_onsets its located rising crossings of δ; film_thickness_min
/// c (1 − min(eps_max, 1)) when lubricated
/// ```
///
/// Source: docs/outputs.md (`metrics`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointMetrics {
    /// Max ε.
    pub eps_max: f64,
    /// Located rising crossings of δ in the window.
    pub contact_onsets: usize,
    /// Max normal contact force, N.
    pub contact_force_max: f64,
    /// max(0, max δ), m.
    pub penetration_max: f64,
    /// Max film force magnitude, N (0 when dry).
    pub film_force_max: f64,
    /// c (1 − min(ε_max, 1)), m (lubricated only).
    pub film_thickness_min: Option<f64>,
}

/// The `metrics` object of summary.json (null fields where a role is missing).
///
/// ```text
/// see the module doc: extrema over every accepted step's dense output and the 2001-point
/// grid of the last revolution, RMS over the grid
/// ```
///
/// Source: docs/outputs.md (`metrics`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Metrics {
    /// Max slider x acceleration, m/s².
    pub slider_acc_max: Option<f64>,
    /// Min slider x acceleration, m/s².
    pub slider_acc_min: Option<f64>,
    /// RMS of (slider acceleration − ideal) on the grid, m/s².
    pub slider_acc_rms_dev_ideal: Option<f64>,
    /// Max ε.
    pub eps_max: Option<f64>,
    /// Located rising crossings of δ in the window.
    pub contact_onsets: Option<usize>,
    /// Max normal contact force, N.
    pub contact_force_max: Option<f64>,
    /// max(0, max δ), m.
    pub penetration_max: Option<f64>,
    /// Max film force magnitude, N (0 when dry).
    pub film_force_max: Option<f64>,
    /// c (1 − min(ε_max, 1)), m (lubricated only).
    pub film_thickness_min: Option<f64>,
    /// Slider x at t_end, m.
    pub slider_x_end: Option<f64>,
    /// Max ‖Φ‖.
    pub constraint_violation_max: f64,
    /// Every clearance joint's metrics, by name (empty without clearance joints).
    #[serde(default)]
    pub clearance_joints: BTreeMap<String, JointMetrics>,
    /// Energy totals over the whole run and their balance error.
    pub energy: Option<Energy>,
}

/// Extrema of one clearance joint over the dense output in the window ([`Peaks`]).
///
/// ```text
/// max ε, max δ, max F_N, max |F_film| over S (module doc)
/// ```
///
/// Source: docs/outputs.md (`metrics`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct JointExtremes {
    /// Joint name.
    pub name: String,
    /// Radial clearance c, m.
    pub clearance: f64,
    /// Whether the joint has an oil film.
    pub lubricated: bool,
    /// Max ε.
    pub eps_max: f64,
    /// Max δ, m.
    pub delta_max: f64,
    /// Max F_N, N.
    pub contact_force_max: f64,
    /// Max |F_film|, N.
    pub film_force_max: f64,
}

/// Extrema over every accepted step's dense output in the window ([`Peaks`]), beside the
/// grid samples.
///
/// ```text
/// slider acceleration (min, max), max ‖Φ‖, every clearance joint (scene order)
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct DenseExtremes {
    /// (min, max) of the slider acceleration, m/s² (slider role).
    pub slider_acc: Option<(f64, f64)>,
    /// Max ‖Φ‖.
    pub constraint_violation_max: f64,
    /// Every clearance joint, in scene order.
    pub joints: Vec<JointExtremes>,
}

/// Running maxima of n quantities over a run's dense output (module doc): what the metrics'
/// extrema are taken over.
///
/// ```text
/// add(v)        a sample of every quantity at one time
/// step(a, b, f) the accepted step [a, b], f(t) = every quantity at t on its dense output:
///               samples at a + (b − a) j/4; a quantity whose best sample beats its running
///               maximum is refined by golden-section search (module doc)
/// ```
///
/// Source: module doc; golden-section search: Kiefer, Proc. AMS 4 (1953) 502–506.
#[derive(Clone, Debug)]
pub(crate) struct Peaks {
    max: Vec<f64>,
    last: Option<(f64, Vec<f64>)>,
    /// Evaluations of f so far.
    pub evals: usize,
    /// Refinements so far.
    pub refinements: usize,
}

type Eval<'a> = dyn FnMut(f64) -> Result<Vec<f64>, Error> + 'a;

impl Peaks {
    /// n quantities, no sample yet (every maximum −∞).
    pub(crate) fn new(n: usize) -> Peaks {
        Peaks {
            max: vec![f64::NEG_INFINITY; n],
            last: None,
            evals: 0,
            refinements: 0,
        }
    }

    /// The running maxima (−∞ before any sample).
    pub(crate) fn max(&self) -> &[f64] {
        &self.max
    }

    /// Adds one sample of every quantity.
    pub(crate) fn add(&mut self, v: &[f64]) {
        for (m, x) in self.max.iter_mut().zip(v) {
            *m = m.max(*x);
        }
    }

    fn eval(&mut self, f: &mut Eval<'_>, t: f64) -> Result<Vec<f64>, Error> {
        let v = f(t)?;
        self.evals += 1;
        self.add(&v);
        Ok(v)
    }

    /// The accepted step [a, b] (a < b) of the dense output `f` (module doc).
    pub(crate) fn step(&mut self, a: f64, b: f64, f: &mut Eval<'_>) -> Result<(), Error> {
        if !(b > a) {
            return Ok(());
        }
        let before = self.max.clone();
        let k = STEP_SAMPLES;
        let ts: Vec<f64> = (0..=k)
            .map(|j| {
                if j == k {
                    b
                } else {
                    a + (b - a) * j as f64 / k as f64
                }
            })
            .collect();
        let first = match self.last.take() {
            Some((t, v)) if t == a => v,
            _ => self.eval(f, a)?,
        };
        let mut vals = vec![first];
        for &t in &ts[1..] {
            vals.push(self.eval(f, t)?);
        }
        let mut probe: Option<Vec<f64>> = None;
        for q in 0..self.max.len() {
            let (j, m) = (0..=k)
                .map(|j| (j, vals[j][q]))
                .fold(
                    (0, f64::NEG_INFINITY),
                    |acc, x| if x.1 > acc.1 { x } else { acc },
                );
            let (lo, hi) = if j == 0 {
                // The step's start holds the record (reached at the previous step's end, where
                // the quantity was still rising, or at the window's start) and the quantity
                // falls from it: its peak may lie in [a, t_1].
                if !(m >= before[q] && vals[1][q] < m) {
                    continue;
                }
                (a, ts[1])
            } else if !(m > before[q]) {
                continue;
            } else if j < k {
                (ts[j - 1], ts[j + 1])
            } else {
                let p = match &probe {
                    Some(p) => p.clone(),
                    None => {
                        let p = self.eval(f, b - (b - a) / 256.0)?;
                        probe = Some(p.clone());
                        p
                    }
                };
                if p[q] < m {
                    continue;
                }
                (ts[k - 1], b)
            };
            self.refine(f, q, lo, hi)?;
        }
        self.last = Some((b, vals.pop().unwrap_or_default()));
        Ok(())
    }

    /// Golden-section search for the maximum of quantity q on [lo, hi].
    fn refine(
        &mut self,
        f: &mut Eval<'_>,
        q: usize,
        mut lo: f64,
        mut hi: f64,
    ) -> Result<(), Error> {
        const G: f64 = 0.618_033_988_749_894_9;
        self.refinements += 1;
        let mut x1 = hi - G * (hi - lo);
        let mut x2 = lo + G * (hi - lo);
        let mut f1 = self.eval(f, x1)?[q];
        let mut f2 = self.eval(f, x2)?[q];
        for _ in 2..REFINE_ITERATIONS {
            if f1 < f2 {
                lo = x1;
                x1 = x2;
                f1 = f2;
                x2 = lo + G * (hi - lo);
                f2 = self.eval(f, x2)?[q];
            } else {
                hi = x2;
                x2 = x1;
                f2 = f1;
                x1 = hi - G * (hi - lo);
                f1 = self.eval(f, x1)?[q];
            }
        }
        Ok(())
    }
}

/// Where the samples lie: the last revolution before `t_end`.
///
/// ```text
/// [t_end − T, t_end],  T = 60 / rpm
/// ```
///
/// Source: docs/outputs.md (`metrics`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Window {
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
/// clearance joint role (None when the scene declares none), the events located during the
/// run, the energy totals (None when the model does not account energy) and the extrema over
/// the dense output in the window (None: the grid alone).
///
/// Errors ([`Error::Internal`], a bug in the caller): not 2001 samples, a sample off the grid,
/// a non-finite value, a column given at some samples only.
pub(crate) fn compute(
    samples: &[Sample],
    window: Window,
    joint: Option<JointInfo>,
    events: &[EventRecord],
    energy: Option<EnergyTotals>,
    dense: Option<&DenseExtremes>,
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

    let onsets_of = |k: Option<usize>| {
        let t0 = t_end - period;
        events
            .iter()
            .filter(|e| e.quantity == EventQuantity::Penetration && e.rising)
            .filter(|e| k.is_none() || e.joint.is_none() || e.joint == k)
            .filter(|e| t0 <= e.t && e.t <= t_end)
            .count()
    };
    let dense_joint = |j: &JointInfo| dense.and_then(|d| d.joints.get(j.index));
    let role = joint.and_then(|j| dense_joint(&j));
    let up = |grid: Option<f64>, d: Option<f64>| match (grid, d) {
        (Some(g), Some(d)) => Some(g.max(d)),
        (g, None) => g,
        (None, d) => d,
    };
    let a_max = up(
        a.as_deref().map(max),
        dense.and_then(|d| d.slider_acc).map(|x| x.1),
    );
    let a_min = match (a.as_deref().map(min), dense.and_then(|d| d.slider_acc)) {
        (Some(g), Some((d, _))) => Some(g.min(d)),
        (g, None) => g,
        (None, Some((d, _))) => Some(d),
    };
    let rms_dev = match (&a, &a_ideal) {
        (Some(a), Some(ai)) => {
            let ss: f64 = a.iter().zip(ai).map(|(x, y)| (x - y) * (x - y)).sum();
            Some((ss / a.len() as f64).sqrt())
        }
        _ => None,
    };
    let eps_max = up(eps.as_deref().map(max), role.map(|r| r.eps_max));
    let (contact_onsets, film_thickness_min) = match joint {
        Some(j) => {
            if !(j.clearance > 0.0 && j.clearance.is_finite()) {
                return Err(Error::Internal(format!(
                    "metrics: clearance must be > 0, got {}",
                    j.clearance
                )));
            }
            let n = onsets_of(dense.map(|_| j.index));
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
    let contact_force_max = up(fnorm.as_deref().map(max), role.map(|r| r.contact_force_max));
    let penetration_max =
        up(delta.as_deref().map(max), role.map(|r| r.delta_max)).map(|d| d.max(0.0));
    let film_force_max = up(
        film.as_deref()
            .map(|f| f.iter().fold(0.0, |m: f64, x| m.max(x.abs()))),
        role.map(|r| r.film_force_max),
    );
    let mut clearance_joints = BTreeMap::new();
    if let Some(d) = dense {
        for (k, jx) in d.joints.iter().enumerate() {
            let is_role = joint.is_some_and(|j| j.index == k);
            let jm = if is_role {
                JointMetrics {
                    eps_max: eps_max.unwrap_or(jx.eps_max),
                    contact_onsets: contact_onsets.unwrap_or(0),
                    contact_force_max: contact_force_max.unwrap_or(jx.contact_force_max),
                    penetration_max: penetration_max.unwrap_or(jx.delta_max.max(0.0)),
                    film_force_max: film_force_max.unwrap_or(jx.film_force_max),
                    film_thickness_min,
                }
            } else {
                JointMetrics {
                    eps_max: jx.eps_max,
                    contact_onsets: onsets_of(Some(k)),
                    contact_force_max: jx.contact_force_max,
                    penetration_max: jx.delta_max.max(0.0),
                    film_force_max: jx.film_force_max,
                    film_thickness_min: jx
                        .lubricated
                        .then(|| jx.clearance * (1.0 - jx.eps_max.min(1.0))),
                }
            };
            let v = [
                jm.eps_max,
                jm.contact_force_max,
                jm.penetration_max,
                jm.film_force_max,
                jm.film_thickness_min.unwrap_or(0.0),
            ];
            if v.iter().any(|x| !x.is_finite()) {
                return Err(Error::Internal(format!(
                    "metrics: non-finite extrema of clearance joint {}: {jm:?}",
                    jx.name
                )));
            }
            clearance_joints.insert(jx.name.clone(), jm);
        }
    }
    let cv_max = match dense {
        Some(d) => max(&cv).max(d.constraint_violation_max),
        None => max(&cv),
    };
    Ok(Metrics {
        slider_acc_max: a_max,
        slider_acc_min: a_min,
        slider_acc_rms_dev_ideal: rms_dev,
        eps_max,
        contact_onsets,
        contact_force_max,
        penetration_max,
        film_force_max,
        film_thickness_min,
        slider_x_end: x.as_deref().and_then(|x| x.last().copied()),
        constraint_violation_max: cv_max,
        clearance_joints,
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
            index: 0,
            clearance: c,
            lubricated: true,
        });
        let m = compute(
            &samples(|t| journal(t, 0.5, 0.3, c)),
            W,
            lub,
            &[],
            None,
            None,
        )
        .unwrap();
        assert!((m.eps_max.unwrap() - 0.8).abs() < 1e-12);
        assert!((m.film_thickness_min.unwrap() - c * 0.2).abs() < 1e-16);
        assert_eq!(m.penetration_max, Some(0.0)); // max δ = −0.2c < 0
        assert_eq!(m.contact_force_max, Some(0.0));
        assert!((m.film_force_max.unwrap() - 200.0).abs() < 1e-9); // |−250 ε| at ε = 0.8
        assert!((m.constraint_violation_max - 0.8e-9).abs() < 1e-20);
        assert_eq!(m.contact_onsets, Some(0));
        // Through the clearance: ε_max = 1.2 → δ_max = 0.2c, film thickness clamps at 0.
        let m = compute(
            &samples(|t| journal(t, 0.9, 0.3, c)),
            W,
            lub,
            &[],
            None,
            None,
        )
        .unwrap();
        assert!((m.penetration_max.unwrap() - 0.2 * c).abs() < 1e-16);
        assert_eq!(m.film_thickness_min, Some(0.0));
        assert!((m.contact_force_max.unwrap() - 2e3).abs() < 1e-8);
        // Dry: no film thickness.
        let dry = Some(JointInfo {
            index: 0,
            clearance: c,
            lubricated: false,
        });
        let m = compute(
            &samples(|t| journal(t, 0.5, 0.3, c)),
            W,
            dry,
            &[],
            None,
            None,
        )
        .unwrap();
        assert_eq!(m.film_thickness_min, None);
        assert!(m.eps_max.is_some());
    }

    #[test]
    fn contact_onsets_count_rising_penetration_events_in_the_window() {
        let c = 1e-4;
        let joint = Some(JointInfo {
            index: 0,
            clearance: c,
            lubricated: false,
        });
        let ev = |t, quantity, rising| EventRecord {
            t,
            quantity,
            rising,
            joint: None,
            index: 0,
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
            None,
        )
        .unwrap();
        assert_eq!(m.contact_onsets, Some(4));
    }

    #[test]
    fn missing_roles_give_null_metrics() {
        let m = compute(&samples(Sample::at), W, None, &[], None, None).unwrap();
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
            load_work: 0.0,
            motor_work: 0.0,
            dissipated_damper: 0.0,
            element_potential_change: 0.0,
            quadrature_error: 1e-9,
            state_tolerance: None,
        };
        let m = compute(&samples(Sample::at), W, None, &[], Some(e), None).unwrap();
        assert_eq!(m.energy.unwrap().balance_error, 0.5);
        // Every element term counts: a motor's and a load's work in, a damper's out (a
        // balance that left one out would be off by exactly that term).
        let el = EnergyTotals {
            load_work: -20.0,
            motor_work: 32.0,
            dissipated_damper: 11.5,
            ..e
        };
        let m = compute(&samples(Sample::at), W, None, &[], Some(el), None).unwrap();
        assert_eq!(m.energy.unwrap().balance_error, 1.0);
        let bad = EnergyTotals {
            driver_work: f64::NAN,
            ..e
        };
        assert!(compute(&samples(Sample::at), W, None, &[], Some(bad), None).is_err());
    }

    /// A pulse A exp(−((t − t*)/w)²) with w = 2e-5 s, far narrower than the 2001-point grid of
    /// a 0.4 s window (spacing 2e-4 s) and than the sample spacing h/4 of steps h = 1e-3 s,
    /// placed at the worst spots: between two samples, just after a step's start, just before
    /// its end, and on a step boundary. Golden-section search on a unimodal bracket finds A to
    /// 1e-9 (module doc: the bracket W ≤ 5e-4 s = 25 w); the grid sees a fraction of it.
    #[test]
    fn peaks_find_a_pulse_narrower_than_the_samples() {
        let (amp, w, h) = (118.0, 2e-5, 1e-3);
        // (t*, whether the grid misses it: 0.25 and 0.001 are grid points)
        for (t_star, missed) in [
            (0.1234567, true),
            (0.2 + 1.5e-5, true),
            (0.3 - 1.2e-5, true),
            (0.25, false),
            (0.001, false),
        ] {
            let f = |t: f64| amp * (-((t - t_star) / w).powi(2)).exp();
            // Two quantities: the pulse, and its negative (a minimum, as slider_acc_min).
            let mut p = Peaks::new(2);
            let mut eval = |t: f64| Ok(vec![f(t), -f(t)]);
            let n = (0.4 / h) as usize;
            for i in 0..n {
                let (a, b) = (i as f64 * h, (i + 1) as f64 * h);
                p.step(a, b, &mut eval).unwrap();
            }
            let found = p.max()[0];
            assert!((found - amp).abs() < 1e-9 * amp, "t* = {t_star}: {found}");
            // The minimum of −f is −f at the samples' ends: the window's ends, 0 to 1e-300.
            assert!(p.max()[1] <= 0.0 && p.max()[1] > -1e-6 * amp);
            // Refinements only where a new maximum appears: a handful, not one per step.
            assert!(p.refinements <= 6, "{}", p.refinements);
            assert!(p.evals < 4 * n + 6 * REFINE_ITERATIONS + n, "{}", p.evals);
            let grid_max = grid(0.4, 0.4).iter().map(|&t| f(t)).fold(0.0, f64::max);
            if missed {
                assert!(grid_max < 0.9 * amp, "t* = {t_star}: grid {grid_max}");
            }
        }
    }

    /// Flat and monotone quantities cost (almost) no search: their extrema lie at samples.
    #[test]
    fn peaks_of_flat_and_monotone_quantities_need_no_search() {
        let mut p = Peaks::new(3);
        let mut eval = |t: f64| Ok(vec![0.0, t, -t]);
        for i in 0..100 {
            let (a, b) = (i as f64 * 0.01, (i + 1) as f64 * 0.01);
            p.step(a, b, &mut eval).unwrap();
        }
        assert_eq!(p.max(), &[0.0, 1.0, 0.0]);
        // One search: the falling quantity at the window's start, whose peak could lie just
        // after it. 5 samples in the first step, 4 in each later one, one probe per step at the
        // end of the rising quantity, and the search's evaluations.
        assert_eq!(p.refinements, 1);
        assert_eq!(p.evals, 1 + 4 * 100 + 100 + REFINE_ITERATIONS);
    }

    #[test]
    fn dense_extrema_raise_the_grid_metrics_and_every_joint_has_its_own() {
        let c = 1e-4;
        let joint = Some(JointInfo {
            index: 1,
            clearance: c,
            lubricated: false,
        });
        let jx = |name: &str, eps: f64, lubricated: bool| JointExtremes {
            name: name.into(),
            clearance: c,
            lubricated,
            eps_max: eps,
            delta_max: c * (eps - 1.0),
            contact_force_max: if eps > 1.0 { 1e4 * (eps - 1.0) } else { 0.0 },
            film_force_max: if lubricated { 700.0 } else { 0.0 },
        };
        let dense = DenseExtremes {
            slider_acc: Some((-9.0, 12.0)),
            constraint_violation_max: 2e-9,
            joints: vec![jx("upper", 0.6, true), jx("elbow", 1.5, false)],
        };
        let ev = |t, joint| EventRecord {
            t,
            quantity: EventQuantity::Penetration,
            rising: true,
            joint: Some(joint),
            index: joint,
        };
        let events = [ev(0.5, 1), ev(0.6, 1), ev(0.7, 0)];
        let m = compute(
            &samples(|t| Sample {
                slider_a: Some(3.0 * (t * 10.0).sin()),
                ..journal(t, 0.9, 0.3, c)
            }),
            W,
            joint,
            &events,
            None,
            Some(&dense),
        )
        .unwrap();
        // Grid: ε ≤ 1.2, |a| ≤ 3; the dense extrema are beyond and win.
        assert_eq!(m.eps_max, Some(1.5));
        assert_eq!(
            (m.slider_acc_min, m.slider_acc_max),
            (Some(-9.0), Some(12.0))
        );
        assert!((m.penetration_max.unwrap() - 0.5 * c).abs() < 1e-18);
        assert!((m.contact_force_max.unwrap() - 5e3).abs() < 1e-9);
        assert_eq!(m.constraint_violation_max, 2e-9);
        assert_eq!(m.contact_onsets, Some(2));
        // Film force: the grid's |−250 ε| at ε = 1.2 beats the dry joint's dense 0.
        assert!((m.film_force_max.unwrap() - 300.0).abs() < 1e-9);
        let names: Vec<&String> = m.clearance_joints.keys().collect();
        assert_eq!(names, ["elbow", "upper"]);
        let e = &m.clearance_joints["elbow"];
        assert_eq!((e.eps_max, e.contact_onsets), (1.5, 2));
        assert_eq!(e.film_thickness_min, None);
        let u = &m.clearance_joints["upper"];
        assert_eq!(
            (u.eps_max, u.contact_onsets, u.penetration_max),
            (0.6, 1, 0.0)
        );
        assert_eq!(u.film_force_max, 700.0);
        assert!((u.film_thickness_min.unwrap() - 0.4 * c).abs() < 1e-18);
        let j = serde_json::to_value(&m).unwrap();
        assert_eq!(j["clearance_joints"]["upper"]["contact_onsets"], 1);
        let back: Metrics = serde_json::from_value(j).unwrap();
        assert_eq!(back, m);
    }

    #[test]
    fn bad_samples_are_bugs_not_silent_nans() {
        let s = samples(Sample::at);
        let e = compute(&s[..2000], W, None, &[], None, None).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Bug);
        let mut off = s.clone();
        off[7].t += 1e-6;
        assert!(compute(&off, W, None, &[], None, None)
            .unwrap_err()
            .to_string()
            .contains("off the grid"));
        let mut nan = s.clone();
        for x in nan.iter_mut() {
            x.slider_a = Some(0.0);
        }
        nan[3].slider_a = Some(f64::NAN);
        assert!(compute(&nan, W, None, &[], None, None)
            .unwrap_err()
            .to_string()
            .contains("slider_a is not finite"));
        let mut mixed = s.clone();
        mixed[0].eps = Some(0.1);
        assert!(compute(&mixed, W, None, &[], None, None)
            .unwrap_err()
            .to_string()
            .contains("eps is given at 1 of 2001"));
        let mut cv = s;
        cv[5].constraint_violation = f64::INFINITY;
        assert!(compute(&cv, W, None, &[], None, None).is_err());
    }
}
