//! Sampled sweeps: `"sample": {count, seed, method, vary: {PATH: distribution}}` of a sweep
//! file, its draws reproducible from the seed on every platform and in every version.
//!
//! ```text
//! generator  SplitMix64 (Steele, Lea & Flood 2014):  x ← x + 0x9E3779B97F4A7C15 (mod 2^64),
//!            z = x;  z ← (z ⊕ z≫30)·0xBF58476D1CE4E5B9;  z ← (z ⊕ z≫27)·0x94D049BB133111EB;
//!            out = z ⊕ z≫31;  the state starts at the seed
//! uniform    u = (out≫11 + 1/2)·2^-53 ∈ (0, 1), never 0 or 1
//! below(n)   ⌊out·n / 2^64⌋ ∈ {0, …, n−1}   (Lemire's multiply-shift, bias ≤ n/2^64)
//! paths      in sorted order, j = 0 … d−1;  samples i = 0 … N−1
//! random     u[i][j] = the (i·d + j)-th uniform (so the first N' < N samples of a larger
//!            count are the same points)
//! latin_hypercube (the default)
//!            for each path j in order: a permutation π_j of 0…N−1 by Fisher–Yates
//!            (k = N−1 … 1: swap π[k] and π[below(k+1)]), then for i = 0 … N−1 a jitter
//!            v = uniform;  u[i][j] = (π_j[i] + v)/N  → exactly one sample in each stratum
//!            [k/N, (k+1)/N) of every path
//! value      uniform [lo, hi]:       lo + (hi − lo)·u
//!            normal [mean, sd]:      mean + sd·Φ⁻¹(u)
//!            lognormal [mu, sigma]:  exp(mu + sigma·Φ⁻¹(u))   (mu, sigma of log x)
//! Φ⁻¹        Wichura's AS241 (PPND16, Applied Statistics 37 (1988) 477–484), relative
//!            error about 1e-16, the algorithm of R's qnorm and Python's NormalDist.inv_cdf
//! checks     count 1 … MAX_COUNT; vary not empty; each PATH well-formed (module set) and not
//!            also in `set`; lo < hi, sd > 0, sigma > 0, every number finite; a drawn value
//!            that is not finite (exp overflowing) is an error naming the path
//! ```
//!
//! Each sampled value goes into the point's `set` map under its PATH as written, so it is laid
//! over the scene, validated before any point runs, hashed into the point's id and a column of
//! merged.csv exactly as a `set` value is.
//!
//! Source: docs/outputs.md ("Sweeps": `sample`).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::Error;

/// The most samples a sweep file may ask for.
pub(crate) const MAX_COUNT: usize = 1_000_000;

/// How the unit hypercube is filled (module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum SampleMethod {
    /// One sample per stratum of every path.
    #[default]
    LatinHypercube,
    /// Independent draws.
    Random,
}

/// The distribution of one sampled field (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Distribution {
    /// `[lo, hi]`, lo < hi.
    Uniform(f64, f64),
    /// `[mean, sd]`, sd > 0.
    Normal(f64, f64),
    /// `[mu, sigma]` of the logarithm, sigma > 0.
    Lognormal(f64, f64),
}

impl Distribution {
    /// The value at the unit coordinate u ∈ (0, 1).
    fn at(self, u: f64) -> f64 {
        match self {
            Distribution::Uniform(lo, hi) => lo + (hi - lo) * u,
            Distribution::Normal(m, s) => m + s * inverse_normal_cdf(u),
            Distribution::Lognormal(m, s) => (m + s * inverse_normal_cdf(u)).exp(),
        }
    }

