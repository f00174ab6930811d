//! Cholesky kernels of the constraint solve: dense (row-major, lower triangle) and in the
//! envelope of a sparse matrix ([`Envelope`]).
//!
//! ```text
//! S = L Lᵀ (in place);  L Lᵀ x = b (forward, then back substitution)
//! ```

/// Cholesky factorisation S = L Lᵀ in place: the lower triangle of the row-major m × m
/// `smat` (holding S) becomes L. `Err(j)` when the pivot d_j = S_jj − Σ_{k<j} L_jk² of row j
/// is not a positive number (S is not positive definite in f64); d_j is then left at (j, j).
/// The reference of [`Envelope::factor`] without `INV`.
#[cfg(test)]
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

/// The envelope (profile, skyline) of a symmetric positive definite matrix S whose rows fall
/// into independent diagonal blocks (rows in different blocks share no entry): row a keeps its
/// entries from the first structurally nonzero column of its block up to the diagonal, stored
/// contiguously, and the Cholesky factor fills in only inside that envelope.
///
/// ```text
/// block B = (r_0 < r_1 < …),  pos(r_p) = p,  first(a) = min { pos(b) : S_ab ≠ 0, b ≤ a }
/// L_ab = 0 for pos(b) < first(a)      (George & Liu, Computer Solution of Large Sparse
///                                      Positive Definite Systems, 1981, §4.2)
/// storage: Σ_a (pos(a) − first(a) + 1) entries;  factor: Σ_a (pos(a) − first(a))² / 2 flops
/// ```
/// The factorisation and solves run the dense kernels' operations in the dense kernels'
/// order, skipping only products with an entry of L outside the envelope (an exact zero): a
/// chain's S is banded and costs O(m) instead of O(m³), with the same numbers.
#[derive(Clone, Debug, Default)]
pub(crate) struct Envelope {
    /// The rows of each block, increasing.
    blocks: Vec<Vec<usize>>,
    /// The block of each row.
    block: Vec<usize>,
    /// The position of each row in its block.
    pos: Vec<usize>,
    /// The position (in its block) of the first column of each row's envelope.
    first: Vec<usize>,
    /// The last position q of the row's block with first(r_q) ≤ pos(row): the rows below the
    /// diagonal whose envelope reaches this row's column.
    last: Vec<usize>,
    /// The offset of each row's first envelope entry in the storage.
    off: Vec<usize>,
    /// Entries stored.
    len: usize,
}

impl Envelope {
    /// The envelope of an m × m matrix with diagonal blocks `blocks` (each increasing, together
    /// every row once) and the structural nonzeros `nonzeros` (a, b), a ≥ b, of its lower
    /// triangle (both rows in one block). The diagonal is always in the envelope.
    pub(crate) fn new(
        m: usize,
        blocks: Vec<Vec<usize>>,
        nonzeros: impl Iterator<Item = (usize, usize)>,
    ) -> Envelope {
        let (mut block, mut pos) = (vec![0; m], vec![0; m]);
        for (bi, blk) in blocks.iter().enumerate() {
            for (p, &r) in blk.iter().enumerate() {
                block[r] = bi;
                pos[r] = p;
            }
        }
        let mut first = pos.clone();
        for (a, b) in nonzeros {
            debug_assert!(a >= b && block[a] == block[b]);
            first[a] = first[a].min(pos[b]);
        }
        let mut last = pos.clone();
        for blk in &blocks {
            for &r in blk {
                for &s in &blk[first[r]..pos[r]] {
                    last[s] = last[s].max(pos[r]);
                }
            }
        }
        let mut off = vec![0; m];
        let mut len = 0;
        for a in 0..m {
            off[a] = len;
            len += pos[a] - first[a] + 1;
        }
        Envelope {
            blocks,
            block,
            pos,
            first,
            last,
            off,
            len,
        }
    }

    /// Entries stored (the length of a matrix or factor in this envelope).
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The rows of each diagonal block.
    pub(crate) fn blocks(&self) -> &[Vec<usize>] {
        &self.blocks
    }

    /// The index of entry (a, b), a ≥ b in one block, inside the envelope.
    #[inline]
    pub(crate) fn at(&self, a: usize, b: usize) -> usize {
        debug_assert!(self.pos[b] >= self.first[a] && self.pos[b] <= self.pos[a]);
        self.off[a] + self.pos[b] - self.first[a]
    }

    /// The index of the diagonal entry of row a.
    #[inline]
    pub(crate) fn diag(&self, a: usize) -> usize {
        self.off[a] + self.pos[a] - self.first[a]
    }

