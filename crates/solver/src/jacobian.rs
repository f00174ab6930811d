//! Dense Jacobians ∂f/∂y for the implicit methods: the system's own when it has one, forward
//! differences of the right-hand side otherwise; and the time derivative ∂f/∂t that
//! Rosenbrock methods need.
//!
//! ```text
//! J[:, j] ≈ (f(t, y + δ_j e_j) − f(t, y)) / δ_j,   δ_j = √ε · max(|y_j|, s_j)
//! ∂f/∂t  ≈ (f(t + δ_t, y) − f(t − δ_t, y)) / 2δ_t,  δ_t = ε^{1/3} · √max(10⁻⁵, |t|)
//! ```
//!
//! ε is the unit round-off. The forward-difference increment √ε·max(|y_j|, s_j) balances
//! truncation (∝ δ) against cancellation (∝ ε/δ) (Dennis & Schnabel, *Numerical Methods for
//! Unconstrained Optimization*, §5.4; the `max(|y|, thresh)` form is MATLAB's `numjac`). The
//! floor s_j is the size below which component j is noise to the solver: the integrators pass
//! s_j = atol_j / rtol, where the absolute and relative tolerances cross. Each increment is
//! rounded so that y_j + δ_j − y_j = δ_j exactly. The time increment is the one of Hairer's
//! RODAS code (HNW II, §IV.7), √ε → ε^{1/3} for the central difference (see
//! [`JacobianEvaluator::time_derivative`] for why central).
//!
//! With a sparsity pattern ([`OdeSystem::jacobian_sparsity`]) the columns are coloured
//! greedily so that no two columns of one colour share a row (structurally orthogonal), and
//! all columns of a colour are perturbed together (Curtis, Powell & Reid, J. Inst. Maths
//! Applics 13, 117–119, 1974; scipy's `group_columns`):
//!
//! ```text
//! for each colour c:  f_c = f(t, y + Σ_{j ∈ c} δ_j e_j);   J[i, j] = (f_c[i] − f(t, y)[i]) / δ_j
//!                     for j ∈ c and i in the pattern of column j (0 elsewhere)
//! ```
//! A banded Jacobian of bandwidth w needs w colours whatever n is.
//!
//! Counting (in [`Stats`]): every Jacobian, analytic or by differences, adds 1 to `jac_evals`;
//! a finite-difference Jacobian adds n to `rhs_evals` (the number of colours with a sparsity
//! pattern), a time derivative 2.

use faer::MatMut;

use crate::stats::Stats;
use crate::system::OdeSystem;

/// Evaluates dense Jacobians and time derivatives of one system, keeping its scratch vectors.
///
/// ```text
/// J = ∂f/∂y (analytic, or forward differences with δ_j = √ε · max(|y_j|, s_j))
/// ```
/// See the module documentation for the increments and their source.
#[derive(Clone, Debug)]
pub struct JacobianEvaluator {
    /// Floors s_j of the difference increments.
    scale: Vec<f64>,
    ytmp: Vec<f64>,
    ftmp: Vec<f64>,
    /// The system's sparsity pattern and its colouring, read at the first finite-difference
    /// Jacobian (None inside: dense).
    colouring: Option<Option<Colouring>>,
    /// Increments of the columns of one colour.
    deltas: Vec<f64>,
}

/// Columns grouped by a greedy colouring of a sparsity pattern (module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Colouring {
    /// For each column, the rows where it may be nonzero.
    pattern: Vec<Vec<usize>>,
    /// The columns of each colour, ascending.
    groups: Vec<Vec<usize>>,
}

impl Colouring {
    /// Colours the columns of `pattern` (for each column j, its possibly nonzero rows, each
    /// < n = `pattern.len()`) greedily in column order: column j takes the first colour none
    /// of whose columns has a row in common with it. None when a row index is out of range.
    pub fn new(pattern: Vec<Vec<usize>>) -> Option<Self> {
        let n = pattern.len();
        Self::rectangular(pattern, n)
    }

