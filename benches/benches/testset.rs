//! The stiff problems of the IVP Test Set (`lash_solver::testset`: ROBER, VDPOLM, HIRES,
//! OREGO) with each stiff method at rtol 1e-6 and the problem's own atol, over the whole span.
//!
//! ```text
//! y' = f(y), y(t0) = y0 on [t0, t_end]  (Mazzia & Magherini, IVP Test Set 2.4)
//! ```

// criterion_group! defines an undocumented public function.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use lash_solver::{solve, testset, Atol, Method, Output, SolverOptions};
use std::hint::black_box;
use std::time::Duration;

const STIFF: [Method; 4] = [
    Method::Bdf,
    Method::Trbdf2,
    Method::Esdirk34,
    Method::Rodas5p,
];

fn stiff_problems(c: &mut Criterion) {
    for name in testset::NAMES {
        let p = testset::by_name(name).expect("a known problem");
        let mut group = c.benchmark_group(format!("testset/{name}"));
        group.sample_size(10);
        group.measurement_time(Duration::from_secs(2));
        group.warm_up_time(Duration::from_millis(300));
        for method in STIFF {
            let opts = SolverOptions {
                method,
                rtol: 1e-6,
                atol: Atol::Scalar(p.atol),
                output: Output::Final,
                ..Default::default()
            };
            group.bench_function(method.name(), |b| {
                b.iter(|| {
                    let sol = solve(p.system.as_ref(), (p.t0, p.t_end), black_box(&p.y0), &opts)
                        .expect("the test problem runs");
                    black_box(sol.y_final)
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, stiff_problems);
criterion_main!(benches);
