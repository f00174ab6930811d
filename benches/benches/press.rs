//! One crank revolution of the dry and the lubricated press (150 rpm, c = 0.1 mm) with every
//! method: the adaptive ones at rtol 1e-6, atol 1e-9 with two event samples per step, RK4 at
//! the step the tests found stable (2e-4 s dry, 2e-6 s lubricated); the options of
//! crates/model/tests/press_methods.rs.
//!
//! ```text
//! y' = f(t, y) on [0, T],  T = 60/150 s,  contact events located
//! ```

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use lash_benches::{press, test_options};
use lash_solver::{solve, Method};
use std::hint::black_box;
use std::time::Duration;

fn one_revolution(c: &mut Criterion) {
    for stem in ["dry_150rpm_c0.1", "lubricated_150rpm_c0.1"] {
        let mut group = c.benchmark_group(format!("revolution/{stem}"));
        group.sample_size(10);
        group.measurement_time(Duration::from_secs(3));
        group.warm_up_time(Duration::from_millis(500));
        let m = press(stem, 1.0);
        let y0 = m.initial_state();
        for method in Method::ALL {
            let opts = test_options(method, stem);
            group.bench_function(method.name(), |b| {
                b.iter(|| {
                    let sol = solve(&m, (m.t_start(), m.t_end()), black_box(&y0), &opts)
                        .expect("the press case runs");
                    black_box(sol.y_final)
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, one_revolution);
criterion_main!(benches);
