//! Every class of scene error gives its documented message: the JSON path and the reason
//! (docs/scene-format.md, "Errors").
mod common;
use common::*;
use lash_model::scene::{MAX_MAGNITUDE, MIN_MAGNITUDE};
use lash_model::{Mechanism, Scene, SceneError};
use serde_json::json;

fn err(v: &serde_json::Value) -> SceneError {
    build(v).expect_err("the scene must be rejected")
}

fn invalid(v: &serde_json::Value) -> (String, String) {
    match err(v) {
        SceneError::Invalid { path, reason } => (path, reason),
        e => panic!("expected an Invalid error, got {e:?}"),
    }
}

fn schema(v: &serde_json::Value) -> (String, String) {
    match err(v) {
        SceneError::Schema { path, message } => (path, message),
        e => panic!("expected a Schema error, got {e:?}"),
    }
}

#[test]
fn the_unmodified_press_is_accepted() {
    build(&dry_press_value()).expect("the dry press is valid");
}

#[test]
fn json_syntax_error_names_line_and_column() {
    let e = Scene::from_json_str("{\n  \"bodies\": [\n").unwrap_err();
    assert_eq!(
        e,
        SceneError::Syntax {
            line: 3,
            column: 0,
            message: "EOF while parsing a list".into()
        }
    );
    assert_eq!(
        e.to_string(),
        "JSON syntax error at line 3, column 0: EOF while parsing a list"
    );
    // A number too large for f64 (the only way JSON can spell a non-finite number).
    let e = Scene::from_json_str("{\"bodies\": [], \"t_end\": 1e999}").unwrap_err();
    assert_eq!(
        e.to_string(),
        "JSON syntax error at line 1, column 29: number out of range"
    );
}

#[test]
fn unknown_fields_are_rejected_with_their_path() {
    let mut v = dry_press_value();
    v["gravityy"] = json!(1);
    let (p, m) = schema(&v);
    assert_eq!(p, "gravityy");
    assert!(
        m.starts_with("unknown field `gravityy`, expected one of"),
        "{m}"
    );

    let mut v = dry_press_value();
    v["joints"][4]["bearing"]["radiuss"] = json!(1);
    let (p, m) = schema(&v);
    assert_eq!(p, "joints[4].bearing.radiuss");
    assert!(
        m.starts_with("unknown field `radiuss`, expected one of `body`, `point`, `at`, `radius`"),
        "{m}"
    );

    let mut v = dry_press_value();
    v["joints"][4]["normal"]["kk"] = json!(1);
    let (p, m) = schema(&v);
    assert_eq!(p, "joints[4].normal.kk");
    assert!(m.starts_with("unknown field `kk`"), "{m}");

    let mut v = dry_press_value();
    v["bodies"][1]["pointz"] = json!(1);
    let (p, _) = schema(&v);
    assert_eq!(p, "bodies[1].pointz");

    let mut v = dry_press_value();
    v["joints"][4]["type"] = json!("clearence");
    let (p, m) = schema(&v);
    assert_eq!(p, "joints[4].type");
    assert!(m.starts_with("unknown joint type `clearence`"), "{m}");

    let mut v = dry_press_value();
    v["joints"][4]["friction"]["law"] = json!("viscous");
    let (p, m) = schema(&v);
    assert_eq!(p, "joints[4].friction.law");
    assert!(m.starts_with("unknown friction law `viscous`"), "{m}");

    let mut v = dry_press_value();
    v["joints"][4]["normal"]["c_max"] = json!("x");
    let (p, m) = schema(&v);
    assert_eq!(p, "joints[4].normal.c_max");
    assert!(
        m.starts_with("invalid type: string \"x\", expected f64"),
        "{m}"
    );
}

