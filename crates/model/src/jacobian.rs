//! The Jacobian ∂f/∂y of the mechanism ODE for implicit methods (docs/model.md §1.7): the
//! formulation's, given the applied forces' ∂g/∂(q, q̇).
//!
//! ```text
//! f(t, y) = formulation(y, q̈(t, q, q̇; g)),  g = g(q, q̇) the applied forces
//! ∂g/∂(q, q̇): mechanism/forces.rs (each revolute clearance joint's closed form,
//!             clearance/revolute_jacobian.rs; each force element's closed form or central
//!             differences of the others and of the prismatic clearance joints)
//! ∂f/∂t:      minimal's (the prescribed bodies carry their subtrees: the same ∂g/∂(q, q̇)
//!             times ∂(q, q̇)/∂t; mechanism/formulation/minimal/jacobian.rs); the others
//!             leave it to the integrator's difference in t
//! ∂f/∂y:      the formulation's (Lagrange–Baumgarte:
//!             mechanism/formulation/lagrange_baumgarte/jacobian.rs)
//! ```

use faer::MatMut;

use crate::mechanism::bodies::Owner;
use crate::mechanism::formulation::Formulation;
use crate::mechanism::Mechanism;

/// Fills `jac` (n × n) with ∂f/∂y at (t, y); NaN rows when the evaluation fails.
pub(crate) fn jacobian(mech: &Mechanism, t: f64, y: &[f64], jac: MatMut<'_, f64>) {
    let mut sc = mech.scratch();
    if !mech.evaluate(t, y, &mut sc, false) {
        mech.formulation()
            .jacobian(mech.constraints(), &sc, None, jac);
        return;
    }
    let mut fw = mech.force_jac_work();
    mech.forces().jacobian(mech.bodies(), t, &sc, &mut fw);
    mech.formulation()
        .jacobian(mech.constraints(), &sc, Some(&fw.dg), jac);
}

/// ∂f/∂t at (t, y) into `out` when the formulation gives it (minimal: its
/// `time_derivative`, from the forces' closed-form ∂g/∂(q, q̇)); false (nothing written)
/// otherwise. NaN when the evaluation fails.
pub(crate) fn time_derivative(mech: &Mechanism, t: f64, y: &[f64], out: &mut [f64]) -> bool {
    let form = mech.formulation();
    if !form.has_time_derivative() {
        return false;
    }
    let mut sc = mech.scratch();
    if !mech.evaluate(t, y, &mut sc, false) {
        out.iter_mut().for_each(|v| *v = f64::NAN);
        return true;
    }
    let mut fw = mech.force_jac_work();
    mech.forces().jacobian(mech.bodies(), t, &sc, &mut fw);
    form.time_derivative(mech.bodies(), mech.forces(), t, &sc, &fw.dg, out)
}

impl Mechanism {
    /// The sparsity pattern of ∂f/∂y: for each column j of the state, the rows where ∂f/∂y_j
    /// may be nonzero, ascending (dense blocks over the mechanism's constraint clusters,
    /// coupled in pairs by the force elements between them; crate::jacobian). Dense (every
    /// row in every column) when the mechanism is one cluster, as a chain or the press.
    pub fn jacobian_pattern(&self) -> Vec<Vec<usize>> {
        pattern(self)
    }

    /// [`OdeSystem::jacobian_sparsity`]: the pattern of [`Mechanism::jacobian_pattern`] when
    /// it is not full, None (dense) when it is (one cluster, or clusters all coupled).
    ///
    /// [`OdeSystem::jacobian_sparsity`]: lash_solver::OdeSystem::jacobian_sparsity
    pub(crate) fn sparsity(&self) -> Option<Vec<Vec<usize>>> {
        let n = lash_solver::OdeSystem::dim(self);
        (pattern_nnz(self) < n * n).then(|| pattern(self))
    }
}

