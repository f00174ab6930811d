//! The option rules of `lash_solver::options`, each through [`SolverOptions::configure`] or an
//! integration: the typed error (field, reason, value, allowed set) and the message the front
//! ends show (the engine's names; `lash` and Python spell the fields their own way).

use lash_solver::method::Family;
use lash_solver::options::{Allowed, Reason};
use lash_solver::*;

/// The error `opts` gives for a system of dimension 4.
fn error(opts: SolverOptions) -> OptionError {
    opts.configure(4).unwrap_err()
}

fn with(method: Method) -> SolverOptions {
    SolverOptions::with_method(method)
}

#[test]
fn rtol_range_is_one_rule() {
    // [1e-14, 1): both ends, NaN and a value just below the bottom.
    for (v, ok) in [
        (1e-14, true),
        (0.5, true),
        (9.9e-15, false),
        (1.0, false),
        (f64::NAN, false),
    ] {
        assert_eq!(Rule::RTOL.check(v).is_ok(), ok, "{v}");
        let r = SolverOptions {
            rtol: v,
            ..Default::default()
        }
        .configure(4);
        assert_eq!(r.is_ok(), ok, "{v}");
    }
    let e = error(SolverOptions {
        rtol: 0.0,
        ..Default::default()
    });
    assert_eq!(e, Rule::RTOL.check(0.0).unwrap_err());
    assert_eq!(e.field, OptionField::Rtol);
    assert_eq!(
        e.reason,
        Reason::OutOfRange {
            value: 0.0,
            allowed: Rule::RTOL.allowed
        }
    );
    assert_eq!(e.to_string(), "rtol must be in [1e-14, 1), got 0");
}

#[test]
fn atol_is_positive_and_one_per_component() {
    let e = error(SolverOptions {
        atol: Atol::Scalar(-1.0),
        ..Default::default()
    });
    assert_eq!(e.to_string(), "atol must be finite and > 0, got -1");
    let e = error(SolverOptions {
        atol: Atol::Vector(vec![1e-9, 1e-9]),
        ..Default::default()
    });
    assert_eq!(
        e.reason,
        Reason::WrongLength {
            len: 2,
            expected: 4
        }
    );
    assert_eq!(e.to_string(), "atol has 2 entries, the system 4");
    let e = error(SolverOptions {
        atol: Atol::Vector(vec![1e-9, 1e-9, 0.0, 1e-9]),
        ..Default::default()
    });
    assert_eq!(e.to_string(), "atol[2] must be finite and > 0, got 0");
}

#[test]
fn fixed_step_needs_its_step_and_nothing_adaptive() {
    let e = error(with(Method::Rk4));
    assert_eq!(
        e,
        OptionError::new(
            OptionField::Step,
            Reason::Required {
                method: Method::Rk4
            }
        )
    );
    // The engine's wording and the solver's earlier one ("needs a fixed step") both hold.
    assert_eq!(
        e.to_string(),
        "method rk4 is fixed-step and needs step (it needs a fixed step size)"
    );
    let rk4 = SolverOptions {
        method: Method::Rk4,
        step: Some(1e-3),
        ..Default::default()
    };
    assert!(rk4.configure(4).is_ok());
    assert_eq!(
        error(SolverOptions {
            step: Some(0.0),
            ..rk4.clone()
        })
        .to_string(),
        "step must be finite and > 0, got 0"
    );
    for (o, field) in [
        (
            SolverOptions {
                h0: Some(1e-3),
                ..rk4.clone()
            },
            "h0",
        ),
        (
            SolverOptions {
                controller: Some(ControllerKind::Pi),
                ..rk4.clone()
            },
            "controller",
        ),
    ] {
        assert_eq!(
            error(o).to_string(),
            format!("{field} is only for adaptive methods, and rk4 is fixed-step")
        );
    }
    // Options that always have a value are ignored by the methods they do not fit, even
    // out of range: one set of options can switch between methods.
    let ignored = SolverOptions {
        rtol: 5.0,
        atol: Atol::Vector(vec![1.0]),
        h_min: 1.0,
        h_max: 0.0,
        limits: StepLimits {
            safety: 2.0,
            ..Default::default()
        },
        ..rk4
    };
    assert!(ignored.configure(4).is_ok());
}

#[test]
fn adaptive_methods_refuse_a_step() {
    for m in [Method::Dopri54, Method::Rodas5p, Method::Bdf] {
        let e = error(SolverOptions {
            step: Some(1e-3),
            ..with(m)
        });
        assert_eq!(e.reason, Reason::NotForMethod { method: m }, "{m}: {e}");
        assert_eq!(
            e.to_string(),
            format!("step is only for fixed-step methods, and {m} is adaptive")
        );
    }
}

#[test]
fn diffsol_takes_no_controller_and_no_fixed_steps() {
    let e = error(SolverOptions {
        controller: Some(ControllerKind::Pi),
        ..with(Method::Bdf)
    });
    assert_eq!(e.field, OptionField::Controller);
    let m = e.to_string();
    assert!(m.starts_with("controller does not apply to bdf"), "{m}");
    assert!(m.contains("takes no controller"), "{m}");
    let e = error(SolverOptions {
        adaptive: false,
        h0: Some(0.1),
        ..with(Method::Trbdf2)
    });
    assert_eq!(
        e.to_string(),
        "adaptive = false does not apply to trbdf2, which uses diffsol's own step control"
    );
    // diffsol's methods use the step bounds but not the limits of our controllers.
    let o = SolverOptions {
        h0: Some(1e-3),
        h_max: 0.5,
        limits: StepLimits {
            safety: 2.0,
            ..Default::default()
        },
        ..with(Method::Esdirk34)
    };
    let Config::Diffsol(c) = o.configure(4).unwrap() else {
        panic!("esdirk34 is diffsol's")
    };
    assert_eq!((c.bounds().h0(), c.bounds().h_max()), (Some(1e-3), 0.5));
}

