//! The metrics window of a run (`--window`): the last crank revolution, the whole run, or a
//! span of it; and where a motor-driven crank's last revolution starts.
//!
//! ```text
//! last-revolution  driven crank (crank_driver, T = 2π/|ω|):  [t_end − T, t_end]
//!                  crank that is not driven (roles.crank; a motor turns it):
//!                    [t*, t_end] with φ(t*) = φ(t_end) − 2π·sign(φ(t_end) − φ(t_start)),
//!                    the last crossing, found by a first pass of the same run (no energy, no
//!                    trajectory) that keeps (t, φ, φ̇) at the step ends of the last turn and
//!                    solves the cubic Hermite interpolant of the bracketing step by bisection
//!                  no crank: an option error
//!                  a run shorter than one revolution: the whole run
//! all              [t_start, t_end]
//! T0:T1            [T0, T1], t_start ≤ T0 < T1 ≤ t_end
//! default          last-revolution with a crank, all without one
//! ```
//!
//! Source: docs/outputs.md (`metrics`, "The metrics window").

use std::collections::VecDeque;
use std::f64::consts::TAU;

use lash_model::MetricsWindow;

use crate::error::{Error, OptionError};
use crate::report::metrics::Window;
use crate::report::trajectory::fmt_num;

/// How a run finds its metrics window (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum WindowPlan {
    /// Known before the run.
    Known(Window),
    /// The last revolution of a crank that is not driven: found by a first pass.
    CrankTurn,
}

/// The window over the whole run [t0, t_end].
pub(crate) fn whole(t0: f64, t_end: f64) -> Window {
    Window {
        t_end,
        period: t_end - t0,
    }
}

/// The plan of a choice (None: the default) for a run over [t0, t_end] with crank period
/// `period` (a driven crank) and `has_crank` (any crank); an option error names `window`.
pub(crate) fn plan(
    choice: Option<MetricsWindow>,
    t0: f64,
    t_end: f64,
    period: Option<f64>,
    has_crank: bool,
) -> Result<WindowPlan, Error> {
    let span = t_end - t0;
    let last = |t: f64| {
        WindowPlan::Known(Window {
            t_end,
            period: t.min(span),
        })
    };
    match (choice, period) {
        (None | Some(MetricsWindow::LastRevolution), Some(t)) => Ok(last(t)),
        (None | Some(MetricsWindow::LastRevolution), None) if has_crank => {
            Ok(WindowPlan::CrankTurn)
        }
        (None, None) => Ok(WindowPlan::Known(whole(t0, t_end))),
        (Some(MetricsWindow::LastRevolution), None) => Err(OptionError::leading(
            "window",
            " last-revolution needs a crank: the scene declares neither roles.crank nor \
             roles.crank_driver (use all or T0:T1)",
        )
        .into()),
        (Some(MetricsWindow::All), _) => Ok(WindowPlan::Known(whole(t0, t_end))),
        (Some(MetricsWindow::Span { from, to }), _) => {
            if !(from >= t0 && to <= t_end && from < to) {
                return Err(OptionError::leading(
                    "window",
                    format!(
                        " {}:{} is not inside the run [{}, {}] s",
                        fmt_num(from),
                        fmt_num(to),
                        fmt_num(t0),
                        fmt_num(t_end)
                    ),
                )
                .into());
            }
            Ok(WindowPlan::Known(Window {
                t_end: to,
                period: to - from,
            }))
        }
    }
}

/// The crank angle at the step ends of the last turn (module doc): (t, φ, φ̇), the oldest
/// dropped once the one after it is a full turn behind the newest.
#[derive(Clone, Debug, Default)]
pub(crate) struct CrankTrack {
    points: VecDeque<[f64; 3]>,
    first: Option<f64>,
}

impl CrankTrack {
    /// Records the crank at a step end (or the start).
    pub(crate) fn push(&mut self, t: f64, phi: f64, rate: f64) {
        self.first.get_or_insert(phi);
        self.points.push_back([t, phi, rate]);
        while self.points.len() > 2 && (phi - self.points[1][1]).abs() > TAU {
            self.points.pop_front();
        }
    }

    /// t* with φ(t*) = φ_end − 2π·sign(φ_end − φ_start), the latest such crossing; None when
    /// the crank has not turned a full revolution since the start.
    pub(crate) fn last_turn_start(&self) -> Option<f64> {
        let (first, last) = (self.first?, *self.points.back()?);
        let turned = last[1] - first;
        if !(turned.abs() >= TAU) {
            return None;
        }
        let target = last[1] - TAU * turned.signum();
        let pts: Vec<[f64; 3]> = self.points.iter().copied().collect();
        pts.windows(2).rev().find_map(|w| {
            let (a, b) = (w[0], w[1]);
            let (ga, gb) = (a[1] - target, b[1] - target);
            if ga == 0.0 {
                return Some(a[0]);
            }
            if ga.signum() == gb.signum() && gb != 0.0 {
                return None;
            }
            Some(hermite_root(a, b, target))
        })
    }
}

