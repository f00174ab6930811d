//! What the extremes matrix runs and what it promises: the tolerances, the budgets, the
//! reference ladders, the constants of the accuracy promise, the plans (full, quick) and the
//! settings of one scene.
//!
//! Source: the module doc of `studies::extremes`; BENCHMARKS.md ("Extremes").

use lash_solver::Method;

use crate::studies::extremes::catalogue::catalogue;
use crate::studies::extremes::catalogue::ExtremeScene;

/// Relative tolerances of the full matrix.
pub(crate) const TOLERANCES: [f64; 6] = [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12];
/// Relative tolerances of the quick subset.
pub(crate) const QUICK_TOLERANCES: [f64; 3] = [1e-3, 1e-6, 1e-9];
/// Scenes of the quick subset: cheap corners (quick references) that still stress each
/// family: hard contact, a film near ε = 1, a clearance 100 times smaller than the
/// penetration.
pub(crate) const QUICK_SCENES: [&str; 3] = [
    "dry_stiffness_1e14",
    "lubricated_eccentricity_0.999",
    "dry_clearance_1um",
];
/// Budget of every run of the quick subset: the explicit methods on the film near ε = 1 are
/// stability-bound and stop at the step budget.
pub(crate) const QUICK_BUDGET: Budget = Budget {
    max_steps: 100_000,
    max_wall_time: 10.0,
};
/// The adaptive methods of the matrix, in the order of docs/outputs.md ("Method and controller
/// names").
pub(crate) const ADAPTIVE: [Method; 8] = [
    Method::Bs32,
    Method::Dopri54,
    Method::Tsit54,
    Method::Dop853,
    Method::Bdf,
    Method::Trbdf2,
    Method::Esdirk34,
    Method::Rodas5p,
];
/// Step budget of every matrix run (attempts).
pub(crate) const MAX_STEPS: usize = 1_000_000;
/// Wall-clock budget of every matrix run, s.
pub(crate) const MAX_WALL_TIME: f64 = 20.0;
/// The reference ladder of a dry scene: the first rtol at which both methods succeed.
pub(crate) const REFERENCE_RTOLS_DRY: [f64; 4] = [1e-13, 1e-12, 1e-11, 1e-10];
/// The reference ladder of a lubricated scene (module doc: why not 1e-13).
pub(crate) const REFERENCE_RTOLS_LUBRICATED: [f64; 3] = [1e-12, 1e-11, 1e-10];
/// Step budget of a reference run.
pub(crate) const REFERENCE_MAX_STEPS: usize = 2_000_000;
/// Wall-clock budget of a reference run, s.
pub(crate) const REFERENCE_MAX_WALL_TIME: f64 = 60.0;

/// The constant C of the promise e ≤ C · rtol^α + F · E_ref on a scene with a dry joint.
///
/// ```text
/// C_dry = 2e5
/// ```
/// Rule for every constant of the promise: the smallest 1–2–5 value at least twice the
/// largest value measured over the full matrix (BENCHMARKS.md, "Extremes", lists them), the
/// measured value of a run being (e − F·E_ref)/rtol^α ([`Cell::measured_c`]), the
/// [`KNOWN_FINDINGS`] left out. An impact turns a small error in the journal's position into an
/// error in the slider's velocity, and the dry press is chaotic (docs/model.md §9), so the
/// global error of a dry scene lies decades further above rtol than that of a lubricated one.
/// With this C the promise can fail for rtol ≤ 1e-7; at looser tolerances C·rtol exceeds any
/// deviation the slider can have, and the check there is that the result is finite.
pub(crate) const PROMISE_C_DRY: f64 = 2e5;
/// The constant C of the promise on a scene whose clearance joints all have a film.
///
/// ```text
/// C_lub = 5e2
/// ```
/// Set by the rule of [`PROMISE_C_DRY`] (the largest measured value: BENCHMARKS.md, "Extremes").
pub(crate) const PROMISE_C_LUBRICATED: f64 = 5e2;
/// The constant C_rk4 of RK4's promise e(h) ≤ C_rk4 · e(h; h/2) + F · E_ref.
///
/// ```text
/// C_rk4 = 5
/// ```
/// For a method of order p ≥ 1, e(h) ≈ e(h; h/2) / (1 − 2^{−p}) ≤ 2 e(h; h/2); RK4 without
/// event location on the non-smooth contact force does not converge at a clean order
/// (BENCHMARKS.md (c)). Set by the rule of [`PROMISE_C_DRY`] (the largest measured value:
/// BENCHMARKS.md, "Extremes").
pub(crate) const PROMISE_C_RK4: f64 = 5.0;
/// The factor F on the reference's error estimate E_ref in the promise: below E_ref an error
/// cannot be told from the reference's own, so F = 1 is not fitted but the definition of the
/// floor.
///
/// ```text
/// F = 1
/// ```
/// The runs whose error exceeds C·rtol^α exceed it by a small fraction of E_ref
/// (BENCHMARKS.md, "Extremes").
pub(crate) const PROMISE_F: f64 = 1.0;

