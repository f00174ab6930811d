//! Time integrals of the power terms over accepted steps: the energy balance of a run.
//!
//! ```text
//! a step the method integrated itself (lash_solver::Integrator::step_quadrature: the power
//!   terms as the system's quadrature, lash_solver::WithQuadrature; RK4, the explicit pairs
//!   and BDF: own_quadrature): value = the method's increment; error = the method's
//!   estimate (explicit pairs, RK4), or, for BDF (diffsol gives no estimate for an output
//!   outside its error control), |increment − Boole's rule on the step's dense output|
//! Rodas5P, TR-BDF2, ESDIRK3(4) (step_ends): the polynomial through the power at the last
//!   3–4 step ends (accurate states only), integrated over the step (StepEnds)
//! any other step (cut at an event, the first after the start or an event, a non-finite
//!   stage power, longer than a panel): Boole's rule on the dense output (Quadrature)
//! ```
//!
//! Source: Boole's rule and Richardson extrapolation of Simpson's rule (Davis & Rabinowitz,
//! Methods of Numerical Integration, §2.2, §6.3); docs/model.md §1.8.

use crate::error::Error;

/// How many power terms are integrated: driver, contact damping, friction, film, applied
/// loads, motors, dampers of the spring-dampers (the order of [`Powers`]).
pub(crate) const TERMS: usize = 7;

/// The power terms at one instant, W, in the order of [`TERMS`].
pub(crate) type Powers = [f64; TERMS];

/// Whether a run with `method` integrates the power terms on its step ends (Rodas5P, TR-BDF2,
/// ESDIRK3(4): the methods without [`own_quadrature`], adaptive; [`StepEnds`]).
pub(crate) fn step_ends(method: lash_solver::Method) -> bool {
    !own_quadrature(method) && !method.is_fixed_step()
}

/// Whether a run with `method` integrates the power terms with the method's own formula
/// (module doc): the explicit methods and BDF. Rodas5P, TR-BDF2 and ESDIRK3(4) keep Boole's
/// rule on the dense output: their stage states are poor approximations of the stiff
/// components of the solution (stage order 1–2), and the power, which depends on those
/// components directly (a lubricant film's force), is then far off at the stages although
/// the step's end is accurate (BENCHMARKS.md, "Energy balance of every case": ESDIRK3(4) on
/// a 44 nm film +16.7 J for −273 J; Rodas5P on the 1 µm film 0.39 J off where Boole's rule is
/// 8e-4 J off). BDF evaluates the power at its step ends only.
pub(crate) fn own_quadrature(method: lash_solver::Method) -> bool {
    use lash_solver::Method;
    !matches!(method, Method::Rodas5p | Method::Trbdf2 | Method::Esdirk34)
}

/// The method's own integrals of the power terms over one step, and its error estimate when
/// it has one (module doc).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Own {
    pub(crate) value: Powers,
    pub(crate) estimate: Option<Powers>,
}

/// Time integrals of the power terms over accepted steps.
///
/// ```text
/// a step no longer than max_panel with the method's own integrals (Own): value += increment,
///   error += estimate (or
///   |increment − Boole's rule on the step|, the panels below, when the method has none)
/// otherwise, on the dense output:
/// panel of 5 equally spaced nodes f0..f4, spacing d:
///   S1 = 2d/3 (f0 + 4 f2 + f4),  S2 = d/3 (f0 + 4 f1 + 2 f2 + 4 f3 + f4)
///   value = S2 + (S2 − S1)/15 (Boole's rule),  error estimate |S2 − S1|/15
/// adaptive step [a, b]: ⌈(b − a)/w⌉ panels (w = max_panel), each with 3 interior nodes from
///   the dense output
/// fixed-step method: four consecutive equal steps form one panel (nodes = step ends);
///   a partial group (at the end, or before an unequal or event-cut step) uses Simpson 3/8,
///   Simpson or the trapezoid, error estimated by the difference with the trapezoid
///   (trapezoid alone: d/2 |f1 − f0|)
/// ```
///
/// Source: Boole's rule and Richardson extrapolation of Simpson's rule (Davis & Rabinowitz,
/// Methods of Numerical Integration, §2.2, §6.3).
#[derive(Clone, Debug)]
pub(crate) struct Quadrature {
    fixed: bool,
    max_panel: f64,
    /// Nodes of the pending group; empty after a step the method integrated (the next
    /// step on the dense output evaluates its left node).
    group: Vec<(f64, Powers)>,
    /// Integrals so far of the terms ([`TERMS`]), J.
    pub total: Powers,
    /// Error estimates so far, J.
    pub err: Powers,
    /// Power evaluations so far (the initial one included; the method's own at its stages
    /// are not counted).
    pub evals: usize,
    /// Steps integrated by the method itself.
    pub own_steps: usize,
    /// The step ends' rule, when the run uses it ([`Quadrature::on_step_ends`]).
    ends: Option<StepEnds>,
}