    /// Why its parameters are unusable, if they are.
    fn problem(self) -> Option<String> {
        let (name, a, b) = match self {
            Distribution::Uniform(a, b) => ("uniform", a, b),
            Distribution::Normal(a, b) => ("normal", a, b),
            Distribution::Lognormal(a, b) => ("lognormal", a, b),
        };
        if !(a.is_finite() && b.is_finite()) {
            return Some(format!("{name}: [{a}, {b}] must be finite"));
        }
        match self {
            Distribution::Uniform(lo, hi) if !(lo < hi) => {
                Some(format!("uniform: needs lo < hi, got [{lo}, {hi}]"))
            }
            Distribution::Normal(_, sd) if !(sd > 0.0) => {
                Some(format!("normal: needs sd > 0, got {sd}"))
            }
            Distribution::Lognormal(_, s) if !(s > 0.0) => {
                Some(format!("lognormal: needs sigma > 0, got {s}"))
            }
            _ => None,
        }
    }
}

/// The `sample` of a sweep file.
///
/// ```text
/// { count: N, seed: S, method: "latin_hypercube" (default) | "random", vary: {PATH: dist} }
/// ```
///
/// Source: docs/outputs.md ("Sweeps": `sample`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SampleSpec {
    /// Number of samples N.
    pub count: usize,
    /// Seed of the generator.
    pub seed: u64,
    /// How the hypercube is filled.
    #[serde(default)]
    pub method: SampleMethod,
    /// The sampled fields by path, each with its distribution.
    pub vary: BTreeMap<String, Distribution>,
}

impl SampleSpec {
    /// Checks the sample (module doc); `set` is the sweep's `set`, whose paths it must not vary.
    pub(crate) fn check(&self, set: Option<&BTreeMap<String, Vec<Value>>>) -> Result<(), Error> {
        let bad = |m: String| Err(Error::Input(format!("sweep: {m}")));
        if self.count == 0 || self.count > MAX_COUNT {
            return bad(format!(
                "sample.count must be in 1 ..= {MAX_COUNT}, got {}",
                self.count
            ));
        }
        if self.vary.is_empty() {
            return bad("sample.vary is empty: name at least one PATH to sample".into());
        }
        for (path, d) in &self.vary {
            if let Err(e) = crate::sweep::set::check_path(path) {
                return bad(format!("sample.vary['{path}']: {e}"));
            }
            if let Some(e) = d.problem() {
                return bad(format!("sample.vary['{path}'].{e}"));
            }
            if set.is_some_and(|s| s.contains_key(path)) {
                return bad(format!(
                    "sample.vary['{path}'] is also in set: vary a path in one of them"
                ));
            }
        }
        Ok(())
    }

    /// The unit coordinates u[i][j] of the module doc (samples × paths in sorted order).
    pub(crate) fn unit_points(&self) -> Vec<Vec<f64>> {
        let (n, d) = (self.count, self.vary.len());
        let mut g = SplitMix64::new(self.seed);
        match self.method {
            SampleMethod::Random => (0..n)
                .map(|_| (0..d).map(|_| g.uniform()).collect())
                .collect(),
            SampleMethod::LatinHypercube => {
                let mut u = vec![vec![0.0; d]; n];
                for j in 0..d {
                    let mut perm: Vec<usize> = (0..n).collect();
                    for k in (1..n).rev() {
                        perm.swap(k, g.below(k as u64 + 1) as usize);
                    }
                    for (i, row) in u.iter_mut().enumerate() {
                        row[j] = (perm[i] as f64 + g.uniform()) / n as f64;
                    }
                }
                u
            }
        }
    }

    /// Each sample's values by path (module doc), in sample order.
    pub(crate) fn draws(&self) -> Result<Vec<BTreeMap<String, Value>>, Error> {
        self.unit_points()
            .into_iter()
            .enumerate()
            .map(|(i, u)| {
                self.vary
                    .iter()
                    .zip(u)
                    .map(|((path, d), u)| {
                        let x = d.at(u);
                        let v = serde_json::Number::from_f64(x).ok_or_else(|| {
                            Error::Input(format!(
                                "sweep: sample.vary['{path}']: sample {i} draws {x}, which is not \
                                 finite"
                            ))
                        })?;
                        Ok((path.clone(), Value::Number(v)))
                    })
                    .collect()
            })
            .collect()
    }
}