#[test]
fn a_joint_naming_a_missing_body_or_point() {
    let mut v = dry_press_value();
    v["joints"][2]["b"]["body"] = json!("rood");
    assert_eq!(
        err(&v).to_string(),
        "joints[2].b.body: no body named 'rood'"
    );
    let mut v = dry_press_value();
    v["joints"][2]["b"]["point"] = json!("C");
    assert_eq!(
        err(&v).to_string(),
        "joints[2].b.point: body 'rod' has no point named 'C'"
    );
    let mut v = dry_press_value();
    v["joints"][4]["journal"]["body"] = json!("conrod");
    assert_eq!(
        err(&v).to_string(),
        "joints[4].journal.body: no body named 'conrod'"
    );
    let mut v = dry_press_value();
    v["joints"][3]["point"] = json!("Z");
    assert_eq!(
        err(&v).to_string(),
        "joints[3].point: body 'slider' has no point named 'Z'"
    );
    let mut v = dry_press_value();
    v["roles"]["slider"] = json!("carriage");
    assert_eq!(
        err(&v).to_string(),
        "roles.slider: no body named 'carriage'"
    );
}

#[test]
fn mass_and_inertia_must_be_positive() {
    let mut v = dry_press_value();
    v["bodies"][1]["mass"] = json!(0.0);
    assert_eq!(
        err(&v).to_string(),
        "bodies[1].mass: mass must be > 0, got 0"
    );
    let mut v = dry_press_value();
    v["bodies"][2]["inertia"] = json!(-1.0);
    assert_eq!(
        err(&v).to_string(),
        "bodies[2].inertia: inertia must be > 0, got -1"
    );
}

#[test]
fn radii_and_clearance() {
    let mut v = dry_press_value();
    v["joints"][4]["bearing"]["radius"] = json!(0.0);
    assert_eq!(
        invalid(&v),
        (
            "joints[4].bearing.radius".into(),
            "bearing radius must be > 0, got 0".into()
        )
    );
    let mut v = dry_press_value();
    v["joints"][4]["journal"]["radius"] = json!(0.05);
    assert_eq!(
        err(&v).to_string(),
        "joints[4].journal.radius: clearance R_B − R_J = 0 m must be > 0 (bearing radius 0.05, journal radius 0.05)"
    );
    let mut v = dry_press_value();
    v["joints"][4]["journal"]["radius"] = json!(-0.01);
    let (p, r) = invalid(&v);
    assert_eq!(p, "joints[4].journal.radius");
    assert!(r.starts_with("clearance R_B − R_J = 0.060000000000000005 m must be smaller than the bearing radius 0.05 m"), "{r}");
}

#[test]
fn viscosity_must_not_be_negative() {
    let mut v = dry_press_value();
    v["joints"][4]["film"] = json!({"viscosity": -0.4, "length": 0.1});
    assert_eq!(
        err(&v).to_string(),
        "joints[4].film.viscosity: viscosity must be >= 0, got -0.4"
    );
    let mut v = dry_press_value();
    v["joints"][4]["film"] = json!({"viscosity": 0.4, "length": 0.1, "eps_cap": 1.0});
    assert_eq!(
        err(&v).to_string(),
        "joints[4].film.eps_cap: eps_cap must lie in (0, 1) or be null (no cap), got 1"
    );
    // null is no cap (docs/model.md §4); Ω₀ belongs to the mirrored models only.
    let mut v = dry_press_value();
    v["joints"][4]["film"] = json!({"viscosity": 0.4, "length": 0.1, "eps_cap": null});
    assert!(lash_model::Scene::from_json_str(&v.to_string()).is_ok());
    let mut v = dry_press_value();
    v["joints"][4]["film"] = json!({"viscosity": 0.4, "length": 0.1, "omega0": 0.01});
    assert!(err(&v)
        .to_string()
        .starts_with("joints[4].film.omega0: omega0 (the width of the smooth sign"));
    let mut v = dry_press_value();
    v["joints"][4]["film"] =
        json!({"model": "long_gumbel_mirrored", "viscosity": 0.4, "length": 0.1, "omega0": 0.0});
    assert!(err(&v).to_string().starts_with("joints[4].film.omega0:"));
}