/// The exponent α of a method's tolerance proportionality (module doc).
///
/// ```text
/// bs32, dopri54, tsit54, dop853, rodas5p: 1;  trbdf2: 2/3;  esdirk34: 3/4;  bdf: 5/6
/// ```
/// Source: HNW I §II.4; diffsol's tableaus (TR-BDF2 order 2, ESDIRK3(4) order 3, BDF 1–5).
pub(crate) fn alpha(m: Method) -> f64 {
    match m {
        Method::Trbdf2 => 2.0 / 3.0,
        Method::Esdirk34 => 3.0 / 4.0,
        Method::Bdf => 5.0 / 6.0,
        _ => 1.0,
    }
}

/// Budgets of every run of the matrix.
///
/// ```text
/// a run stops with TooManySteps after max_steps attempts, BudgetExhausted after
/// max_wall_time seconds of integration
/// ```
///
/// Source: docs/outputs.md ("`lash extremes`": every run has a step and a wall-clock budget).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Budget {
    /// Most step attempts of one run.
    pub max_steps: usize,
    /// Most wall-clock seconds of one run.
    pub max_wall_time: f64,
}

impl Default for Budget {
    fn default() -> Self {
        Budget {
            max_steps: MAX_STEPS,
            max_wall_time: MAX_WALL_TIME,
        }
    }
}

/// What the matrix runs.
///
/// ```text
/// scenes (stems of the catalogue) × {rk4 at h_in and h_out, ADAPTIVE × tolerances}
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Plan {
    /// Scene stems, in catalogue order.
    pub scenes: Vec<String>,
    /// Relative tolerances of the adaptive methods.
    pub tolerances: Vec<f64>,
    /// Budget of every run.
    pub budget: Budget,
    /// Parallel runs (≥ 1).
    pub jobs: usize,
}

impl Plan {
    /// The full matrix: every scene, [`TOLERANCES`].
    pub(crate) fn full() -> Plan {
        Plan {
            scenes: catalogue().iter().map(|s| s.stem.to_string()).collect(),
            tolerances: TOLERANCES.to_vec(),
            budget: Budget::default(),
            jobs: 1,
        }
    }

    /// The quick subset: [`QUICK_SCENES`], [`QUICK_TOLERANCES`], [`QUICK_BUDGET`].
    pub(crate) fn quick() -> Plan {
        Plan {
            scenes: QUICK_SCENES.iter().map(|s| s.to_string()).collect(),
            tolerances: QUICK_TOLERANCES.to_vec(),
            budget: QUICK_BUDGET,
            jobs: 1,
        }
    }
}

/// The setting of one run.
///
/// ```text
/// Rk4Inside { h } | Rk4Beyond { h } | Adaptive { method, rtol }
/// ```
///
/// Source: module doc.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Setting {
    /// RK4 at a step inside its stability limit.
    Rk4Inside {
        /// Step, s.
        h: f64,
    },
    /// RK4 at a step beyond its stability limit: must fail with Rk4Unstable or NonFiniteState.
    Rk4Beyond {
        /// Step, s.
        h: f64,
    },
    /// An adaptive method at a relative tolerance.
    Adaptive {
        /// Method.
        method: Method,
        /// Relative tolerance.
        rtol: f64,
    },
}

impl Setting {
    /// The method.
    pub(crate) fn method(&self) -> Method {
        match self {
            Setting::Rk4Inside { .. } | Setting::Rk4Beyond { .. } => Method::Rk4,
            Setting::Adaptive { method, .. } => *method,
        }
    }

    /// The row label in the tables: `rk4`, `rk4 beyond`, or the method name.
    pub(crate) fn label(&self) -> String {
        match self {
            Setting::Rk4Inside { .. } => "rk4".into(),
            Setting::Rk4Beyond { .. } => "rk4 beyond".into(),
            Setting::Adaptive { method, .. } => method.name().into(),
        }
    }
}

/// The settings of one scene: RK4 inside and beyond, then every adaptive method × tolerance.
pub(crate) fn settings(scene: &ExtremeScene, tolerances: &[f64]) -> Vec<Setting> {
    let mut v = vec![
        Setting::Rk4Inside {
            h: scene.rk4_inside,
        },
        Setting::Rk4Beyond {
            h: scene.rk4_beyond,
        },
    ];
    for m in ADAPTIVE {
        for &rtol in tolerances {
            v.push(Setting::Adaptive { method: m, rtol });
        }
    }
    v
}
