//! Tests of the stiffness diagnostics' pieces.

use lash_solver::analysis::stiffness::Eigenvalue;

use super::report::*;
use super::sample::*;
use crate::diagnostics::stiffness::sample::median;
use crate::diagnostics::stiffness::sample::percentile;

#[test]
fn percentile_is_the_value_of_its_rank() {
    let v: Vec<f64> = (0..=100).rev().map(f64::from).collect();
    assert_eq!(percentile(&v, 0.05), Some(5.0));
    assert_eq!(percentile(&v, 0.0), Some(0.0));
    assert_eq!(percentile(&v, 1.0), Some(100.0));
    assert_eq!(percentile(&[], 0.5), None);
}

#[test]
fn median_of_odd_and_even_counts() {
    assert_eq!(median(&[]), None);
    assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
    assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
}

#[test]
fn csv_leaves_missing_values_empty() {
    let p = StiffnessPoint {
        t: 0.5,
        crank_angle: None,
        dominant: Eigenvalue { re: -2.0, im: 0.0 },
        spectral_radius: 2.0,
        stiffness_ratio: None,
        rk4_h_max: Some(1.5),
        limiting: None,
        n_unstable: 1,
    };
    let csv = to_csv(&[p]);
    let row = csv.lines().nth(1).unwrap();
    assert_eq!(row, "0.5,,-2,0,2,2,,1.5,,,1");
    assert_eq!(
        csv.lines().next().unwrap().split(',').count(),
        row.split(',').count()
    );
}