#[test]
fn non_finite_numbers_are_rejected() {
    // JSON cannot spell NaN or infinity; scenes built in code can.
    let mut scene = Scene::from_json_str(&dry_press_value().to_string()).unwrap();
    scene.gravity[1] = f64::NAN;
    assert_eq!(
        Mechanism::from_scene(&scene).unwrap_err().to_string(),
        "gravity[1]: must be a finite number, got NaN"
    );
    let mut scene = Scene::from_json_str(&dry_press_value().to_string()).unwrap();
    scene.bodies[0]
        .points
        .insert("X".into(), [f64::INFINITY, 0.0]);
    assert_eq!(
        Mechanism::from_scene(&scene).unwrap_err().to_string(),
        "bodies[0].points.X[0]: must be a finite number, got inf"
    );
}

#[test]
fn redundant_constraints_are_named() {
    // A second slide on the slider repeats the first.
    let mut v = dry_press_value();
    let mut slide = v["joints"][3].clone();
    slide["name"] = json!("slide2");
    v["joints"].as_array_mut().unwrap().push(slide);
    match err(&v) {
        SceneError::Redundant { path, reason } => {
            assert_eq!(path, "joints[5]");
            assert!(
                reason.starts_with("equation 'across the line' of translational joint 'slide2' depends on the equations before it"),
                "{reason}"
            );
        }
        e => panic!("expected Redundant, got {e:?}"),
    }
    // A second driver on the prescribed crank.
    let mut v = dry_press_value();
    let mut drv = v["joints"][1].clone();
    drv["name"] = json!("second_driver");
    v["joints"].as_array_mut().unwrap().push(drv);
    assert_eq!(
        err(&v).to_string(),
        "joints[5]: redundant or contradictory constraints: driver joint 'second_driver' acts only on the ground and on bodies whose motion is already prescribed by drivers and pins"
    );
}

#[test]
fn an_assembly_that_cannot_close_names_the_equation_and_residual() {
    // The slide 1 m above the crank pivot: a rod of 0.35 m cannot reach it.
    let mut v = dry_press_value();
    v["joints"][3]["origin"] = json!([0.0, 1.0]);
    match err(&v) {
        SceneError::Assembly { path, reason } => {
            assert!(path.starts_with("joints["), "{path}");
            assert!(reason.starts_with("positions: equation '"), "{reason}");
            assert!(reason.contains("has residual"), "{reason}");
            assert!(reason.ends_with("after 50 Newton iterations"), "{reason}");
        }
        e => panic!("expected Assembly, got {e:?}"),
    }
}

#[test]
fn other_documented_checks() {
    let mut v = dry_press_value();
    v["t_end"] = json!(1.0);
    assert_eq!(
        err(&v).to_string(),
        "revolutions: give either t_end or revolutions, not both"
    );
    let mut v = dry_press_value();
    v["joints"][1]["omega"] = json!(1.0);
    assert_eq!(
        err(&v).to_string(),
        "joints[1].rpm: give either omega (rad/s) or rpm, not both"
    );
    let mut v = dry_press_value();
    v["joints"][4]["normal"] = json!({"law": "flores", "k": 1e9, "restitution": 0.0});
    assert_eq!(
        err(&v).to_string(),
        "joints[4].normal.restitution: the coefficient of restitution must lie in (0, 1], got 0"
    );
    let mut v = dry_press_value();
    v["bodies"][1]["name"] = json!("ground");
    assert_eq!(
        err(&v).to_string(),
        "bodies[1].name: \"ground\" is reserved for the fixed frame"
    );
    let mut v = dry_press_value();
    v["roles"]["crank_driver"] = json!("slide");
    assert_eq!(
        err(&v).to_string(),
        "roles.crank_driver: joint 'slide' is a translational joint, not a driver"
    );
}