/// The power's integral over a step from its values at the last step ends alone, none of
/// them on the dense output inside a step (for the one-step implicit methods, whose dense
/// output is far from a stiff solution inside a step while the step's ends are accurate).
///
/// ```text
/// nodes t_{n−k+1} < … < t_n < t_{n+1} = the last k + 1 step ends (k + 1 = 4, or 3),
///   none before the start or the last event
/// value    = ∫_{t_n}^{t_{n+1}} p_k(t) dt,  p_k the polynomial through the k + 1 nodes
///            (k = 3: order 4, a variable-step Adams–Moulton formula)
/// estimate = |value − ∫ p_{k−1}|,  p_{k−1} through the newest k nodes (k − 1 = 1: the
///            trapezoid)
/// a rule whose weights sum in magnitude to more than 3 (t_{n+1} − t_n) (a step much longer
///   than the ones before it, where p_k extrapolates) is replaced by the one of the next
///   lower degree; with fewer than 3 usable nodes (the first step after the start or an
///   event) the step takes Boole's rule on its dense output
/// ```
///
/// Weights by 3-point Gauss–Legendre on the Lagrange basis (exact for degree ≤ 5). Source:
/// Hairer, Nørsett & Wanner, Solving ODEs I, §III.5 (variable-step Adams formulas).
#[derive(Clone, Debug, Default)]
struct StepEnds {
    /// The last step ends since the start or the last event (at most 3: with the new end,
    /// the 4 nodes of a cubic).
    hist: Vec<(f64, Powers)>,
    /// Steps integrated by this rule.
    steps: usize,
}

/// Largest Σ|wⱼ|/h accepted for a rule on the step ends.
const MAX_WEIGHT_SUM: f64 = 3.0;

impl StepEnds {
    /// The weights wⱼ of ∫_{a}^{b} p(t) dt = Σ wⱼ f(tⱼ) for the polynomial p through `ts`
    /// (b = the last of them).
    fn weights(ts: &[f64], a: f64) -> Vec<f64> {
        let b = ts[ts.len() - 1];
        let h = b - a;
        // Shifted to b to keep the differences small.
        let s: Vec<f64> = ts.iter().map(|t| t - b).collect();
        let g = [
            (-(0.6f64).sqrt(), 5.0 / 9.0),
            (0.0, 8.0 / 9.0),
            ((0.6f64).sqrt(), 5.0 / 9.0),
        ];
        (0..s.len())
            .map(|j| {
                g.iter()
                    .map(|&(x, w)| {
                        let u = -h / 2.0 + x * h / 2.0;
                        let l: f64 = (0..s.len())
                            .filter(|&m| m != j)
                            .map(|m| (u - s[m]) / (s[j] - s[m]))
                            .product();
                        w * h / 2.0 * l
                    })
                    .sum()
            })
            .collect()
    }

