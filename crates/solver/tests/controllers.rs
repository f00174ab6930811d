//! The controller presets against the Söderlind filter computed here from its formula and the
//! published coefficients, and the limits layer.
//!
//! ```text
//! h_{n+1} = h_n ε_n^{−k1/k} ε_{n−1}^{−k2/k} ε_{n−2}^{−k3/k} (h_n/h_{n−1})^{k4} (h_{n−1}/h_{n−2})^{k5}
//! (Söderlind 2003, ACM TOMS 29(1); SUNDIALS SUNAdaptController_Soderlind), with the
//! I controller h_{n+1} = h_n ε_n^{−1/k} until the filter has its history (SUNDIALS).
//! ```

use lash_solver::*;

/// Published coefficients (SUNDIALS sunadaptcontroller_soderlind.c defaults; Söderlind 2003
/// for H211b/H312b; Gustafsson 1994 with k̂1 = 0.98, k̂2 = 0.95 mapped as k1 = k̂1 + k̂2,
/// k2 = −k̂2, k4 = 1).
fn published(c: ControllerKind) -> [f64; 5] {
    match c {
        ControllerKind::I => [1.0, 0.0, 0.0, 0.0, 0.0],
        ControllerKind::Pi => [0.8, -0.31, 0.0, 0.0, 0.0],
        ControllerKind::Pid => [0.58, -0.21, 0.1, 0.0, 0.0],
        ControllerKind::H211 => [1.0 / 4.0, 1.0 / 4.0, 0.0, -1.0 / 4.0, 0.0],
        ControllerKind::H312 => [1.0 / 8.0, 2.0 / 8.0, 1.0 / 8.0, -3.0 / 8.0, -1.0 / 8.0],
        ControllerKind::Gustafsson => [0.98 + 0.95, -0.95, 0.0, 1.0, 0.0],
    }
}

#[test]
fn preset_coefficients_are_the_published_ones() {
    for c in ControllerKind::ALL {
        let (ours, theirs) = (c.coefficients(), published(c));
        for i in 0..5 {
            assert!(
                (ours[i] - theirs[i]).abs() <= 2.0 * f64::EPSILON,
                "{c}: k{} = {} vs {}",
                i + 1,
                ours[i],
                theirs[i]
            );
        }
        assert_eq!(ControllerKind::from_name(c.name()), Some(c));
    }
}

/// Expected step sequence, computed from the formula: errs[n] is the error of step n (all
/// accepted), h0 the first step, k = q̂ + 1.
fn expected_steps(kc: [f64; 5], errs: &[f64], h0: f64, q_hat: usize) -> Vec<f64> {
    let k = (q_hat + 1) as f64;
    let need = if kc[2] != 0.0 || kc[4] != 0.0 {
        2
    } else if kc[1] != 0.0 || kc[3] != 0.0 {
        1
    } else {
        0
    };
    let mut h = vec![h0];
    for n in 0..errs.len() {
        let hn = h[n];
        let next = if n < need {
            hn * errs[n].powf(-1.0 / k)
        } else {
            let mut f = errs[n].powf(-kc[0] / k);
            if need >= 1 {
                f *= errs[n - 1].powf(-kc[1] / k) * (hn / h[n - 1]).powf(kc[3]);
            }
            if need >= 2 {
                f *= errs[n - 2].powf(-kc[2] / k) * (h[n - 1] / h[n - 2]).powf(kc[4]);
            }
            hn * f
        };
        h.push(next);
    }
    h
}

const ERRS: [f64; 9] = [0.3, 0.7, 0.1, 0.9, 0.5, 0.02, 1.0, 0.6, 0.25];

#[test]
fn every_preset_reproduces_the_soderlind_formula() {
    for c in ControllerKind::ALL {
        for q_hat in [2, 4, 7] {
            let want = expected_steps(published(c), &ERRS, 0.01, q_hat);
            let mut ctrl = c.build();
            let mut h = 0.01;
            for (n, &e) in ERRS.iter().enumerate() {
                let f = ctrl.factor(h, e, q_hat);
                ctrl.accept(h, e);
                h *= f;
                assert!(
                    (h - want[n + 1]).abs() <= 1e-13 * want[n + 1],
                    "{c} q̂ = {q_hat}, step {}: {h} vs {}",
                    n + 1,
                    want[n + 1]
                );
            }
        }
    }
}

#[test]
fn history_needed_follows_sundials() {
    let need: Vec<usize> = ControllerKind::ALL
        .iter()
        .map(|c| c.build().history_needed())
        .collect();
    // i, pi, pid, h211, h312, gustafsson
    assert_eq!(need, vec![0, 1, 2, 1, 2, 1]);
}

#[test]
fn reset_forgets_history_and_factor_does_not_commit() {
    // factor() alone never changes the proposal; after reset the I controller is back.
    let mut c = ControllerKind::H312.build();
    let f0 = c.factor(0.1, 0.5, 4);
    assert_eq!(c.factor(0.1, 0.5, 4), f0);
    assert_eq!(f0, 0.5f64.powf(-1.0 / 5.0));
    for e in [0.3, 0.6, 0.2] {
        c.accept(0.1, e);
    }
    assert_ne!(c.factor(0.1, 0.5, 4), f0);
    c.reset();
    assert_eq!(c.factor(0.1, 0.5, 4), f0);
}