/// The sparsity pattern of ∂f/∂y (for each column j of y, the rows i where ∂f_i/∂y_j may be
/// nonzero, ascending): dense blocks over the mechanism's constraint clusters, coupled in
/// pairs by the force elements between them.
///
/// ```text
/// absolute formulations (Lagrange–Baumgarte, augmented Lagrangian):
///   cluster   integrated bodies joined by constraint rows (the ideal joints and the drivers
///             of integrated bodies), transitively; every other integrated body alone
///   coupling  a force node (an element, a joint without constraint rows — a clearance joint
///             —, a body's own forces) reaching bodies of clusters A and B couples A × B and
///             B × A (force_reach: the bodies it names, transitively through the joints and
///             elements it names)
///   pattern   the state components (q, q̇) of cluster A depend on those of A and of every
///             cluster coupled with A, on no other
/// minimal:    one block per cluster of bodies joined by a joint (ideal, driver or clearance)
///             or a force element, transitively (a body's θ moves its whole tree, and a force
///             on it reaches the tree's root through the mass matrix); no couplings between
///             blocks
/// ```
/// Why it covers ∂f/∂y: a body's applied forces come from the force nodes that reach it,
/// which read only the bodies they reach; the constraint solve couples the bodies of one
/// connected set of constraint rows (S = Φ_q M⁻¹ Φ_qᵀ, and M + Φ_qᵀαΦ_q, are block diagonal
/// over them), so q̈ of cluster A reads g of A's bodies only; a prescribed body is a function
/// of t. A chain of N links whose elbows are clearance joints is N clusters, block
/// tridiagonal (36 (3N − 2) entries instead of 36 N²). The names are read from the scene's
/// JSON form of each joint, element and body (every string equal to a body, joint or element
/// name), so a reference of a kind added later is counted without code here. The augmented
/// Lagrangian's multiplier iteration stops on a global test, which couples clusters only
/// through when it stops (below its tolerance).
fn pattern(mech: &Mechanism) -> Vec<Vec<usize>> {
    let (blocks, coupled) = coupled_blocks(mech);
    let n = blocks.iter().map(Vec::len).sum::<usize>();
    let mut pattern = vec![Vec::new(); n];
    for (b, block) in blocks.iter().enumerate() {
        let mut rows: Vec<usize> = coupled[b]
            .iter()
            .flat_map(|&a| blocks[a].iter().copied())
            .collect();
        rows.sort_unstable();
        for &j in block {
            pattern[j] = rows.clone();
        }
    }
    pattern
}

/// Entries of [`pattern`] without building it.
fn pattern_nnz(mech: &Mechanism) -> usize {
    let (blocks, coupled) = coupled_blocks(mech);
    coupled
        .iter()
        .zip(&blocks)
        .map(|(with, block)| block.len() * with.iter().map(|&a| blocks[a].len()).sum::<usize>())
        .sum()
}

/// The state components of each cluster ([`pattern`]), clusters in order of their first
/// body, and for each cluster the clusters it is coupled with (itself included, ascending).
fn coupled_blocks(mech: &Mechanism) -> (Vec<Vec<usize>>, Vec<Vec<usize>>) {
    let absolute = !matches!(mech.formulation(), Formulation::Minimal(_));
    let clusters = if absolute {
        constraint_clusters(mech)
    } else {
        body_clusters(mech)
    };
    // State components of each integrated body.
    let nint = clusters.len();
    let mut of_body: Vec<Vec<usize>> = vec![Vec::new(); nint];
    match mech.formulation() {
        Formulation::LagrangeBaumgarte(_) | Formulation::AugmentedLagrangian(_) => {
            let nq = mech.nq();
            for (i, comps) in of_body.iter_mut().enumerate() {
                comps.extend((0..3).map(|k| 3 * i + k));
                comps.extend((0..3).map(|k| nq + 3 * i + k));
            }
        }
        Formulation::Minimal(f) => {
            let tree = f.tree();
            for tb in &tree.bodies {
                let d = tb.link.dof();
                of_body[tb.int].extend(tb.col..tb.col + d);
                of_body[tb.int].extend(tree.n + tb.col..tree.n + tb.col + d);
            }
        }
    }
    let mut index_of_root = vec![usize::MAX; nint];
    let mut blocks: Vec<Vec<usize>> = Vec::new();
    let mut block_of_body = vec![0; nint];
    for (i, comps) in of_body.into_iter().enumerate() {
        let root = clusters[i];
        if index_of_root[root] == usize::MAX {
            index_of_root[root] = blocks.len();
            blocks.push(Vec::new());
        }
        block_of_body[i] = index_of_root[root];
        blocks[index_of_root[root]].extend(comps);
    }
    let mut coupled: Vec<Vec<usize>> = (0..blocks.len()).map(|b| vec![b]).collect();
    if absolute {
        for reach in force_reach(mech) {
            let mut bs: Vec<usize> = reach.iter().map(|&i| block_of_body[i]).collect();
            bs.sort_unstable();
            bs.dedup();
            for &a in &bs {
                coupled[a].extend(&bs);
            }
        }
    }
    for with in &mut coupled {
        with.sort_unstable();
        with.dedup();
    }
    // Blocks without state components (bodies of no coordinates) are dropped, their indices
    // kept consistent.
    let keep: Vec<bool> = blocks.iter().map(|b| !b.is_empty()).collect();
    if keep.iter().all(|&k| k) {
        return (blocks, coupled);
    }
    let mut new_index = vec![usize::MAX; blocks.len()];
    let mut count = 0;
    for (b, &k) in keep.iter().enumerate() {
        if k {
            new_index[b] = count;
            count += 1;
        }
    }
    let coupled = coupled
        .into_iter()
        .zip(&keep)
        .filter(|(_, &k)| k)
        .map(|(with, _)| {
            with.into_iter()
                .filter(|&a| keep[a])
                .map(|a| new_index[a])
                .collect()
        })
        .collect();
    blocks.retain(|b| !b.is_empty());
    (blocks, coupled)
}