/// `roles.crank`: a body or a revolute joint, the same crank as `crank_driver` when both are
/// given; the crank angle of the body, of its pivot (φ_crank − φ_ground) and of the driver
/// agree exactly.
#[test]
fn the_crank_role_names_a_body_or_a_revolute_joint() {
    for (name, expect) in [
        (
            "slide",
            "roles.crank: joint 'slide' is a translational joint, not a revolute joint (a crank is a body or a revolute joint)",
        ),
        ("nope", "roles.crank: no body or revolute joint named 'nope'"),
        (
            "ground",
            "roles.crank: the ground does not turn: name a body or a revolute joint",
        ),
        (
            "rod",
            "roles.crank: 'rod' is not the body 'crank' that the crank driver 'crank_driver' turns against the ground (crank_driver implies the crank; give one)",
        ),
    ] {
        let mut v = dry_press_value();
        v["roles"]["crank"] = json!(name);
        assert_eq!(err(&v).to_string(), expect);
    }
    let driven = build(&dry_press_value()).unwrap();
    let y = driven.initial_state();
    let phi = driven.outputs(0.1, &y).crank_angle.unwrap();
    for crank in ["crank", "crank_pivot"] {
        let mut v = dry_press_value();
        v["roles"]["crank"] = json!(crank);
        let m = build(&v).unwrap();
        assert_eq!(m.outputs(0.1, &y).crank_angle, Some(phi), "{crank}");
        // Without the driver role the body alone is the crank (and the run needs t_end).
        v["roles"].as_object_mut().unwrap().remove("crank_driver");
        v.as_object_mut().unwrap().remove("revolutions");
        v["t_end"] = json!(0.8);
        let m = build(&v).unwrap();
        assert_eq!(m.outputs(0.1, &y).crank_angle, Some(phi), "{crank}");
        assert_eq!(m.roles().crank_driver, None);
    }
    // The crank against the rod: φ_crank − φ_rod.
    let mut v = dry_press_value();
    v["roles"].as_object_mut().unwrap().remove("crank_driver");
    v.as_object_mut().unwrap().remove("revolutions");
    v["t_end"] = json!(0.8);
    v["roles"]["crank"] = json!("crank_rod");
    let o = build(&v).unwrap().outputs(0.1, &y);
    let (k, r) = (o.bodies[0].theta, o.bodies[1].theta);
    assert_eq!(o.crank_angle, Some(k - r));
    assert_eq!(o.crank_rate, Some(o.bodies[0].omega - o.bodies[1].omega));
}

#[test]
fn output_lookups_name_the_unknown_body_or_point() {
    let m = build(&dry_press_value()).unwrap();
    let y = m.initial_state();
    assert_eq!(
        m.point_kinematics("wheel", "A", 0.0, &y)
            .unwrap_err()
            .to_string(),
        "unknown body 'wheel'"
    );
    assert_eq!(
        m.point_kinematics("rod", "Q", 0.0, &y)
            .unwrap_err()
            .to_string(),
        "unknown point 'Q' on body 'rod'"
    );
}

/// The paper's press with ideal joints (the rod pinned to the crank and to the slider).
fn ideal_press_value() -> serde_json::Value {
    use lash_model::cases::{press_scene, PressJoint};
    serde_json::from_str(&press_scene(PressJoint::Ideal, 150.0, 1e-4).to_json_pretty()).unwrap()
}

fn dynamics(v: &serde_json::Value) -> (String, String) {
    let e = err(v);
    let shown = e.to_string();
    match e {
        SceneError::Dynamics { path, reason } => {
            assert_eq!(
                shown,
                format!("{path}: the equations of motion fail at the initial state: {reason}")
            );
            (path, reason)
        }
        e => panic!("expected a Dynamics error, got {e:?}"),
    }
}