    /// [`Colouring::new`] for a matrix of `n` rows (and `pattern.len()` columns).
    pub fn rectangular(pattern: Vec<Vec<usize>>, n: usize) -> Option<Self> {
        if pattern.iter().flatten().any(|&i| i >= n) {
            return None;
        }
        // rows_used[c][i]: colour c already has a column with row i.
        let mut rows_used: Vec<Vec<bool>> = Vec::new();
        let mut groups: Vec<Vec<usize>> = Vec::new();
        for (j, rows) in pattern.iter().enumerate() {
            let c = match rows_used
                .iter()
                .position(|used| rows.iter().all(|&i| !used[i]))
            {
                Some(c) => c,
                None => {
                    rows_used.push(vec![false; n]);
                    groups.push(Vec::new());
                    groups.len() - 1
                }
            };
            for &i in rows {
                rows_used[c][i] = true;
            }
            groups[c].push(j);
        }
        Some(Colouring { pattern, groups })
    }

    /// Number of colours: RHS evaluations per finite-difference Jacobian.
    pub fn colours(&self) -> usize {
        self.groups.len()
    }

    /// For each column, the rows where it may be nonzero.
    pub fn pattern(&self) -> &[Vec<usize>] {
        &self.pattern
    }

    /// The columns of each colour.
    pub fn groups(&self) -> &[Vec<usize>] {
        &self.groups
    }
}

impl JacobianEvaluator {
    /// An evaluator for a system of dimension `scale.len()` with the increment floors `scale`
    /// (each > 0; non-positive or non-finite entries are replaced by 1).
    pub fn new(scale: Vec<f64>) -> Self {
        let n = scale.len();
        let scale = scale
            .into_iter()
            .map(|s| if s.is_finite() && s > 0.0 { s } else { 1.0 })
            .collect();
        JacobianEvaluator {
            scale,
            ytmp: vec![0.0; n],
            ftmp: vec![0.0; n],
            colouring: None,
            deltas: vec![0.0; n],
        }
    }