/// For each integrated body, a representative integrated body of its constraint cluster
/// (integrated bodies joined by constraint rows, [`pattern`]).
fn constraint_clusters(mech: &Mechanism) -> Vec<usize> {
    let nint = mech.nq() / 3;
    let mut uf = UnionFind::new(nint);
    let cons = mech.constraints();
    for (row, ints) in cons.rows.iter().zip(&cons.row_int) {
        let mut on = ints[..row.n_terms].iter().flatten();
        if let Some(&first) = on.next() {
            for &other in on {
                uf.union(first, other);
            }
        }
    }
    (0..nint).map(|i| uf.find(i)).collect()
}

/// For each integrated body, a representative integrated body of its cluster ([`pattern`]).
fn body_clusters(mech: &Mechanism) -> Vec<usize> {
    let scene = mech.scene();
    let info = mech.body_info();
    let (nb, nj) = (scene.bodies.len(), scene.joints.len());
    // Nodes: scene bodies, then joints, then force elements.
    let mut uf = UnionFind::new(nb + nj + scene.forces.len());
    let mut names: std::collections::HashMap<&str, Vec<usize>> = Default::default();
    for (k, b) in info.iter().enumerate() {
        if matches!(b.owner, Owner::Int(_)) {
            names.entry(b.name.as_str()).or_default().push(k);
        }
    }
    for (j, joint) in scene.joints.iter().enumerate() {
        names.entry(joint.name()).or_default().push(nb + j);
    }
    for (e, element) in scene.forces.iter().enumerate() {
        names.entry(element.name()).or_default().push(nb + nj + e);
    }
    let mut link = |node: usize, value: serde_json::Value| {
        let mut stack = vec![value];
        while let Some(v) = stack.pop() {
            match v {
                serde_json::Value::String(s) => {
                    for &other in names.get(s.as_str()).into_iter().flatten() {
                        uf.union(node, other);
                    }
                }
                serde_json::Value::Array(a) => stack.extend(a),
                serde_json::Value::Object(o) => stack.extend(o.into_iter().map(|(_, v)| v)),
                _ => {}
            }
        }
    };
    let json = |v: Result<serde_json::Value, serde_json::Error>| v.unwrap_or_default();
    for (j, joint) in scene.joints.iter().enumerate() {
        link(nb + j, json(serde_json::to_value(joint)));
    }
    for (e, element) in scene.forces.iter().enumerate() {
        link(nb + nj + e, json(serde_json::to_value(element)));
    }
    for (k, body) in scene.bodies.iter().enumerate() {
        if matches!(info[k].owner, Owner::Int(_)) {
            link(k, json(serde_json::to_value(body)));
        }
    }
    // A prescribed body is no name above: it joined nothing. Each cluster is named by the
    // integrated index of its first body in scene order.
    let nint = info
        .iter()
        .filter(|b| matches!(b.owner, Owner::Int(_)))
        .count();
    let mut first: std::collections::HashMap<usize, usize> = Default::default();
    let mut out = vec![0; nint];
    for (k, b) in info.iter().enumerate() {
        if let Owner::Int(i) = b.owner {
            out[i] = *first.entry(uf.find(k)).or_insert(i);
        }
    }
    out
}

