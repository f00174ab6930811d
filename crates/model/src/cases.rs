//! Generators of the paper's press scenes (`cases/press/*.json`), so that the committed files
//! stay consistent: `cargo run -p lash-model --example write_press_cases -- cases/press`
//! rewrites them and a test checks the files against these functions.
//!
//! ```text
//! crank (prescribed: pinned at O = (0,0), φ = ω t) — rod (ideal pin at the crank tip)
//!   — slider (translational along +x through O); rod–slider: clearance joint
//!   (rod = journal, slider = bearing) or an ideal pin (ideal cases)
//! r = 0.015 m, l = 0.35 m, m = 453.87 / 412.53 / 2700.71 kg, I = m r²/12, m l²/12, 1 kg·m²
//! K = 2.34e10 N/m^1.5, c_max = 100 N·s/m, d_max = 1e-5 m, μ = 0.01, v₀ = 1e-4, v₁ = 2e-4 m/s
//! R_B = 0.05 m, R_J = R_B − c; film: long Gümbel, μ = 0.4 Pa·s, L = 0.1 m, ε_cap = 0.99
//! g = 9.81 m/s² along −y, α = β = 5 s⁻¹, θ(0) = 0, two crank revolutions
//! ```
//! Source: docs/model.md §5–§6 (Peng et al. 2025, §4 and Figure 3; assumed values marked there).

use std::collections::BTreeMap;

use crate::laws::FilmModel;
use crate::scene::{
    Attachment, Baumgarte, BodySpec, ClearanceEnd, ClearanceSpec, CoulombSpec, DriverSpec,
    FilmSpec, FrictionSpec, ImpactSpec, JointSpec, NormalSpec, RevoluteSpec, RoleNames, Scene,
    TranslationalSpec,
};

/// Crank radius r (m).
pub const CRANK_R: f64 = 0.015;
/// Rod length l (m).
pub const ROD_L: f64 = 0.35;
/// Crank mass (kg).
pub const CRANK_MASS: f64 = 453.87;
/// Rod mass (kg).
pub const ROD_MASS: f64 = 412.53;
/// Slider mass (kg).
pub const SLIDER_MASS: f64 = 2700.71;
/// Contact stiffness K (N/m^1.5).
pub const K_CONTACT: f64 = 2.34e10;
/// Bearing radius R_B (m) (assumed).
pub const BEARING_RADIUS: f64 = 0.05;

/// Which joint joins the rod and the slider.
///
/// ```text
/// Ideal       Φ = r_rod^B − r_slider^B = 0              (closed form of docs/model.md §5)
/// Dry         IMPACT contact + Coulomb friction         (docs/model.md §3)
/// Lubricated  long-bearing Gümbel film + dry contact    (docs/model.md §4)
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PressJoint {
    /// Ideal revolute joint (no clearance).
    Ideal,
    /// Dry clearance joint (IMPACT contact and Coulomb friction).
    Dry,
    /// Lubricated clearance joint (long-bearing Gümbel film, plus dry contact if δ > 0).
    Lubricated,
}

fn round12(x: f64) -> f64 {
    (x * 1e12).round() / 1e12
}

fn attach(body: &str, point: &str) -> Attachment {
    Attachment {
        body: body.into(),
        point: Some(point.into()),
        at: None,
    }
}

fn body(name: &str, mass: f64, inertia: f64, x: f64, points: &[(&str, [f64; 2])]) -> BodySpec {
    BodySpec {
        name: name.into(),
        mass,
        inertia,
        points: points
            .iter()
            .map(|(n, p)| (n.to_string(), *p))
            .collect::<BTreeMap<_, _>>(),
        position: [x, 0.0],
        angle: 0.0,
        velocity: [0.0, 0.0],
        angular_velocity: 0.0,
        initial_velocity: None,
    }
}

