//! `lash stiffness` and `lash poincare` through the built binary: a pendulum whose answers are
//! known in closed form (eigenvalues ±i√(m g d / I_O), RK4 limit 2√2/ω); the files of both
//! commands on the dry press; usage errors and solver failures. (The library functions the
//! commands are built on: `crates/validation/tests/diagnostics.rs`.)

mod common;
use common::{json, lash, ok};
use std::path::{Path, PathBuf};

use lash_model::cases::{press_scene, PressJoint};

fn csv(p: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    let head = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (head, rows)
}

fn col(head: &[String], rows: &[Vec<String>], name: &str) -> Vec<f64> {
    let k = head.iter().position(|h| h == name).unwrap();
    rows.iter().map(|r| r[k].parse::<f64>().unwrap()).collect()
}

// Pendulum: a body of mass m = 1 kg, I_c = 1e-4 kg·m², hanging d = 0.01 m below an ideal pin.
const M: f64 = 1.0;
const IC: f64 = 1e-4;
const D: f64 = 0.01;
const G: f64 = 9.81;
const THETA0: f64 = 1e-4;
const T_END: f64 = 128.0;

/// ω = √(m g d / I_O), I_O = I_c + m d².
fn omega() -> f64 {
    (M * G * D / (IC + M * D * D)).sqrt()
}

