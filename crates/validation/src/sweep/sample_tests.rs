//! Tests of sampled sweeps: the generator and Φ⁻¹ against values computed independently, the
//! Latin hypercube's strata, the moments of the draws, the checks, and a sampled sweep that
//! resumes like a grid.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use serde_json::Value;

use super::merge::merge;
use super::runner::*;
use super::sample::*;
use super::spec::*;
use crate::error::Error;
use crate::progress::NoProgress;
use crate::store::io;

fn spec(dir: &Path, json: &str) -> Result<SweepSpec, Error> {
    std::fs::write(dir.join("base.json"), b"{\"scene\": true}").unwrap();
    let p = dir.join("sweep.json");
    std::fs::write(&p, json).unwrap();
    SweepSpec::load(&p)
}

fn sample(
    method: SampleMethod,
    count: usize,
    seed: u64,
    vary: &[(&str, Distribution)],
) -> SampleSpec {
    SampleSpec {
        count,
        seed,
        method,
        vary: vary.iter().map(|(p, d)| (p.to_string(), *d)).collect(),
    }
}

/// The first outputs of SplitMix64, against the reference C code (Vigna's splitmix64.c)
/// transcribed to Python with explicit `& (2**64 - 1)` wrapping; seed 0 starts with
/// 0xE220A8397B1DCDAF, the value other implementations publish as their test vector.
#[test]
fn splitmix64_draws_match_the_reference() {
    let mut g = SplitMix64::new(0);
    let first: Vec<u64> = (0..3).map(|_| g.next_u64()).collect();
    assert_eq!(
        first,
        [
            16294208416658607535,
            7960286522194355700,
            487617019471545679
        ]
    );
    assert_eq!(first[0], 0xE220_A839_7B1D_CDAF);
    let mut g = SplitMix64::new(42);
    let first: Vec<u64> = (0..3).map(|_| g.next_u64()).collect();
    assert_eq!(
        first,
        [
            13679457532755275413,
            2949826092126892291,
            5139283748462763858
        ]
    );
    // The same outputs as uniforms ((out >> 11) + 0.5) * 2^-53, computed in Python the same way
    // (exact in f64: 53-bit integers and a power of two).
    let mut g = SplitMix64::new(42);
    let u: Vec<f64> = (0..3).map(|_| g.uniform()).collect();
    assert_eq!(
        u,
        [0.7415648787718234, 0.15991039287692016, 0.2786011302551387]
    );
    // below(n) is ⌊out·n/2^64⌋: for n = 2^k the top k bits of the output.
    let mut a = SplitMix64::new(9);
    let mut b = SplitMix64::new(9);
    for _ in 0..100 {
        assert_eq!(a.below(1 << 10), b.next_u64() >> 54);
    }
}

