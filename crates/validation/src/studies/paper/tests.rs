//! Tests of the study's statistics and runner.

use std::collections::BTreeMap;
use std::f64::consts::PI;

use lash_model::scene::JointSpec;
use lash_model::{IdealSliderCrank, Scene};

use crate::report::metrics::{self, Sample};
use crate::store::cache::CACHE_DIR;

use super::figures;
use super::plan::*;
use super::result::*;
use super::runner::*;
use super::stats::*;
use crate::progress::NoProgress;
use crate::run::press::PressCase;
use crate::studies::paper::runner::realisation;

const RPM: f64 = 150.0;

fn ideal() -> IdealSliderCrank {
    IdealSliderCrank {
        r: 0.015,
        l: 0.35,
        omega: RPM * PI / 30.0,
        theta0: 0.0,
        offset: 0.0,
    }
}

/// Samples of the second revolution (or the first) built from the ideal mechanism plus
/// the given deviations of x, ẍ and e/c, as functions of the crank angle θ.
fn window(
    second: bool,
    dx: impl Fn(f64) -> f64,
    da: impl Fn(f64) -> f64,
    e: impl Fn(f64) -> (f64, f64),
) -> Vec<Sample> {
    let m = ideal();
    let period = 60.0 / RPM;
    let t_end = if second { 2.0 * period } else { period };
    metrics::grid(t_end, period)
        .into_iter()
        .map(|t| {
            let th = m.omega * t;
            let (ex, ey) = e(th);
            let eps = ex.hypot(ey);
            Sample {
                crank_angle: Some(th),
                slider_x: Some(m.x_at(th) + dx(th)),
                slider_v: Some(m.v_at(th)),
                slider_a: Some(m.a_at(th) + da(th)),
                ex_over_c: Some(ex),
                ey_over_c: Some(ey),
                eps: Some(eps),
                delta: Some(1e-4 * (eps - 1.0)),
                ..Sample::at(t)
            }
        })
        .collect()
}

#[test]
fn deviations_of_the_ideal_itself_vanish() {
    let w = window(true, |_| 0.0, |_| 0.0, |_| (0.5, 0.0));
    let d = deviations(&w, &w, &ideal()).unwrap();
    assert_eq!(
        (d.x_dev_max, d.v_dev_max, d.a_dev_max, d.x_dev_bdc),
        (0.0, 0.0, 0.0, 0.0)
    );
    assert_eq!(
        (d.x_dev_rel, d.a_dev_rel, d.fluctuation_sectors),
        (0.0, 0.0, 0)
    );
    assert_eq!(
        (d.contact_fraction, d.orbit_closure),
        (Some(0.0), Some(0.0))
    );
    // Stroke 2r: θ = 0 and π are grid points (i = 0, 1000, 2000).
    assert!((d.stroke - 0.03).abs() < 1e-15, "{}", d.stroke);
    // Ideal peak |ẍ| at θ = 0: r ω² (1 + r/l) (docs/model.md §5: 3.85972 m/s² at 150 rpm).
    assert!(
        (d.a_ideal_peak - 3.85972).abs() < 5e-6,
        "{}",
        d.a_ideal_peak
    );
}

#[test]
fn deviations_measure_known_offsets() {
    let (d0, amp) = (2e-4, 0.3);
    // x off by d0 sin θ: max d0 at 90° (grid point i = 500); within ±15° of θ = 0 the largest
    // grid angle is 83 × 0.18° = 14.94°. ẍ off by amp sin 4θ: peaks amp at 22.5° + k 45°, all
    // grid points (i = 125 + 250 k), one per 45° sector.
    let last = window(
        true,
        |th| d0 * th.sin(),
        |th| amp * (4.0 * th).sin(),
        |th| {
            // In contact (ε = 1.2) for θ in (45.09°, 135.09°): grid points i = 251..=750.
            let deg = th.to_degrees().rem_euclid(360.0);
            let eps = if deg > 45.09 && deg < 135.09 {
                1.2
            } else {
                0.5
            };
            (eps, 0.0)
        },
    );
    let mut prev = last.clone();
    for s in prev.iter_mut() {
        s.ex_over_c = s.ex_over_c.map(|x| x + 0.03);
        s.ey_over_c = s.ey_over_c.map(|y| y - 0.04);
    }
    let d = deviations(&last, &prev, &ideal()).unwrap();
    assert!((d.x_dev_max - d0).abs() < 1e-15, "{}", d.x_dev_max); // x ≈ 0.365 m: rounding 1e-16
    let bdc = d0 * (83.0 * 0.18f64).to_radians().sin();
    assert!((d.x_dev_bdc - bdc).abs() < 1e-15, "{} {bdc}", d.x_dev_bdc);
    assert!((d.a_dev_max - amp).abs() < 1e-12);
    // 0.3 is 7.8 % of the 3.86 m/s² peak: no sector passes the 10 % mark.
    assert_eq!(d.fluctuation_sectors, 0);
    // Near θ = 0: |sin 4θ| is largest at the window's edge, 4 × 14.94°; near π likewise.
    let dc = amp * (4.0 * 83.0 * 0.18f64).to_radians().sin();
    assert!(
        (d.a_dev_dead_centres - dc).abs() < 1e-12,
        "{}",
        d.a_dev_dead_centres
    );
    assert_eq!(d.contact_fraction, Some(500.0 / 2001.0));
    assert!((d.orbit_closure.unwrap() - 0.05).abs() < 1e-15);
    // RMS of d0 sin θ over the 2001 points is d0 sqrt(1000/2001); the ideal x about its mean
    // is about r/√2 (plus the small l-term): the ratio is checked against its definition.
    let xi: Vec<f64> = last
        .iter()
        .map(|s| ideal().x_at(s.crank_angle.unwrap()))
        .collect();
    let mean = xi.iter().sum::<f64>() / 2001.0;
    let den = (xi.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 2001.0).sqrt();
    let rel = d0 * (1000.0f64 / 2001.0).sqrt() / den;
    assert!(
        (d.x_dev_rel - rel).abs() < 1e-12 * rel,
        "{} {rel}",
        d.x_dev_rel
    );
    // With amp above 10 % of the peak every sector fluctuates.
    let big = window(true, |_| 0.0, |th| 0.5 * (4.0 * th).sin(), |_| (0.5, 0.0));
    assert_eq!(
        deviations(&big, &big, &ideal())
            .unwrap()
            .fluctuation_sectors,
        8
    );
}