/// SplitMix64 (module doc): 64-bit state, one addition and two multiply-xorshifts per draw.
#[derive(Clone, Debug)]
pub(crate) struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// The generator whose state starts at `seed`.
    pub(crate) fn new(seed: u64) -> SplitMix64 {
        SplitMix64 { state: seed }
    }

    /// The next 64-bit output.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform draw in (0, 1): (out≫11 + 1/2)·2^-53.
    pub(crate) fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
    }

    /// A draw in {0, …, n−1}: ⌊out·n / 2^64⌋.
    pub(crate) fn below(&mut self, n: u64) -> u64 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }
}

/// Φ⁻¹(p), the standard normal quantile, for p ∈ (0, 1) (Wichura's AS241, PPND16: rational
/// approximations of degree 7 in three ranges of p; ±∞ at 0 and 1, NaN outside).
#[allow(clippy::excessive_precision)]
pub(crate) fn inverse_normal_cdf(p: f64) -> f64 {
    if !(p > 0.0 && p < 1.0) {
        return if p == 0.0 {
            f64::NEG_INFINITY
        } else if p == 1.0 {
            f64::INFINITY
        } else {
            f64::NAN
        };
    }
    let q = p - 0.5;
    if q.abs() <= 0.425 {
        let r = 0.180625 - q * q;
        let num = (((((((2.5090809287301226727e+3 * r + 3.3430575583588128105e+4) * r
            + 6.7265770927008700853e+4)
            * r
            + 4.5921953931549871457e+4)
            * r
            + 1.3731693765509461125e+4)
            * r
            + 1.9715909503065514427e+3)
            * r
            + 1.3314166789178437745e+2)
            * r
            + 3.3871328727963666080e+0)
            * q;
        let den = ((((((5.2264952788528545610e+3 * r + 2.8729085735721942674e+4) * r
            + 3.9307895800092710610e+4)
            * r
            + 2.1213794301586595867e+4)
            * r
            + 5.3941960214247511077e+3)
            * r
            + 6.8718700749205790830e+2)
            * r
            + 4.2313330701600911252e+1)
            * r
            + 1.0;
        return num / den;
    }
    let r = if q <= 0.0 { p } else { 1.0 - p };
    let r = (-r.ln()).sqrt();
    let x = if r <= 5.0 {
        let r = r - 1.6;
        let num = ((((((7.74545014278341407640e-4 * r + 2.27238449892691845833e-2) * r
            + 2.41780725177450611770e-1)
            * r
            + 1.27045825245236838258e+0)
            * r
            + 3.64784832476320460504e+0)
            * r
            + 5.76949722146069140550e+0)
            * r
            + 4.63033784615654529590e+0)
            * r
            + 1.42343711074968357734e+0;
        let den = ((((((1.05075007164441684324e-9 * r + 5.47593808499534494600e-4) * r
            + 1.51986665636164571966e-2)
            * r
            + 1.48103976427480074590e-1)
            * r
            + 6.89767334985100004550e-1)
            * r
            + 1.67638483018380384940e+0)
            * r
            + 2.05319162663775882187e+0)
            * r
            + 1.0;
        num / den
    } else {
        let r = r - 5.0;
        let num = ((((((2.01033439929228813265e-7 * r + 2.71155556874348757815e-5) * r
            + 1.24266094738807843860e-3)
            * r
            + 2.65321895265761230930e-2)
            * r
            + 2.96560571828504891230e-1)
            * r
            + 1.78482653991729133580e+0)
            * r
            + 5.46378491116411436990e+0)
            * r
            + 6.65790464350110377720e+0;
        let den = ((((((2.04426310338993978564e-15 * r + 1.42151175831644588870e-7) * r
            + 1.84631831751005468180e-5)
            * r
            + 7.86869131145613259100e-4)
            * r
            + 1.48753612908506148525e-2)
            * r
            + 1.36929880922735805310e-1)
            * r
            + 5.99832206555887937690e-1)
            * r
            + 1.0;
        num / den
    };
    if q < 0.0 {
        -x
    } else {
        x
    }
}