/// For each force node of the mechanism, the integrated bodies whose applied forces it may
/// set or read, ascending: every force element, every joint without constraint rows (a
/// clearance joint, a driver of a prescribed body) and every integrated body (its own
/// forces). A node reaches the integrated bodies it names (its JSON form's strings, as
/// [`pattern`] reads them) and, transitively, those of the joints and elements it names;
/// never through a body (a body's name is the body, not what acts on it).
pub(crate) fn force_reach(mech: &Mechanism) -> Vec<Vec<usize>> {
    let scene = mech.scene();
    let info = mech.body_info();
    let (nb, nj) = (scene.bodies.len(), scene.joints.len());
    let mut names: std::collections::HashMap<&str, Vec<usize>> = Default::default();
    for (k, b) in info.iter().enumerate() {
        if matches!(b.owner, Owner::Int(_)) {
            names.entry(b.name.as_str()).or_default().push(k);
        }
    }
    for (j, joint) in scene.joints.iter().enumerate() {
        names.entry(joint.name()).or_default().push(nb + j);
    }
    for (e, element) in scene.forces.iter().enumerate() {
        names.entry(element.name()).or_default().push(nb + nj + e);
    }
    let named = |value: serde_json::Value| -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![value];
        while let Some(v) = stack.pop() {
            match v {
                serde_json::Value::String(s) => {
                    out.extend(names.get(s.as_str()).into_iter().flatten());
                }
                serde_json::Value::Array(a) => stack.extend(a),
                serde_json::Value::Object(o) => stack.extend(o.into_iter().map(|(_, v)| v)),
                _ => {}
            }
        }
        out
    };
    let json = |v: Result<serde_json::Value, serde_json::Error>| v.unwrap_or_default();
    // Direct names of each joint and element node (indices nb.. of the node numbering).
    let mut direct: Vec<Vec<usize>> = vec![Vec::new(); nb + nj + scene.forces.len()];
    for (j, joint) in scene.joints.iter().enumerate() {
        direct[nb + j] = named(json(serde_json::to_value(joint)));
    }
    for (e, element) in scene.forces.iter().enumerate() {
        direct[nb + nj + e] = named(json(serde_json::to_value(element)));
    }
    for (k, body) in scene.bodies.iter().enumerate() {
        if matches!(info[k].owner, Owner::Int(_)) {
            direct[k] = named(json(serde_json::to_value(body)));
            direct[k].push(k);
        }
    }
    let mut constrained = vec![false; nj];
    for row in &mech.constraints().rows {
        constrained[row.joint] = true;
    }
    let int_of = |k: usize| match info[k].owner {
        Owner::Int(i) => Some(i),
        Owner::Pres(_) => None,
    };
    let reach_of = |start: usize| -> Vec<usize> {
        let mut seen = std::collections::HashSet::from([start]);
        let mut stack = vec![start];
        let mut out = Vec::new();
        while let Some(node) = stack.pop() {
            for &other in &direct[node] {
                if other < nb {
                    out.extend(int_of(other));
                } else if seen.insert(other) {
                    stack.push(other);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    };
    let mut reach = Vec::new();
    for j in (0..nj).filter(|&j| !constrained[j]) {
        reach.push(reach_of(nb + j));
    }
    for e in 0..scene.forces.len() {
        reach.push(reach_of(nb + nj + e));
    }
    for k in (0..nb).filter(|&k| int_of(k).is_some()) {
        reach.push(reach_of(k));
    }
    reach.retain(|r| !r.is_empty());
    reach
}

/// Disjoint sets with path halving.
struct UnionFind(Vec<usize>);

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind((0..n).collect())
    }
    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb)] = ra.min(rb);
        }
    }
}
