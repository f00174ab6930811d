//! Brent's method on one event function along the dense output of the step that holds its
//! crossing (the root finding of [`Integrator::locate_events`]: the integrator's module
//! documentation).

use super::{sign, Integrator, OdeSystem, SolveError};

impl<S: OdeSystem + ?Sized> Integrator<'_, S> {
    /// Brent's method (Brent 1973, ch. 4: bisection, secant and inverse quadratic
    /// interpolation, as `zeroin`) on g_i(t, y_dense(t)) over [ta, tb], g(ta) = ga and
    /// g(tb) = gb of opposite signs, until the bracket is at most 4 ulps of t wide
    /// (`|b − c| ≤ 2 ε |b|`), or g is exactly zero. Returns the end of the final bracket on the
    /// side after the crossing (where g has the sign of gb, the sign the event's direction
    /// gives it), or the point where g is exactly zero.
    pub(super) fn brent(
        &mut self,
        i: usize,
        ta: f64,
        ga: f64,
        tb: f64,
        gb: f64,
    ) -> Result<f64, SolveError> {
        let mut g = std::mem::take(&mut self.g_t);
        let new_sign = sign(gb);
        // b: best estimate; c: the other end of the bracket (g(b), g(c) of opposite signs);
        // a: the previous b.
        let (mut a, mut fa, mut b, mut fb) = (ta, ga, tb, gb);
        let (mut c, mut fc) = (a, fa);
        let mut d = b - a;
        let mut e = d;
        let mut root = None;
        for _ in 0..200 {
            if sign(fb) == sign(fc) {
                c = a;
                fc = fa;
                d = b - a;
                e = d;
            }
            if fc.abs() < fb.abs() {
                a = b;
                b = c;
                c = a;
                fa = fb;
                fb = fc;
                fc = fa;
            }
            // ε|b| is 1 to 2 ulps of b, so a step of tol always moves b; the bracket [b, c] is
            // final once |c − b| ≤ 2 ε |b| (at most 4 ulps).
            let tol = f64::EPSILON * b.abs().max(f64::MIN_POSITIVE);
            let m = 0.5 * (c - b);
            if fb == 0.0 {
                root = Some(b);
                break;
            }
            if m.abs() <= tol {
                break;
            }
            if e.abs() >= tol && fa.abs() > fb.abs() {
                // Secant (a = c) or inverse quadratic interpolation.
                let s = fb / fa;
                let (mut p, mut q);
                if a == c {
                    p = 2.0 * m * s;
                    q = 1.0 - s;
                } else {
                    let qa = fa / fc;
                    let r = fb / fc;
                    p = s * (2.0 * m * qa * (qa - r) - (b - a) * (r - 1.0));
                    q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
                }
                if p > 0.0 {
                    q = -q;
                } else {
                    p = -p;
                }
                if 2.0 * p < (3.0 * m * q - (tol * q).abs()).min((e * q).abs()) {
                    e = d;
                    d = p / q;
                } else {
                    d = m;
                    e = m;
                }
            } else {
                d = m;
                e = m;
            }
            a = b;
            fa = fb;
            b += if d.abs() > tol { d } else { tol.copysign(m) };
            if let Err(e) = self.eval_g_dense(b, &mut g) {
                self.g_t = g;
                return Err(e);
            }
            fb = g[i];
        }
        self.g_t = g;
        Ok(root.unwrap_or(if sign(fb) == new_sign { b } else { c }))
    }
}
