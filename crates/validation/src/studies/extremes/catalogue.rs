//! The scenes of the extremes matrix: the press of `cases/press` with one parameter pushed to
//! a corner, and the RK4 steps of each (inside and beyond its stability limit).
//!
//! Source: docs/model.md §6; BENCHMARKS.md ("Extremes").

use std::path::PathBuf;

use lash_model::cases::{press_scene, PressJoint};
use lash_model::scene::{FrictionSpec, JointSpec, NormalSpec, SolverSpec};
use lash_model::{FormulationName, Scene};
use lash_solver::Method;

use crate::error::Error;
use crate::run::case::{sha256_hex, Case, CaseSource};
use crate::run::prepare::Prepared;

/// One scene of the catalogue and its RK4 steps.
///
/// ```text
/// stem, what it stresses, the scene (press_scene + one parameter at a corner),
/// h_in: RK4 runs (stability check on, simulate.rs) and meets its promise;
/// h_out: RK4 fails with Rk4Unstable (its stability check) or NonFiniteState (the divergence
/// bound)
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug)]
pub struct ExtremeScene {
    /// File stem in `cases/extremes/`.
    pub stem: &'static str,
    /// What the scene stresses, in words.
    pub stresses: &'static str,
    /// The scene.
    pub scene: Scene,
    /// RK4 step inside its stability limit, s.
    pub rk4_inside: f64,
    /// RK4 step beyond its stability limit, s.
    pub rk4_beyond: f64,
}

impl ExtremeScene {
    /// The file's content: pretty JSON and a final newline.
    pub fn json(&self) -> String {
        self.scene.to_json_pretty() + "\n"
    }

    /// The case, as if loaded from `cases/extremes/STEM.json` (same name and hash).
    pub(crate) fn prepared(&self) -> Result<Prepared, Error> {
        let text = self.json();
        let json = serde_json::from_str(&text)
            .map_err(|e| Error::Internal(format!("{}: {e}", self.stem)))?;
        let case = Case {
            name: self.stem.to_string(),
            source: CaseSource::File {
                path: PathBuf::from(format!("cases/extremes/{}.json", self.stem)),
                sha256: sha256_hex(text.as_bytes()),
                bytes: text.into_bytes(),
                json,
            },
        };
        Prepared::with_scene(case, self.scene.clone())
    }
}

/// The note of a scene whose solver section tightens rtol.
const TIGHT_NOTE: &str = "solver: rtol 1e-10 (the default run: at the press's rtol 1e-8 the \
     energy balance is integration error, BENCHMARKS.md \"Energy balance of every case\").";

/// What is changed from the press, for [`catalogue`].
#[derive(Clone, Copy, Default)]
struct Corner {
    lubricated: bool,
    rpm: Option<f64>,
    clearance: Option<f64>,
    k: Option<f64>,
    mu: Option<f64>,
    viscosity: Option<f64>,
    eps_cap: Option<f64>,
    /// End time, s (replaces the press's two revolutions).
    t_end: Option<f64>,
    /// Revolutions (replaces the press's two).
    revolutions: Option<f64>,
    /// The scene's own solver section (`lash run`'s defaults for it): (method, rtol).
    solver: Option<(Option<Method>, f64)>,
    /// The scene's formulation, where the default (`auto`) does not hold for it.
    formulation: Option<FormulationName>,
}

