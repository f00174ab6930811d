//! The contact-aware step limit (`SolverOptions::h_max_near_events`, crate::integrator's
//! module documentation): its value in closed form, the steps it allows on a motion whose
//! reach is known exactly, and a graze that hides inside the steps of a run without it and is
//! found with it, for a fraction of the steps a blanket h_max would cost.
//!
//! ```text
//! r(g, ġ, g̈) = 2d / (|ġ| + √(ġ² + 2|g̈| d)),  d = |g|/κ, κ = 2
//!   constant rate:          r = |g| / (κ |ġ|)
//!   from rest, constant g̈:  r = √(|g| / (κ/2 · |g̈|)) = √(|g| / |g̈|)
//! uniform approach x' = v to a wall at D: the step after a step ending at x is at most
//!   max(H, (D − x) / (κ v))
//! graze x = sin t, g = x − (1 − ε): g > 0 for |t − π/2| < acos(1 − ε), τ = 2 acos(1 − ε)
//! ```

use lash_solver::integrator::reach_limit;
use lash_solver::*;

#[test]
fn the_reach_in_closed_form() {
    // Constant rate: the distance over κ times the rate.
    assert_eq!(reach_limit(-1.0, 4.0, 0.0), 1.0 / 8.0);
    assert_eq!(reach_limit(3.0, -0.5, 0.0), 3.0);
    // From rest under a constant second derivative: ½ g̈ r² = |g|/κ.
    let r = reach_limit(-0.5, 0.0, 4.0);
    assert!((r - 0.5f64.sqrt() / 2.0).abs() < 1e-15, "{r}");
    // Both terms: |ġ| r + ½ |g̈| r² = |g|/κ exactly.
    let (g, gd, gdd) = (-2e-4, 3e-2, -7.0);
    let r = reach_limit(g, gd, gdd);
    let travel = gd.abs() * r + 0.5 * gdd.abs() * r * r;
    assert!((travel - g.abs() / 2.0).abs() < 1e-15 * g.abs(), "{travel}");
    // At a zero nothing may be skipped; without motion nothing limits.
    assert_eq!(reach_limit(0.0, 1.0, 1.0), 0.0);
    assert_eq!(reach_limit(-1.0, 0.0, 0.0), f64::INFINITY);
}

/// x' = v: a point moving uniformly towards a wall at x = D (event g = x − D).
struct Approach {
    v: f64,
    wall: f64,
}

impl OdeSystem for Approach {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, _y: &[f64], dy: &mut [f64]) {
        dy[0] = self.v;
    }
    fn n_events(&self) -> usize {
        1
    }
    fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g[0] = y[0] - self.wall;
    }
    fn event_rates(&self, _t: f64, y: &[f64], g: &mut [f64], g_dot: &mut [f64]) -> bool {
        g[0] = y[0] - self.wall;
        g_dot[0] = self.v;
        true
    }
}

#[test]
fn a_uniform_approach_steps_half_the_remaining_distance() {
    let sys = Approach { v: 2.0, wall: 1.0 };
    let h_near = 1e-3;
    for method in [Method::Dopri54, Method::Rodas5p, Method::Bdf] {
        let mut o = SolverOptions::with_method(method);
        o.h_max_near_events = h_near;
        let sol = Problem::new(&sys, &o)
            .unwrap()
            .solve((0.0, 1.0), &[0.0])
            .unwrap();
        // The wall is reached at t = D/v = 0.5, located there.
        assert_eq!(sol.events.len(), 1, "{method}");
        assert!((sol.events[0].t - 0.5).abs() < 1e-12, "{method}");
        // Every step after the first is at most max(H, (D − x)/(κ v)), x at its start; the
        // first (no rate change known yet) at most H.
        let mut tight = 0;
        let before_wall: Vec<f64> = sol.t.iter().copied().filter(|t| *t <= 0.5).collect();
        for (k, w) in before_wall.windows(2).enumerate() {
            let (t0, t1) = (w[0], w[1]);
            let x = sys.v * t0;
            let bound = if k == 0 {
                h_near
            } else {
                h_near.max((sys.wall - x) / (2.0 * sys.v))
            };
            assert!(
                t1 - t0 <= bound * (1.0 + 1e-9),
                "{method}: step {k} {t0} → {t1}"
            );
            if ((t1 - t0) - bound).abs() <= 1e-9 * bound && bound > h_near {
                tight += 1;
            }
        }
        // The exact solution asks for no limit of accuracy: the limit is what sets the steps,
        // halving the distance each time, then H near the wall; a blanket h_max = H would
        // take 500 steps (bdf, starting at 2e-6 s and doubling, takes 63).
        // Our one-step methods take the limit itself; diffsol's BDF halves its step at each
        // stop time it reaches, so it stays under the limit.
        if method != Method::Bdf {
            assert!(tight >= 3, "{method}: {tight} steps at the limit");
        }
        assert!(
            before_wall.len() < 100,
            "{method}: {} steps",
            before_wall.len()
        );
    }
}

