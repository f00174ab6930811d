//! trajectory.csv: one row per output time, the columns scripts rely on, SI units.
//!
//! ```text
//! t,crank_angle,slider_x,slider_v,slider_a,ex_over_c,ey_over_c,delta,contact_force,
//! friction_force,film_force,constraint_violation,driver_torque[,EXTRA...]
//! ```
//!
//! A column whose role the scene does not declare is left empty. Numbers are written in the
//! shortest form that reads back to the same f64. Source: docs/outputs.md (`trajectory.csv`).

use std::fmt::Write as _;
use std::path::Path;

use crate::error::Error;
use crate::io;
use crate::metrics::Sample;

/// File name of the trajectory in an output directory.
pub const TRAJECTORY_FILE: &str = "trajectory.csv";

/// The fixed columns, in order (docs/outputs.md, "`trajectory.csv`").
pub const COLUMNS: [&str; 13] = [
    "t",
    "crank_angle",
    "slider_x",
    "slider_v",
    "slider_a",
    "ex_over_c",
    "ey_over_c",
    "delta",
    "contact_force",
    "friction_force",
    "film_force",
    "constraint_violation",
    "driver_torque",
];

/// An extra column after the fixed ones: a name and one value per sample.
///
/// ```text
/// header = COLUMNS, extra names...;  row i = fixed values, extra values[i]...
/// ```
///
/// Source: docs/outputs.md (`trajectory.csv`: extra columns after).
#[derive(Clone, Copy, Debug)]
pub struct Extra<'a> {
    /// Column name (no comma, quote or newline; not a fixed column's name).
    pub name: &'a str,
    /// One value per sample.
    pub values: &'a [f64],
}

/// Formats a number so that it reads back to the same f64: plain decimal for
/// 1e-4 ≤ |x| < 1e15 (and 0), else scientific.
pub fn fmt_num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

fn fixed_values(s: &Sample) -> [Option<f64>; 13] {
    [
        Some(s.t),
        s.crank_angle,
        s.slider_x,
        s.slider_v,
        s.slider_a,
        s.ex_over_c,
        s.ey_over_c,
        s.delta,
        s.contact_force,
        s.friction_force,
        s.film_force,
        Some(s.constraint_violation),
        s.driver_torque,
    ]
}