    /// Writes ∂f/∂y at (t, y) into `jac` (n × n): the system's Jacobian when it has one,
    /// forward differences otherwise. `f0` must hold f(t, y) (used by the differences only).
    pub fn jacobian<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        y: &[f64],
        f0: &[f64],
        jac: MatMut<'_, f64>,
        stats: &mut Stats,
    ) {
        if sys.has_jacobian() {
            let mut jac = jac;
            jac.fill(0.0);
            sys.jacobian(t, y, jac);
            stats.jac_evals += 1;
        } else {
            self.finite_difference(sys, t, y, f0, jac, stats);
        }
    }

    /// Forward-difference Jacobian at (t, y) into `jac`, whatever the system offers.
    /// `f0` must hold f(t, y). Costs n RHS evaluations, or one per colour when the system
    /// gives its sparsity pattern (module documentation).
    pub fn finite_difference<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        y: &[f64],
        f0: &[f64],
        mut jac: MatMut<'_, f64>,
        stats: &mut Stats,
    ) {
        let n = y.len();
        let colouring = self.colouring.get_or_insert_with(|| {
            sys.jacobian_sparsity()
                .filter(|p| p.len() == n)
                .and_then(Colouring::new)
        });
        self.ytmp.copy_from_slice(y);
        match colouring {
            None => {
                for j in 0..n {
                    let delta = increment(y[j], self.scale[j]);
                    self.ytmp[j] = y[j] + delta;
                    sys.rhs(t, &self.ytmp, &mut self.ftmp);
                    self.ytmp[j] = y[j];
                    let inv = 1.0 / delta;
                    for i in 0..n {
                        jac[(i, j)] = (self.ftmp[i] - f0[i]) * inv;
                    }
                }
                stats.rhs_evals += n;
            }
            Some(c) => {
                jac.fill(0.0);
                for group in &c.groups {
                    for &j in group {
                        self.deltas[j] = increment(y[j], self.scale[j]);
                        self.ytmp[j] = y[j] + self.deltas[j];
                    }
                    sys.rhs(t, &self.ytmp, &mut self.ftmp);
                    for &j in group {
                        self.ytmp[j] = y[j];
                        let inv = 1.0 / self.deltas[j];
                        for &i in &c.pattern[j] {
                            jac[(i, j)] = (self.ftmp[i] - f0[i]) * inv;
                        }
                    }
                }
                stats.rhs_evals += c.groups.len();
            }
        }
        stats.jac_evals += 1;
    }

    /// Forward-difference Jacobian at (t, y) into the values of a compressed-column matrix
    /// (column j's rows `row_idx[col_ptr[j]..col_ptr[j + 1]]`, its entries the same range of
    /// `values`), one RHS evaluation per colour of `colouring`, whose pattern must hold every
    /// entry of the matrix's; `f0` must hold f(t, y). O(colours · cost(f) + nnz) work and no
    /// n × n storage: the Jacobian of diffsol's sparse path (crate::linear_algebra). The
    /// increments and the columns of each colour are those of
    /// [`JacobianEvaluator::finite_difference`] with the same pattern.
    #[allow(clippy::too_many_arguments)]
    pub fn sparse_difference<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        y: &[f64],
        f0: &[f64],
        colouring: &Colouring,
        (col_ptr, row_idx): (&[usize], &[usize]),
        values: &mut [f64],
        stats: &mut Stats,
    ) {
        self.ytmp.copy_from_slice(y);
        for group in &colouring.groups {
            for &j in group {
                self.deltas[j] = increment(y[j], self.scale[j]);
                self.ytmp[j] = y[j] + self.deltas[j];
            }
            sys.rhs(t, &self.ytmp, &mut self.ftmp);
            for &j in group {
                self.ytmp[j] = y[j];
                let inv = 1.0 / self.deltas[j];
                for k in col_ptr[j]..col_ptr[j + 1] {
                    let i = row_idx[k];
                    values[k] = (self.ftmp[i] - f0[i]) * inv;
                }
            }
        }
        stats.rhs_evals += colouring.groups.len();
        stats.jac_evals += 1;
    }

    /// Central-difference ∂f/∂t at (t, y) into `out`; `f0` must hold f(t, y). Costs 2 RHS
    /// evaluations. When f is not finite at one of t ± δ_t (a right-hand side defined up to
    /// a time only), the one-sided difference with f0 on the other side is used instead.
    ///
    /// ```text
    /// ∂f/∂t ≈ (f(t₊, y) − f(t₋, y)) / (t₊ − t₋),  t± = t ± δ_t,  δ_t = ε^{1/3} · √max(10⁻⁵, |t|)
    /// ```
    /// Why central: a forward difference has a relative error ~ √ε ≈ 1e-8, and a Rosenbrock
    /// method uses f_t inside its order conditions (the d_i h f_t terms), so that error sets
    /// a floor: measured on Prothero–Robinson y' = λ(y − sin t) + cos t, λ = −1, fixed steps,
    /// the dense output of Rodas5P converged with order 2 (error ≈ 1.6e-8 h²) instead of 4–5,
    /// and at λ = −1e3 the step-end error stalled near 1e-12. The central difference (error
    /// ~ ε^{2/3} ≈ 4e-11) restores the orders (`rodas5p_dense_output_of_a_forced_problem`).
    /// δ_t is RODAS's increment √(ε·max(10⁻⁵, |t|)) (HNW II, §IV.7) with √ε replaced by
    /// ε^{1/3}, the balance of truncation (∝ δ²) and cancellation (∝ ε/δ) of a central
    /// difference (Dennis & Schnabel, §5.6).
    pub fn time_derivative<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        y: &[f64],
        f0: &[f64],
        out: &mut [f64],
        stats: &mut Stats,
    ) {
        let delta = f64::EPSILON.cbrt() * t.abs().max(1e-5).sqrt();
        let (mut tp, mut tm) = (t + delta, t - delta);
        sys.rhs(tp, y, &mut self.ftmp);
        sys.rhs(tm, y, out);
        stats.rhs_evals += 2;
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !finite(&self.ftmp) {
            self.ftmp.copy_from_slice(f0);
            tp = t;
        } else if !finite(out) {
            out.copy_from_slice(f0);
            tm = t;
        }
        let inv = 1.0 / (tp - tm);
        for (o, fp) in out.iter_mut().zip(&self.ftmp) {
            *o = (fp - *o) * inv;
        }
    }
}

