//! The redundant data of every Butcher tableau: row sums, the order conditions of b, b̂ and
//! the continuous extension for all rooted trees (generated, not listed by hand), FSAL rows.
//!
//! ```text
//! tree t = [t_1, …, t_m]:  g(•) = 1,  g(t)_i = Π_k (A g(t_k))_i,  γ(t) = |t| Π_k γ(t_k)
//! order p  ⇔  bᵀ g(t) = 1/γ(t)            for all |t| ≤ p          (Butcher; HNW I §II.2)
//! dense q  ⇔  b(θ)ᵀ g(t) = θ^|t| / γ(t)   for all |t| ≤ q, all θ   (HNW I §II.6, (6.7))
//! ```

use lash_solver::erk::{ErrorEstimate, Tableau, BS32, DOP853, DOPRI54, TSIT54};

/// A rooted tree: its order and its children (indices into the tree list, non-increasing).
struct Tree {
    order: usize,
    children: Vec<usize>,
}

/// All rooted trees up to `max_order`, sorted by order. Each tree of order n is a root with a
/// multiset of smaller trees whose orders add to n − 1; multisets are enumerated as
/// non-increasing index sequences, so every tree appears once.
fn trees(max_order: usize) -> Vec<Tree> {
    let mut list = vec![Tree {
        order: 1,
        children: vec![],
    }];
    fn multisets(
        list: &[Tree],
        remaining: usize,
        max_idx: usize,
        cur: &mut Vec<usize>,
        out: &mut Vec<Vec<usize>>,
    ) {
        if remaining == 0 {
            out.push(cur.clone());
            return;
        }
        for idx in (0..=max_idx).rev() {
            if list[idx].order <= remaining {
                cur.push(idx);
                multisets(list, remaining - list[idx].order, idx, cur, out);
                cur.pop();
            }
        }
    }
    for n in 2..=max_order {
        let mut out = Vec::new();
        let last = list.len() - 1;
        multisets(&list, n - 1, last, &mut Vec::new(), &mut out);
        for children in out {
            list.push(Tree { order: n, children });
        }
    }
    list
}

/// γ(t) of every tree.
fn gammas(list: &[Tree]) -> Vec<f64> {
    let mut g = Vec::with_capacity(list.len());
    for t in list {
        let prod: f64 = t.children.iter().map(|&c| g[c]).product();
        g.push(t.order as f64 * prod);
    }
    g
}

/// Dense square A (all stored stages) of a tableau.
fn full_a(tab: &Tableau) -> Vec<Vec<f64>> {
    let ns = tab.c.len();
    (0..ns)
        .map(|i| {
            let mut row = vec![0.0; ns];
            row[..tab.a[i].len()].copy_from_slice(tab.a[i]);
            row
        })
        .collect()
}

/// g(t) for every tree: the stage vectors of the elementary weights, with |g|, the same
/// products taken in absolute values (the size of the terms, for the rounding bound).
fn stage_vectors(list: &[Tree], a: &[Vec<f64>]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let ns = a.len();
    let mut g: Vec<Vec<f64>> = Vec::with_capacity(list.len());
    let mut ga: Vec<Vec<f64>> = Vec::with_capacity(list.len());
    for t in list {
        let mut v = vec![1.0; ns];
        let mut va = vec![1.0; ns];
        for &c in &t.children {
            for i in 0..ns {
                let (mut s, mut sa) = (0.0, 0.0);
                for j in 0..ns {
                    s += a[i][j] * g[c][j];
                    sa += (a[i][j] * ga[c][j]).abs();
                }
                v[i] *= s;
                va[i] *= sa;
            }
        }
        g.push(v);
        ga.push(va);
    }
    (g, ga)
}

/// Residuals |wᵀ g(t) − θ^|t|/γ(t)| divided by the rounding bound 1e-15·(1 + |w|ᵀ|g|(t)),
/// for the trees of one order. A value ≤ 1 means the condition holds to rounding error of
/// the f64 coefficients.
fn scaled_residuals(
    list: &[Tree],
    gam: &[f64],
    g: &[Vec<f64>],
    ga: &[Vec<f64>],
    w: &[f64],
    theta: f64,
    order: usize,
) -> Vec<f64> {
    (0..list.len())
        .filter(|&t| list[t].order == order)
        .map(|t| {
            let s: f64 = w.iter().zip(&g[t]).map(|(w, g)| w * g).sum();
            let size: f64 = w.iter().zip(&ga[t]).map(|(w, g)| (w * g).abs()).sum();
            let exact = theta.powi(order as i32) / gam[t];
            (s - exact).abs() / (1e-15 * (1.0 + size))
        })
        .collect()
}