fn corner_scene(stem: &str, stresses: &str, c: Corner, notes: &[&str]) -> Scene {
    let kind = if c.lubricated {
        PressJoint::Lubricated
    } else {
        PressJoint::Dry
    };
    let rpm = c.rpm.unwrap_or(150.0);
    let mut s = press_scene(kind, rpm, c.clearance.unwrap_or(1e-4));
    for j in s.joints.iter_mut() {
        if let JointSpec::Clearance(cl) = j {
            if let (NormalSpec::Impact(i), Some(k)) = (&mut cl.normal, c.k) {
                i.k = Some(k);
            }
            if let (FrictionSpec::Coulomb(f), Some(mu)) = (&mut cl.friction, c.mu) {
                f.mu = mu;
            }
            if let Some(f) = cl.film.as_mut() {
                if let Some(v) = c.viscosity {
                    f.viscosity = v;
                }
                if let Some(e) = c.eps_cap {
                    f.eps_cap = Some(e);
                }
            }
        }
    }
    if let Some(t) = c.t_end {
        s.t_end = Some(t);
        s.revolutions = None;
    } else if let Some(r) = c.revolutions {
        s.revolutions = Some(r);
    }
    if let Some((method, rtol)) = c.solver {
        s.solver = SolverSpec {
            method,
            rtol: Some(rtol),
            atol: None,
        };
    }
    if let Some(f) = c.formulation {
        s.formulation = f;
    }
    s.description = format!(
        "Extreme scene '{stem}' ({stresses}): cases/press/{}_150rpm_c0.1.json with one \
         parameter at a corner of the extremes matrix (lash extremes; notes marked Extremes).",
        if c.lubricated { "lubricated" } else { "dry" }
    );
    s.notes
        .extend(notes.iter().map(|n| format!("Extremes: {n}")));
    s
}

