//! A run's trajectory as a table of named columns, read back from trajectory.csv or handed
//! over in memory, and the unit of every column.
//!
//! ```text
//! Table::from_csv(text)        header line, then one line per row; an empty cell is a
//!                              missing value (a column whose role the scene lacks)
//! Table::from_columns(n, d)    names and their values (NaN = missing), as a library
//!                              caller holds them (the Python binding's Run.columns)
//! column(name) = Some(values)  only when the column exists and no row misses it
//! unit(name)                   SI unit of a trajectory.csv column, by its name alone
//! ```
//!
//! Source: docs/outputs.md (`trajectory.csv`: the fixed columns and the per-element columns
//! `<body>.x`, … of `Mechanism::output_columns`).

use crate::error::Error;

/// A trajectory: column names and their values, one per row.
///
/// ```text
/// names[k] ↔ values[k]; values[k].len() = rows for every k; NaN marks a missing value
/// ```
///
/// Source: docs/outputs.md (`trajectory.csv`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Table {
    names: Vec<String>,
    values: Vec<Vec<f64>>,
}

impl Table {
    /// Reads the text of a trajectory.csv: the header, then rows of numbers (empty cells are
    /// missing values). `what` names the file in errors ([`Error::Input`]: a line with the
    /// wrong number of cells, a cell that is not a number, no header, no row).
    pub(crate) fn from_csv(text: &str, what: &str) -> Result<Table, Error> {
        let mut lines = text.lines();
        let header = lines
            .next()
            .filter(|h| !h.trim().is_empty())
            .ok_or_else(|| Error::Input(format!("{what} is empty: no header line")))?;
        let names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
        if names.first().map(String::as_str) != Some("t") {
            return Err(Error::Input(format!(
                "{what}: the first column is '{}', not t: not a lash trajectory",
                names[0]
            )));
        }
        let mut values = vec![Vec::new(); names.len()];
        for (i, line) in lines.enumerate() {
            if line.is_empty() {
                continue;
            }
            let mut n = 0;
            for (k, cell) in line.split(',').enumerate() {
                n += 1;
                let Some(col) = values.get_mut(k) else {
                    continue;
                };
                let v = if cell.is_empty() {
                    f64::NAN
                } else {
                    cell.trim().parse::<f64>().map_err(|_| {
                        Error::Input(format!(
                            "{what} line {}: '{cell}' in column {} is not a number",
                            i + 2,
                            names[k]
                        ))
                    })?
                };
                col.push(v);
            }
            if n != names.len() {
                return Err(Error::Input(format!(
                    "{what} line {}: {n} cells for {} columns",
                    i + 2,
                    names.len()
                )));
            }
        }
        if values[0].is_empty() {
            return Err(Error::Input(format!("{what} has no rows")));
        }
        Ok(Table { names, values })
    }

    /// A table of columns held in memory: `names[k]` with `values[k]` (NaN = missing). Errors
    /// ([`Error::Usage`]): unequal lengths, no column `t` first, no rows.
    pub(crate) fn from_columns(names: Vec<String>, values: Vec<Vec<f64>>) -> Result<Table, Error> {
        if names.len() != values.len() {
            return Err(Error::Usage(format!(
                "{} column names for {} columns",
                names.len(),
                values.len()
            )));
        }
        if names.first().map(String::as_str) != Some("t") {
            return Err(Error::Usage("the first column must be t".into()));
        }
        let rows = values[0].len();
        if rows == 0 {
            return Err(Error::Usage("the trajectory has no rows".into()));
        }
        if let Some(k) = values.iter().position(|v| v.len() != rows) {
            return Err(Error::Usage(format!(
                "column {} has {} values, t has {rows}",
                names[k],
                values[k].len()
            )));
        }
        Ok(Table { names, values })
    }

    /// Number of rows.
    pub(crate) fn rows(&self) -> usize {
        self.values[0].len()
    }

    /// Column names, in order.
    #[cfg(test)]
    pub(crate) fn names(&self) -> &[String] {
        &self.names
    }

    /// The values of column `name` when it exists and no row misses it.
    pub(crate) fn column(&self, name: &str) -> Option<&[f64]> {
        let k = self.names.iter().position(|n| n == name)?;
        let v = &self.values[k];
        v.iter().all(|x| !x.is_nan()).then_some(v.as_slice())
    }