fn pad(w: &[f64], n: usize) -> Vec<f64> {
    let mut v = w.to_vec();
    v.resize(n, 0.0);
    v
}

/// Checks that weights `w` have order exactly `p`: every condition up to p holds to rounding
/// (scaled residual ≤ 8, i.e. 8·1e-15 relative to the size of the terms; the largest
/// observed is about 2), and some
/// condition of order p + 1 fails by far more (> 1e6 scaled, i.e. a real defect of order
/// p + 1, not rounding).
fn assert_order(name: &str, tab: &Tableau, w: &[f64], p: usize) {
    let list = trees(p + 1);
    let gam = gammas(&list);
    let a = full_a(tab);
    let (g, ga) = stage_vectors(&list, &a);
    let w = pad(w, a.len());
    for q in 1..=p {
        let r = scaled_residuals(&list, &gam, &g, &ga, &w, 1.0, q);
        let worst = r.iter().cloned().fold(0.0, f64::max);
        assert!(
            worst <= 8.0,
            "{name}: order-{q} condition violated, scaled residual {worst:e}"
        );
    }
    let r = scaled_residuals(&list, &gam, &g, &ga, &w, 1.0, p + 1);
    let worst = r.iter().cloned().fold(0.0, f64::max);
    assert!(
        worst > 1e6,
        "{name}: order {} conditions all hold (scaled residual {worst:e}), order is not {p}",
        p + 1
    );
}

#[test]
fn rooted_tree_counts_match_oeis_a000081() {
    // Number of rooted trees of order 1..10: 1, 1, 2, 4, 9, 20, 48, 115, 286, 719.
    let list = trees(10);
    let counts: Vec<usize> = (1..=10)
        .map(|n| list.iter().filter(|t| t.order == n).count())
        .collect();
    assert_eq!(counts, vec![1, 1, 2, 4, 9, 20, 48, 115, 286, 719]);
    // γ of the bushy tree of order 4 (root with three leaves) is 4; of the tall one 24.
    let gam = gammas(&list);
    let bushy = list
        .iter()
        .position(|t| t.order == 4 && t.children == vec![0, 0, 0])
        .unwrap();
    assert_eq!(gam[bushy], 4.0);
    let tall = list
        .iter()
        .position(|t| {
            t.order == 4
                && t.children.len() == 1
                && list[t.children[0]].order == 3
                && list[t.children[0]].children.len() == 1
        })
        .unwrap();
    assert_eq!(gam[tall], 24.0);
}

const ALL: [&Tableau; 4] = [&BS32, &DOPRI54, &TSIT54, &DOP853];

#[test]
fn row_sums_equal_nodes() {
    // c_i = Σ_j a_ij for every stage, to 4 ulp of the sum of |a_ij| (the printed
    // coefficients are rounded to f64 once each).
    for tab in ALL {
        assert_eq!(tab.a.len(), tab.c.len(), "{}", tab.name);
        for (i, row) in tab.a.iter().enumerate() {
            assert_eq!(row.len(), i, "{}: row {i} length", tab.name);
            let s: f64 = row.iter().sum();
            let size: f64 = row.iter().map(|a| a.abs()).sum::<f64>().max(1.0);
            assert!(
                (s - tab.c[i]).abs() <= 4.0 * f64::EPSILON * size,
                "{} row {i}: Σa = {s}, c = {}",
                tab.name,
                tab.c[i]
            );
        }
    }
}