/// Every scene of `cases/extremes/`, with its RK4 steps.
///
/// ```text
/// scan (examples/extremes_rk4_scan.rs): RK4 at the 1–2–5 series from t_end/10 down
/// rk4_beyond  the smallest step of the scan that was stopped (Rk4Unstable, NonFiniteState) while every
///             larger one was too, chosen so that the stop comes within the quick budget
/// rk4_inside  one series value below the largest step that ran to t_end and met its promise;
///             where no step up to 2e6 steps ran to t_end (lubricated_clearance_1um,
///             lubricated_viscosity_10, lubricated_eccentricity_0.999) the series value below
///             the largest step that was not stopped within 2e6 steps: RK4 at its stable step
///             does not fit the budget there, and the run ends with too many steps
/// ```
/// Since RK4's stability check confirms a suspect step by the eigenvalues of ∂f/∂y (it no
/// longer stops a stable run), three beyond steps were scanned again and raised to the next
/// stopped value: lubricated_speed_2000rpm 2e-6 → 5e-6, lubricated_clearance_1mm 2e-5 → 5e-5,
/// lubricated_viscosity_10 1e-7 → 2e-7 (the old steps ran to t_end; at 2e-6 and 2e-5 within
/// RK4's promise). The inside steps were kept: each still runs and agrees.
pub fn catalogue() -> Vec<ExtremeScene> {
    let one_rev = Some(1.0);
    let mut v = Vec::new();
    let mut add = |stem: &'static str,
                   stresses: &'static str,
                   c: Corner,
                   notes: &[&str],
                   rk4_inside: f64,
                   rk4_beyond: f64| {
        v.push(ExtremeScene {
            stem,
            stresses,
            scene: corner_scene(stem, stresses, c, notes),
            rk4_inside,
            rk4_beyond,
        });
    };
    add(
        "dry_clearance_1nm",
        "a clearance of 1e-9 m, the lower end of '1e-6 mm'",
        Corner {
            clearance: Some(1e-9),
            revolutions: one_rev,
            ..Default::default()
        },
        &[
            "clearance c = 1e-9 m (R_J = R_B - 1e-9): the journal sits in contact all the time, \
             penetrating ~1e5 c; its position relative to the bearing is ~1e-8 of the body \
             coordinates, near the resolution of double precision.",
            "one crank revolution (0.4 s); errors are measured over the first half revolution.",
        ],
        1e-3,
        5e-3,
    );
    add(
        "dry_clearance_1um",
        "a clearance of 1e-6 m",
        Corner {
            clearance: Some(1e-6),
            revolutions: one_rev,
            ..Default::default()
        },
        &["clearance c = 1e-6 m; one crank revolution (0.4 s)."],
        1e-3,
        5e-3,
    );
    add(
        "dry_clearance_1mm",
        "a clearance of 1e-3 m",
        Corner {
            clearance: Some(1e-3),
            revolutions: one_rev,
            ..Default::default()
        },
        &["clearance c = 1e-3 m: long free flights and hard impacts; one crank revolution."],
        5e-4,
        2e-3,
    );
    add(
        "lubricated_clearance_1um",
        "a lubricated clearance of 1e-6 m: a film 1e6 times stiffer than at 0.1 mm",
        Corner {
            lubricated: true,
            clearance: Some(1e-6),
            t_end: Some(0.1),
            solver: Some((Some(Method::Rodas5p), 1e-10)),
            formulation: Some(FormulationName::LagrangeBaumgarte),
            ..Default::default()
        },
        &[
            "clearance c = 1e-6 m with the film of cases/press: the squeeze damping grows as \
             1/c^3 (~2e13 N s/m) and the journal stays within 4e-5 c of the centre, where the \
             film force turns with e/|e|: explicit methods need steps below 1e-11 s (RK4 \
             diverges at every step down to 2e-12 s).",
            "t_end = 0.1 s (a quarter revolution): long enough for the load to swing, short \
             enough for the stiff methods' references.",
            "solver: rodas5p at rtol 1e-10 (the default run): the driver's torque is the \
             multiplier of a film 1e6 times stiffer than the press's, so its power amplifies \
             any state error; bdf's dense output misplaces it by 3e-2 J at every rtol, rodas5p \
             at 1e-10 closes the balance to its quadrature error (BENCHMARKS.md, \"Energy \
             balance of every case\").",
            "formulation: lagrange_baumgarte, not the default auto (which takes minimal here, a \
             tree): in joint coordinates the crank carries the journal across this film at a \
             fixed state, so f depends stiffly on t right beside the turn of the film's \
             direction at e = 0; rodas5p at rtol 1e-10 stalls before t = 4e-5 s, and bdf at \
             1e-10 ends 0.26 J off its balance (lagrange_baumgarte: 0.04 J). Under \
             lagrange_baumgarte rodas5p closes it to -8.3e-4 J (BENCHMARKS.md, \"The minimal \
             formulation and auto\").",
        ],
        1e-12,
        1e-9,
    );
    add(
        "lubricated_clearance_1mm",
        "a lubricated clearance of 1e-3 m: a film too weak to keep the journal off the bearing",
        Corner {
            lubricated: true,
            clearance: Some(1e-3),
            revolutions: one_rev,
            ..Default::default()
        },
        &["clearance c = 1e-3 m with the film of cases/press; one crank revolution."],
        5e-6,
        5e-5,
    );
    add(
        "dry_stiffness_1e6",
        "a contact stiffness of 1e6 N/m^1.5",
        Corner {
            k: Some(1e6),
            revolutions: one_rev,
            ..Default::default()
        },
        &[
            "K = 1e6 N/m^1.5, 2.34e4 times softer than the paper's: the journal sinks ~300 c \
             (3 cm) into the 5 cm bearing, which is not physical but must still integrate.",
        ],
        2e-2,
        1e-1,
    );
    add(
        "dry_stiffness_1e14",
        "a contact stiffness of 1e14 N/m^1.5",
        Corner {
            k: Some(1e14),
            t_end: Some(0.02),
            ..Default::default()
        },
        &[
            "K = 1e14 N/m^1.5, 4300 times stiffer than the paper's: 4 impacts in 0.02 s.",
            "t_end = 0.02 s (1/20 revolution): with this hard contact the press is chaotic \
             (docs/model.md §9) on a short time scale, and converged runs agree closely enough \
             to check the methods only over a short run (BENCHMARKS.md, Extremes).",
        ],
        2e-5,
        2e-4,
    );
    add(
        "dry_speed_1rpm",
        "a crank speed of 1 rpm",
        Corner {
            rpm: Some(1.0),
            t_end: Some(1.0),
            ..Default::default()
        },
        &[
            "1 rpm: a revolution lasts 60 s. t_end = 1 s (1/60 revolution): the crank hardly \
             moves, gravity drops the journal onto the bearing and it bounces (hundreds of \
             located contact events); a longer run adds more of the same at 60 times the cost.",
        ],
        1e-3,
        5e-3,
    );
    add(
        "dry_speed_2000rpm",
        "a crank speed of 2000 rpm",
        Corner {
            rpm: Some(2000.0),
            revolutions: one_rev,
            solver: Some((None, 1e-10)),
            ..Default::default()
        },
        &[
            "2000 rpm: slider inertia forces ~2 MN, penetration ~30 c; one revolution \
             (0.03 s).",
            TIGHT_NOTE,
        ],
        5e-4,
        2e-3,
    );
    add(
        "lubricated_speed_2000rpm",
        "a lubricated joint at 2000 rpm",
        Corner {
            lubricated: true,
            rpm: Some(2000.0),
            revolutions: Some(2.0),
            solver: Some((None, 1e-10)),
            ..Default::default()
        },
        &[
            "2000 rpm with the film of cases/press: ε up to 0.94; two revolutions (0.06 s).",
            TIGHT_NOTE,
        ],
        5e-7,
        5e-6,
    );
    add(
        "lubricated_viscosity_1e-4",
        "a film of viscosity 1e-4 Pa s",
        Corner {
            lubricated: true,
            viscosity: Some(1e-4),
            revolutions: one_rev,
            ..Default::default()
        },
        &[
            "viscosity 1e-4 Pa s, 4000 times thinner than the paper's oil: the film cannot \
             carry the load and the journal touches the bearing; one crank revolution.",
        ],
        2e-5,
        1e-4,
    );
    add(
        "lubricated_viscosity_10",
        "a film of viscosity 10 Pa s",
        Corner {
            lubricated: true,
            viscosity: Some(10.0),
            revolutions: one_rev,
            solver: Some((None, 1e-11)),
            ..Default::default()
        },
        &[
            "viscosity 10 Pa s, 25 times the paper's oil: ε stays below 0.02, and the squeeze \
             damping makes the problem 25 times stiffer; one crank revolution.",
            "solver: rtol 1e-11 (the default run: at the press's rtol 1e-8 the energy balance \
             is integration error, BENCHMARKS.md \"Energy balance of every case\"; under the \
             default formulation, auto (minimal here), bdf at rtol 1e-10 leaves -2.6e-5 J of a \
             driver work of 0.029 J, at 1e-11 4.5e-7 J; lagrange_baumgarte closes to -3.6e-7 J \
             at 1e-10, BENCHMARKS.md \"The minimal formulation and auto\").",
        ],
        2e-8,
        2e-7,
    );
    add(
        "lubricated_eccentricity_0.999",
        "a film loaded to ε ≈ 0.999",
        Corner {
            lubricated: true,
            viscosity: Some(0.065),
            eps_cap: Some(0.9999),
            revolutions: one_rev,
            solver: Some((None, 1e-10)),
            ..Default::default()
        },
        &[
            "viscosity 0.065 Pa s and eps_cap = 0.9999 (the default cap 0.99 would hold the \
             film force at ε = 0.99): the load drives the journal to ε_max = 0.99925 without \
             contact, where (1 - ε^2)^(-3/2) = 1.1e4; one crank revolution.",
            TIGHT_NOTE,
        ],
        2e-8,
        5e-6,
    );
    add(
        "dry_friction_0",
        "frictionless contact",
        Corner {
            mu: Some(0.0),
            revolutions: one_rev,
            ..Default::default()
        },
        &["friction coefficient 0 (no friction code runs); one crank revolution."],
        1e-3,
        5e-3,
    );
    add(
        "dry_friction_0.5",
        "a friction coefficient of 0.5",
        Corner {
            mu: Some(0.5),
            revolutions: one_rev,
            ..Default::default()
        },
        &["friction coefficient 0.5, 50 times the paper's; one crank revolution."],
        5e-4,
        2e-3,
    );
    v
}