/// x'' = −x from x = 0, x' = 1 (x = sin t), event g = x − (1 − ε): a graze of duration
/// τ = 2 acos(1 − ε) around t = π/2.
struct Graze {
    eps: f64,
}

impl OdeSystem for Graze {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -y[0];
    }
    fn n_events(&self) -> usize {
        1
    }
    fn events(&self, _t: f64, y: &[f64], g: &mut [f64]) {
        g[0] = y[0] - (1.0 - self.eps);
    }
    fn event_rates(&self, _t: f64, y: &[f64], g: &mut [f64], g_dot: &mut [f64]) -> bool {
        g[0] = y[0] - (1.0 - self.eps);
        g_dot[0] = y[1];
        true
    }
}

#[test]
fn a_graze_that_hides_without_the_limit_is_found_with_it() {
    let sys = Graze { eps: 1e-6 };
    let tau = 2.0 * (1.0 - sys.eps).acos();
    let half = std::f64::consts::FRAC_PI_2;
    let (t_in, t_out) = (half - tau / 2.0, half + tau / 2.0);
    let span = (0.0, std::f64::consts::PI);
    for method in [
        Method::Dopri54,
        Method::Dop853,
        Method::Rodas5p,
        Method::Bdf,
    ] {
        let run = |h_near: f64, h_max: f64| {
            let mut o = SolverOptions::with_method(method);
            o.rtol = 1e-6;
            o.atol = Atol::Scalar(1e-9);
            o.h_max_near_events = h_near;
            o.h_max = h_max;
            Problem::new(&sys, &o)
                .unwrap()
                .solve(span, &[0.0, 1.0])
                .unwrap()
        };
        // Without a limit the steps near the peak are far longer than 5 τ: the 4 interior
        // samples miss the excursion (what makes this a test of the limit).
        let free = run(f64::INFINITY, f64::INFINITY);
        assert!(free.events.is_empty(), "{method}: {:?}", free.events);
        assert!(free.stats.h_max_used > 5.0 * tau, "{method}");
        // With H = τ an excursion longer than H/5 cannot hide: both crossings are found.
        let limited = run(tau, f64::INFINITY);
        assert_eq!(limited.events.len(), 2, "{method}: {:?}", limited.events);
        assert!(limited.events[0].rising && !limited.events[1].rising);
        // Where: within τ/10, the solution's error at rtol 1e-6 over the rate ġ = cos t ≈ τ/2
        // at the crossings (an error of 1e-7 in x moves them by 7e-5 = τ/40).
        assert!((limited.events[0].t - t_in).abs() < 0.1 * tau, "{method}");
        assert!((limited.events[1].t - t_out).abs() < 0.1 * tau, "{method}");
        // A blanket h_max = τ finds them too, at ⌈π/τ⌉ = 1111 steps or more; the limit pays
        // for the steps near the peak only.
        let blanket = run(f64::INFINITY, tau);
        assert_eq!(blanket.events.len(), 2, "{method}");
        let (nl, nb) = (limited.stats.accepted, blanket.stats.accepted);
        assert!(nb >= 1111, "{method}: {nb}");
        assert!(
            10 * nl < nb,
            "{method}: {nl} steps with the limit, {nb} with h_max"
        );
    }
}

/// Under the limit, diffsol's methods get a stop time only where it binds (crate::
/// diffsol_backend's module documentation): a limit above every step the free run takes
/// leaves the run bit for bit the free run's, whereas a stop time held at t + H until reached
/// would cut the step that crosses it and rescale the method's history.
#[test]
fn a_limit_that_never_binds_leaves_diffsols_steps_alone() {
    let sys = Graze { eps: 1e-6 };
    let span = (0.0, std::f64::consts::PI);
    for method in [Method::Bdf, Method::Trbdf2, Method::Esdirk34] {
        let run = |h_near: f64| {
            let mut o = SolverOptions::with_method(method);
            o.rtol = 1e-6;
            o.atol = Atol::Scalar(1e-9);
            o.h_max_near_events = h_near;
            o.output = Output::Steps;
            Problem::new(&sys, &o)
                .unwrap()
                .solve(span, &[0.0, 1.0])
                .unwrap()
        };
        let free = run(f64::INFINITY);
        // H above every free step: the limit max(H, r) never binds, yet it is in force (the
        // stepper's h_max is set after every step).
        let h_near = 1.5 * free.stats.h_max_used;
        let limited = run(h_near);
        assert!(free.t.len() > 20, "{method}: {} steps", free.t.len());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&limited.t), bits(&free.t), "{method}: step times");
        assert_eq!(bits(&limited.y), bits(&free.y), "{method}: states");
        assert_eq!(limited.stats.rhs_evals, free.stats.rhs_evals, "{method}");
    }
}