fn pendulum(dir: &Path) -> PathBuf {
    let (s, c) = THETA0.sin_cos();
    let scene = serde_json::json!({
        "description": "pendulum on an ideal pin, small amplitude: λ = ±i√(m g d / I_O)",
        "bodies": [{"name": "bob", "mass": M, "inertia": IC, "points": {"O": [0.0, D]},
                    "position": [D * s, -D * c], "angle": THETA0}],
        "joints": [{"type": "revolute", "name": "pivot", "a": {"body": "bob", "point": "O"},
                    "b": {"body": "ground", "at": [0.0, 0.0]}}],
        "gravity": [0.0, -G],
        "t_end": T_END,
        // The absolute coordinates these tests were written for: RK4's growth |R(iωh)|^n
        // (joint coordinates keep sin θ bounded and do not overflow).
        "formulation": "lagrange_baumgarte"
    });
    let p = dir.join("pendulum.json");
    std::fs::write(&p, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    p
}

/// The pendulum's Jacobian has λ = ±i ω √cos θ on its constraint manifold (θ̈ = −ω² sin θ
/// linearised at θ), the Baumgarte modes −α ± √(α² − β²) = −5 (double, twice) across it, so
/// the dominant pair along a swing of amplitude θ0 = 1e-4 has |λ| ∈ [ω(1 − θ0²/4), ω]: to
/// 2.5e-9. Tolerance 1e-8 relative on top: the model's Jacobian differences the constraint
/// geometry with steps 1e-8·max(|q|, 1), whose rounding error is ε/1e-8 ≈ 1e-8 relative
/// (it also bounds Re λ of the pair). The predicted RK4 limit is r(±π/2)/ω = 2√2/ω.
///
/// The measured limit: below 2√2/ω nothing grows (|R(iy)|² = 1 − y⁶/72 + y⁸/576 < 1, and the
/// pendulum softens with amplitude), so the unstable end lies above the prediction. A step
/// h*(1 + δ) is caught once φ̇ (amplitude ω θ0 = 2.2e-3 rad/s) exceeds 10 × max ‖y‖∞ of the
/// reference run (|y| = d = 0.01 m): a growth by 45 = |R|^N over N = T/h* ≈ 1002 steps, so
/// δ ≈ ln 45/(N κ) with κ = d ln|R|/d ln h = 7.11 on the imaginary axis; the stable end lies at
/// most 2 ln 45/(N κ) + 1e-4 (the bisection's width) ≈ 1.2e-3 above the prediction.
#[test]
fn stiffness_of_a_pendulum_matches_its_closed_form() {
    let d = tempfile::tempdir().unwrap();
    let case = pendulum(d.path());
    let out = ok(
        &[
            "stiffness",
            case.to_str().unwrap(),
            "--samples",
            "200",
            "--out",
            "st",
        ],
        d.path(),
    );
    assert!(out.contains("verdict: explicit"), "{out}");
    let w = omega();
    let o = d.path().join("st");
    let (head, rows) = csv(&o.join("stiffness.csv"));
    assert_eq!(
        head.join(","),
        "t,crank_angle,lambda_re,lambda_im,lambda_abs,spectral_radius,stiffness_ratio,\
         rk4_h_max,limiting_re,limiting_im,n_unstable"
    );
    assert_eq!(rows.len(), 200);
    let tol = 1e-8;
    let lo = 1.0 - THETA0 * THETA0 / 4.0 - tol;
    for (k, ((&a, &re), &im)) in col(&head, &rows, "lambda_abs")
        .iter()
        .zip(&col(&head, &rows, "lambda_re"))
        .zip(&col(&head, &rows, "lambda_im"))
        .enumerate()
    {
        assert!(
            (lo..=1.0 + tol).contains(&(a / w)),
            "sample {k}: |λ| = {a}, ω = {w}"
        );
        assert!(
            re.abs() <= tol * w && im > 0.0,
            "sample {k}: λ = {re} + {im}i"
        );
    }
    let h_pred = 8f64.sqrt() / w;
    for (k, h) in col(&head, &rows, "rk4_h_max").iter().enumerate() {
        assert!(
            (h / h_pred - 1.0).abs() <= THETA0 * THETA0 / 4.0 + 2.0 * tol,
            "sample {k}: {h} vs 2√2/ω = {h_pred}"
        );
    }
    assert!(col(&head, &rows, "n_unstable").iter().all(|&n| n == 0.0));
    let s = json(&o.join("stiffness.json"));
    let pred = s["rk4_limit_predicted"]["value"].as_f64().unwrap();
    assert!((pred / h_pred - 1.0).abs() <= THETA0 * THETA0 / 4.0 + 2.0 * tol);
    let p05 = s["rk4_limit_predicted_p05"].as_f64().unwrap();
    assert!((p05 / h_pred - 1.0).abs() <= THETA0 * THETA0 / 4.0 + 2.0 * tol);
    let m = &s["rk4_limit_measured"];
    let (hs, hu) = (
        m["h_stable"].as_f64().unwrap(),
        m["h_unstable"].as_f64().unwrap(),
    );
    let n_steps = T_END / h_pred;
    let bound = 2.0 * 45f64.ln() / (n_steps * 7.11) + 1e-4;
    assert!(
        hu > h_pred,
        "flagged unstable below the limit: {hu} < {h_pred}"
    );
    assert!(
        hs / h_pred - 1.0 <= bound,
        "δ = {:.3e} > {bound:.3e}",
        hs / h_pred - 1.0
    );
    assert!(hu / hs <= 1.0 + 1e-4 + 1e-12);
    assert_eq!(s["verdict"]["family"], "explicit");
    assert_eq!(s["jacobian"], "analytic");
    assert_eq!(s["samples"], 200);
    for f in ["stiffness.png", "stiffness.svg", "stiffness.md"] {
        assert!(o.join(f).is_file(), "{f}");
    }
    let md = std::fs::read_to_string(o.join("stiffness.md")).unwrap();
    assert!(md.contains("**Verdict: explicit.**"), "{md}");
}

/// A dry press over a few revolutions: every file, finite numbers, one section point per
/// revolution, one Lyapunov row per renormalisation; and `lash stiffness --no-measure` on the
/// same case.
#[test]
fn poincare_and_stiffness_commands_write_their_files() {
    let d = tempfile::tempdir().unwrap();
    let mut s = press_scene(PressJoint::Dry, 150.0, 1e-4);
    s.revolutions = Some(1.0);
    let case = d.path().join("dry.json");
    std::fs::write(&case, s.to_json_pretty()).unwrap();
    let out = ok(
        &[
            "poincare",
            case.to_str().unwrap(),
            "--revolutions",
            "4",
            "--renorm-per-rev",
            "5",
            "--out",
            "pc",
        ],
        d.path(),
    );
    assert!(out.contains("Lyapunov: λ = "), "{out}");
    let o = d.path().join("pc");
    for f in [
        "poincare.csv",
        "poincare.png",
        "poincare.svg",
        "poincare_eps.png",
        "lyapunov.csv",
        "lyapunov.png",
        "poincare.md",
        "poincare.json",
    ] {
        assert!(o.join(f).is_file(), "{f}");
    }
    let (head, rows) = csv(&o.join("poincare.csv"));
    assert_eq!(
        head.join(","),
        "revolution,t,crank_angle,ex_over_c,ey_over_c,eps"
    );
    assert_eq!(rows.len(), 5);
    let t = col(&head, &rows, "t");
    for (j, tj) in t.iter().enumerate() {
        assert!((tj - 0.4 * j as f64).abs() < 1e-12, "{tj}");
    }
    // The journal starts centred (e = 0), and |e|/c = hypot(e_x, e_y)/c.
    let (ex, ey, eps) = (
        col(&head, &rows, "ex_over_c"),
        col(&head, &rows, "ey_over_c"),
        col(&head, &rows, "eps"),
    );
    assert_eq!((ex[0], ey[0], eps[0]), (0.0, 0.0, 0.0));
    for j in 0..5 {
        assert!((ex[j].hypot(ey[j]) - eps[j]).abs() < 1e-12);
    }
    let (lh, lr) = csv(&o.join("lyapunov.csv"));
    assert_eq!(lh.join(","), "k,t,revolution,log_growth,running");
    assert_eq!(lr.len(), 20);
    let run = col(&lh, &lr, "running");
    let g = col(&lh, &lr, "log_growth");
    assert!(run.iter().chain(&g).all(|v| v.is_finite()));
    // running[k] = Σ g / (t_k − t0).
    let tk = col(&lh, &lr, "t");
    let sum: f64 = g.iter().sum();
    assert!((run[19] - sum / tk[19]).abs() < 1e-9 * run[19].abs().max(1.0));
    let j = json(&o.join("poincare.json"));
    let l = &j["lyapunov"];
    for k in [
        "exponent",
        "std_error",
        "exponent_running",
        "running_spread",
    ] {
        assert!(l[k].as_f64().unwrap().is_finite(), "{k}");
    }
    assert_eq!(j["revolutions"], 4);
    assert_eq!(j["rtol"], 1e-11, "Benettin's default tolerance");
    assert!((j["renorm_interval"].as_f64().unwrap() - 0.08).abs() < 1e-15);
    // Late half: revolutions 2..4 of the section.
    let late_max = eps[2..].iter().cloned().fold(0.0, f64::max);
    assert_eq!(j["section_eps_max_late"].as_f64().unwrap(), late_max);

    let out = ok(
        &[
            "stiffness",
            case.to_str().unwrap(),
            "--samples",
            "50",
            "--no-measure",
            "--out",
            "st",
        ],
        d.path(),
    );
    assert!(
        out.contains("measured RK4 limit: not measured (measure off)"),
        "{out}"
    );
    let st = json(&d.path().join("st/stiffness.json"));
    assert!(st["rk4_limit_measured"].is_null());
    let (sh, sr) = csv(&d.path().join("st/stiffness.csv"));
    assert_eq!(sr.len(), 50);
    // The press has a crank: the angle column is filled, θ = ω t (2π·150/60 rad/s).
    let th = col(&sh, &sr, "crank_angle");
    let ts = col(&sh, &sr, "t");
    for (a, t) in th.iter().zip(&ts) {
        assert!(
            (a - 5.0 * std::f64::consts::PI * t).abs() < 1e-9,
            "{a} at {t}"
        );
    }
}

/// The punch press, whose crank a motor turns (no driver): `lash poincare` takes the section
/// where the crank angle completes each turn (φ = 2πk to the integration error, rtol 1e-11
/// on about 30 rad: 1e-6 rad leaves a wide margin) and reports the mean turn as T. T is
/// bounded by the motor's line T_s(1 − ω/ω_0): above the no-load 155 rpm its torque brakes and
/// the punch only takes energy, so T > 60/155 s; at 150 rpm it still gives 3000·5/155 =
/// 96.8 N m, 608 J a turn, more than the punch's 60 kN over 6 mm = 360 J, so T < 60/150 s.
/// `lash run --until-periodic` on the same scene ends at a full turn: crank_revolutions is the
/// whole number it reports.
#[test]
fn poincare_and_until_periodic_of_a_motor_driven_crank() {
    let d = tempfile::tempdir().unwrap();
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/press/punch_motor_150rpm_c0.1.json");
    let c = case.to_str().unwrap();
    let out = ok(
        &["poincare", c, "--revolutions", "4", "--out", "pc"],
        d.path(),
    );
    assert!(out.contains("Lyapunov: λ = "), "{out}");
    let (head, rows) = csv(&d.path().join("pc/poincare.csv"));
    assert_eq!(rows.len(), 5);
    let (t, phi) = (col(&head, &rows, "t"), col(&head, &rows, "crank_angle"));
    for (k, a) in phi.iter().enumerate() {
        assert!(
            (a - std::f64::consts::TAU * k as f64).abs() < 1e-6,
            "turn {k}: {a}"
        );
    }
    let j = json(&d.path().join("pc/poincare.json"));
    assert_eq!(j["section_on_crank_angle"], true);
    let period = j["period"].as_f64().unwrap();
    assert!((period - (t[4] - t[0]) / 4.0).abs() < 1e-15);
    assert!(60.0 / 155.0 < period && period < 60.0 / 150.0, "{period}");
    assert!((j["renorm_interval"].as_f64().unwrap() - period / 10.0).abs() < 1e-15);
    let md = std::fs::read_to_string(d.path().join("pc/poincare.md")).unwrap();
    assert!(md.contains("full turn of the crank angle"), "{md}");
    let out = ok(
        &[
            "run",
            c,
            "--until-periodic",
            "1e-2",
            "--max-revolutions",
            "3",
            "--out",
            "up",
        ],
        d.path(),
    );
    assert!(out.contains("until periodic"), "{out}");
    let s = json(&d.path().join("up/summary.json"));
    let k = s["until_periodic"]["revolutions"].as_u64().unwrap();
    assert!((2..=3).contains(&k), "{s}");
    let turns = s["crank_revolutions"].as_f64().unwrap();
    assert!((turns - k as f64).abs() < 1e-9, "{turns} turns, K = {k}");
}

/// Usage errors exit 2 and write nothing: a case without a crank, bad numbers.
#[test]
fn diagnostics_usage_errors() {
    let d = tempfile::tempdir().unwrap();
    let case = pendulum(d.path());
    let c = case.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["poincare", c, "--out", "x"],
            "needs a scene with a crank (",
        ),
        (
            vec!["poincare", "testset:hires", "--out", "x"],
            "needs a scene with a crank (",
        ),
        (
            vec!["poincare", c, "--revolutions", "0"],
            "must be a whole number >= 1",
        ),
        (
            vec!["poincare", c, "--perturbation", "2"],
            "perturbation must be in (0, 1)",
        ),
        (
            vec!["stiffness", c, "--samples", "1"],
            "samples must be a whole number >= 2",
        ),
        (vec!["stiffness", c, "--method", "rk4"], "needs --step"),
        (
            vec!["stiffness", "testset:hires", "--t-end", "1"],
            "--t-end does not apply",
        ),
    ] {
        let o = lash(&args, d.path());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
    assert!(!d.path().join("x").exists());
}