#[test]
fn magnitudes_outside_the_scene_range_are_rejected_with_their_path() {
    // An inertia of 1e-182 used to pass validation and fail at the first right-hand side (its
    // inverse times a squared lever overflows); now every number is 0 or within
    // [1e-150, 1e150], where squares and products of two scene values stay normal f64 numbers.
    for (ptr, path, value) in [
        ("/bodies/1/inertia", "bodies[1].inertia", 1e-182),
        ("/bodies/2/mass", "bodies[2].mass", 1e200),
        ("/bodies/2/position/0", "bodies[2].position[0]", -1e-151),
        ("/joints/4/normal/k", "joints[4].normal.k", 1.5e150),
        ("/gravity/1", "gravity[1]", -1e300),
    ] {
        let mut v = dry_press_value();
        *v.pointer_mut(ptr).unwrap() = json!(value);
        // As the scene parser reads it (serde_json's parser is not correctly rounded:
        // 1e-182 reads as 9.999999999999999e-183).
        let value: f64 = serde_json::from_str(&json!(value).to_string()).unwrap();
        assert_eq!(
            invalid(&v),
            (
                path.to_string(),
                format!(
                    "must be 0 or of magnitude between 1e-150 and 1e150 (squares and products \
                     of scene values must be normal f64 numbers), got {value:e}"
                )
            )
        );
    }
    // The ends of the range, and 0, are valid numbers.
    for value in [MAX_MAGNITUDE, -MAX_MAGNITUDE, MIN_MAGNITUDE, 0.0] {
        let mut v = dry_press_value();
        v["bodies"][2]["velocity"][1] = json!(value);
        Scene::from_json_str(&v.to_string())
            .unwrap()
            .validate()
            .unwrap_or_else(|e| panic!("{value:e}: {e}"));
    }
}

#[test]
fn a_radius_of_gyration_too_small_for_a_held_point_names_the_inertia() {
    // The rod (m = 412.53 kg) is held by the crank at its point A, |s'| = l/2 = 0.175 m. The
    // inverse mass seen at A has eigenvalues 1/m and 1/m + |s'|²/I: their ratio
    // 1 + m|s'|²/I must stay below 1e14 (1/PIVOT_TOL), i.e. I > m|s'|²/(1e14 − 1) = 1.263e-13.
    let limit = 412.53 * 0.175f64.powi(2) / (1e14 - 1.0);
    let mut v = dry_press_value();
    v["bodies"][1]["inertia"] = json!(0.99 * limit);
    let (path, reason) = dynamics(&v);
    assert_eq!(path, "bodies[1].inertia");
    let gyration = (0.99 * limit / 412.53f64).sqrt();
    assert!(
        reason.starts_with(&format!(
            "the radius of gyration √(I/m) = {gyration:e} m of body 'rod' (mass 4.1253e2 kg"
        )),
        "{reason}"
    );
    assert!(
        reason.contains("its point 'A' at 1.75e-1 m from the centre of mass that revolute joint 'crank_rod' holds"),
        "{reason}"
    );
    assert!(reason.contains("is 1.010e14 times 1/m"), "{reason}");
    v["bodies"][1]["inertia"] = json!(1.01 * limit);
    build(&v).expect("just inside the limit");
}

#[test]
fn a_constraint_system_singular_in_f64_names_the_joint_and_bodies() {
    // The ideal press's rod between the crank and a 2700 kg slider: at 1e-12 kg the pivot of the
    // rod–slider pin in Φ_q M⁻¹ Φ_qᵀ is about m_rod/m_slider = 4e-16 of its diagonal, below the
    // 1e-14 that f64 resolves; at 1e-8 kg (4e-12) it is solved.
    let mut v = ideal_press_value();
    v["bodies"][1]["mass"] = json!(1e-12);
    let (path, reason) = dynamics(&v);
    assert_eq!(path, "joints[4]");
    assert!(
        reason.starts_with(
            "Φ_q M⁻¹ Φ_qᵀ is singular in f64: equation 'x' of revolute joint 'rod_slider', \
             weighted by the inverse masses and inertias, is a combination of the equations \
             before it (Cholesky pivot d/S_jj = "
        ),
        "{reason}"
    );
    assert!(
        reason.ends_with(
            "it acts on body 'rod' (mass 1e-12 kg, inertia 4.21124375e0 kg·m²) and body \
             'slider' (mass 2.70071e3 kg, inertia 1e0 kg·m²): masses and inertias too far \
             apart to be solved together"
        ),
        "{reason}"
    );
    v["bodies"][1]["mass"] = json!(1e-8);
    build(&v).expect("a light rod that f64 still solves");
}

