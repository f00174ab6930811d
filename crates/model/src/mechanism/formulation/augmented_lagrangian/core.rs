//! The augmented Lagrangian solve on any (M, Φ_q, c): absolute coordinates or a reduced
//! (joint-coordinate) system alike. Nothing here knows about bodies or joints.
//!
//! ```text
//! find q̈ with  M q̈ + Φ_qᵀ λ = f,   Φ_q q̈ = c      (c = γ − 2ξωΦ̇ − ω²Φ in an ODE)
//! A = M + α Φ_qᵀ Φ_q   (symmetric positive definite for any Φ_q, M > 0)
//! λ₀ = 0;  A q̈ₖ₊₁ = f − Φ_qᵀ λₖ + α Φ_qᵀ c,   λₖ₊₁ = λₖ + α (Φ_q q̈ₖ₊₁ − c)
//! stop when max|q̈ₖ₊₁ − q̈ₖ| ≤ tol · max|q̈ₖ₊₁|  (k ≥ 1)
//! ```
//! When Φ_q q̈ = c can be met (full row rank, or redundant rows with consistent c), the iterates
//! converge to the q̈ of the KKT system — with redundant rows to its unique q̈ and to one of
//! its multipliers — and the error in the constraint space shrinks by about
//! 1/(1 + α σ) per iteration, σ the smallest nonzero eigenvalue of Φ_q M⁻¹ Φ_qᵀ (Bayo &
//! Ledesma, Nonlinear Dynamics 9 (1996) 113–130; García de Jalón & Bayo, Kinematic and Dynamic
//! Simulation of Multibody Systems, 1994, §5.3). When it cannot (c outside the range of Φ_q:
//! a singular configuration with a nonzero stabilisation term), λ grows in the null space of
//! Φ_qᵀ, which q̈ does not see: q̈ still converges, to the least-squares compromise.
//!
//! A is stored in its envelope (crate::linalg::Envelope, one block: from the first nonzero of
//! each row to the diagonal, fixed by the sparsity of M and Φ_q), and only that is written,
//! factored and read: the Cholesky factor of a matrix has no fill outside its envelope (George
//! & Liu, Computer Solution of Large Sparse Positive Definite Systems, 1981, §4.2). A chain of
//! bodies numbered along the chain (the N-four-bar) is then banded and costs O(n b) memory and
//! O(n b²) work. The kernels below are those of the dense storage it replaced, operation for
//! operation in the same order (the same numbers bit for bit); only the index of entry (i, k)
//! changed, from i·n + k to its place in the envelope.

use crate::linalg::Envelope;

/// A sparse constraint Jacobian by rows (compressed sparse rows; repeated columns add up).
#[derive(Clone, Debug, Default)]
pub(crate) struct SparseRows {
    /// Row r's entries are `start[r]..start[r + 1]`.
    pub start: Vec<usize>,
    /// Column of each entry.
    pub col: Vec<usize>,
    /// Value of each entry.
    pub val: Vec<f64>,
}