/// Φ⁻¹ against the standard normal CDF of the C library: each p below is 0.5·erfc(−x/√2)
/// computed with Python's math.erfc (glibc's libm, an implementation independent of AS241),
/// so Φ⁻¹(p) must give back x, to the error p's rounding allows (|dx| ≤ 2 ulp(p)/φ(x)).
#[test]
fn inverse_normal_cdf_inverts_the_libm_cdf() {
    let cases = [
        (-8.0f64, 6.220960574271819e-16f64),
        (-3.0, 0.0013498980316300957),
        (-1.0, 0.15865525393145707),
        (0.3, 0.6179114221889526),
        (2.5, 0.9937903346742238),
    ];
    for (x, p) in cases {
        let phi = (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt();
        let ulp = f64::EPSILON * f64::max(p, 1e-300);
        let tol = 2.0 * ulp / phi + 4.0 * f64::EPSILON * f64::abs(x);
        let got = inverse_normal_cdf(p);
        assert!(
            (got - x).abs() <= tol,
            "Φ⁻¹({p}) = {got}, want {x} ± {tol:e}"
        );
    }
    // Well-known quantiles (1.96 for 97.5 %, 1.645 for 95 %, 2.576 for 99.5 %), to 17 digits.
    assert_eq!(inverse_normal_cdf(0.5), 0.0);
    assert!((inverse_normal_cdf(0.975) - 1.959963984540054).abs() < 1e-15);
    assert!((inverse_normal_cdf(0.95) - 1.6448536269514722).abs() < 1e-15);
    assert!((inverse_normal_cdf(0.005) + 2.5758293035489004).abs() < 1e-14);
    // Odd symmetry where 1 − p is exact, and the ends.
    for p in [0.0625, 0.125, 0.25, 0.375, 2f64.powi(-30)] {
        assert_eq!(inverse_normal_cdf(p), -inverse_normal_cdf(1.0 - p));
    }
    assert_eq!(inverse_normal_cdf(0.0), f64::NEG_INFINITY);
    assert_eq!(inverse_normal_cdf(1.0), f64::INFINITY);
    assert!(inverse_normal_cdf(1.5).is_nan() && inverse_normal_cdf(f64::NAN).is_nan());
}

/// The first random draws of a sample, against Python: the generator above, then
/// `1 + 2u` and `statistics.NormalDist(2, 0.5).inv_cdf(v)` (Python's own AS241), paths in
/// sorted order ("a" before "b"), one uniform per path per sample.
#[test]
fn random_draws_match_values_computed_in_python() {
    let s = sample(
        SampleMethod::Random,
        3,
        7,
        &[
            ("b", Distribution::Normal(2.0, 0.5)),
            ("a", Distribution::Uniform(1.0, 3.0)),
        ],
    );
    let d = s.draws().unwrap();
    let want = [
        (1.7796594967825432, 0.9374399275916889),
        (2.801521361213767, 2.1046978085717987),
        (1.9048837900229367, 1.661860123017631),
    ];
    for (row, (a, b)) in d.iter().zip(want) {
        let (ga, gb) = (row["a"].as_f64().unwrap(), row["b"].as_f64().unwrap());
        assert!((ga - a).abs() <= 2.0 * f64::EPSILON * a, "{ga} vs {a}");
        assert!(
            (gb - b).abs() <= 4.0 * f64::EPSILON * b.abs(),
            "{gb} vs {b}"
        );
    }
    // Random draws of a smaller count are the first samples of a larger one.
    let more = SampleSpec {
        count: 10,
        ..s.clone()
    };
    assert_eq!(more.draws().unwrap()[..3], d[..]);
}

/// A Latin hypercube puts exactly one sample in each of the N strata [k/N, (k+1)/N) of every
/// path, and its values are the distributions' values at those coordinates.
#[test]
fn latin_hypercube_has_one_sample_per_stratum_per_path() {
    let n = 97;
    let s = sample(
        SampleMethod::LatinHypercube,
        n,
        2024,
        &[
            ("x", Distribution::Uniform(-1.0, 4.0)),
            ("y", Distribution::Normal(0.0, 1.0)),
            ("z", Distribution::Lognormal(-2.0, 0.5)),
        ],
    );
    let u = s.unit_points();
    assert_eq!(u.len(), n);
    for j in 0..3 {
        let mut strata: Vec<usize> = u.iter().map(|r| (r[j] * n as f64) as usize).collect();
        strata.sort_unstable();
        assert_eq!(strata, (0..n).collect::<Vec<_>>(), "path {j}");
    }
    // The columns are not all in the same order (independent permutations).
    let order = |j: usize| -> Vec<usize> { u.iter().map(|r| (r[j] * n as f64) as usize).collect() };
    assert_ne!(order(0), order(1));
    assert_ne!(order(1), order(2));
    // Values: stratum k of y lies between Φ⁻¹(k/N) and Φ⁻¹((k+1)/N), and z = exp(−2 + 0.5 Φ⁻¹).
    let d = s.draws().unwrap();
    for (r, row) in u.iter().zip(&d) {
        let k = (r[1] * n as f64) as usize;
        let y = row["y"].as_f64().unwrap();
        assert!(inverse_normal_cdf(k as f64 / n as f64) <= y);
        assert!(y <= inverse_normal_cdf((k + 1) as f64 / n as f64));
        let x = row["x"].as_f64().unwrap();
        assert_eq!(x, -1.0 + 5.0 * r[0]);
        let z = row["z"].as_f64().unwrap();
        assert_eq!(z, (-2.0 + 0.5 * inverse_normal_cdf(r[2])).exp());
    }
    // The same seed gives the same sample; another seed another.
    assert_eq!(s.draws().unwrap(), d);
    let other = SampleSpec { seed: 2025, ..s };
    assert_ne!(other.draws().unwrap(), d);
}

/// Sample moments converge: with N draws the mean is within 4 standard errors (σ/√N) of the
/// distribution's mean and the standard deviation within 4·σ/√(2N) of σ (the normal's
/// standard error of s; a chance of about 6e-5 of failing for a correct sampler, and none
/// with the fixed seeds here). For the lognormal the moments of ln x.
#[test]
fn sample_moments_converge_to_the_distributions() {
    let n = 20_000;
    for method in [SampleMethod::Random, SampleMethod::LatinHypercube] {
        let s = sample(
            method,
            n,
            11,
            &[
                ("u", Distribution::Uniform(1.0, 3.0)),
                ("g", Distribution::Normal(2.0, 0.5)),
                ("l", Distribution::Lognormal(0.1, 0.3)),
            ],
        );
        let d = s.draws().unwrap();
        let col = |p: &str, f: fn(f64) -> f64| -> Vec<f64> {
            d.iter().map(|r| f(r[p].as_f64().unwrap())).collect()
        };
        let moments = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64;
            (m, var.sqrt())
        };
        let nn = n as f64;
        for (name, v, mean, sd) in [
            ("u", col("u", |x| x), 2.0, 2.0 / 12f64.sqrt()),
            ("g", col("g", |x| x), 2.0, 0.5),
            ("ln l", col("l", f64::ln), 0.1, 0.3),
        ] {
            let (m, s) = moments(&v);
            assert!(
                (m - mean).abs() < 4.0 * sd / nn.sqrt(),
                "{method:?} {name}: mean {m}"
            );
            assert!(
                (s - sd).abs() < 4.0 * sd / (2.0 * nn).sqrt(),
                "{method:?} {name}: sd {s}"
            );
        }
    }
}