/// The forward-difference increment of a component y_j with floor s_j: √ε·max(|y_j|, s_j),
/// rounded so that (y_j + δ) − y_j = δ exactly (module documentation).
pub(crate) fn increment(yj: f64, scale: f64) -> f64 {
    let mut delta = f64::EPSILON.sqrt() * yj.abs().max(scale);
    let yp = yj + delta;
    delta = yp - yj;
    if delta == 0.0 {
        delta = f64::MIN_POSITIVE.max(yj.abs() * f64::EPSILON);
    }
    delta
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    /// f = (y0² y1, sin(y0) + t y1), J = [[2 y0 y1, y0²], [cos y0, t]], f_t = (0, y1).
    struct Quad;
    impl OdeSystem for Quad {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[0] * y[0] * y[1];
            dy[1] = y[0].sin() + t * y[1];
        }
    }

    #[test]
    fn finite_differences_match_the_analytic_jacobian() {
        let (t, y) = (0.7, [1.3, -0.4]);
        let mut f0 = [0.0; 2];
        Quad.rhs(t, &y, &mut f0);
        let mut ev = JacobianEvaluator::new(vec![1e-3; 2]);
        let mut jac = Mat::<f64>::zeros(2, 2);
        let mut stats = Stats::default();
        ev.jacobian(&Quad, t, &y, &f0, jac.as_mut(), &mut stats);
        let exact = [[2.0 * y[0] * y[1], y[0] * y[0]], [y[0].cos(), t]];
        // Forward differences: error ≈ |f''| δ/2 + ε|f|/δ with δ ≈ 1.5e-8·|y|, i.e. ~1e-8.
        for i in 0..2 {
            for j in 0..2 {
                let e = (jac[(i, j)] - exact[i][j]).abs();
                assert!(e < 3e-8 * (1.0 + exact[i][j].abs()), "J[{i},{j}] err {e}");
            }
        }
        assert_eq!(stats.rhs_evals, 2);
        assert_eq!(stats.jac_evals, 1);
        let mut ft = [0.0; 2];
        ev.time_derivative(&Quad, t, &y, &f0, &mut ft, &mut stats);
        // f is linear in t: the central difference is exact up to cancellation, ε|f|/δ_t
        // with δ_t ≈ 5e-6 (the forward difference of before reached only 1e-7 here).
        assert!(
            ft[0].abs() < 1e-12 && (ft[1] - y[1]).abs() < 1e-10,
            "{ft:?}"
        );
        assert_eq!(stats.rhs_evals, 4);
    }

    #[test]
    fn zero_components_use_the_floor() {
        // At y = 0 the increment is √ε·s; with s = 1e-3 the column of y0² y1 w.r.t. y0 is
        // 2 y0 y1 + δ y1 = δ y1, with y1 = 0 exactly 0.
        let y = [0.0, 0.0];
        let mut f0 = [0.0; 2];
        Quad.rhs(0.0, &y, &mut f0);
        let mut ev = JacobianEvaluator::new(vec![1e-3, 1e-3]);
        let mut jac = Mat::<f64>::zeros(2, 2);
        ev.finite_difference(&Quad, 0.0, &y, &f0, jac.as_mut(), &mut Stats::default());
        assert_eq!(jac[(0, 0)], 0.0);
        assert!((jac[(1, 0)] - 1.0).abs() < 1e-10);
        assert!((0..2).all(|i| (0..2).all(|j| jac[(i, j)].is_finite())));
    }

    /// scipy's test_num_jac_sparse system: f_i couples y_{i−1}, y_i, y_{i+1} (tridiagonal),
    /// f_0 = 2 e_0, f_i = 3 e_{i−1} + 2 e_i, f_{n−1} = 3 e_{n−2}, e_i = y_{i+1}³ − y_i².
    struct Tri {
        n: usize,
        sparse: bool,
    }
    impl OdeSystem for Tri {
        fn dim(&self) -> usize {
            self.n
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            let n = self.n;
            let e = |i: usize| y[i + 1].powi(3) - y[i] * y[i];
            dy[0] = 2.0 * e(0);
            for i in 1..n - 1 {
                dy[i] = 3.0 * e(i - 1) + 2.0 * e(i);
            }
            dy[n - 1] = 3.0 * e(n - 2);
        }
        fn jacobian_sparsity(&self) -> Option<Vec<Vec<usize>>> {
            self.sparse.then(|| {
                (0..self.n)
                    .map(|j| (j.saturating_sub(1)..(j + 2).min(self.n)).collect())
                    .collect()
            })
        }
    }

    #[test]
    fn a_coloured_jacobian_equals_the_dense_one_at_the_cost_of_its_colours() {
        let n = 20;
        // A fixed pseudo-random state (no RNG dependency): y_j = sin(1.7 j + 0.3).
        let y: Vec<f64> = (0..n).map(|j| (1.7 * j as f64 + 0.3).sin()).collect();
        let mut f0 = vec![0.0; n];
        let dense_sys = Tri { n, sparse: false };
        dense_sys.rhs(0.0, &y, &mut f0);
        let mut dense = Mat::<f64>::zeros(n, n);
        let mut sd = Stats::default();
        JacobianEvaluator::new(vec![1e-3; n]).finite_difference(
            &dense_sys,
            0.0,
            &y,
            &f0,
            dense.as_mut(),
            &mut sd,
        );
        let mut sparse = Mat::<f64>::from_fn(n, n, |_, _| f64::NAN);
        let mut ss = Stats::default();
        let mut ev = JacobianEvaluator::new(vec![1e-3; n]);
        let sys = Tri { n, sparse: true };
        ev.finite_difference(&sys, 0.0, &y, &f0, sparse.as_mut(), &mut ss);
        // The same increments and the same differences: entries in the pattern agree to the
        // rounding of f (scipy asks 1e-12 relative), and those outside it are exactly 0, as
        // the dense differences of a function that does not depend on them.
        for i in 0..n {
            for j in 0..n {
                let (d, s) = (dense[(i, j)], sparse[(i, j)]);
                assert!(
                    (d - s).abs() <= 1e-12 * d.abs().max(1e-2),
                    "J[{i},{j}] {d} {s}"
                );
                if i.abs_diff(j) > 1 {
                    assert_eq!(s, 0.0);
                }
            }
        }
        // A tridiagonal pattern needs 3 colours: 3 RHS evaluations instead of n = 20.
        assert_eq!(sd.rhs_evals, n);
        assert_eq!(ss.rhs_evals, 3);
        assert_eq!(ss.jac_evals, 1);
        // The colouring is kept: a second Jacobian costs 3 again.
        ev.finite_difference(&sys, 0.0, &y, &f0, sparse.as_mut(), &mut ss);
        assert_eq!(ss.rhs_evals, 6);
    }

    #[test]
    fn colourings_of_simple_patterns() {
        let diag = Colouring::new((0..5).map(|j| vec![j]).collect()).unwrap();
        assert_eq!(diag.colours(), 1);
        let full = Colouring::new(vec![(0..4).collect(); 4]).unwrap();
        assert_eq!(full.colours(), 4);
        // Tridiagonal: columns j, j+3, j+6, … share a colour.
        let tri: Vec<Vec<usize>> = (0..7usize)
            .map(|j| (j.saturating_sub(1)..(j + 2).min(7)).collect())
            .collect();
        let c = Colouring::new(tri).unwrap();
        assert_eq!(c.groups(), &[vec![0, 3, 6], vec![1, 4], vec![2, 5]]);
        // A row index out of range is no pattern.
        assert!(Colouring::new(vec![vec![0], vec![2]]).is_none());
    }
}