impl SparseRows {
    /// Number of rows.
    pub(crate) fn rows(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// out = Φ_q x.
    #[inline]
    pub(crate) fn mul(&self, x: &[f64], out: &mut [f64]) {
        for (r, o) in out.iter_mut().enumerate().take(self.rows()) {
            let mut s = 0.0;
            for e in self.start[r]..self.start[r + 1] {
                s += self.val[e] * x[self.col[e]];
            }
            *o = s;
        }
    }

    /// out += Φ_qᵀ v.
    #[inline]
    pub(crate) fn mul_t_add(&self, v: &[f64], out: &mut [f64]) {
        for (r, &vr) in v.iter().enumerate().take(self.rows()) {
            for e in self.start[r]..self.start[r + 1] {
                out[self.col[e]] += self.val[e] * vr;
            }
        }
    }
}

/// The mass matrix given to [`AlCore::assemble`].
#[derive(Clone, Copy, Debug)]
pub(crate) enum Mass<'a> {
    /// Diagonal (absolute coordinates: m, m, I of every body).
    Diagonal(&'a [f64]),
    /// Dense symmetric, n × n row-major (a reduced system: minimal/loops.rs); only its lower
    /// triangle inside the envelope is read.
    Dense(&'a [f64]),
}

/// What one solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Iterations {
    /// Solves with the factor of A (iterations of the multipliers).
    pub count: usize,
    /// Whether the change of q̈ fell below the tolerance.
    pub converged: bool,
}

/// The leading matrix A = M + αΦ_qᵀΦ_q, its factor, and the multiplier iteration.
#[derive(Clone, Debug, Default)]
pub(crate) struct AlCore {
    n: usize,
    /// α (the penalty, in the units that make αΦ_qᵀΦ_q comparable with M).
    pub alpha: f64,
    /// Relative tolerance on the change of q̈.
    pub tol: f64,
    /// Most iterations of one solve.
    pub max_iter: usize,
    /// First column of the envelope of each row of A.
    first: Vec<usize>,
    /// The envelope's storage of A (one block, rows in order).
    env: Envelope,
    /// A, then its factor: strict lower triangle L, diagonal 1/L_jj (in `env`).
    a: Vec<f64>,
    /// Scratch: the right-hand side and the previous iterate.
    b: Vec<f64>,
    prev: Vec<f64>,
    res: Vec<f64>,
    /// Scratch of [`AlCore::refine`]: the residuals and the correction.
    r: Vec<f64>,
    e: Vec<f64>,
    dl: Vec<f64>,
    dx: Vec<f64>,
}

impl AlCore {
    /// The structure for n coordinates: the envelope of M (`dense_mass`: full lower triangle;
    /// else diagonal) together with that of Φ_qᵀΦ_q for the sparsity pattern of `phi`.
    pub(crate) fn new(
        n: usize,
        dense_mass: bool,
        phi: &SparseRows,
        alpha: f64,
        tol: f64,
        max_iter: usize,
    ) -> AlCore {
        let mut first: Vec<usize> = if dense_mass {
            vec![0; n]
        } else {
            (0..n).collect()
        };
        for r in 0..phi.rows() {
            let cols = &phi.col[phi.start[r]..phi.start[r + 1]];
            if let Some(&lo) = cols.iter().min() {
                for &c in cols {
                    first[c] = first[c].min(lo);
                }
            }
        }
        let env = Envelope::new(n, vec![(0..n).collect()], (0..n).map(|i| (i, first[i])));
        AlCore {
            n,
            alpha,
            tol,
            max_iter,
            a: vec![0.0; env.len()],
            first,
            env,
            b: vec![0.0; n],
            prev: vec![0.0; n],
            res: vec![0.0; phi.rows()],
            r: vec![0.0; n],
            e: vec![0.0; phi.rows()],
            dl: vec![0.0; phi.rows()],
            dx: vec![0.0; n],
        }
    }

    /// A = M + αΦ_qᵀΦ_q (lower triangle, within the envelope).
    pub(crate) fn assemble(&mut self, mass: Mass<'_>, phi: &SparseRows) {
        let n = self.n;
        self.a.fill(0.0);
        match mass {
            Mass::Diagonal(d) => {
                for i in 0..n {
                    self.a[self.env.diag(i)] = d[i];
                }
            }
            Mass::Dense(m) => {
                for i in 0..n {
                    for j in self.first[i]..=i {
                        self.a[self.env.at(i, j)] = m[i * n + j];
                    }
                }
            }
        }
        let alpha = self.alpha;
        for r in 0..phi.rows() {
            let range = phi.start[r]..phi.start[r + 1];
            for e in range.clone() {
                let (ci, vi) = (phi.col[e], alpha * phi.val[e]);
                for f in range.clone() {
                    let cj = phi.col[f];
                    if cj <= ci {
                        self.a[self.env.at(ci, cj)] += vi * phi.val[f];
                    }
                }
            }
        }
    }

    /// Cholesky factorisation of A in place (envelope only). `Err(j)`: the pivot of row j is
    /// not a positive number (A is not positive definite in f64: M is not, or α overflows).
    pub(crate) fn factor(&mut self) -> Result<(), usize> {
        let n = self.n;
        let a = &mut self.a;
        // Entry (i, k) of row i is at oi + k − fi; (j, k) at oj + k − first[j].
        for i in 0..n {
            let fi = self.first[i];
            let oi = self.env.at(i, fi);
            for j in fi..i {
                let fj = self.first[j].max(fi);
                let oj = self.env.at(j, self.first[j]) - self.first[j];
                let mut s = a[oi + j - fi];
                for k in fj..j {
                    s -= a[oi + k - fi] * a[oj + k];
                }
                a[oi + j - fi] = s * a[oj + j];
            }
            let mut d = a[oi + i - fi];
            for k in fi..i {
                d -= a[oi + k - fi] * a[oi + k - fi];
            }
            if !(d > 0.0) {
                return Err(i);
            }
            a[oi + i - fi] = 1.0 / d.sqrt();
        }
        Ok(())
    }