    /// The value and estimate over [a, b] from `nodes` (the last is (b, P(b))), or None when
    /// no rule of degree ≥ 2 has acceptable weights.
    fn integrate(nodes: &[(f64, Powers)], a: f64) -> Option<(Powers, Powers)> {
        let h = nodes[nodes.len() - 1].0 - a;
        let rule = |nodes: &[(f64, Powers)]| -> Option<Powers> {
            let ts: Vec<f64> = nodes.iter().map(|n| n.0).collect();
            let w = StepEnds::weights(&ts, a);
            if w.iter().map(|x| x.abs()).sum::<f64>() > MAX_WEIGHT_SUM * h {
                return None;
            }
            Some(std::array::from_fn(|c| {
                w.iter().zip(nodes).map(|(w, n)| w * n.1[c]).sum()
            }))
        };
        let mut from = 0;
        while nodes.len() - from >= 3 {
            if let Some(v) = rule(&nodes[from..]) {
                let lower = rule(&nodes[from + 1..])?;
                return Some((v, std::array::from_fn(|c| (v[c] - lower[c]).abs())));
            }
            from += 1;
        }
        None
    }
}

impl Quadrature {
    /// Starts at (t0, P(t0)); `fixed` groups equal steps; a step longer than `max_panel`
    /// (> 0, may be ∞) is split into panels no longer than it.
    pub(crate) fn new(fixed: bool, max_panel: f64, t0: f64, p0: Powers) -> Quadrature {
        Quadrature {
            fixed,
            max_panel,
            group: vec![(t0, p0)],
            total: [0.0; TERMS],
            err: [0.0; TERMS],
            evals: 1,
            own_steps: 0,
            ends: None,
        }
    }

    /// Integrates the steps on their ends ([`StepEnds`]) instead of the dense output's
    /// panels, except where the module doc says.
    pub(crate) fn on_step_ends(mut self) -> Quadrature {
        self.ends = Some(StepEnds {
            hist: self.group.clone(),
            steps: 0,
        });
        self
    }

    /// Steps integrated on their ends.
    #[cfg(test)]
    pub(crate) fn step_end_steps(&self) -> usize {
        self.ends.as_ref().map_or(0, |e| e.steps)
    }

    fn last(&self) -> (f64, Powers) {
        *self
            .group
            .last()
            .expect("the group always holds its left node")
    }

    /// Adds the accepted step [ta, tb]; `cut` when it ended at an event; `own` the method's
    /// own integrals over it, if any (module doc); `node(t)` evaluates the power on the
    /// step's dense output.
    pub(crate) fn step(
        &mut self,
        ta: f64,
        tb: f64,
        cut: bool,
        own: Option<Own>,
        node: &mut dyn FnMut(f64) -> Result<Powers, Error>,
    ) -> Result<(), Error> {
        let h = tb - ta;
        if h <= 0.0 {
            return Ok(());
        }
        // A step longer than a panel (a run with nothing for the error control to see: every
        // body prescribed) takes the panels on the dense output.
        if let Some(own) = own.filter(|_| h <= self.max_panel) {
            self.flush();
            let estimate = match own.estimate {
                Some(e) => e,
                None => {
                    let left = (ta, node(ta)?);
                    self.evals += 1;
                    let (boole, _) = self.panels(ta, tb, left, node)?;
                    std::array::from_fn(|c| (own.value[c] - boole[c]).abs())
                }
            };
            for c in 0..TERMS {
                self.total[c] += own.value[c];
                self.err[c] += estimate[c];
            }
            self.own_steps += 1;
            self.group.clear();
            return Ok(());
        }
        if let Some(ends) = self.ends.as_mut() {
            // A history that ends at ta (anything else — a restart — has been cleared).
            let usable = !cut
                && h <= self.max_panel
                && ends.hist.len() >= 2
                && ends.hist.last().is_some_and(|n| n.0 == ta);
            if usable {
                let pb = (tb, node(tb)?);
                self.evals += 1;
                let mut nodes = ends.hist.clone();
                nodes.push(pb);
                if let Some((value, err)) = StepEnds::integrate(&nodes, ta) {
                    for c in 0..TERMS {
                        self.total[c] += value[c];
                        self.err[c] += err[c];
                    }
                    ends.steps += 1;
                    ends.hist = nodes[nodes.len().saturating_sub(3)..].to_vec();
                    self.group = vec![pb];
                    return Ok(());
                }
            }
        }
        if self.group.is_empty() {
            self.group.push((ta, node(ta)?));
            self.evals += 1;
        }
        if self.fixed && !cut {
            let k = self.group.len();
            let equal = k < 2 || {
                let d = self.group[1].0 - self.group[0].0;
                (h - d).abs() <= 1e-6 * d
            };
            if equal {
                self.group.push((tb, node(tb)?));
                self.evals += 1;
                if self.group.len() == 5 {
                    self.boole();
                }
                return Ok(());
            }
        }
        self.flush();
        let left = self.last();
        let (value, err) = self.panels(ta, tb, left, node)?;
        for c in 0..TERMS {
            self.total[c] += value[c];
            self.err[c] += err[c];
        }
        if let Some(ends) = self.ends.as_mut() {
            // The step's end (the panels' last node) continues the history, or restarts it
            // after an event or a step that broke it.
            let end = self.group[0];
            let continues = !cut && ends.hist.last().is_some_and(|n| n.0 == ta);
            if !continues {
                ends.hist.clear();
            }
            ends.hist.push(end);
            let k = ends.hist.len();
            ends.hist.drain(..k.saturating_sub(3));
        }
        Ok(())
    }

