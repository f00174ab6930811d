//! One right-hand-side evaluation of the dry and the lubricated press (150 rpm, c = 0.1 mm),
//! at the state of largest penetration of a DOP853 run (in contact; for the lubricated joint
//! the most loaded film) and at the state of smallest penetration (free flight).
//!
//! ```text
//! f(t, y) = (q̇, q̈),  q̈ from the Schur complement of the KKT system (crates/model)
//! ```
//! Also the mechanism's Jacobian ∂f/∂y at the contact state (what Rodas5P and BDF call).

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

criterion_group!(benches, rhs, jacobian);
criterion_main!(benches);