    /// Solves A x = b in place with the factor.
    #[inline]
    pub(crate) fn apply_inverse(&self, x: &mut [f64]) {
        let n = self.n;
        let a = &self.a;
        // Entry (i, k) of row i is at oi + k.
        let row = |i: usize| self.env.at(i, self.first[i]) - self.first[i];
        for i in 0..n {
            let (fi, oi) = (self.first[i], row(i));
            let mut s = x[i];
            for k in fi..i {
                s -= a[oi + k] * x[k];
            }
            x[i] = s * a[oi + i];
        }
        for i in (0..n).rev() {
            let oi = row(i);
            let v = x[i] * a[oi + i];
            x[i] = v;
            let fi = self.first[i];
            for k in fi..i {
                x[k] -= a[oi + k] * v;
            }
        }
    }

    /// The multiplier iteration (module doc) after [`AlCore::factor`]: q̈ into `x`, the
    /// multipliers into `lam` (which it starts from: zero for a right-hand side, so that q̈
    /// is a function of (t, y) alone).
    pub(crate) fn solve(
        &mut self,
        phi: &SparseRows,
        f: &[f64],
        c: &[f64],
        lam: &mut [f64],
        x: &mut [f64],
    ) -> Iterations {
        let n = self.n;
        let alpha = self.alpha;
        let mut b = std::mem::take(&mut self.b);
        let mut prev = std::mem::take(&mut self.prev);
        let mut res = std::mem::take(&mut self.res);
        let mut out = Iterations::default();
        for k in 1..=self.max_iter {
            // b = f + Φ_qᵀ (α c − λ).
            b[..n].copy_from_slice(&f[..n]);
            for ((r, &ci), &li) in res.iter_mut().zip(c).zip(lam.iter()) {
                *r = alpha * ci - li;
            }
            phi.mul_t_add(&res, &mut b);
            self.apply_inverse(&mut b);
            // λ += α (Φ_q q̈ − c).
            phi.mul(&b, &mut res);
            for ((l, &r), &ci) in lam.iter_mut().zip(&res).zip(c) {
                *l += alpha * (r - ci);
            }
            out.count = k;
            if k > 1 {
                let mut diff = 0.0f64;
                let mut size = 0.0f64;
                for (bi, pi) in b[..n].iter().zip(&prev[..n]) {
                    diff = diff.max((bi - pi).abs());
                    size = size.max(bi.abs());
                }
                if diff <= self.tol * size {
                    out.converged = true;
                    prev[..n].copy_from_slice(&b[..n]);
                    break;
                }
            }
            prev[..n].copy_from_slice(&b[..n]);
        }
        x[..n].copy_from_slice(&prev[..n]);
        self.b = b;
        self.prev = prev;
        self.res = res;
        out
    }