/// A solver failure exits 3 with the time and state and writes nothing: the pendulum's
/// reference run with RK4 at ω h = 11 (|R(11i)| ≈ 610 per step overflows within 128 s), and
/// the lubricated press's trajectories with RK4 at 1 ms, 200× its stability limit.
#[test]
fn diagnostics_solver_failures_exit_3() {
    let d = tempfile::tempdir().unwrap();
    let case = pendulum(d.path());
    let mut s = press_scene(PressJoint::Lubricated, 150.0, 1e-4);
    s.revolutions = Some(1.0);
    let lub = d.path().join("lub.json");
    std::fs::write(&lub, s.to_json_pretty()).unwrap();
    for args in [
        vec![
            "stiffness",
            case.to_str().unwrap(),
            "--method",
            "rk4",
            "--step",
            "0.5",
        ],
        vec![
            "poincare",
            lub.to_str().unwrap(),
            "--revolutions",
            "2",
            "--method",
            "rk4",
            "--step",
            "1e-3",
        ],
    ] {
        let mut a = args.clone();
        a.extend(["--out", "x"]);
        let o = lash(&a, d.path());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{args:?}: {err}");
        assert!(
            err.contains("solver failed") && err.contains("at t = "),
            "{err}"
        );
        assert!(!d.path().join("x").exists());
    }
}