#[test]
fn fsal_rows_equal_b() {
    // FSAL pairs: the last main stage is evaluated at (t + h, y_{n+1}): c_s = 1, a_s = b,
    // b_s = 0. DOP853 is not FSAL but its stage 13 (the next k₁) has the same property.
    for tab in ALL {
        let fi = tab.f_new_stage();
        assert_eq!(tab.c[fi], 1.0, "{}", tab.name);
        let row = tab.a[fi];
        assert_eq!(row.len(), fi);
        for j in 0..fi {
            assert_eq!(row[j], tab.b[j], "{} a[{fi}][{j}]", tab.name);
        }
        if tab.fsal {
            assert_eq!(fi, tab.stages() - 1);
            assert_eq!(tab.b[fi], 0.0, "{}", tab.name);
        } else {
            assert_eq!(fi, tab.stages());
        }
    }
    let fsal: Vec<bool> = ALL.iter().map(|t| t.fsal).collect();
    assert_eq!(fsal, vec![true, true, true, false]);
}

#[test]
fn bs32_orders() {
    assert_order("bs32 b", &BS32, BS32.b, 3);
    assert_order("bs32 b̂", &BS32, &BS32.b_hat(), 2);
}

#[test]
fn dopri54_orders() {
    assert_order("dopri54 b", &DOPRI54, DOPRI54.b, 5);
    assert_order("dopri54 b̂", &DOPRI54, &DOPRI54.b_hat(), 4);
}

#[test]
fn tsit54_orders() {
    assert_order("tsit54 b", &TSIT54, TSIT54.b, 5);
    assert_order("tsit54 b̂", &TSIT54, &TSIT54.b_hat(), 4);
}

#[test]
fn dop853_orders() {
    // All 200 trees up to order 8 for b, and the failure of some order-9 tree.
    assert_order("dop853 b", &DOP853, DOP853.b, 8);
    // The 5th-order estimator b̂5 = b − er and the 3rd-order b̂3 = bhh.
    assert_order("dop853 b̂5", &DOP853, &DOP853.b_hat(), 5);
    let ErrorEstimate::Dop853 { b3, .. } = DOP853.error else {
        panic!("dop853 has the combined estimator")
    };
    assert_order("dop853 b̂3", &DOP853, b3, 3);
}

#[test]
fn declared_orders_match_the_weights() {
    // The orders the stepper uses are the ones the conditions prove (tests above).
    let declared: Vec<(usize, usize, usize)> = ALL
        .iter()
        .map(|t| (t.order, t.embedded_order, t.dense_order))
        .collect();
    assert_eq!(declared, vec![(3, 2, 3), (5, 4, 4), (5, 4, 4), (8, 5, 7)]);
    // The controller exponent is 1/(q̂+1): q̂ = p̂ for single estimators, 7 for DOP853 whose
    // combined estimate E₅²/√(E₅² + 0.01E₃²) ~ h⁶·h⁶/h⁴ = h⁸ (HNW I §II.10, dop853.f EXPO1).
    let est: Vec<usize> = ALL.iter().map(|t| t.estimate_order).collect();
    assert_eq!(est, vec![2, 4, 4, 7]);
}

