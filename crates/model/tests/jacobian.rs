//! The Jacobian ∂f/∂y that implicit methods use (central finite differences of the KKT
//! solution) against analytic derivatives of the contact, friction and film laws
//! (MODEL.md §3–§4) on a free journal in a ground bearing, where q̈ = force / mass.
use faer::Mat;
use lash_model::{Mechanism, Scene};
use lash_solver::OdeSystem;
use serde_json::json;

const MASS: f64 = 2.0;
const INERTIA: f64 = 0.1;
const RB: f64 = 0.010;
const RJ: f64 = 0.009;
const C: f64 = RB - RJ;

fn journal(
    normal: serde_json::Value,
    friction: serde_json::Value,
    film: Option<serde_json::Value>,
) -> Mechanism {
    let mut joint = json!({"type": "clearance", "name": "j",
        "bearing": {"body": "ground", "at": [0.0, 0.0], "radius": RB},
        "journal": {"body": "pin", "point": "c", "radius": RJ},
        "normal": normal, "friction": friction});
    if let Some(f) = film {
        joint["film"] = f;
    }
    let v = json!({
        "bodies": [{"name": "pin", "mass": MASS, "inertia": INERTIA, "points": {"c": [0.0, 0.0]}}],
        "joints": [joint],
        "t_end": 1.0
    });
    Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap()
}

fn jac(m: &Mechanism, y: &[f64]) -> Mat<f64> {
    let mut j = Mat::<f64>::zeros(6, 6);
    assert!(m.has_jacobian());
    m.jacobian(0.0, y, j.as_mut());
    // Upper blocks: ∂q̇/∂q = 0, ∂q̇/∂q̇ = I exactly.
    for r in 0..3 {
        for c in 0..6 {
            assert_eq!(j[(r, c)], if c == r + 3 { 1.0 } else { 0.0 });
        }
    }
    j
}

/// Compares the lower block with the expected rows (q̈ over y), relative to the row scale
/// (a row that is zero is compared with 1e-9 of the largest entry: rounding of the KKT solve).
fn check(j: &Mat<f64>, expect: [[f64; 6]; 3], tol: f64) {
    let global = expect.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    for r in 0..3 {
        let scale = expect[r]
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()))
            .max(1e-9 * global);
        for c in 0..6 {
            let d = (j[(r + 3, c)] - expect[r][c]).abs();
            assert!(
                d <= tol * scale,
                "∂q̈{r}/∂y{c}: FD {} vs analytic {} (row scale {scale:e})",
                j[(r + 3, c)],
                expect[r][c]
            );
        }
    }
}

#[test]
fn impact_law_derivatives() {
    let (k, cmax, dmax) = (1e10, 1e3, 1e-4);
    let m = journal(
        json!({"law": "impact", "k": k, "c_max": cmax, "d_max": dmax}),
        json!({"law": "none"}),
        None,
    );
    let delta = 5e-5;
    let e = C + delta;
    let vx = 0.1;
    let y = [e, 0.0, 0.3, vx, 0.0, 0.0];
    let s = delta / dmax;
    let cd = cmax * s * s * (3.0 - 2.0 * s);
    let cd_p = cmax * 6.0 * s * (1.0 - s) / dmax;
    let f_n = k * delta.powf(1.5) + cd * vx;
    let mut expect = [[0.0; 6]; 3];
    expect[0][0] = -(1.5 * k * delta.sqrt() + cd_p * vx) / MASS;
    expect[0][3] = -cd / MASS;
    expect[1][1] = -f_n / (MASS * e);
    check(&jac(&m, &y), expect, 1e-6);
}

#[test]
fn coulomb_friction_derivatives() {
    let (k, cmax, dmax, mu) = (1e10, 1e3, 1e-4, 0.2);
    let m = journal(
        json!({"law": "impact", "k": k, "c_max": cmax, "d_max": dmax}),
        json!({"law": "coulomb", "mu": mu, "v0": 1e-4, "v1": 2e-4}),
        None,
    );
    let delta = 5e-5;
    let e = C + delta;
    let (vx, vy) = (0.1, 0.05); // slip v_T = vy > v1: full friction, F_T = −μ F_N
    let y = [e, 0.0, 0.0, vx, vy, 0.0];
    let s = delta / dmax;
    let cd = cmax * s * s * (3.0 - 2.0 * s);
    let cd_p = cmax * 6.0 * s * (1.0 - s) / dmax;
    let f_n = k * delta.powf(1.5) + cd * vx;
    let f_t = -mu * f_n;
    let dfn_dx = 1.5 * k * delta.sqrt() + cd_p * vx;
    let dfn_dy = cd * vy / e; // through δ̇ = n·ė, ∂n_y/∂e_y = 1/|e|
    let mut expect = [[0.0; 6]; 3];
    // ẍ = (−F_N n_x + F_T t_x)/m, t_x = −n_y
    expect[0][0] = -dfn_dx / MASS;
    expect[0][1] = (-dfn_dy - f_t / e) / MASS;
    expect[0][3] = -cd / MASS;
    // ÿ = (−F_N n_y + F_T t_y)/m, t_y = n_x
    expect[1][0] = -mu * dfn_dx / MASS;
    expect[1][1] = (-f_n / e - mu * dfn_dy) / MASS;
    expect[1][3] = -mu * cd / MASS;
    // φ̈ = R_J F_T / I (arm R_J n)
    expect[2][0] = -RJ * mu * dfn_dx / INERTIA;
    expect[2][1] = -RJ * mu * dfn_dy / INERTIA;
    expect[2][3] = -RJ * mu * cd / INERTIA;
    check(&jac(&m, &y), expect, 1e-6);
}

#[test]
fn sommerfeld_film_derivatives() {
    let (mu, len) = (0.4, 0.02);
    let m = journal(
        json!({"law": "impact", "k": 1e10, "c_max": 0.0, "d_max": 1e-5}),
        json!({"law": "none"}),
        Some(json!({"model": "long_sommerfeld", "viscosity": mu, "length": len})),
    );
    let eps = 0.5;
    let e = eps * C;
    let vx = 0.01;
    let y = [e, 0.0, 0.0, vx, 0.0, 0.0];
    let s = 12.0 * std::f64::consts::PI * mu * len * RJ.powi(3) / (C * C);
    let one = 1.0 - eps * eps;
    let eps_dot = vx / C;
    let f_r = -s * eps_dot / one.powf(1.5);
    let dft_domega = s * eps / ((2.0 + eps * eps) * one.sqrt());
    let mut expect = [[0.0; 6]; 3];
    // ẍ = F_r/m: ∂/∂x through ε (∂ε/∂x = 1/c), ∂/∂ẋ through ε̇ (1/c).
    expect[0][0] = f_r * 3.0 * eps / one / C / MASS;
    expect[0][3] = -s / one.powf(1.5) / C / MASS;
    // ÿ = (F_r n_y + F_t t_y)/m with F_t = dF_t/dΩ · Ω, Ω = φ̇ − 2γ̇, γ̇ = ė_y/|e|.
    // ∂γ̇/∂e_y = −ė_x/|e|², so ∂Ω/∂y = 2 ẋ/|e|².
    expect[1][1] = (f_r / e + dft_domega * 2.0 * vx / (e * e)) / MASS;
    expect[1][4] = -2.0 / e * dft_domega / MASS;
    expect[1][5] = dft_domega / MASS;
    check(&jac(&m, &y), expect, 1e-6);
}