/// The press of docs/model.md §5–§6 at `rpm` with the rod–slider joint `joint` and radial clearance
/// `clearance` (m; ignored for [`PressJoint::Ideal`]).
pub fn press_scene(joint: PressJoint, rpm: f64, clearance: f64) -> Scene {
    let r = CRANK_R;
    let l = ROD_L;
    let crank_inertia = round12(CRANK_MASS * r * r / 12.0);
    let rod_inertia = round12(ROD_MASS * l * l / 12.0);
    let bodies = vec![
        body(
            "crank",
            CRANK_MASS,
            crank_inertia,
            r / 2.0,
            &[("O", [-r / 2.0, 0.0]), ("A", [r / 2.0, 0.0])],
        ),
        body(
            "rod",
            ROD_MASS,
            rod_inertia,
            r + l / 2.0,
            &[("A", [-l / 2.0, 0.0]), ("B", [l / 2.0, 0.0])],
        ),
        body(
            "slider",
            SLIDER_MASS,
            1.0,
            round12(r + l),
            &[("B", [0.0, 0.0])],
        ),
    ];
    let mut joints = vec![
        JointSpec::Revolute(RevoluteSpec {
            name: "crank_pivot".into(),
            a: attach("crank", "O"),
            b: Attachment {
                body: crate::GROUND.into(),
                point: None,
                at: Some([0.0, 0.0]),
            },
            initial_rate: None,
        }),
        JointSpec::Driver(DriverSpec {
            name: "crank_driver".into(),
            body: "crank".into(),
            theta0: 0.0,
            omega: None,
            rpm: Some(rpm),
        }),
        JointSpec::Revolute(RevoluteSpec {
            name: "crank_rod".into(),
            a: attach("crank", "A"),
            b: attach("rod", "A"),
            initial_rate: None,
        }),
        JointSpec::Translational(TranslationalSpec {
            name: "slide".into(),
            body: "slider".into(),
            point: "B".into(),
            origin: [0.0, 0.0],
            direction: [1.0, 0.0],
            angle: Some(0.0),
            initial_rate: None,
        }),
    ];
    let mut notes = vec![
        "Peng et al. 2025 (Lubricants 13(3) 124), slider-crank press of Figure 3; values of docs/model.md §6."
            .to_string(),
        "From the paper: r = 0.015 m, l = 0.35 m, masses 453.87 / 412.53 / 2700.71 kg.".into(),
        "Assumed: centres of mass at mid-length of crank and rod, slider at its pin; inertias crank m r^2/12 = 0.0085100625, rod m l^2/12 = 4.21124375, slider 1 kg m^2 (its rotation is locked).".into(),
        "Assumed: gravity 9.81 m/s^2 along -y (horizontal slide), Baumgarte alpha = beta = 5 1/s, theta(0) = 0, two crank revolutions.".into(),
    ];
    let description;
    let mut roles = RoleNames {
        slider: Some("slider".into()),
        crank_driver: Some("crank_driver".into()),
        clearance_joint: None,
        crank: None,
    };
    match joint {
        PressJoint::Ideal => {
            description = format!("Slider-crank press at {rpm} rpm with ideal joints (no clearance): the closed form of docs/model.md §5 holds.");
            joints.push(JointSpec::Revolute(RevoluteSpec {
                name: "rod_slider".into(),
                a: attach("rod", "B"),
                b: attach("slider", "B"),
                initial_rate: None,
            }));
        }
        PressJoint::Dry | PressJoint::Lubricated => {
            let lub = joint == PressJoint::Lubricated;
            description = format!(
                "Slider-crank press at {rpm} rpm with a {} revolute clearance joint (c = {} mm) between rod (journal) and slider (bearing).",
                if lub { "lubricated" } else { "dry" },
                round12(clearance * 1e3)
            );
            notes.push("From the paper: contact stiffness K = 2.34e10 N/m^1.5, friction coefficient 0.01, c_max = 0.1 N s/mm = 100 N s/m, d_max = 0.01 mm = 1e-5 m (ADAMS IMPACT).".into());
            notes.push("Assumed: friction thresholds v0 = 1e-4 m/s, v1 = 2e-4 m/s (Ambrosio); bearing radius R_B = 0.05 m, journal radius R_J = R_B - c; the journal starts centred (e = 0) in the ideally assembled mechanism.".into());
            if lub {
                notes.push("Assumed film: long-bearing Guembel model as the paper prints it (long_gumbel), viscosity 0.4 Pa s (ISO VG 460 at 40 C), bearing length L = 0.1 m, eps_cap = 0.99; dry contact is added whenever the journal penetrates.".into());
                notes.push("Caveat (docs/model.md §4): L = 0.1 m equals the bearing diameter (L/D = 1), where the infinitely-long-bearing model over-predicts the film force; the paper's model is kept as the default.".into());
            }
            roles.clearance_joint = Some("rod_slider".into());
            joints.push(JointSpec::Clearance(ClearanceSpec {
                name: "rod_slider".into(),
                bearing: ClearanceEnd {
                    body: "slider".into(),
                    point: Some("B".into()),
                    at: None,
                    radius: BEARING_RADIUS,
                },
                journal: ClearanceEnd {
                    body: "rod".into(),
                    point: Some("B".into()),
                    at: None,
                    radius: round12(BEARING_RADIUS - clearance),
                },
                normal: NormalSpec::Impact(ImpactSpec {
                    k: Some(K_CONTACT),
                    materials: None,
                    c_max: 100.0,
                    d_max: 1e-5,
                }),
                friction: FrictionSpec::Coulomb(CoulombSpec {
                    mu: 0.01,
                    v0: 1e-4,
                    v1: 2e-4,
                }),
                film: lub.then_some(FilmSpec {
                    model: FilmModel::LongGumbel,
                    viscosity: 0.4,
                    length: 0.1,
                    eps_cap: Some(0.99),
                    omega0: None,
                }),
                initial_eccentricity: [0.0, 0.0],
                initial_eccentricity_rate: [0.0, 0.0],
                allow_initial_penetration: false,
            }));
        }
    }
    Scene {
        description,
        notes,
        bodies,
        joints,
        forces: Vec::new(),
        gravity: [0.0, -9.81],
        baumgarte: Baumgarte {
            alpha: 5.0,
            beta: 5.0,
        },
        t_start: 0.0,
        t_end: None,
        revolutions: Some(2.0),
        roles,
        kink_events: None,
        formulation: Default::default(),
        augmented_lagrangian: Default::default(),
        solver: Default::default(),
        body_names: Default::default(),
    }
}

/// Every scene of `cases/press/`: (file stem, scene). 18 cases: dry and lubricated at 120, 150,
/// 180, 200 rpm with c = 0.1 mm; dry and lubricated at 150 rpm with c = 0.2, 0.3, 0.5 mm; ideal
/// at the four speeds.
pub fn press_catalogue() -> Vec<(String, Scene)> {
    let mut out = Vec::new();
    for (kind, name) in [
        (PressJoint::Dry, "dry"),
        (PressJoint::Lubricated, "lubricated"),
    ] {
        for rpm in [120.0, 150.0, 180.0, 200.0] {
            out.push((
                format!("{name}_{rpm}rpm_c0.1"),
                press_scene(kind, rpm, 1e-4),
            ));
        }
        for (c, label) in [(2e-4, "0.2"), (3e-4, "0.3"), (5e-4, "0.5")] {
            out.push((
                format!("{name}_150rpm_c{label}"),
                press_scene(kind, 150.0, c),
            ));
        }
    }
    for rpm in [120.0, 150.0, 180.0, 200.0] {
        out.push((
            format!("ideal_{rpm}rpm"),
            press_scene(PressJoint::Ideal, rpm, 0.0),
        ));
    }
    out
}