#[test]
fn forces_that_overflow_at_the_initial_state_name_the_joint() {
    // K = 1e150 N/m^1.5 and a journal held δ = 1e110 m into its bearing: K δ^1.5 = 1e315.
    // Each number is inside the range; their product is not. (A start in contact is stated
    // explicitly, and its depth stays below the journal radius, as the scene checks ask.)
    let mut v = dry_press_value();
    v["joints"][4]["normal"]["k"] = json!(1e150);
    v["joints"][4]["bearing"]["radius"] = json!(3e110);
    v["joints"][4]["journal"]["radius"] = json!(2e110);
    v["joints"][4]["initial_eccentricity"] = json!([2e110, 0.0]);
    v["joints"][4]["allow_initial_penetration"] = json!(true);
    let (path, reason) = dynamics(&v);
    assert_eq!(path, "joints[4]");
    assert!(
        reason.starts_with(
            "the forces of clearance joint 'rod_slider' are not finite: δ = 1e110 m, δ̇ = "
        ),
        "{reason}"
    );
    assert!(reason.contains("F_N = inf N"), "{reason}");
}

/// Names become trajectory.csv column prefixes: a comma, a quote or a control character is a
/// scene error at the name's JSON path.
#[test]
fn names_that_would_break_a_csv_header_are_rejected() {
    for (bad, shown) in [("a,b", "','"), ("a\"b", "'\"'"), ("a\nb", "'\\n'")] {
        let mut v: serde_json::Value = serde_json::from_str(
            &lash_model::cases::press_scene(lash_model::cases::PressJoint::Dry, 150.0, 1e-4)
                .to_json_pretty(),
        )
        .unwrap();
        v["bodies"][1]["name"] = serde_json::Value::String(bad.into());
        let e = lash_model::Scene::from_json_str(&v.to_string())
            .unwrap_err()
            .to_string();
        assert!(e.contains("bodies[1].name") && e.contains(shown), "{e}");
    }
}

/// The `solver` section (docs/scene-format.md, "Top level"): an adaptive method, rtol in the
/// solver's range [1e-14, 1), atol > 0; errors name `solver.FIELD`; unknown fields and
/// method names are schema errors with their path.
#[test]
fn the_solver_section_is_checked_field_by_field() {
    let mut v = dry_press_value();
    v["solver"] = json!({"method": "rodas5p", "rtol": 1e-10, "atol": 1e-12});
    build(&v).expect("a full solver section is valid");
    let s = Scene::from_json_str(&v.to_string()).unwrap();
    assert_eq!(s.solver.method, Some(lash_solver::Method::Rodas5p));
    assert_eq!((s.solver.rtol, s.solver.atol), (Some(1e-10), Some(1e-12)));
    v["solver"] = json!({"method": "rk4"});
    let (p, m) = invalid(&v);
    assert_eq!(p, "solver.method");
    assert!(m.contains("rk4 is a fixed-step method"), "{m}");
    v["solver"] = json!({"rtol": 1e-15});
    let (p, m) = invalid(&v);
    assert_eq!(p, "solver.rtol");
    assert!(m.contains("1e-14"), "{m}");
    v["solver"] = json!({"rtol": 1.0});
    assert_eq!(invalid(&v).0, "solver.rtol");
    v["solver"] = json!({"atol": 0.0});
    assert_eq!(invalid(&v).0, "solver.atol");
    v["solver"] = json!({"rtoll": 1e-9});
    assert_eq!(schema(&v).0, "solver.rtoll");
    v["solver"] = json!({"method": "radau"});
    assert_eq!(schema(&v).0, "solver.method");
}
