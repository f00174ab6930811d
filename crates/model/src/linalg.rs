//! Dense Cholesky kernels of the constraint solve (row-major, lower triangle).
//!
//! ```text
//! S = L Lᵀ (in place);  L Lᵀ x = b (forward, then back substitution)
//! ```

/// Cholesky factorisation S = L Lᵀ in place: the lower triangle of the row-major m × m
/// `smat` (holding S) becomes L. `Err(j)` when the pivot d_j = S_jj − Σ_{k<j} L_jk² of row j
/// is not a positive number (S is not positive definite in f64); d_j is then left at (j, j).
#[inline]
pub(crate) fn cholesky_in_place(smat: &mut [f64], m: usize) -> Result<(), usize> {
    for j in 0..m {
        let (row_j, rest) = smat[j * m..m * m].split_at_mut(m);
        let mut d = row_j[j];
        for &v in &row_j[..j] {
            d -= v * v;
        }
        if !(d > 0.0) {
            row_j[j] = d;
            return Err(j);
        }
        let d = d.sqrt();
        row_j[j] = d;
        let lj = &row_j[..j];
        for row_i in rest.chunks_exact_mut(m) {
            let mut s = row_i[j];
            for (&x, &y) in row_i[..j].iter().zip(lj) {
                s -= x * y;
            }
            row_i[j] = s / d;
        }
    }
    Ok(())
}

/// Cholesky factorisation S = L Lᵀ in place over the rows `blk` of a diagonal block of S (the
/// entries of S between `blk` and the other rows being zero, those of L are too): the strict
/// lower triangle of the row-major m × m `smat` becomes that of L and its diagonal holds
/// 1/L_jj, so that the solves multiply instead of divide (one division per column, none per
/// solve: the latency of divisions and square roots dominated the Schur-complement solve of a
/// small S). `Err(j)` when the pivot d_j = S_jj − Σ_k L_jk² of row j is not a positive number
/// (S is not positive definite in f64).
#[inline]
pub(crate) fn block_cholesky_inv(smat: &mut [f64], m: usize, blk: &[usize]) -> Result<(), usize> {
    for (p, &j) in blk.iter().enumerate() {
        let mut d = smat[j * m + j];
        for &k in &blk[..p] {
            let v = smat[j * m + k];
            d -= v * v;
        }
        if !(d > 0.0) {
            smat[j * m + j] = d;
            return Err(j);
        }
        let r = 1.0 / d.sqrt();
        smat[j * m + j] = r;
        for &i in &blk[p + 1..] {
            let mut s = smat[i * m + j];
            for &k in &blk[..p] {
                s -= smat[i * m + k] * smat[j * m + k];
            }
            smat[i * m + j] = s * r;
        }
    }
    Ok(())
}

/// [`cholesky_solve`] restricted to the rows `blk` of a diagonal block (after
/// [`block_cholesky_inv`]).
#[inline]
pub(crate) fn block_cholesky_solve(l: &[f64], m: usize, blk: &[usize], b: &mut [f64]) {
    for (p, &i) in blk.iter().enumerate() {
        let mut s = b[i];
        for &k in &blk[..p] {
            s -= l[i * m + k] * b[k];
        }
        b[i] = s * l[i * m + i];
    }
    for (p, &i) in blk.iter().enumerate().rev() {
        let mut s = b[i];
        for &k in &blk[p + 1..] {
            s -= l[k * m + i] * b[k];
        }
        b[i] = s * l[i * m + i];
    }
}

/// Solves L Lᵀ x = b in place (forward, then back substitution), L the dense factor left by
/// [`block_cholesky_inv`] on every block of S (the diagonal holding 1/L_jj).
#[inline]
pub(crate) fn cholesky_solve(l: &[f64], m: usize, b: &mut [f64]) {
    let l = &l[..m * m];
    let b = &mut b[..m];
    for i in 0..m {
        let li = &l[i * m..i * m + i];
        let mut s = b[i];
        for (&x, &y) in li.iter().zip(&b[..i]) {
            s -= x * y;
        }
        b[i] = s * l[i * m + i];
    }
    for i in (0..m).rev() {
        let mut s = b[i];
        for k in i + 1..m {
            s -= l[k * m + i] * b[k];
        }
        b[i] = s * l[i * m + i];
    }
}

/// `v` resized to `len` and zeroed (no allocation once it has been that long).
pub(crate) fn zeroed<T: Copy + Default>(v: &mut Vec<T>, len: usize) -> &mut [T] {
    v.clear();
    v.resize(len, T::default());
    v
}

/// Starts ∂f/∂y of a first-order system y = (q, q̇), f = (q̇, q̈) with n_q = `nq`: `jac`
/// (2 n_q × 2 n_q) zeroed with the identity in its upper right block; when the evaluation at
/// (t, y) failed (`ok` false) its lower rows are NaN. The formulations fill the lower rows.
pub(crate) fn first_order_jacobian_frame(jac: &mut faer::MatMut<'_, f64>, nq: usize, ok: bool) {
    let n = 2 * nq;
    jac.fill(0.0);
    for i in 0..nq {
        jac[(i, nq + i)] = 1.0;
    }
    if !ok {
        for j in 0..n {
            for i in nq..n {
                jac[(i, j)] = f64::NAN;
            }
        }
    }
}