    /// Cholesky factorisation S = L Lᵀ in place, row by row in increasing row order: the
    /// envelope of S becomes that of L. With `INV` the diagonal holds 1/L_jj and the entries
    /// below it are multiplied by it ([`block_cholesky_inv`]'s numbers), else the diagonal
    /// holds L_jj and they are divided by it ([`cholesky_in_place`]'s numbers). `Err(j)` for
    /// the first row j whose pivot d_j = S_jj − Σ_k L_jk² is not a positive number, left at
    /// its diagonal; the rows before j are factored.
    pub(crate) fn factor<const INV: bool>(&self, l: &mut [f64]) -> Result<(), usize> {
        for a in 0..self.pos.len() {
            let blk = &self.blocks[self.block[a]];
            let (p, fa, oa) = (self.pos[a], self.first[a], self.off[a]);
            for q in fa..p {
                let j = blk[q];
                let (fj, oj) = (self.first[j], self.off[j]);
                let k0 = fa.max(fj);
                let mut s = l[oa + q - fa];
                for k in k0..q {
                    s -= l[oa + k - fa] * l[oj + k - fj];
                }
                let dj = l[oj + q - fj];
                l[oa + q - fa] = if INV { s * dj } else { s / dj };
            }
            let mut d = l[oa + p - fa];
            for &v in &l[oa..oa + p - fa] {
                d -= v * v;
            }
            if !(d > 0.0) {
                l[oa + p - fa] = d;
                return Err(a);
            }
            let d = d.sqrt();
            l[oa + p - fa] = if INV { 1.0 / d } else { d };
        }
        Ok(())
    }

    /// Solves L Lᵀ x = b in place after [`Envelope::factor`] with `INV` (forward, then back
    /// substitution; [`cholesky_solve`]'s numbers).
    pub(crate) fn solve(&self, l: &[f64], b: &mut [f64]) {
        let m = self.pos.len();
        for a in 0..m {
            let blk = &self.blocks[self.block[a]];
            let (p, fa, oa) = (self.pos[a], self.first[a], self.off[a]);
            let mut s = b[a];
            for (k, &r) in blk.iter().enumerate().take(p).skip(fa) {
                s -= l[oa + k - fa] * b[r];
            }
            b[a] = s * l[oa + p - fa];
        }
        for a in (0..m).rev() {
            let blk = &self.blocks[self.block[a]];
            let p = self.pos[a];
            let mut s = b[a];
            for &r in &blk[p + 1..=self.last[a]] {
                if self.first[r] <= p {
                    s -= l[self.off[r] + p - self.first[r]] * b[r];
                }
            }
            b[a] = s * l[self.diag(a)];
        }
    }