/// The root of H(t) = target on [a.t, b.t], H the cubic Hermite interpolant of (t, φ, φ̇) at
/// both ends (H − target changes sign there), by bisection to the last bit.
fn hermite_root(a: [f64; 3], b: [f64; 3], target: f64) -> f64 {
    let h = b[0] - a[0];
    let eval = |s: f64| {
        // Hermite basis on s ∈ [0, 1].
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        h00 * a[1] + h10 * h * a[2] + h01 * b[1] + h11 * h * b[2] - target
    };
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    let sign_lo = (a[1] - target).signum();
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if eval(mid).signum() == sign_lo {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    a[0] + h * 0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_three_forms_and_names_the_option() {
        let parse = |s: &str| s.parse::<MetricsWindow>();
        assert_eq!(parse("all").unwrap(), MetricsWindow::All);
        assert_eq!(
            parse("last-revolution").unwrap(),
            MetricsWindow::LastRevolution
        );
        assert_eq!(
            parse("0.4:0.8").unwrap(),
            MetricsWindow::Span { from: 0.4, to: 0.8 }
        );
        assert_eq!(parse("0.4:0.8").unwrap().to_string(), "0.4:0.8");
        for bad in ["last", "0.8:0.4", "a:1", "1:inf", "0.4"] {
            let e = parse(bad).unwrap_err();
            assert!(
                e.contains(&format!("'{bad}'")) && e.contains("T0:T1"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn plans_follow_the_crank() {
        let t = 0.4;
        // Driven crank: [t_end − T, t_end] by default and on request; all without a crank.
        let known = |w| WindowPlan::Known(w);
        assert_eq!(
            plan(None, 0.0, 0.8, Some(t), true).unwrap(),
            known(Window {
                t_end: 0.8,
                period: t
            })
        );
        assert_eq!(
            plan(None, 0.0, 0.8, None, false).unwrap(),
            known(whole(0.0, 0.8))
        );
        assert_eq!(
            plan(None, 0.0, 0.8, None, true).unwrap(),
            WindowPlan::CrankTurn
        );
        assert!(plan(Some(MetricsWindow::LastRevolution), 0.0, 0.8, None, false).is_err());
        let span = MetricsWindow::Span { from: 0.1, to: 0.5 };
        assert_eq!(
            plan(Some(span), 0.0, 0.8, Some(t), true).unwrap(),
            known(Window {
                t_end: 0.5,
                period: 0.5 - 0.1
            })
        );
        let outside = MetricsWindow::Span { from: 0.1, to: 0.9 };
        assert!(plan(Some(outside), 0.0, 0.8, Some(t), true).is_err());
    }

    /// φ(t) = ω t + A sin(ν t) sampled at uneven step ends: the turn start solves
    /// φ(t*) = φ(t_end) − 2π; the Hermite interpolant on steps of h ≤ 5e-3 s is within
    /// h⁴ max|φ''''| / 384 ≈ 6e-10 rad of φ, i.e. 6e-10/ω s in time.
    #[test]
    fn the_last_turn_starts_where_the_angle_is_one_turn_behind() {
        let (w, amp, nu) = (15.0, 0.3, 20.0);
        let phi = |t: f64| w * t + amp * (nu * t).sin();
        let rate = |t: f64| w + amp * nu * (nu * t).cos();
        let mut tr = CrankTrack::default();
        let mut t = 0.0;
        let mut k = 0;
        while t < 1.0 {
            tr.push(t, phi(t), rate(t));
            t += if k % 2 == 0 { 5e-3 } else { 3e-3 };
            k += 1;
        }
        let t_end = t - if (k - 1) % 2 == 0 { 5e-3 } else { 3e-3 };
        let target = phi(t_end) - TAU;
        // Newton on the exact φ for the reference.
        let mut r = t_end - TAU / w;
        for _ in 0..50 {
            r -= (phi(r) - target) / rate(r);
        }
        let got = tr.last_turn_start().unwrap();
        assert!((got - r).abs() < 1e-9, "{got} vs {r}");
        // The track keeps about one turn, not the run.
        assert!(tr.points.len() < 150, "{}", tr.points.len());
        // Less than a turn: none.
        let mut short = CrankTrack::default();
        short.push(0.0, 0.0, 1.0);
        short.push(1.0, 6.0, 1.0);
        assert_eq!(short.last_turn_start(), None);
    }
}