    /// Boole's rule over [ta, tb] from the left node `left` (at ta): ⌈(tb − ta)/max_panel⌉
    /// panels; the value and the error estimate. The group ends as the last panel's right
    /// node.
    fn panels(
        &mut self,
        ta: f64,
        tb: f64,
        left: (f64, Powers),
        node: &mut dyn FnMut(f64) -> Result<Powers, Error>,
    ) -> Result<(Powers, Powers), Error> {
        let h = tb - ta;
        let panels = if self.max_panel.is_finite() {
            ((h / self.max_panel).ceil() as usize).max(1)
        } else {
            1
        };
        let w = h / panels as f64;
        let (mut value, mut err) = ([0.0; TERMS], [0.0; TERMS]);
        let mut a = left;
        for k in 0..panels {
            let pa = a.0;
            let pb = if k + 1 == panels {
                tb
            } else {
                ta + w * (k + 1) as f64
            };
            let mut nodes = [a; 5];
            for (j, nd) in nodes.iter_mut().enumerate().skip(1) {
                let t = if j == 4 {
                    pb
                } else {
                    pa + (pb - pa) * j as f64 / 4.0
                };
                *nd = (t, node(t)?);
            }
            self.evals += 4;
            let (v, e) = boole(&nodes);
            for c in 0..TERMS {
                value[c] += v[c];
                err[c] += e[c];
            }
            a = nodes[4];
        }
        self.group = vec![a];
        Ok((value, err))
    }

    /// Boole's rule on the five nodes of the group; the group restarts at its last node.
    fn boole(&mut self) {
        let (v, e) = boole(&self.group);
        for c in 0..TERMS {
            self.total[c] += v[c];
            self.err[c] += e[c];
        }
        let last = self.last();
        self.group = vec![last];
    }

    /// Integrates a partial group of 2–4 equally spaced nodes.
    fn flush(&mut self) {
        let g = &self.group;
        let k = g.len();
        if k < 2 {
            return;
        }
        let d = (g[k - 1].0 - g[0].0) / (k - 1) as f64;
        for c in 0..TERMS {
            let f: Vec<f64> = g.iter().map(|x| x.1[c]).collect();
            let trap = d * (f.iter().sum::<f64>() - 0.5 * (f[0] + f[k - 1]));
            let (v, e) = match k {
                2 => (trap, 0.5 * d * (f[1] - f[0]).abs()),
                3 => {
                    let s = d / 3.0 * (f[0] + 4.0 * f[1] + f[2]);
                    (s, (s - trap).abs())
                }
                _ => {
                    let s = 3.0 * d / 8.0 * (f[0] + 3.0 * f[1] + 3.0 * f[2] + f[3]);
                    (s, (s - trap).abs())
                }
            };
            self.total[c] += v;
            self.err[c] += e;
        }
        let last = self.last();
        self.group = vec![last];
    }

