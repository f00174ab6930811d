//! trajectory.csv: one row per output time, the columns scripts rely on, SI units; and the
//! sinks a run pushes its rows into as it goes.
//!
//! ```text
//! header  t,crank_angle,slider_x,slider_v,slider_a,ex_over_c,ey_over_c,delta,contact_force,
//!         friction_force,film_force,constraint_violation,driver_torque,   (COLUMNS, fixed)
//!         <body>.x, …, <joint>.ex_over_c, …, <driver>.torque, …           (a mechanism's
//!                                              Mechanism::output_columns, in that order)
//!         y0, y1, …                                                       (a test problem)
//! row     one value per column; a fixed column whose role the scene lacks is absent: its
//!         cells are empty in the CSV and NaN in a row pushed to a sink
//!
//! sink.start(header) → sink.row(values) × rows → sink.finish()    (TrajectorySink)
//!   CsvFile        streams the CSV to a file as the run goes (memory: one buffer)
//!   Columns        keeps every column in memory (a library caller's arrays)
//! ```
//!
//! Every sink receives the same rows, so the CSV of a [`Columns`] collector
//! ([`Columns::to_csv`]) is byte for byte the file a [`CsvFile`] streamed. Numbers are written
//! in the shortest form that reads back to the same f64. Source: docs/outputs.md
//! (`trajectory.csv`).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::Error;
use crate::report::number::push_num;
use crate::store::io;

/// File name of the trajectory in an output directory.
pub(crate) const TRAJECTORY_FILE: &str = "trajectory.csv";

/// File name of the trajectory up to a solver failure (docs/outputs.md, "`failure.json`").
pub(crate) const PARTIAL_TRAJECTORY_FILE: &str = "partial_trajectory.csv";

/// The fixed columns, in order (docs/outputs.md, "`trajectory.csv`").
pub(crate) const COLUMNS: [&str; 13] = [
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

/// Write buffer of a streamed trajectory, bytes: the memory a [`CsvFile`] holds.
pub(crate) const WRITE_BUFFER: usize = 1 << 16;

/// Formats a number so that it reads back to the same f64: plain decimal for
/// 1e-4 ≤ |x| < 1e15 (and 0), else scientific.
pub(crate) fn fmt_num(x: f64) -> String {
    let mut s = String::new();
    push_num(&mut s, x);
    s
}

/// The columns of one run's trajectory: their names and which of them the run fills.
///
/// ```text
/// names = COLUMNS ++ element columns;  present[k] = false: column k is empty in every row
/// ```
///
/// Source: docs/outputs.md (`trajectory.csv`).
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    names: Vec<String>,
    present: Vec<bool>,
}

impl Header {
    /// The fixed columns (`fixed_present[k]`: whether the run fills [`COLUMNS`]`[k]`) followed
    /// by `extra` columns, all filled. Errors ([`Error::Internal`]): an extra name that is
    /// empty, holds a comma, quote or line break, or repeats a name.
    pub(crate) fn new(fixed_present: [bool; 13], extra: Vec<String>) -> Result<Header, Error> {
        let mut names: Vec<String> = COLUMNS.iter().map(|s| s.to_string()).collect();
        let mut seen: std::collections::HashSet<String> = names.iter().cloned().collect();
        for e in &extra {
            if e.is_empty() || e.contains([',', '"', '\n', '\r']) || !seen.insert(e.clone()) {
                return Err(Error::Internal(format!(
                    "trajectory: bad or repeated column name '{e}'"
                )));
            }
        }
        let mut present = fixed_present.to_vec();
        present.extend(std::iter::repeat_n(true, extra.len()));
        names.extend(extra);
        Ok(Header { names, present })
    }

    /// Column names, in order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Whether each column is filled.
    pub fn present(&self) -> &[bool] {
        &self.present
    }

    /// Number of columns.
    pub(crate) fn len(&self) -> usize {
        self.names.len()
    }

    /// Index of the column `name`.
    pub(crate) fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// The header line (no line break).
    pub(crate) fn line(&self) -> String {
        self.names.join(",")
    }

    /// Checks one row: one value per column, every filled one finite ([`Error::Internal`]: a
    /// non-finite output is a bug of the model, docs/outputs.md).
    pub(crate) fn check(&self, values: &[f64]) -> Result<(), Error> {
        if values.len() != self.names.len() {
            return Err(Error::Internal(format!(
                "trajectory: a row of {} values for {} columns",
                values.len(),
                self.names.len()
            )));
        }
        for (k, v) in values.iter().enumerate() {
            if self.present[k] && !v.is_finite() {
                return Err(Error::Internal(format!(
                    "trajectory: {} is {v} at t = {:e}",
                    self.names[k], values[0]
                )));
            }
        }
        Ok(())
    }