#[test]
fn limits_layer_clamps_as_documented() {
    // PI controller with the default limits (safety 0.9, first growth ≤ 1e4, growth ≤ 5,
    // shrink ≥ 0.2, after a rejection ≤ 0.9 then ≤ 0.3, growth after a rejection ≤ 1).
    let l = StepLimits::default();
    let mut s = StepSizeControl::new(Box::new(ControllerKind::Pi.build()), l.clone());
    let k = 5.0;
    // First step, ε = 1e-20 (floored at 1e-10), q̂ = 1: I controller 0.9·(1e-10)^(−1/2) = 9e4,
    // capped at max_first_growth = 1e4.
    let h1 = s.accept(1e-6, 1e-20, 1);
    assert_eq!(h1, 1e-6 * 1e4);
    // Second step (q̂ = 4 from here): PI with ε_{n−1} = 1e-10:
    // 0.9·(1e-10)^(−0.8/5)·(1e-10)^(0.31/5) = 8.6, capped at max_growth = 5.
    let h2 = s.accept(h1, 1e-10, 4);
    assert_eq!(h2, h1 * 5.0);
    // Rejection with ε = 2: elementary controller 0.9·2^(−1/5) = 0.783 < 0.9.
    let r1 = s.reject(h2, 2.0, 4);
    assert!((r1 / h2 - 0.9 * 2f64.powf(-1.0 / k)).abs() < 1e-15);
    // Second rejection in a row: capped at 0.3 even for ε barely above 1.
    let r2 = s.reject(r1, 1.01, 4);
    assert!((r2 / r1 - 0.3).abs() < 1e-15);
    // Huge error: shrink bounded by min_shrink = 0.2.
    let r3 = s.reject(r2, 1e12, 4);
    assert!((r3 / r2 - 0.2).abs() < 1e-15);
    // Accepted right after rejections, PI proposes 0.9·(1e-8)^(−0.16)·(1e-10)^(0.062) = 4.1:
    // capped at max_growth_after_reject = 1. The rejected attempts left no history.
    let h3 = s.accept(r3, 1e-8, 4);
    assert_eq!(h3, r3);
    // Then PI again, with ε_{n−1} = 1e-8 from the last accepted step, inside the caps.
    let h4 = s.accept(h3, 0.5, 4);
    let want = 0.9 * 0.5f64.powf(-0.8 / k) * 1e-8f64.powf(0.31 / k);
    assert!(want > 0.2 && want < 5.0);
    assert!((h4 / h3 - want).abs() < 1e-14, "{} vs {want}", h4 / h3);
    // reset(): first-step cap again.
    s.reset();
    assert_eq!(s.accept(1.0, 1e-20, 1), 1e4);
}

#[test]
fn deadband_keeps_the_step() {
    let l = StepLimits {
        deadband: (1.0, 1.5),
        ..Default::default()
    };
    let mut s = StepSizeControl::new(Box::new(ControllerKind::I.build()), l);
    // Leave the first-step regime.
    s.accept(1.0, 0.5, 4);
    // 0.9 · 0.3^(−1/5) = 1.141 ∈ [1, 1.5] → unchanged
    assert_eq!(s.accept(2.0, 0.3, 4), 2.0);
    // 0.9 · 0.01^(−1/5) = 2.26 → outside, applied
    let h = s.accept(2.0, 0.01, 4);
    assert!((h / 2.0 - 0.9 * 0.01f64.powf(-0.2)).abs() < 1e-14);
}

#[test]
fn invalid_limits_are_typed_errors() {
    use lash_solver::options::Reason;
    struct Decay;
    impl OdeSystem for Decay {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = -y[0];
        }
    }
    let bad = [
        (
            StepLimits {
                safety: 0.0,
                ..Default::default()
            },
            OptionField::Safety,
            "limits.safety must be in (0, 1], got 0",
        ),
        (
            StepLimits {
                max_growth: 1.0,
                ..Default::default()
            },
            OptionField::MaxGrowth,
            "limits.max_growth must be finite and > 1, got 1",
        ),
        (
            StepLimits {
                min_shrink: 1.0,
                ..Default::default()
            },
            OptionField::MinShrink,
            "limits.min_shrink must be in (0, 1), got 1",
        ),
        (
            StepLimits {
                deadband: (1.2, 1.5),
                ..Default::default()
            },
            OptionField::Deadband,
            "limits.deadband[0] must be in (0, 1], got 1.2",
        ),
    ];
    for (l, field, message) in bad {
        let e = l.validate().unwrap_err();
        assert_eq!(e.field, field);
        assert!(matches!(
            e.reason,
            Reason::OutOfRange { .. } | Reason::EntryOutOfRange { index: 0, .. }
        ));
        assert_eq!(e.to_string(), message);
        // Through an integration the same error is the solver's InvalidOptions.
        let opts = SolverOptions {
            limits: l,
            ..Default::default()
        };
        assert_eq!(
            solve(&Decay, (0.0, 1.0), &[1.0], &opts).unwrap_err(),
            SolveError::InvalidOptions(e)
        );
    }
    assert!(StepLimits::default().validate().is_ok());
}
