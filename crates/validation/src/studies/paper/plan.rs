//! What the paper's study runs: its 18 cases, the solver settings (study, reference, loose),
//! the realisations and the runs until periodic.
//!
//! Source: the module doc of `studies::paper`; docs/model.md §6, §9.

use lash_solver::{Atol, Method, SolverOptions};

use crate::run::prepare::DEFAULT_MAX_STEPS;
use crate::run::press::PressCase;
use crate::run::steady::UntilPeriodic;

/// Dry cases of the speed study (0.1 mm), in increasing speed.
pub(crate) const DRY_SPEEDS: [PressCase; 4] = [
    PressCase::dry(120, 100),
    PressCase::dry(150, 100),
    PressCase::dry(180, 100),
    PressCase::dry(200, 100),
];
/// Lubricated cases of the speed study (0.1 mm), in increasing speed.
pub(crate) const LUB_SPEEDS: [PressCase; 4] = [
    PressCase::lubricated(120, 100),
    PressCase::lubricated(150, 100),
    PressCase::lubricated(180, 100),
    PressCase::lubricated(200, 100),
];
/// Dry cases of the clearance study (150 rpm), in increasing clearance.
pub(crate) const DRY_CLEARANCES: [PressCase; 4] = [
    PressCase::dry(150, 100),
    PressCase::dry(150, 200),
    PressCase::dry(150, 300),
    PressCase::dry(150, 500),
];
/// Lubricated cases of the clearance study (150 rpm), in increasing clearance.
pub(crate) const LUB_CLEARANCES: [PressCase; 4] = [
    PressCase::lubricated(150, 100),
    PressCase::lubricated(150, 200),
    PressCase::lubricated(150, 300),
    PressCase::lubricated(150, 500),
];
/// The ideal mechanism at the four speeds.
pub(crate) const IDEALS: [PressCase; 4] = [
    PressCase::ideal(120),
    PressCase::ideal(150),
    PressCase::ideal(180),
    PressCase::ideal(200),
];
/// Radial clearances of the clearance study, mm (the order of [`DRY_CLEARANCES`]).
pub(crate) const CLEARANCES_MM: [f64; 4] = [0.1, 0.2, 0.3, 0.5];

/// Tolerance of the study's runs until periodic, units of c: 5 × tighter than the claim's
/// "periodic" threshold (`claims::PERIODIC`).
pub(crate) const STEADY_TOL: f64 = 1e-2;
/// Cap on the revolutions of the study's runs until periodic.
pub(crate) const STEADY_MAX_REVOLUTIONS: usize = 40;

/// Half-width of the windows around the dead centres, degrees of crank angle.
pub(crate) const DEAD_CENTRE_WINDOW_DEG: f64 = 15.0;

/// The 18 cases of the study: the speed and clearance studies, dry then lubricated, then the
/// ideal mechanism.
pub(crate) fn study_cases() -> Vec<PressCase> {
    let mut v = Vec::new();
    for set in [
        &DRY_SPEEDS[..],
        &DRY_CLEARANCES[1..],
        &LUB_SPEEDS[..],
        &LUB_CLEARANCES[1..],
        &IDEALS[..],
    ] {
        v.extend_from_slice(set);
    }
    v
}

/// Solver settings of one study run.
///
/// ```text
/// method, rtol, atol (scalar), event_samples interior points per step for the event search
/// (an adaptive step may otherwise hold a whole contact, onset and loss, and skip it)
/// ```
///
/// Source: this study (chosen and checked for convergence in the report);
/// `lash_solver::SolverOptions`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settings {
    /// Integration method.
    pub method: Method,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Interior points sampled per step by the event search.
    pub event_samples: usize,
}

impl Settings {
    /// The solver options of a study run: these settings, event location on, no h_max, the
    /// runner's step limit (`simulate::DEFAULT_MAX_STEPS`).
    pub(crate) fn options(&self) -> SolverOptions {
        let mut o = SolverOptions::with_method(self.method);
        o.rtol = self.rtol;
        o.atol = Atol::Scalar(self.atol);
        o.event_samples = self.event_samples;
        o.max_steps = DEFAULT_MAX_STEPS;
        o
    }
}

/// What the study runs.
///
/// ```text
/// every case × realisations k = 0..N−1 (crank θ₀ = k·Δθ) × {settings, reference, loose}
/// ```
///
/// Source: this module (docs/model.md §9 for why an ensemble).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Plan {
    /// Settings of the reported runs.
    pub settings: Settings,
    /// Tighter settings of the convergence check.
    pub reference: Settings,
    /// Looser settings, run to show what they would change.
    pub loose: Settings,
    /// Realisations per clearance case (N ≥ 1).
    pub realisations: usize,
    /// Step Δθ of the crank's initial angle between realisations, rad.
    pub phase_step_rad: f64,
    /// Steady state of the periodicity claim: runs until the section settles.
    pub steady: UntilPeriodic,
}

impl Plan {
    /// The plan of `lash study paper`: BDF at rtol 1e-10 (reference 1e-12, loose 1e-8),
    /// atol = rtol/100,
    /// two event samples per step, 8 realisations 1e-6 rad of crank phase apart.
    pub fn paper() -> Plan {
        let s = |rtol: f64| Settings {
            method: Method::Bdf,
            rtol,
            atol: rtol * 1e-2,
            event_samples: 2,
        };
        Plan {
            settings: s(1e-10),
            reference: s(1e-12),
            loose: s(1e-8),
            realisations: 8,
            phase_step_rad: 1e-6,
            steady: UntilPeriodic {
                tol: STEADY_TOL,
                max_revolutions: STEADY_MAX_REVOLUTIONS,
            },
        }
    }
}

/// Which of the plan's solver settings.
///
/// ```text
/// Study = Plan::settings (reported);  Reference = Plan::reference;  Loose = Plan::loose
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Setting {
    /// The reported runs.
    Study,
    /// The tighter convergence check.
    Reference,
    /// The looser comparison.
    Loose,
}

impl Setting {
    /// All three, study first.
    pub(crate) const ALL: [Setting; 3] = [Setting::Study, Setting::Reference, Setting::Loose];
}

impl Plan {
    /// The solver settings of `which`.
    pub(crate) fn get(&self, which: Setting) -> Settings {
        match which {
            Setting::Study => self.settings,
            Setting::Reference => self.reference,
            Setting::Loose => self.loose,
        }
    }
}