    /// Appends the CSV line of `values` (with its line break) to `out`.
    pub(crate) fn push_line(&self, out: &mut String, values: &[f64]) {
        for (k, v) in values.iter().enumerate() {
            if k > 0 {
                out.push(',');
            }
            if self.present[k] {
                push_num(out, *v);
            }
        }
        out.push('\n');
    }
}

/// Where the rows of a run's trajectory go, as the run produces them.
///
/// ```text
/// start(header) once, then row(values) per output time (time order), then finish()
/// values: one per header column; absent columns NaN; filled ones finite (checked before)
/// ```
///
/// An error from a sink ends the run with that error (an I/O error is exit 2).
///
/// Source: docs/outputs.md (`trajectory.csv`); module doc.
pub(crate) trait TrajectorySink {
    /// The columns of the rows to come.
    fn start(&mut self, header: &Header) -> Result<(), Error>;
    /// One row.
    fn row(&mut self, values: &[f64]) -> Result<(), Error>;
    /// No more rows (also after a solver failure: the rows up to it).
    fn finish(&mut self) -> Result<(), Error> {
        Ok(())
    }
}

/// Streams trajectory.csv to a file as the run goes: the header at `start`, each row as it
/// comes through a [`WRITE_BUFFER`]-byte buffer, flushed and synced at `finish`.
///
/// ```text
/// memory = WRITE_BUFFER + one line, whatever the number of rows
/// ```
///
/// Source: module doc.
#[derive(Debug)]
pub(crate) struct CsvFile {
    path: PathBuf,
    out: Option<BufWriter<File>>,
    header: Option<Header>,
    line: String,
    rows: usize,
}

impl CsvFile {
    /// Creates (or truncates) `path`; nothing is written before `start`.
    pub(crate) fn create(path: &Path) -> Result<CsvFile, Error> {
        let f = File::create(path).map_err(|e| Error::io(path, e))?;
        Ok(CsvFile {
            path: path.to_path_buf(),
            out: Some(BufWriter::with_capacity(WRITE_BUFFER, f)),
            header: None,
            line: String::new(),
            rows: 0,
        })
    }

    /// Rows written so far.
    pub(crate) fn rows(&self) -> usize {
        self.rows
    }

    fn write_line(&mut self) -> Result<(), Error> {
        let out = self
            .out
            .as_mut()
            .ok_or_else(|| Error::Internal("trajectory: a row after finish".into()))?;
        out.write_all(self.line.as_bytes())
            .map_err(|e| Error::io(&self.path, e))
    }
}

impl TrajectorySink for CsvFile {
    fn start(&mut self, header: &Header) -> Result<(), Error> {
        self.line.clear();
        self.line.push_str(&header.line());
        self.line.push('\n');
        self.header = Some(header.clone());
        self.write_line()
    }

    fn row(&mut self, values: &[f64]) -> Result<(), Error> {
        let h = self
            .header
            .as_ref()
            .ok_or_else(|| Error::Internal("trajectory: a row before the header".into()))?;
        self.line.clear();
        h.push_line(&mut self.line, values);
        self.write_line()?;
        self.rows += 1;
        Ok(())
    }

    fn finish(&mut self) -> Result<(), Error> {
        if let Some(out) = self.out.take() {
            let f = out
                .into_inner()
                .map_err(|e| Error::io(&self.path, e.into_error()))?;
            f.sync_all().map_err(|e| Error::io(&self.path, e))?;
        }
        Ok(())
    }
}

/// Keeps every row in memory, column by column: what a library caller turns into arrays.
///
/// ```text
/// column(name)[i] = value of `name` in row i (absent columns: None)
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Columns {
    header: Option<Header>,
    data: Vec<Vec<f64>>,
}

impl Columns {
    /// An empty collector.
    pub(crate) fn new() -> Columns {
        Columns::default()
    }

    /// The header (None before the run started).
    pub fn header(&self) -> Option<&Header> {
        self.header.as_ref()
    }

    /// Number of rows (a run's `trajectory_rows`).
    pub(crate) fn len(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }

    /// Whether no row was collected.
    #[cfg(test)]
    pub(crate) fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values of column `name`; None for an unknown or absent column.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        let h = self.header.as_ref()?;
        let k = h.index(name)?;
        h.present[k].then(|| self.data[k].as_slice())
    }

    /// Row `i`, one value per column (NaN where absent).
    pub(crate) fn row_values(&self, i: usize) -> Vec<f64> {
        self.data.iter().map(|c| c[i]).collect()
    }

    /// The CSV text of the rows (the header only when empty; "" before the run started).
    pub(crate) fn to_csv(&self) -> String {
        let Some(h) = &self.header else {
            return String::new();
        };
        let mut out = h.line();
        out.push('\n');
        for i in 0..self.len() {
            h.push_line(&mut out, &self.row_values(i));
        }
        out
    }

    /// Writes the CSV to `path` atomically.
    pub(crate) fn write_csv(&self, path: &Path) -> Result<(), Error> {
        io::write_atomic(path, self.to_csv().as_bytes())
    }
}