#[test]
fn bad_samples_name_their_key() {
    let d = tempfile::tempdir().unwrap();
    let msg = |body: &str| {
        spec(d.path(), &format!(r#"{{"case": "base.json", {body}}}"#))
            .and_then(|s| s.points())
            .unwrap_err()
            .to_string()
    };
    let vary = r#""vary": {"bodies[1].mass": {"uniform": [1, 2]}}"#;
    for (body, want) in [
        (
            format!(r#""sample": {{"count": 0, "seed": 1, {vary}}}"#),
            "sample.count must be in 1 ..= 1000000, got 0",
        ),
        (
            format!(r#""sample": {{"count": "ten", "seed": 1, {vary}}}"#),
            "sample.count: invalid type: string \"ten\"",
        ),
        (
            format!(r#""sample": {{"count": 5, "seed": -1, {vary}}}"#),
            "sample.seed: invalid value",
        ),
        (
            format!(r#""sample": {{"count": 5, "seed": 1, "method": "sobol", {vary}}}"#),
            "sample.method: unknown variant `sobol`",
        ),
        (
            format!(r#""sample": {{"count": 5, "seed": 1, "n": 3, {vary}}}"#),
            "sample.n: unknown field `n`",
        ),
        (
            r#""sample": {"count": 5, "seed": 1, "vary": {"m": {"uniform": [2, 1]}}}"#.into(),
            "sample.vary['m'].uniform: needs lo < hi, got [2, 1]",
        ),
        (
            r#""sample": {"count": 5, "seed": 1, "vary": {"m": {"normal": [2, 0]}}}"#.into(),
            "sample.vary['m'].normal: needs sd > 0, got 0",
        ),
        (
            r#""sample": {"count": 5, "seed": 1, "vary": {"m": {"lognormal": [0, -1]}}}"#.into(),
            "sample.vary['m'].lognormal: needs sigma > 0, got -1",
        ),
        (
            r#""sample": {"count": 5, "seed": 1, "vary": {"m": {"beta": [1, 2]}}}"#.into(),
            "sample.vary.m: unknown variant `beta`",
        ),
        (
            r#""sample": {"count": 5, "seed": 1, "vary": {"m": {"uniform": [1]}}}"#.into(),
            "sample.vary.m.uniform: invalid length 1",
        ),
        (
            r#""sample": {"count": 5, "seed": 1, "vary": {}}"#.into(),
            "sample.vary is empty",
        ),
        (
            r#""sample": {"count": 5, "seed": 1, "vary": {"a[": {"normal": [1, 1]}}}"#.into(),
            "sample.vary['a[']: 'a[': expected [INDEX] or [NAME]",
        ),
        (
            format!(
                r#""set": {{"bodies[1].mass": [1, 2]}}, "sample": {{"count": 5, "seed": 1, {vary}}}"#
            ),
            "sample.vary['bodies[1].mass'] is also in set",
        ),
        (
            r#""sample": {"count": 5, "seed": 1, "vary": {"m": {"lognormal": [700, 30]}}}"#.into(),
            "which is not finite",
        ),
    ] {
        let e = msg(&body);
        assert!(e.contains(want), "{body}\n  gave: {e}\n  want: {want}");
        assert_eq!(e.lines().count(), 1, "{e}");
    }
}

/// A fake runner: one value, the sampled mass doubled.
fn fake(p: &SweepPoint, dir: &Path, calls: &AtomicUsize) -> Result<PointResult, Error> {
    calls.fetch_add(1, Ordering::SeqCst);
    io::write_atomic(&dir.join("summary.json"), b"{}")?;
    let m = p.params.set["bodies[1].mass"].as_f64().unwrap();
    Ok(PointResult::flatten(
        &serde_json::json!({"metrics": {"twice": 2.0 * m}}),
    ))
}

/// A sampled sweep is a grid like any other: the same file gives the same points and ids; a
/// sweep stopped after k points and run again runs only the others; each sampled path is a
/// column of the merged table named as written and a key of the point's params.
#[test]
fn a_sampled_sweep_resumes_like_a_grid() {
    let d = tempfile::tempdir().unwrap();
    let file = r#"{"case": "base.json", "method": ["bdf"], "rtol": [1e-6, 1e-8],
        "sample": {"count": 6, "seed": 3, "method": "latin_hypercube",
                   "vary": {"bodies[1].mass": {"uniform": [0.5, 1.5]},
                            "joints[j].friction.mu": {"lognormal": [-2.3, 0.2]}}}}"#;
    let pts = spec(d.path(), file).unwrap().points().unwrap();
    assert_eq!(pts.len(), 12);
    // Samples vary slower than the solver choices: points 2k and 2k+1 share a sample.
    for k in 0..6 {
        assert_eq!(pts[2 * k].params.set, pts[2 * k + 1].params.set);
        assert_eq!(pts[2 * k].params.rtol, Some(1e-6));
    }
    let again = spec(d.path(), file).unwrap().points().unwrap();
    assert_eq!(pts, again);
    // The id hashes the sampled values as `set` values are hashed.
    let p = &pts[4].params;
    let canon = p.canonical_json();
    assert!(canon.contains("\"bodies[1].mass\":") && canon.contains("\"joints[j].friction.mu\":"));
    assert_eq!(pts[4].id, p.id());

    let root = d.path().join("out");
    let k = 5;
    let r = super::tests::run_stopped_after(&pts, &root, k, |p, dir| {
        fake(p, dir, &AtomicUsize::new(0))
    });
    assert_eq!((r.ok, r.failed.len()), (k, 12 - k));
    let reloaded = spec(d.path(), file).unwrap().points().unwrap();
    let calls = AtomicUsize::new(0);
    let opts = SweepOptions {
        jobs: Some(1),
        ..Default::default()
    };
    let r = run_sweep(
        &reloaded,
        &root,
        &opts,
        |p, dir| fake(p, dir, &calls),
        &NoProgress,
    )
    .unwrap();
    assert_eq!((r.skipped, r.ok), (k, 12 - k));
    assert_eq!(calls.load(Ordering::SeqCst), 12 - k);
    let t = merge(std::slice::from_ref(&root)).unwrap();
    assert_eq!(t.rows.len(), 12);
    let col = |n: &str| t.columns.iter().position(|c| c == n).expect(n);
    let (mass, mu, twice) = (
        col("bodies[1].mass"),
        col("joints[j].friction.mu"),
        col("metrics.twice"),
    );
    for (row, p) in t.rows.iter().zip(&pts) {
        let m: f64 = row[mass].parse().unwrap();
        assert_eq!(m, p.params.set["bodies[1].mass"].as_f64().unwrap());
        assert!((0.5..1.5).contains(&m));
        assert_eq!(row[twice].parse::<f64>().unwrap(), 2.0 * m);
        let f: f64 = row[mu].parse().unwrap();
        assert!(f > 0.0);
    }
    let rec: BTreeMap<String, Value> =
        serde_json::from_slice(&std::fs::read(root.join(&pts[0].id).join(RESULT_FILE)).unwrap())
            .unwrap();
    assert!(rec["params"]["joints[j].friction.mu"].is_number());
}
