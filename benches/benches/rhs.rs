//! One right-hand-side evaluation of the dry and the lubricated press (150 rpm, c = 0.1 mm),
//! at the state of largest penetration of a DOP853 run (in contact; for the lubricated joint
//! the most loaded film) and at the state of smallest penetration (free flight).
//!
//! ```text
//! f(t, y) = (q̇, q̈),  q̈ from the Schur complement of the KKT system (crates/model)
//! ```
//! Also the mechanism's Jacobian ∂f/∂y at the contact state (what Rodas5P and BDF call), and
//! group `formulation`: the right-hand side and the Jacobian of each formulation
//! (docs/model.md §12) on the dry press at its contact state and on IFToMM A02 (N = 1, 40) at
//! its initial state (`minimal` refuses A02's loops): the Jacobian's cost in right-hand sides
//! is the ratio of the two.

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

criterion_group!(benches, rhs, jacobian, formulation);
criterion_main!(benches);