    /// [`Envelope::solve`] on `width` right-hand sides at once: `b` is m × `width`, row-major
    /// (row a holds the a-th entry of every right-hand side), each of its columns solved with
    /// the numbers of [`Envelope::solve`], the inner loops running along the rows.
    pub(crate) fn solve_rows(&self, l: &[f64], b: &mut [f64], width: usize) {
        let m = self.pos.len();
        let mut acc = vec![0.0; width];
        for a in 0..m {
            let blk = &self.blocks[self.block[a]];
            let (p, fa, oa) = (self.pos[a], self.first[a], self.off[a]);
            acc.copy_from_slice(&b[a * width..(a + 1) * width]);
            for (k, &r) in blk.iter().enumerate().take(p).skip(fa) {
                let lk = l[oa + k - fa];
                for (s, v) in acc.iter_mut().zip(&b[r * width..(r + 1) * width]) {
                    *s -= lk * v;
                }
            }
            let d = l[oa + p - fa];
            for (x, s) in b[a * width..(a + 1) * width].iter_mut().zip(&acc) {
                *x = s * d;
            }
        }
        for a in (0..m).rev() {
            let blk = &self.blocks[self.block[a]];
            let p = self.pos[a];
            acc.copy_from_slice(&b[a * width..(a + 1) * width]);
            for &r in &blk[p + 1..=self.last[a]] {
                if self.first[r] <= p {
                    let lr = l[self.off[r] + p - self.first[r]];
                    for (s, v) in acc.iter_mut().zip(&b[r * width..(r + 1) * width]) {
                        *s -= lr * v;
                    }
                }
            }
            let d = l[self.diag(a)];
            for (x, s) in b[a * width..(a + 1) * width].iter_mut().zip(&acc) {
                *x = s * d;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    //! The envelope kernels give the dense kernels' numbers bit for bit.
    use super::*;

    /// A symmetric positive definite 7 × 7 matrix in two blocks, {0, 2, 3, 6} (an arrow and a
    /// band) and {1, 4, 5}, with the structural nonzeros of its lower triangle.
    type Example = (Vec<f64>, Vec<Vec<usize>>, Vec<(usize, usize)>);

    fn example() -> Example {
        let m = 7;
        let nz = [(2, 0), (3, 2), (6, 0), (6, 3), (4, 1), (5, 4)];
        let mut s = vec![0.0; m * m];
        for (k, &(a, b)) in nz.iter().enumerate() {
            let v = 0.3 + 0.1 * k as f64 * if k % 2 == 0 { 1.0 } else { -1.0 };
            s[a * m + b] = v;
            s[b * m + a] = v;
        }
        for a in 0..m {
            s[a * m + a] = 2.0 + 0.37 * a as f64;
        }
        let mut pairs: Vec<(usize, usize)> = nz.to_vec();
        pairs.extend((0..m).map(|a| (a, a)));
        (s, vec![vec![0, 2, 3, 6], vec![1, 4, 5]], pairs)
    }

    fn load(env: &Envelope, s: &[f64], pairs: &[(usize, usize)], m: usize) -> Vec<f64> {
        let mut l = vec![0.0; env.len()];
        for &(a, b) in pairs {
            l[env.at(a, b)] = s[a * m + b];
        }
        l
    }

    #[test]
    fn envelope_factor_and_solve_equal_the_dense_kernels() {
        let m = 7;
        let (s, blocks, pairs) = example();
        let env = Envelope::new(m, blocks.clone(), pairs.iter().copied());
        // Rows 6's envelope reaches back to row 0 (position 0 of its block): 4 entries.
        assert_eq!(env.len(), 1 + 1 + 2 + 2 + 2 + 2 + 4);
        // Without INV: cholesky_in_place's factor.
        let mut dense = s.clone();
        cholesky_in_place(&mut dense, m).unwrap();
        let mut l = load(&env, &s, &pairs, m);
        env.factor::<false>(&mut l).unwrap();
        for a in 0..m {
            for &b in &blocks[env.block[a]][env.first[a]..=env.pos[a]] {
                assert_eq!(l[env.at(a, b)].to_bits(), dense[a * m + b].to_bits());
            }
        }
        // With INV: block_cholesky_inv's factor and cholesky_solve's solution.
        let mut dense = s.clone();
        for blk in &blocks {
            block_cholesky_inv(&mut dense, m, blk).unwrap();
        }
        let mut l = load(&env, &s, &pairs, m);
        env.factor::<true>(&mut l).unwrap();
        for a in 0..m {
            for &b in &blocks[env.block[a]][env.first[a]..=env.pos[a]] {
                assert_eq!(l[env.at(a, b)].to_bits(), dense[a * m + b].to_bits());
            }
        }
        let rhs: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7).sin() + 0.1).collect();
        let (mut x, mut y) = (rhs.clone(), rhs.clone());
        cholesky_solve(&dense, m, &mut x);
        env.solve(&l, &mut y);
        assert_eq!(
            x.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            y.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        // And it solves S x = b.
        for i in 0..m {
            let r: f64 = (0..m).map(|j| s[i * m + j] * y[j]).sum();
            assert!((r - rhs[i]).abs() < 1e-14, "{i}: {r} vs {}", rhs[i]);
        }
    }

    /// `solve_rows` on three right-hand sides gives each column `solve`'s numbers, bit for bit.
    #[test]
    fn envelope_solve_rows_equals_solve_per_column() {
        let m = 7;
        let (s, blocks, pairs) = example();
        let env = Envelope::new(m, blocks, pairs.iter().copied());
        let mut l = load(&env, &s, &pairs, m);
        env.factor::<true>(&mut l).unwrap();
        let width = 3;
        let mut b: Vec<f64> = (0..m * width)
            .map(|k| (k as f64 * 0.37).cos() - 0.2)
            .collect();
        let cols: Vec<Vec<f64>> = (0..width)
            .map(|c| {
                let mut x: Vec<f64> = (0..m).map(|a| b[a * width + c]).collect();
                env.solve(&l, &mut x);
                x
            })
            .collect();
        env.solve_rows(&l, &mut b, width);
        for (c, x) in cols.iter().enumerate() {
            for a in 0..m {
                assert_eq!(
                    b[a * width + c].to_bits(),
                    x[a].to_bits(),
                    "row {a} column {c}"
                );
            }
        }
    }

    #[test]
    fn envelope_reports_the_first_non_positive_pivot_in_row_order() {
        let m = 7;
        let (mut s, blocks, pairs) = example();
        // Row 5 (block 2) and row 6 (block 1) singular; row 5 comes first.
        s[5 * m + 5] = s[5 * m + 4] * s[5 * m + 4] / 4.0;
        s[6 * m + 6] = 0.0;
        let env = Envelope::new(m, blocks, pairs.iter().copied());
        let mut dense = s.clone();
        let want = cholesky_in_place(&mut dense, m).unwrap_err();
        let mut l = load(&env, &s, &pairs, m);
        assert_eq!(env.factor::<false>(&mut l), Err(want));
        assert_eq!(want, 5);
        assert_eq!(l[env.diag(5)].to_bits(), dense[5 * m + 5].to_bits());
    }
}