/// The CSV text. Errors ([`Error::Internal`]): a non-finite value, an extra column of the
/// wrong length or with a bad name.
pub fn to_csv(samples: &[Sample], extra: &[Extra<'_>]) -> Result<String, Error> {
    for (k, e) in extra.iter().enumerate() {
        if e.values.len() != samples.len() {
            return Err(Error::Internal(format!(
                "trajectory: column {} has {} values for {} rows",
                e.name,
                e.values.len(),
                samples.len()
            )));
        }
        if e.name.is_empty()
            || e.name.contains([',', '"', '\n', '\r'])
            || COLUMNS.contains(&e.name)
            || extra[..k].iter().any(|o| o.name == e.name)
        {
            return Err(Error::Internal(format!(
                "trajectory: bad extra column name '{}'",
                e.name
            )));
        }
    }
    let mut out = COLUMNS.join(",");
    for e in extra {
        out.push(',');
        out.push_str(e.name);
    }
    out.push('\n');
    for (i, s) in samples.iter().enumerate() {
        let fixed = fixed_values(s);
        let cells = fixed
            .iter()
            .enumerate()
            .map(|(k, v)| (COLUMNS[k], *v))
            .chain(extra.iter().map(|e| (e.name, Some(e.values[i]))));
        for (k, (name, v)) in cells.enumerate() {
            if k > 0 {
                out.push(',');
            }
            if let Some(v) = v {
                if !v.is_finite() {
                    return Err(Error::Internal(format!(
                        "trajectory: {name} is {v} at t = {:e}",
                        s.t
                    )));
                }
                let _ = write!(out, "{}", fmt_num(v));
            }
        }
        out.push('\n');
    }
    Ok(out)
}

/// Writes `dir/trajectory.csv` atomically.
pub fn write(dir: &Path, samples: &[Sample], extra: &[Extra<'_>]) -> Result<(), Error> {
    let text = to_csv(samples, extra)?;
    io::write_atomic(&dir.join(TRAJECTORY_FILE), text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn full(t: f64) -> Sample {
        Sample {
            t,
            crank_angle: Some(15.707963267948966 * t),
            slider_x: Some(0.365 - 1e-7 * t),
            slider_v: Some(-0.1 * t),
            slider_a: Some(-3.859722),
            ex_over_c: Some(0.3),
            ey_over_c: Some(-0.4),
            eps: Some(0.5),
            delta: Some(-5e-5),
            contact_force: Some(0.0),
            friction_force: Some(-0.0),
            film_force: Some(1234.5),
            constraint_violation: 3.2e-13,
            driver_torque: Some(-1.0e16),
            ideal_slider_a: Some(-3.86),
        }
    }

    #[test]
    fn header_is_exactly_the_interface() {
        let csv = to_csv(&[], &[]).unwrap();
        assert_eq!(
            csv,
            "t,crank_angle,slider_x,slider_v,slider_a,ex_over_c,ey_over_c,delta,contact_force,friction_force,film_force,constraint_violation,driver_torque\n"
        );
    }

    #[test]
    fn values_round_trip_bit_exactly() {
        let samples: Vec<Sample> = (0..50).map(|i| full(i as f64 * 0.0173)).collect();
        let extra_vals: Vec<f64> = (0..50).map(|i| 1e-300 * i as f64).collect();
        let csv = to_csv(
            &samples,
            &[Extra {
                name: "lambda_0",
                values: &extra_vals,
            }],
        )
        .unwrap();
        let mut lines = csv.lines();
        assert!(lines.next().unwrap().ends_with(",driver_torque,lambda_0"));
        for (s, line) in samples.iter().zip(lines) {
            let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
            assert_eq!(cells.len(), 14);
            let want: Vec<f64> = fixed_values(s).iter().map(|v| v.unwrap()).collect();
            for (a, b) in cells[..13].iter().zip(&want) {
                assert_eq!(a.to_bits(), b.to_bits(), "{line}");
            }
        }
        assert_eq!(fmt_num(1.0e16), "1e16");
        assert_eq!(fmt_num(0.25), "0.25");
        assert_eq!(fmt_num(3.2e-13), "3.2e-13");
    }

    #[test]
    fn missing_roles_are_empty_cells() {
        let csv = to_csv(&[Sample::at(0.5)], &[]).unwrap();
        assert_eq!(csv.lines().nth(1).unwrap(), "0.5,,,,,,,,,,,0,");
    }

    #[test]
    fn bad_rows_and_columns_are_refused_and_nothing_is_written() {
        let d = tempfile::tempdir().unwrap();
        let mut s = full(0.1);
        s.slider_a = Some(f64::NAN);
        let e = write(d.path(), &[s], &[]).unwrap_err();
        assert!(e.to_string().contains("slider_a is NaN at t = 1e-1"), "{e}");
        assert!(!d.path().join(TRAJECTORY_FILE).exists());
        let one = [1.0];
        for name in ["delta", "a,b", ""] {
            assert!(
                to_csv(&[full(0.0)], &[Extra { name, values: &one }]).is_err(),
                "{name}"
            );
        }
        assert!(to_csv(
            &[full(0.0)],
            &[Extra {
                name: "x",
                values: &[]
            }]
        )
        .is_err());
        write(d.path(), &[full(0.0)], &[]).unwrap();
        assert_eq!(
            std::fs::read_to_string(d.path().join(TRAJECTORY_FILE))
                .unwrap()
                .lines()
                .count(),
            2
        );
    }
}