#[test]
fn deviations_refuse_mismatched_or_missing_samples() {
    let w = window(true, |_| 0.0, |_| 0.0, |_| (0.5, 0.0));
    assert!(deviations(&w, &w[1..], &ideal()).is_err());
    let mut bad = w.clone();
    bad[3].slider_v = None;
    let e = deviations(&bad, &w, &ideal()).unwrap_err();
    assert!(e.to_string().contains("slider_v missing"), "{e}");
    // No clearance joint: no contact fraction, no orbit.
    let bare: Vec<Sample> = w
        .iter()
        .map(|s| Sample {
            ex_over_c: None,
            ey_over_c: None,
            delta: None,
            eps: None,
            ..s.clone()
        })
        .collect();
    let d = deviations(&bare, &bare, &ideal()).unwrap();
    assert_eq!((d.contact_fraction, d.orbit_closure), (None, None));
}

#[test]
fn spread_is_the_largest_pointwise_range() {
    let (a, b, c) = (
        vec![1.0, 2.0, 3.0],
        vec![1.5, 0.0, 3.0],
        vec![1.2, 2.5, 3.1],
    );
    assert_eq!(spread(&[&a, &b, &c]), 2.5);
    assert_eq!(spread(&[&a]), 0.0);
}

#[test]
fn realisations_move_only_the_crank_phase() {
    let s = &PressCase::dry(150, 100).scene();
    let r = realisation(s, 3, 1e-6);
    let theta0 = |s: &Scene| {
        s.joints
            .iter()
            .find_map(|j| match j {
                JointSpec::Driver(d) => Some(d.theta0),
                _ => None,
            })
            .unwrap()
    };
    assert_eq!(theta0(&r), theta0(s) + 3e-6);
    let mut back = r.clone();
    for j in back.joints.iter_mut() {
        if let JointSpec::Driver(d) = j {
            d.theta0 = theta0(s);
        }
    }
    assert_eq!(&back, s);
    assert_eq!(&realisation(s, 0, 1e-6), s);
}

#[test]
fn ideal_run_reproduces_the_closed_form() {
    // docs/model.md §5: ẍ(θ = 0) = −r ω² (1 + r/l) = −3.85972 m/s² at 150 rpm; the last grid
    // point is θ = 4π. The run's RMS deviation from the closed form is the integration
    // error, far below the 1e-6 relative that M1 asks for.
    let case = PressCase::ideal(150);
    let r = run_case(case, &case.scene(), &Plan::paper().settings, None).unwrap();
    assert_eq!((r.last.len(), r.previous.len()), (2001, 2001));
    assert_eq!(r.last[0].t, r.previous[2000].t);
    let m = &r.metrics;
    assert!((m.slider_acc_min.unwrap() + 3.85972).abs() < 5e-6, "{m:?}");
    assert!(m.slider_acc_rms_dev_ideal.unwrap() < 1e-6 * 3.86, "{m:?}");
    assert_eq!((m.eps_max, m.contact_onsets), (None, None));
    let d = deviations(&r.last, &r.previous, r.ideal.as_ref().unwrap()).unwrap();
    assert!((d.stroke - 0.03).abs() < 1e-9, "{}", d.stroke);
}

#[test]
fn a_failing_study_writes_nothing() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("study");
    let mut plan = Plan::paper();
    plan.settings.rtol = 0.0; // refused by the solver's option check
    plan.realisations = 1;
    let e = run_and_write_with(&plan, &out, &NoProgress).unwrap_err();
    assert_eq!(e.kind(), crate::ErrorKind::Solver, "{e}");
    // Only the cache of the runs that finished (at the other settings) may be there.
    for f in [JSON_FILE, REPORT_FILE, FIGURES_DIR] {
        assert!(!out.join(f).exists(), "{f}");
    }
    if out.exists() {
        let names: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, [CACHE_DIR]);
    }
    let out = d.path().join("study2");
    plan = Plan::paper();
    plan.realisations = 0;
    assert_eq!(
        run_and_write_with(&plan, &out, &NoProgress)
            .unwrap_err()
            .kind(),
        crate::ErrorKind::BadInput
    );
    assert!(!out.exists());
}

#[test]
fn the_study_has_the_papers_eighteen_cases() {
    let names = study_cases();
    assert_eq!(names.len(), 18);
    // Every case is a scene of cases/press, written by the model's generator.
    let cat: BTreeMap<String, Scene> = lash_model::cases::press_catalogue().into_iter().collect();
    for n in &names {
        assert!(cat.contains_key(&n.to_string()), "{n}");
    }
    let mut sorted = names.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), 18);
    assert_eq!(figures::count(), 44);
}