/// `lash stiffness` and `lash run --method rk4` apply one RK4 stability criterion (issue 22):
/// on the four-bar with a dry clearance, the run accepts the step stiffness measured stable and
/// stops at the step it measured unstable with the run's own "beyond its stability limit".
/// (Before, the measurement left the run's check out and called 4.87e-4 s stable, while the
/// run failed from 3.25e-4 s.)
#[test]
fn stiffness_and_run_give_one_rk4_limit() {
    let d = tempfile::tempdir().unwrap();
    // The case as shipped: its formulation is `auto`. `lash run --method rk4` of an `auto`
    // scene runs lagrange_baumgarte (the paper's method), and `lash stiffness` analyses that
    // formulation too, so that both give one limit.
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../cases/examples/fourbar_clearance.json");
    let scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(src).unwrap()).unwrap();
    assert!(scene.get("formulation").is_none(), "{scene}");
    let case = d.path().join("fourbar_clearance.json");
    std::fs::write(&case, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    let case = case.to_str().unwrap();
    ok(
        &["stiffness", case, "--out", "st", "--samples", "50"],
        d.path(),
    );
    assert_eq!(
        json(&d.path().join("st/stiffness.json"))["formulation"],
        "lagrange_baumgarte"
    );
    let m = &json(&d.path().join("st/stiffness.json"))["rk4_limit_measured"];
    let (stable, unstable) = (
        m["h_stable"].as_f64().unwrap(),
        m["h_unstable"].as_f64().unwrap(),
    );
    assert!(unstable / stable <= 1.0 + 1.1e-4, "{m}");
    let step = |h: f64| format!("{h:e}");
    ok(
        &[
            "run",
            case,
            "--method",
            "rk4",
            "--step",
            &step(stable),
            "--out",
            "a",
        ],
        d.path(),
    );
    let o = lash(
        &[
            "run",
            case,
            "--method",
            "rk4",
            "--step",
            &step(unstable),
            "--out",
            "b",
        ],
        d.path(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains("beyond its stability limit"), "{err}");
}