/// The values of every column, in the header's order (NaN in absent columns), handed over
/// without a copy: what a front end wraps as arrays (lash.run's columns).
impl From<Columns> for Vec<Vec<f64>> {
    fn from(c: Columns) -> Vec<Vec<f64>> {
        c.data
    }
}

impl TrajectorySink for Columns {
    fn start(&mut self, header: &Header) -> Result<(), Error> {
        self.data = vec![Vec::new(); header.len()];
        self.header = Some(header.clone());
        Ok(())
    }

    fn row(&mut self, values: &[f64]) -> Result<(), Error> {
        if values.len() != self.data.len() {
            return Err(Error::Internal(format!(
                "trajectory: a row of {} values for {} columns",
                values.len(),
                self.data.len()
            )));
        }
        for (c, v) in self.data.iter_mut().zip(values) {
            c.push(*v);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> Header {
        let mut p = [true; 13];
        for k in [5, 6, 7, 8, 9, 10] {
            p[k] = false;
        }
        Header::new(p, vec!["crank.x".into(), "lambda_0".into()]).unwrap()
    }

    fn row(t: f64) -> Vec<f64> {
        let mut v = vec![
            t,
            15.707963267948966 * t,
            0.365 - 1e-7 * t,
            -0.1 * t,
            -3.859722,
        ];
        v.extend([f64::NAN; 6]);
        v.extend([3.2e-13, -1.0e16, 0.0075, 1e-300 * t]);
        v
    }

    #[test]
    fn header_is_exactly_the_interface() {
        let h = Header::new([true; 13], Vec::new()).unwrap();
        assert_eq!(
            h.line(),
            "t,crank_angle,slider_x,slider_v,slider_a,ex_over_c,ey_over_c,delta,contact_force,friction_force,film_force,constraint_violation,driver_torque"
        );
        assert_eq!(header().index("lambda_0"), Some(14));
    }

    #[test]
    fn values_round_trip_bit_exactly_and_absent_cells_are_empty() {
        let h = header();
        let mut c = Columns::new();
        c.start(&h).unwrap();
        let rows: Vec<Vec<f64>> = (0..50).map(|i| row(i as f64 * 0.0173)).collect();
        for r in &rows {
            h.check(r).unwrap();
            TrajectorySink::row(&mut c, r).unwrap();
        }
        let csv = c.to_csv();
        let mut lines = csv.lines();
        assert!(lines
            .next()
            .unwrap()
            .ends_with(",driver_torque,crank.x,lambda_0"));
        for (r, line) in rows.iter().zip(lines) {
            let cells: Vec<&str> = line.split(',').collect();
            assert_eq!(cells.len(), 15);
            for (k, cell) in cells.iter().enumerate() {
                if h.present()[k] {
                    assert_eq!(cell.parse::<f64>().unwrap().to_bits(), r[k].to_bits());
                } else {
                    assert_eq!(*cell, "", "{line}");
                }
            }
        }
        assert_eq!(c.column("slider_x").unwrap().len(), 50);
        assert_eq!(c.column("delta"), None);
        assert_eq!(fmt_num(1.0e16), "1e16");
        assert_eq!(fmt_num(0.25), "0.25");
        assert_eq!(fmt_num(3.2e-13), "3.2e-13");
    }

    #[test]
    fn the_streamed_file_is_the_collected_csv() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join(TRAJECTORY_FILE);
        let h = header();
        let mut f = CsvFile::create(&p).unwrap();
        let mut c = Columns::new();
        for s in [&mut f as &mut dyn TrajectorySink, &mut c] {
            s.start(&h).unwrap();
            for i in 0..3000 {
                s.row(&row(i as f64 * 1e-3)).unwrap();
            }
            s.finish().unwrap();
        }
        assert_eq!(f.rows(), 3000);
        assert_eq!(std::fs::read_to_string(&p).unwrap(), c.to_csv());
    }

    #[test]
    fn bad_rows_and_columns_are_refused() {
        let h = header();
        let mut r = row(0.1);
        r[4] = f64::NAN;
        let e = h.check(&r).unwrap_err();
        assert!(e.to_string().contains("slider_a is NaN at t = 1e-1"), "{e}");
        assert_eq!(e.kind(), crate::ErrorKind::Bug);
        // An absent column may hold anything.
        let mut r = row(0.1);
        r[7] = f64::INFINITY;
        h.check(&r).unwrap();
        assert!(h.check(&r[..10]).is_err());
        for name in ["delta", "a,b", "", "x\"y"] {
            assert!(
                Header::new([true; 13], vec![name.into()]).is_err(),
                "{name}"
            );
        }
        assert!(Header::new([true; 13], vec!["b.x".into(), "b.x".into()]).is_err());
    }
}