/// Continuous extension: order q conditions at several θ, exact failure of some order-q+1
/// condition, b(1) = b (continuity at the step end) and b'(0) = e₁, b'(1) = e_fnew (the
/// interpolant's derivative matches f at both ends: C¹ dense output).
fn assert_dense(tab: &Tableau) {
    let q = tab.dense_order;
    let list = trees(q + 1);
    let gam = gammas(&list);
    let a = full_a(tab);
    let (g, ga) = stage_vectors(&list, &a);
    let r = tab.dense_weights();
    assert_eq!(r.len(), a.len(), "{}", tab.name);
    let eval = |theta: f64| -> Vec<f64> {
        r.iter()
            .map(|ri| {
                ri.iter()
                    .enumerate()
                    .map(|(m, c)| c * theta.powi(m as i32 + 1))
                    .sum()
            })
            .collect()
    };
    let deriv = |theta: f64| -> Vec<f64> {
        r.iter()
            .map(|ri| {
                ri.iter()
                    .enumerate()
                    .map(|(m, c)| c * (m as f64 + 1.0) * theta.powi(m as i32))
                    .sum()
            })
            .collect()
    };
    let mut worst_next: f64 = 0.0;
    for &theta in &[0.1, 0.3, 0.5, 0.7, 0.9] {
        let w = eval(theta);
        for order in 1..=q {
            let res = scaled_residuals(&list, &gam, &g, &ga, &w, theta, order);
            let worst = res.iter().cloned().fold(0.0, f64::max);
            assert!(
                worst <= 8.0,
                "{} dense θ = {theta}: order-{order} residual {worst:e}",
                tab.name
            );
        }
        let res = scaled_residuals(&list, &gam, &g, &ga, &w, theta, q + 1);
        worst_next = worst_next.max(res.iter().cloned().fold(0.0, f64::max));
    }
    assert!(
        worst_next > 1e6,
        "{}: dense output is of order > {q} ({worst_next:e})",
        tab.name
    );
    let w1 = eval(1.0);
    let b = pad(tab.b, a.len());
    for i in 0..a.len() {
        assert!(
            (w1[i] - b[i]).abs() <= 1e-13 * (1.0 + b[i].abs()),
            "{} b_{i}(1) = {} ≠ b_{i} = {}",
            tab.name,
            w1[i],
            b[i]
        );
    }
    let (d0, d1) = (deriv(0.0), deriv(1.0));
    let fi = tab.f_new_stage();
    for i in 0..a.len() {
        let e0 = if i == 0 { 1.0 } else { 0.0 };
        let e1 = if i == fi { 1.0 } else { 0.0 };
        let scale: f64 = r[i].iter().map(|c| c.abs()).sum::<f64>().max(1.0);
        assert!(
            (d0[i] - e0).abs() <= 1e-14 * scale,
            "{} b'_{i}(0) = {}",
            tab.name,
            d0[i]
        );
        assert!(
            (d1[i] - e1).abs() <= 1e-14 * scale,
            "{} b'_{i}(1) = {}",
            tab.name,
            d1[i]
        );
    }
}

#[test]
fn dense_outputs_have_their_orders() {
    for tab in ALL {
        assert_dense(tab);
    }
}

#[test]
fn shapes_are_validated() {
    for tab in ALL {
        assert_eq!(tab.validate(), Ok(()), "{}", tab.name);
    }
    // A custom tableau with a short row of A is refused with a typed error, not a panic.
    static BROKEN: Tableau = Tableau {
        name: "broken",
        a: &[&[], &[0.5], &[1.0]],
        ..BS32
    };
    let tol =
        lash_solver::options::Tolerances::new(1e-6, lash_solver::Atol::Scalar(1e-9), 1).unwrap();
    let r = lash_solver::erk::ErkMethod::with_tableau(lash_solver::Method::Bs32, &tol, 1, &BROKEN);
    let Err(lash_solver::SolveError::InvalidOptions(e)) = r else {
        panic!("a broken tableau must be refused")
    };
    assert_eq!(e.field, lash_solver::OptionField::Tableau);
}

/// The method table ([`Method::info`]) agrees with the tableaus: the orders it states are the
/// ones the order conditions of all rooted trees prove, and its estimate order, stages, FSAL
/// flag and dense-output degree are the tableau's.
#[test]
fn method_table_agrees_with_the_tableaus() {
    use lash_solver::erk::tableau_of;
    use lash_solver::method::{Family, Method};
    let pairs: Vec<Method> = Method::ALL
        .into_iter()
        .filter(|m| m.info().family == Family::Explicit)
        .collect();
    assert_eq!(pairs.len(), ALL.len());
    for m in pairs {
        let info = m.info();
        let tab = tableau_of(m).unwrap();
        assert_eq!(tab.name, info.name);
        assert_order(info.name, tab, tab.b, info.order);
        let embedded = info
            .embedded_order
            .expect("every pair has an embedded formula");
        assert_order(&format!("{m} b̂"), tab, &tab.b_hat(), embedded);
        assert_eq!(Some(tab.estimate_order), info.error_order, "{m}");
        assert_eq!(Some(tab.stages()), info.stages, "{m}");
        assert_eq!(tab.fsal, info.fsal, "{m}");
        // Degree of the dense output: the highest power of θ with a nonzero weight.
        let degree = tab
            .dense_weights()
            .iter()
            .filter_map(|r| r.iter().rposition(|c| *c != 0.0).map(|k| k + 1))
            .max()
            .unwrap();
        assert_eq!(degree, info.dense_degree, "{m}");
    }
}
