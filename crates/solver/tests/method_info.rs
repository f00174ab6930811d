//! The method table ([`Method::info`]) against what the methods do: the degree of each dense
//! output measured on the interpolant itself, the Jacobian flag on the counters, the default
//! controller on the driver, RHS evaluations per step against stages and FSAL, BDF's highest
//! order, and the family against the configuration the options produce. (The orders of the
//! explicit pairs are proved from their tableaus in `erk_tableaus.rs`.)
//!
//! ```text
//! dense degree d:  on a step [t_a, t_b], the polynomial of degree d through the interpolant's
//!                  values at the d + 1 Chebyshev–Lobatto points reproduces it at any θ
//!                  (to rounding), and the one of degree d − 1 through d points does not
//!                  (on large steps, where the top coefficient is far above rounding)
//! ```

mod common;
use common::*;
use lash_solver::diffsol_backend::DiffsolStepper;
use lash_solver::method::Family;
use lash_solver::*;

/// θ_j = (1 − cos(π j / m)) / 2, j = 0..m.
fn lobatto(m: usize) -> Vec<f64> {
    (0..=m)
        .map(|j| 0.5 * (1.0 - (std::f64::consts::PI * j as f64 / m as f64).cos()))
        .collect()
}

/// The Lagrange interpolant through (x_j, v_j) at x.
fn lagrange(xs: &[f64], vs: &[f64], x: f64) -> f64 {
    let mut s = 0.0;
    for (j, (xj, vj)) in xs.iter().zip(vs).enumerate() {
        let mut l = 1.0;
        for (k, xk) in xs.iter().enumerate() {
            if k != j {
                l *= (x - xk) / (xj - xk);
            }
        }
        s += l * vj;
    }
    s
}