    /// One step of iterative refinement after [`AlCore::solve`] (x, λ from it): the residuals
    /// of the KKT system in f64,
    /// ```text
    /// r = f − M x − Φ_qᵀ λ,   e = c − Φ_q x
    /// ```
    /// and the correction (δx, δλ) of M δx + Φ_qᵀ δλ = r, Φ_q δx = e by the same iteration
    /// from δλ = 0, added to x and λ. Why: every iterate of `solve` is a solve with A =
    /// M + αΦ_qᵀΦ_q, whose condition grows like α‖Φ_q‖²/λ_min(M), so x carries a relative
    /// rounding error of about ε α‖Φ_q‖²/λ_min(M) along the directions the constraints leave
    /// free (the iteration's floor, `AugmentedLagrangianParams`); the correction carries the
    /// same relative error of the much smaller δx (Wilkinson's iterative refinement; the
    /// residual needs no extra precision because A's conditioning, not the KKT system's,
    /// limits the first solve). It also continues an iteration that stopped at
    /// `max_iterations` near a singular configuration. Used by the reduced system's loop
    /// closures (minimal/loops.rs, where it takes IFToMM A02 N = 1 from 2.0e-6 m to 2.7e-10 m
    /// at rtol 1e-10); the absolute coordinates' formulation does not call it.
    pub(crate) fn refine(
        &mut self,
        mass: Mass<'_>,
        phi: &SparseRows,
        f: &[f64],
        c: &[f64],
        lam: &mut [f64],
        x: &mut [f64],
    ) -> Iterations {
        let n = self.n;
        let mut r = std::mem::take(&mut self.r);
        let mut e = std::mem::take(&mut self.e);
        let mut dl = std::mem::take(&mut self.dl);
        let mut dx = std::mem::take(&mut self.dx);
        r[..n].copy_from_slice(&f[..n]);
        match mass {
            Mass::Diagonal(d) => {
                for i in 0..n {
                    r[i] -= d[i] * x[i];
                }
            }
            Mass::Dense(m) => {
                for i in 0..n {
                    let mut s = 0.0;
                    for (j, xj) in x.iter().enumerate().take(n) {
                        let mij = if j <= i { m[i * n + j] } else { m[j * n + i] };
                        s += mij * xj;
                    }
                    r[i] -= s;
                }
            }
        }
        for (d, l) in dl.iter_mut().zip(lam.iter()) {
            *d = -l;
        }
        phi.mul_t_add(&dl, &mut r);
        phi.mul(x, &mut e);
        for (ei, &ci) in e.iter_mut().zip(c) {
            *ei = ci - *ei;
        }
        dl.iter_mut().for_each(|v| *v = 0.0);
        let it = self.solve(phi, &r, &e, &mut dl, &mut dx);
        for (xi, d) in x.iter_mut().zip(&dx) {
            *xi += d;
        }
        for (l, d) in lam.iter_mut().zip(&dl) {
            *l += d;
        }
        self.r = r;
        self.e = e;
        self.dl = dl;
        self.dx = dx;
        it
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three unit masses on a line (coordinates x₀, x₁, x₂), M = diag(1, 2, 3).
    fn rows(entries: &[&[(usize, f64)]]) -> SparseRows {
        let mut s = SparseRows {
            start: vec![0],
            ..Default::default()
        };
        for r in entries {
            for &(c, v) in *r {
                s.col.push(c);
                s.val.push(v);
            }
            s.start.push(s.col.len());
        }
        s
    }

    #[test]
    fn redundant_consistent_rows_give_the_kkt_acceleration() {
        // Constraint x₀ − x₁ = 0 (accelerations: q̈₀ − q̈₁ = c), written twice (redundant).
        // KKT with one row: q̈₀ = q̈₁ = a, (1 + 2) a = f₀ + f₁ + ... with c = 0:
        // M q̈ + Φᵀλ = f, Φ q̈ = 0: a = (f₀ + f₁)/(m₀ + m₁); q̈₂ = f₂/m₂.
        let phi = rows(&[&[(0, 1.0), (1, -1.0)], &[(0, 2.0), (1, -2.0)]]);
        let mass = [1.0, 2.0, 3.0];
        let mut core = AlCore::new(3, false, &phi, 1e2, 1e-15, 60);
        core.assemble(Mass::Diagonal(&mass), &phi);
        core.factor().unwrap();
        let f = [3.0, -1.5, 6.0];
        let (mut lam, mut x) = (vec![0.0; 2], vec![0.0; 3]);
        let it = core.solve(&phi, &f, &[0.0, 0.0], &mut lam, &mut x);
        assert!(it.converged && it.count <= 12, "{it:?}");
        let a = (3.0 - 1.5) / 3.0;
        for (got, want) in x.iter().zip([a, a, 2.0]) {
            assert!((got - want).abs() < 1e-13, "{x:?}");
        }
        // The reaction Φᵀλ balances: m₀ a = f₀ − (λ₀ + 2λ₁).
        assert!((1.0 * a - (3.0 - (lam[0] + 2.0 * lam[1]))).abs() < 1e-9);
    }

    #[test]
    fn an_inconsistent_row_leaves_the_least_squares_acceleration_finite() {
        // Φ = [1 −1 0] twice with c = (1, 3): no q̈ meets both; the iterates of q̈ still settle
        // (λ grows along (2, −1)/√5, the null space of Φᵀ... here (1, 1) rows are equal: the
        // null space of Φᵀ is (1, −1)) on q̈₀ − q̈₁ = 2, the mean of the targets.
        let phi = rows(&[&[(0, 1.0), (1, -1.0)], &[(0, 1.0), (1, -1.0)]]);
        let mass = [1.0, 1.0, 1.0];
        let mut core = AlCore::new(3, false, &phi, 1e2, 1e-15, 60);
        core.assemble(Mass::Diagonal(&mass), &phi);
        core.factor().unwrap();
        let (mut lam, mut x) = (vec![0.0; 2], vec![0.0; 3]);
        let it = core.solve(&phi, &[0.0; 3], &[1.0, 3.0], &mut lam, &mut x);
        assert!(it.converged, "{it:?}");
        assert!((x[0] - x[1] - 2.0).abs() < 1e-12, "{x:?}");
        assert!((x[0] + x[1]).abs() < 1e-12 && x[2] == 0.0, "{x:?}");
    }

    #[test]
    fn the_envelope_factor_equals_the_dense_solve() {
        // A chain: rows couple (0,1), (1,2), (2,3), (3,4); dense SPD mass on top. The
        // envelope solve of A x = b against a solve of the dense A by faer.
        let phi = rows(&[
            &[(0, 1.0), (1, -0.5)],
            &[(1, 1.0), (2, -1.0)],
            &[(2, 0.3), (3, -1.0)],
            &[(3, 1.0), (4, -2.0)],
        ]);
        let n = 5;
        let mut mass = vec![0.0; n * n];
        for i in 0..n {
            mass[i * n + i] = 2.0 + i as f64;
            if i > 0 {
                mass[i * n + i - 1] = 0.4;
                mass[(i - 1) * n + i] = 0.4;
            }
        }
        let mut core = AlCore::new(n, false, &phi, 10.0, 1e-14, 30);
        // The mass couples neighbours: inside the envelope of Φ_qᵀΦ_q already.
        core.assemble(Mass::Dense(&mass), &phi);
        let assembled = core.a.clone();
        let mut dense = faer::Mat::<f64>::zeros(n, n);
        for i in 0..n {
            for j in 0..n {
                dense[(i, j)] = mass[i * n + j];
            }
        }
        for r in 0..phi.rows() {
            for e in phi.start[r]..phi.start[r + 1] {
                for f in phi.start[r]..phi.start[r + 1] {
                    dense[(phi.col[e], phi.col[f])] += 10.0 * phi.val[e] * phi.val[f];
                }
            }
        }
        core.factor().unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut x = b.clone();
        core.apply_inverse(&mut x);
        for i in 0..n {
            let ax: f64 = (0..n).map(|j| dense[(i, j)] * x[j]).sum();
            assert!((ax - b[i]).abs() < 1e-13, "row {i}: {ax} vs {}", b[i]);
        }
        // The dense row-major storage's kernels (before A moved into its envelope), on the
        // same A: the envelope's factor and solve are theirs bit for bit.
        let first = core.first.clone();
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in first[i]..=i {
                a[i * n + j] = assembled[core.env.at(i, j)];
            }
        }
        for i in 0..n {
            let fi = first[i];
            for j in fi..i {
                let fj = first[j].max(fi);
                let mut s = a[i * n + j];
                for k in fj..j {
                    s -= a[i * n + k] * a[j * n + k];
                }
                a[i * n + j] = s * a[j * n + j];
            }
            let mut d = a[i * n + i];
            for k in fi..i {
                d -= a[i * n + k] * a[i * n + k];
            }
            a[i * n + i] = 1.0 / d.sqrt();
        }
        for i in 0..n {
            for j in first[i]..=i {
                assert_eq!(a[i * n + j].to_bits(), core.a[core.env.at(i, j)].to_bits());
            }
        }
        let mut y = b.clone();
        for i in 0..n {
            let mut s = y[i];
            for k in first[i]..i {
                s -= a[i * n + k] * y[k];
            }
            y[i] = s * a[i * n + i];
        }
        for i in (0..n).rev() {
            let v = y[i] * a[i * n + i];
            y[i] = v;
            for k in first[i]..i {
                y[k] -= a[i * n + k] * v;
            }
        }
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&x), bits(&y));
        // Stored: the envelope (row i from its first column), not n².
        let stored: usize = (0..n).map(|i| i - first[i] + 1).sum();
        assert_eq!(core.a.len(), stored);
        assert!(stored < n * n);
    }
}