    /// Integrates what is left at the end of the run.
    pub(crate) fn finish(&mut self) {
        self.flush();
    }
}

/// Boole's rule on five equally spaced nodes: the value and the Richardson estimate
/// |S₂ − S₁|/15 of each term.
fn boole(g: &[(f64, Powers)]) -> (Powers, Powers) {
    let d = (g[4].0 - g[0].0) / 4.0;
    let (mut value, mut err) = ([0.0; TERMS], [0.0; TERMS]);
    for c in 0..TERMS {
        let f: [f64; 5] = std::array::from_fn(|j| g[j].1[c]);
        let s1 = 2.0 * d / 3.0 * (f[0] + 4.0 * f[2] + f[4]);
        let s2 = d / 3.0 * (f[0] + 4.0 * f[1] + 2.0 * f[2] + 4.0 * f[3] + f[4]);
        value[c] = s2 + (s2 - s1) / 15.0;
        err[c] = (s2 - s1).abs() / 15.0;
    }
    (value, err)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly(t: f64) -> Powers {
        // Degree 5: Boole's rule is exact up to degree 5. The last three terms repeat the
        // first three, scaled: every term goes through the same rule.
        [
            1.0 + t + t * t * t * t * t,
            3.0 * t * t,
            4.0 * t * t * t,
            (2.0 * t).cos(),
            -2.0 * (1.0 + t + t * t * t * t * t),
            6.0 * t * t,
            8.0 * t * t * t,
        ]
    }

    fn exact(a: f64, b: f64) -> Powers {
        let f0 = |t: f64| t + t * t / 2.0 + t.powi(6) / 6.0;
        [
            f0(b) - f0(a),
            b.powi(3) - a.powi(3),
            b.powi(4) - a.powi(4),
            ((2.0 * b).sin() - (2.0 * a).sin()) / 2.0,
            -2.0 * (f0(b) - f0(a)),
            2.0 * (b.powi(3) - a.powi(3)),
            2.0 * (b.powi(4) - a.powi(4)),
        ]
    }

    #[test]
    fn boole_panels_integrate_quintics_exactly_on_uneven_steps() {
        let mut q = Quadrature::new(false, f64::INFINITY, 0.0, poly(0.0));
        let ts = [0.0, 0.1, 0.35, 0.4, 1.0, 1.7];
        for w in ts.windows(2) {
            q.step(w[0], w[1], false, None, &mut |t| Ok(poly(t)))
                .unwrap();
        }
        q.finish();
        let ex = exact(0.0, 1.7);
        for c in [0, 1, 2, 4, 5, 6] {
            assert!((q.total[c] - ex[c]).abs() < 1e-13 * ex[c].abs(), "{c}");
            // The error estimate is |S2 − S1|/15: zero for cubics (Simpson exact), not for
            // the quintic.
        }
        assert!(q.err[1] < 1e-15 && q.err[2] < 1e-15);
        assert!(q.err[0] > 0.0);
        // cos: the estimate bounds the actual error of the Boole value.
        let e3 = (q.total[3] - ex[3]).abs();
        assert!(e3 <= q.err[3], "{e3} vs {}", q.err[3]);
        assert_eq!(q.evals, 1 + 4 * 5);
    }

    #[test]
    fn long_steps_are_split_into_panels() {
        // One step over [0, 3] of cos(2t): one panel vs 12 panels (max_panel 0.25).
        let integrate = |max_panel: f64| {
            let mut q = Quadrature::new(false, max_panel, 0.0, poly(0.0));
            q.step(0.0, 3.0, false, None, &mut |t| Ok(poly(t))).unwrap();
            q.finish();
            (q.total[3], q.err[3], q.evals)
        };
        let ex = exact(0.0, 3.0)[3];
        let (one, est_one, n1) = integrate(f64::INFINITY);
        let (many, est_many, n12) = integrate(0.25);
        assert_eq!((n1, n12), (5, 1 + 4 * 12));
        assert!(
            (one - ex).abs() > 1e-3,
            "one panel is coarse: {one} vs {ex}"
        );
        assert!((many - ex).abs() < 1e-8 && (many - ex).abs() <= est_many);
        assert!(est_many < 1e-3 * est_one);
    }

    #[test]
    fn fixed_steps_group_into_fours_and_converge_at_order_six() {
        // ∫₀^1 cos(2t) with n equal steps: Boole panels of 4 steps, error O(h⁶).
        let run = |n: usize| {
            let h = 1.0 / n as f64;
            let mut q = Quadrature::new(true, f64::INFINITY, 0.0, poly(0.0));
            for k in 0..n {
                let (a, b) = (k as f64 * h, (k + 1) as f64 * h);
                q.step(a, b, false, None, &mut |t| Ok(poly(t))).unwrap();
            }
            q.finish();
            assert_eq!(q.evals, n + 1, "one evaluation per step");
            ((q.total[3] - exact(0.0, 1.0)[3]).abs(), q.err[3])
        };
        let ((e1, est1), (e2, est2)) = (run(8), run(16));
        let order = (e1 / e2).log2();
        assert!((5.7..6.5).contains(&order), "order {order}: {e1} {e2}");
        assert!(e1 <= est1 && e2 <= est2, "{e1} {est1} {e2} {est2}");
        // A partial group (10 steps = 2 panels + 2 steps) is closed by Simpson, whose error
        // is estimated by its difference with the trapezoid.
        let (e, est) = run(10);
        assert!(e <= est && est < 1e-3, "{e} {est}");
    }

    /// ∫ over uneven steps on the step ends: the first step takes Boole's rule on the dense
    /// output (exact to degree 5), the second the quadratic through three ends, the rest the
    /// cubic through four: exact for the quadratics (terms 1 and 5); for the cubic (terms 2
    /// and 6) only the quadratic step errs, within its estimate; for the quintic too. Only the
    /// step ends are evaluated after the first step.
    #[test]
    fn step_ends_integrate_on_uneven_steps_within_their_estimate() {
        let ts = [0.0, 0.1, 0.25, 0.3, 0.5, 0.9, 1.2];
        let mut q = Quadrature::new(false, f64::INFINITY, 0.0, poly(0.0)).on_step_ends();
        for w in ts.windows(2) {
            q.step(w[0], w[1], false, None, &mut |t| Ok(poly(t)))
                .unwrap();
        }
        q.finish();
        let ex = exact(0.0, 1.2);
        for c in [1, 5] {
            assert!((q.total[c] - ex[c]).abs() < 1e-13 * ex[c].abs(), "{c}");
        }
        // The cubic errs on the quadratic's step [0.1, 0.25] alone; the quintic on every
        // step-end step: nonzero and within the estimate.
        for c in [0, 2, 6] {
            let e = (q.total[c] - ex[c]).abs();
            assert!(e > 1e-9 && e <= q.err[c], "{c}: {e:e} {:e}", q.err[c]);
        }
        assert_eq!(q.step_end_steps(), 5);
        assert_eq!(q.evals, 1 + 4 + 5);
        // The cubic rule alone (four uneven ends, Σ|wⱼ| = 1.4 h) is exact for cubics; on
        // 0.25, 0.3, 0.5, 0.9 (Σ|wⱼ| = 5 h: a step 2–8 times longer than those before it)
        // it gives way to the quadratic.
        let ends =
            |ts: &[f64]| -> Vec<(f64, Powers)> { ts.iter().map(|&t| (t, poly(t))).collect() };
        let (v, _) = StepEnds::integrate(&ends(&[0.3, 0.5, 0.9, 1.2]), 0.9).unwrap();
        let ex = exact(0.9, 1.2);
        for c in [1, 2, 5, 6] {
            assert!((v[c] - ex[c]).abs() < 1e-13 * ex[c].abs(), "{c}");
        }
        let (v, _) = StepEnds::integrate(&ends(&[0.25, 0.3, 0.5, 0.9]), 0.5).unwrap();
        let (quadratic, _) = StepEnds::integrate(&ends(&[0.3, 0.5, 0.9]), 0.5).unwrap();
        assert_eq!(v, quadratic);
    }

    /// On n equal steps of cos 2t over [0, 1] the cubic rule's error falls as h⁴ (order 4),
    /// and the estimate (its difference with the quadratic, one order lower) bounds it.
    #[test]
    fn step_ends_converge_at_order_four() {
        let run = |n: usize| {
            let h = 1.0 / n as f64;
            let mut q = Quadrature::new(false, f64::INFINITY, 0.0, poly(0.0)).on_step_ends();
            for k in 0..n {
                let (a, b) = (k as f64 * h, (k + 1) as f64 * h);
                q.step(a, b, false, None, &mut |t| Ok(poly(t))).unwrap();
            }
            q.finish();
            ((q.total[3] - exact(0.0, 1.0)[3]).abs(), q.err[3])
        };
        let ((e1, est1), (e2, est2)) = (run(40), run(80));
        let order = (e1 / e2).log2();
        assert!((3.7..4.4).contains(&order), "order {order}: {e1:e} {e2:e}");
        assert!(e1 <= est1 && e2 <= est2, "{e1:e} {est1:e} {e2:e} {est2:e}");
    }

    /// A step 100 times longer than the ones before it: the cubic and the quadratic through
    /// the clustered ends extrapolate (weights far above 3h), so the step takes Boole's rule
    /// on its dense output; an event restarts the history (the next step too).
    #[test]
    fn step_ends_fall_back_to_boole_where_they_would_extrapolate() {
        let mut q = Quadrature::new(false, f64::INFINITY, 0.0, poly(0.0)).on_step_ends();
        let mut f = |t: f64| Ok(poly(t));
        for (a, b) in [(0.0, 0.001), (0.001, 0.002), (0.002, 0.003)] {
            q.step(a, b, false, None, &mut f).unwrap();
        }
        assert_eq!(q.step_end_steps(), 2);
        q.step(0.003, 0.3, false, None, &mut f).unwrap();
        assert_eq!(q.step_end_steps(), 2, "the long step took Boole's rule");
        q.step(0.3, 0.31, true, None, &mut f).unwrap();
        q.step(0.31, 0.32, false, None, &mut f).unwrap();
        assert_eq!(q.step_end_steps(), 2, "no rule across an event");
        q.step(0.32, 0.33, false, None, &mut f).unwrap();
        assert_eq!(q.step_end_steps(), 3);
        q.finish();
        let ex = exact(0.0, 0.33);
        for c in [1, 5] {
            assert!((q.total[c] - ex[c]).abs() < 1e-13 * ex[c].abs(), "{c}");
        }
    }

    #[test]
    fn event_cut_steps_flush_the_group() {
        let mut q = Quadrature::new(true, f64::INFINITY, 0.0, poly(0.0));
        let h = 0.01;
        for k in 0..6 {
            q.step(k as f64 * h, (k + 1) as f64 * h, false, None, &mut |t| {
                Ok(poly(t))
            })
            .unwrap();
        }
        // A step cut by an event: the two pending steps are closed with Simpson, the cut step
        // gets its own Boole panel.
        q.step(0.06, 0.063, true, None, &mut |t| Ok(poly(t)))
            .unwrap();
        q.step(0.063, 0.073, false, None, &mut |t| Ok(poly(t)))
            .unwrap();
        q.finish();
        let ex = exact(0.0, 0.073);
        for c in 0..TERMS {
            let e = (q.total[c] - ex[c]).abs();
            // Terms 4–6 are terms 0–2 scaled by −2 or 2: so are their error estimates.
            let scale = if c >= 4 { 2.0 } else { 1.0 };
            assert!(
                e <= q.err[c] + 1e-16 && q.err[c] < 1e-4 * scale,
                "{c}: {e} {}",
                q.err[c]
            );
        }
        // Nodes: the start, 6 step ends, 4 for the cut step (its own Boole panel), 1 for the
        // last step (closed alone by the trapezoid, error bound d/2 |f1 − f0|).
        assert_eq!(q.evals, 1 + 6 + 4 + 1);
    }
}
