//! One right-hand-side evaluation of the dry and the lubricated press (150 rpm, c = 0.1 mm),
//! at the state of largest penetration of a DOP853 run (in contact; for the lubricated joint
//! the most loaded film) and at the state of smallest penetration (free flight).
//!
//! ```text
//! f(t, y) = (q̇, q̈),  q̈ from the Schur complement of the KKT system (crates/model)
//! ```
//! Also the mechanism's Jacobian ∂f/∂y at the contact state (what Rodas5P and BDF call), and
//! group `formulation`: the right-hand side and the Jacobian of each formulation
//! (docs/model.md §12) on the dry press at its contact state and on IFToMM A02 (N = 1, 40) and
//! Andrews' mechanism at their initial states (`minimal` with its loop closures on the last
//! three): the Jacobian's cost in right-hand sides is the ratio of the two.

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use faer::Mat;
use lash_benches::{contact_and_free_states, press};
use lash_solver::OdeSystem;
use std::hint::black_box;
use std::time::Duration;

fn rhs(c: &mut Criterion) {
    let mut group = c.benchmark_group("rhs");
    group.measurement_time(Duration::from_secs(2));
    group.warm_up_time(Duration::from_millis(500));
    for stem in ["dry_150rpm_c0.1", "lubricated_150rpm_c0.1"] {
        let m = press(stem, 2.0);
        let (contact, free) = contact_and_free_states(&m);
        for (label, s) in [("contact", contact), ("free", free)] {
            let mut dy = vec![0.0; m.dim()];
            group.bench_function(format!("{stem}/{label}"), |b| {
                b.iter(|| m.rhs(black_box(s.t), black_box(&s.y), black_box(&mut dy)))
            });
        }
    }
    group.finish();
}

fn jacobian(c: &mut Criterion) {
    let mut group = c.benchmark_group("jacobian");
    group.measurement_time(Duration::from_secs(2));
    group.warm_up_time(Duration::from_millis(500));
    for stem in ["dry_150rpm_c0.1", "lubricated_150rpm_c0.1"] {
        let m = press(stem, 2.0);
        let (contact, _) = contact_and_free_states(&m);
        let n = m.dim();
        let mut jac = Mat::<f64>::zeros(n, n);
        group.bench_function(format!("{stem}/contact"), |b| {
            b.iter(|| m.jacobian(black_box(contact.t), black_box(&contact.y), jac.as_mut()))
        });
    }
    group.finish();
}

fn formulation(c: &mut Criterion) {
    use lash_model::{iftomm::n_four_bar, FormulationName, Mechanism};
    let mut group = c.benchmark_group("formulation");
    group.measurement_time(Duration::from_secs(2));
    group.warm_up_time(Duration::from_millis(500));
    let dry = press("dry_150rpm_c0.1", 2.0);
    let (contact, _) = contact_and_free_states(&dry);
    let mut cases = vec![(
        "dry_press",
        dry.scene().clone(),
        contact.t,
        contact.y.clone(),
    )];
    for n in [1, 40] {
        let scene = n_four_bar(n, 20.0).0;
        let y0 = Mechanism::from_scene(&scene).unwrap().initial_state();
        cases.push((if n == 1 { "a02_n1" } else { "a02_n40" }, scene, 0.0, y0));
    }
    let andrews = lash_model::Scene::from_path(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../cases/andrews/andrews.json"
    ))
    .unwrap();
    let y0 = Mechanism::from_scene(&andrews).unwrap().initial_state();
    cases.push(("andrews", andrews, 0.0, y0));
    for (name, scene, t, y) in cases {
        for f in FormulationName::ALL {
            let mut s = scene.clone();
            s.formulation = f;
            let Ok(m) = Mechanism::from_scene(&s) else {
                continue;
            };
            // The same state in the formulation's coordinates (minimal: joint coordinates).
            let y = m.state_of_absolute(&y);
            let n = m.dim();
            let mut dy = vec![0.0; n];
            let mut jac = Mat::<f64>::zeros(n, n);
            group.bench_function(format!("{name}/{f}/rhs"), |b| {
                b.iter(|| m.rhs(black_box(t), black_box(&y), black_box(&mut dy)))
            });
            group.bench_function(format!("{name}/{f}/jacobian"), |b| {
                b.iter(|| m.jacobian(black_box(t), black_box(&y), jac.as_mut()))
            });
        }
    }
    group.finish();
}

/// A chain of `n` uniform links (1 m, 1 kg), the first pinned to the ground, each pinned to
/// the one before, released from the horizontal under gravity: a tree of n degrees of
/// freedom.
fn chain(n: usize) -> lash_model::Scene {
    let bodies: Vec<String> = (0..n)
        .map(|i| {
            format!(
                r#"{{"name": "l{i}", "mass": 1.0, "inertia": 0.0833333333333333,
                "position": [{}, 0.0], "points": {{"O": [-0.5, 0.0], "P": [0.5, 0.0]}}}}"#,
                i as f64 + 0.5
            )
        })
        .collect();
    let joints: Vec<String> = (0..n)
        .map(|i| {
            let b = if i == 0 {
                r#"{"body": "ground", "at": [0.0, 0.0]}"#.to_string()
            } else {
                format!(r#"{{"body": "l{}", "point": "P"}}"#, i - 1)
            };
            format!(
                r#"{{"type": "revolute", "name": "j{i}", "a": {{"body": "l{i}", "point": "O"}},
                "b": {b}}}"#
            )
        })
        .collect();
    let text = format!(
        r#"{{"bodies": [{}], "joints": [{}], "gravity": [0.0, -9.81], "t_end": 1.0}}"#,
        bodies.join(", "),
        joints.join(", ")
    );
    lash_model::Scene::from_json_str(&text).expect("a valid chain")
}

/// Group `formulation_chain`: one right-hand side of `minimal` (dense RᵀMR: O(n³)) and of
/// `augmented_lagrangian` (banded: O(n)) on a chain of n links (`chain`), at a moving state:
/// where they cross is where `auto` switches (docs/model.md §12).
fn formulation_chain(c: &mut Criterion) {
    use lash_model::{FormulationName, Mechanism};
    let mut group = c.benchmark_group("formulation_chain");
    group.measurement_time(Duration::from_secs(2));
    group.warm_up_time(Duration::from_millis(300));
    group.sample_size(20);
    for n in [4, 8, 16, 32, 64, 128, 300] {
        let scene = chain(n);
        for f in [
            FormulationName::Minimal,
            FormulationName::AugmentedLagrangian,
        ] {
            let mut s = scene.clone();
            s.formulation = f;
            let m = Mechanism::from_scene(&s).unwrap();
            let mut y = m.initial_state();
            let half = y.len() / 2;
            for (i, v) in y[half..].iter_mut().enumerate() {
                *v += 0.1 * (i as f64).sin();
            }
            let mut dy = vec![0.0; y.len()];
            group.bench_function(format!("{f}/{n}"), |b| {
                b.iter(|| m.rhs(black_box(0.0), black_box(&y), black_box(&mut dy)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, rhs, jacobian, formulation, formulation_chain);
criterion_main!(benches);