    /// Names of the columns every row fills, in order.
    pub(crate) fn present(&self) -> Vec<&str> {
        self.names
            .iter()
            .zip(&self.values)
            .filter(|(_, v)| v.iter().all(|x| !x.is_nan()))
            .map(|(n, _)| n.as_str())
            .collect()
    }

    /// Whether column `name` exists (filled or not).
    pub(crate) fn has(&self, name: &str) -> bool {
        self.names.iter().any(|n| n == name)
    }

    /// The time column.
    pub(crate) fn t(&self) -> &[f64] {
        &self.values[0]
    }
}

/// The SI unit of a trajectory.csv column, from its name: the fixed columns by name, the
/// per-element columns `<name>.<quantity>` by their quantity; "" for a dimensionless column
/// (e/c) and for the state columns `y0`, … of a test problem, whose units are the problem's.
///
/// ```text
/// t s · crank_angle, theta, angle, tilt rad · slider_x, x, y, delta, length, offset m ·
/// slider_v, vx, vy m/s · slider_a, ax, ay m/s² · omega, speed rad/s · alpha rad/s² ·
/// *_force, force N · torque, driver_torque N·m · constraint_violation m (and rad) ·
/// ex_over_c, ey_over_c 1
/// ```
pub(crate) fn unit(name: &str) -> &'static str {
    let q = match name {
        "t" => return "s",
        "crank_angle" => return "rad",
        "slider_x" => return "m",
        "slider_v" => return "m/s",
        "slider_a" => return "m/s²",
        "driver_torque" => return "N·m",
        "constraint_violation" => return "m, rad",
        _ => name.rsplit('.').next().unwrap_or(name),
    };
    match q {
        "x" | "y" | "delta" | "length" | "offset" => "m",
        "theta" | "angle" | "tilt" => "rad",
        "vx" | "vy" => "m/s",
        "ax" | "ay" => "m/s²",
        "omega" | "speed" => "rad/s",
        "alpha" => "rad/s²",
        "contact_force" | "friction_force" | "film_force" | "force" => "N",
        "torque" => "N·m",
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip_with_missing_columns() {
        let csv = "t,crank_angle,slider_x,b.x\n0,0,,0.25\n0.5,1.5,,-1e-17\n";
        let t = Table::from_csv(csv, "trajectory.csv").unwrap();
        assert_eq!(t.rows(), 2);
        assert_eq!(t.column("b.x").unwrap(), &[0.25, -1e-17]);
        assert_eq!(t.column("slider_x"), None);
        assert!(t.has("slider_x"));
        assert_eq!(t.present(), vec!["t", "crank_angle", "b.x"]);
        let e = Table::from_csv("t,a\n0,1\n1\n", "f.csv").unwrap_err();
        assert_eq!(e.to_string(), "f.csv line 3: 1 cells for 2 columns");
        let e = Table::from_csv("t,a\n0,x\n", "f.csv").unwrap_err();
        assert!(e.to_string().contains("'x' in column a"), "{e}");
        assert!(Table::from_csv("", "f.csv").is_err());
        assert!(Table::from_csv("a,t\n1,2\n", "f.csv").is_err());
        assert!(Table::from_csv("t,a\n", "f.csv").is_err());
    }

    #[test]
    fn columns_in_memory_are_checked() {
        let t = Table::from_columns(
            vec!["t".into(), "a".into()],
            vec![vec![0.0, 1.0], vec![f64::NAN, 2.0]],
        )
        .unwrap();
        assert_eq!(
            t.column("a"),
            None,
            "a missing value makes the column absent"
        );
        assert!(Table::from_columns(vec!["t".into()], vec![vec![0.0], vec![1.0]]).is_err());
        assert!(Table::from_columns(
            vec!["t".into(), "a".into()],
            vec![vec![0.0, 1.0], vec![2.0]]
        )
        .is_err());
    }

    #[test]
    fn units_follow_docs_outputs() {
        for (name, u) in [
            ("t", "s"),
            ("slider_a", "m/s²"),
            ("contact_force", "N"),
            ("ex_over_c", ""),
            ("rod.theta", "rad"),
            ("rod.x", "m"),
            ("rod.alpha", "rad/s²"),
            ("a.b.vx", "m/s"),
            ("rod_slider.film_force", "N"),
            ("crank_driver.torque", "N·m"),
            ("spring.length", "m"),
            ("motor.speed", "rad/s"),
            ("guide.tilt", "rad"),
            ("y3", ""),
        ] {
            assert_eq!(unit(name), u, "{name}");
        }
    }
}