/// Over every step of a run, the largest misfit (relative to max|y| on the step) of the
/// polynomial of degree `d` through the dense output's values at the Lobatto points, at four
/// other points of the step.
fn misfit(opts: &SolverOptions, t_end: f64, d: usize) -> f64 {
    let sys = Kepler { e: 0.5 };
    let y0 = sys.y0();
    let problem = Problem::new(&sys, opts).unwrap();
    let mut st = make_stepper(&problem, 0.0, &y0).unwrap();
    let nodes = lobatto(d);
    let mut worst: f64 = 0.0;
    let mut y = [0.0; 4];
    while st.t() < t_end {
        st.step(t_end).unwrap();
        let (ta, tb) = (st.t_prev(), st.t());
        let h = tb - ta;
        let vals: Vec<[f64; 4]> = nodes
            .iter()
            .map(|th| {
                st.interpolate(ta + th * h, &mut y);
                y
            })
            .collect();
        let scale = vals
            .iter()
            .flat_map(|v| v.iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for th in [0.13, 0.37, 0.61, 0.89] {
            st.interpolate(ta + th * h, &mut y);
            for c in 0..4 {
                let col: Vec<f64> = vals.iter().map(|v| v[c]).collect();
                let p = lagrange(&nodes, &col, th);
                worst = worst.max((p - y[c]).abs() / scale);
            }
        }
    }
    worst
}

/// Options with large steps, so that the top coefficient of each interpolant is far above
/// rounding: one-step methods at fixed steps of 0.4 (a fifteenth of the period 2π), diffsol's
/// at a loose tolerance.
fn large_steps(m: Method) -> SolverOptions {
    match m.info().family {
        Family::FixedStep => SolverOptions {
            method: m,
            step: Some(0.4),
            ..Default::default()
        },
        Family::Explicit | Family::Rosenbrock => SolverOptions {
            method: m,
            adaptive: false,
            h0: Some(0.4),
            ..Default::default()
        },
        Family::Diffsol => SolverOptions {
            method: m,
            rtol: 1e-3,
            atol: Atol::Scalar(1e-3),
            ..Default::default()
        },
    }
}

#[test]
fn dense_output_has_the_tables_degree() {
    for m in Method::ALL {
        let d = m.dense_degree();
        let opts = large_steps(m);
        let fit = misfit(&opts, 6.0, d);
        assert!(fit < 1e-11, "{m}: degree {d} leaves a misfit {fit:e}");
        // BDF's degree is its current order, below 5 at this tolerance: the bound only.
        if m != Method::Bdf {
            let below = misfit(&opts, 6.0, d - 1);
            assert!(below > 1e-6, "{m}: degree {} fits too ({below:e})", d - 1);
        }
    }
}

#[test]
fn bdf_reaches_the_tables_order_and_its_dense_degree() {
    // At rtol 1e-5 on the orbit BDF climbs to its highest order, 5, with steps large enough
    // that its dense output (the interpolating polynomial of its difference table) shows
    // that degree: degree 5 reproduces it, degree 4 misses by ~6e-9.
    let sys = Kepler { e: 0.5 };
    let y0 = sys.y0();
    let opts = SolverOptions {
        method: Method::Bdf,
        rtol: 1e-5,
        atol: Atol::Scalar(1e-7),
        ..Default::default()
    };
    let problem = Problem::new(&sys, &opts).unwrap();
    let mut st = DiffsolStepper::new(problem.diffsol().unwrap(), 0.0, &y0, &opts).unwrap();
    let mut highest = 0;
    while st.t() < 6.0 {
        st.step(6.0).unwrap();
        highest = highest.max(st.order());
    }
    assert_eq!(highest, Method::Bdf.info().order);
    assert_eq!(Method::Bdf.dense_degree(), highest);
    assert!(misfit(&opts, 6.0, highest) < 1e-11);
    let below = misfit(&opts, 6.0, highest - 1);
    assert!(below > 1e-10, "{below:e}");
}

#[test]
fn jacobian_flag_matches_the_counters() {
    // Kepler has no analytic Jacobian: a method that uses one differences f, and every
    // Jacobian counts in jac_evals.
    let sys = Kepler { e: 0.1 };
    for m in Method::ALL {
        let mut opts = large_steps(m);
        opts.output = Output::Final;
        let s = solve(&sys, (0.0, 1.0), &sys.y0(), &opts).unwrap();
        assert_eq!(
            s.stats.jac_evals > 0,
            m.info().jacobian,
            "{m}: {:?}",
            s.stats
        );
    }
}

#[test]
fn the_driver_uses_the_tables_default_controller() {
    let sys = Arenstorf;
    let y0 = Arenstorf::Y0;
    for m in Method::ALL
        .into_iter()
        .filter(|m| m.info().family.is_one_step())
    {
        let base = SolverOptions {
            method: m,
            rtol: 1e-6,
            atol: Atol::Scalar(1e-8),
            output: Output::Final,
            ..Default::default()
        };
        let default = m.default_controller().unwrap();
        let run = |c: Option<ControllerKind>| {
            let o = SolverOptions {
                controller: c,
                ..base.clone()
            };
            assert_eq!(o.controller_in_use(), Some(c.unwrap_or(default)));
            solve(&sys, (0.0, 2.0), &y0, &o).unwrap().stats
        };
        let implicit = run(None);
        assert_eq!(implicit, run(Some(default)), "{m}");
        // Another controller takes other steps: the comparison above can fail.
        let other = if default == ControllerKind::I {
            ControllerKind::Pid
        } else {
            ControllerKind::I
        };
        assert_ne!(implicit, run(Some(other)), "{m}");
    }
}

#[test]
fn rhs_evaluations_per_fixed_step_are_stages_less_fsal() {
    // 10 fixed steps: 1 RHS at the start, then s − 1 per step for an FSAL pair (its last
    // stage is the next first) and s for the others (RK4 evaluates f at the new state as its
    // next k1; DOP853 its f(t + h, y_{n+1}) stage).
    let sys = Kepler { e: 0.1 };
    for m in Method::ALL
        .into_iter()
        .filter(|m| matches!(m.info().family, Family::FixedStep | Family::Explicit))
    {
        let i = m.info();
        let per_step = i.stages.unwrap() - usize::from(i.fsal);
        let s = solve(&sys, (0.0, 1.0), &sys.y0(), &fixed(m, 0.1)).unwrap();
        assert_eq!(s.stats.accepted, 10, "{m}");
        assert_eq!(s.stats.rhs_evals, 1 + 10 * per_step, "{m}");
    }
}

#[test]
fn the_family_decides_the_configuration() {
    for m in Method::ALL {
        let o = match m.info().family {
            Family::FixedStep => SolverOptions {
                method: m,
                step: Some(0.1),
                ..Default::default()
            },
            _ => SolverOptions::with_method(m),
        };
        let c = o.configure(4).unwrap();
        assert_eq!(c.method(), m);
        let family = match c {
            Config::Fixed(_) => Family::FixedStep,
            Config::OneStep(c) => {
                let options::StepControl::Adaptive(a) = c.control() else {
                    panic!("{m}: adaptive by default")
                };
                assert_eq!(Some(a.controller()), m.default_controller());
                m.info().family
            }
            Config::Diffsol(_) => Family::Diffsol,
        };
        assert_eq!(family, m.info().family, "{m}");
        assert!(family.is_one_step() || m.default_controller().is_none());
    }
}