#[test]
fn fixed_steps_of_one_step_methods_need_h0() {
    let e = error(SolverOptions {
        adaptive: false,
        ..with(Method::Dopri54)
    });
    assert_eq!(
        e,
        OptionError::new(
            OptionField::H0,
            Reason::RequiredBy {
                other: OptionField::Adaptive
            }
        )
    );
    assert_eq!(
        e.to_string(),
        "adaptive = false needs h0, the size of every step"
    );
    let o = SolverOptions {
        adaptive: false,
        h0: Some(0.25),
        ..with(Method::Rodas5p)
    };
    let Config::OneStep(c) = o.configure(4).unwrap() else {
        panic!("rodas5p is a one-step method")
    };
    assert_eq!(c.control(), &options::StepControl::Fixed { h: 0.25 });
}

#[test]
fn step_bounds_and_limits() {
    assert_eq!(
        error(SolverOptions {
            h_max: 0.0,
            ..Default::default()
        })
        .to_string(),
        "h_max (0) must exceed h_min (0)"
    );
    assert_eq!(
        error(SolverOptions {
            h_min: -1.0,
            ..Default::default()
        })
        .to_string(),
        "h_min must be finite and >= 0, got -1"
    );
    assert_eq!(
        error(SolverOptions {
            h0: Some(-1.0),
            ..Default::default()
        })
        .to_string(),
        "h0 must be finite and > 0, got -1"
    );
    let e = error(SolverOptions {
        limits: StepLimits {
            max_after_reject: 0.0,
            ..Default::default()
        },
        ..Default::default()
    });
    assert_eq!(e.field, OptionField::MaxAfterReject);
}

#[test]
fn every_method_checks_budgets_events_and_output() {
    let rk4 = SolverOptions {
        method: Method::Rk4,
        step: Some(1e-3),
        ..Default::default()
    };
    for base in [rk4, with(Method::Tsit54), with(Method::Bdf)] {
        let cases: [(SolverOptions, &str); 7] = [
            (
                SolverOptions {
                    max_steps: 0,
                    ..base.clone()
                },
                "max_steps must be >= 1, got 0",
            ),
            (
                SolverOptions {
                    max_wall_time: Some(f64::INFINITY),
                    ..base.clone()
                },
                "max_wall_time must be finite and > 0, got inf",
            ),
            (
                SolverOptions {
                    event_rtol: 1e-2,
                    ..base.clone()
                },
                "event_rtol must be in [1e-15, 1e-3], got 0.01",
            ),
            (
                SolverOptions {
                    event_samples: 65,
                    ..base.clone()
                },
                "event_samples must be <= 64, got 65",
            ),
            (
                SolverOptions {
                    divergence_bound: 0.0,
                    ..base.clone()
                },
                "divergence_bound must be > 0, got 0",
            ),
            (
                SolverOptions {
                    output: Output::Times(vec![0.1, f64::NAN]),
                    ..base.clone()
                },
                "output[1] is not finite, got NaN",
            ),
            (
                SolverOptions {
                    output: Output::Times(vec![0.1, 0.3, 0.2]),
                    ..base.clone()
                },
                "output must be non-decreasing, and entry 2 is smaller than entry 1",
            ),
        ];
        for (o, message) in cases {
            assert_eq!(error(o).to_string(), message, "{}", base.method);
        }
    }
}

#[test]
fn integration_arguments_are_typed_too() {
    struct Decay;
    impl OdeSystem for Decay {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = -y[0];
        }
    }
    let o = SolverOptions::default();
    let fails = |span: (f64, f64), y0: &[f64]| match solve(&Decay, span, y0, &o) {
        Err(SolveError::InvalidOptions(e)) => e,
        other => panic!("{other:?}"),
    };
    let e = fails((0.0, 1.0), &[1.0, 2.0]);
    assert_eq!(e.to_string(), "y0 has 2 entries, the system 1");
    let e = fails((1.0, 1.0), &[1.0]);
    assert_eq!(e.field, OptionField::TEnd);
    assert_eq!(e.to_string(), "t_end (1) must exceed t0 (1)");
    let e = fails((0.0, 1.0), &[f64::NAN]);
    assert_eq!(e.to_string(), "y0[0] is not finite, got NaN");
    assert_eq!(
        SolveError::InvalidOptions(e).to_string(),
        "invalid options: y0[0] is not finite, got NaN"
    );
}

#[test]
fn the_takes_table() {
    use OptionField as F;
    // Absent-able options given to a family that does not take them are refused; the table
    // says which.
    let rows = [
        (F::Step, [true, false, false, false]),
        (F::Rtol, [false, true, true, true]),
        (F::H0, [false, true, true, true]),
        (F::Controller, [false, true, true, false]),
        (F::Safety, [false, true, true, false]),
        (F::Adaptive, [true, true, true, false]),
        (F::Rk4InstabilitySteps, [true, false, false, false]),
        (F::MaxSteps, [true, true, true, true]),
        (F::EventSamples, [true, true, true, true]),
    ];
    let families = [
        Family::FixedStep,
        Family::Explicit,
        Family::Rosenbrock,
        Family::Diffsol,
    ];
    for (field, takes) in rows {
        for (family, t) in families.into_iter().zip(takes) {
            assert_eq!(family.takes(field), t, "{family:?} {field}");
        }
    }
    // The allowed set of a rule is what its message states.
    assert_eq!(Rule::EVENT_RTOL.allowed.to_string(), "in [1e-15, 1e-3]");
    assert_eq!(Allowed::FiniteAbove(0.0).to_string(), "finite and > 0");
}
