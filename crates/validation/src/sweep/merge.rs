//! Merging finished points into one table: merged.csv and merged.md, with the points of the
//! grids that have no usable result.
//!
//! Source: docs/outputs.md ("Sweeps").

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::{Error, OptionError};
use crate::store::claim;
use crate::store::io;
use crate::sweep::runner::point_state;
use crate::sweep::runner::Manifest;
use crate::sweep::runner::ManifestPoint;
use crate::sweep::runner::PointRecord;
use crate::sweep::runner::PointState;
use crate::sweep::runner::PointStatus;
use crate::sweep::runner::MANIFEST_FILE;
use crate::sweep::runner::RESULT_FILE;
use crate::sweep::spec::PointParams;
use crate::sweep::spec::PARAM_COLUMNS;

/// A point of the grid that has no usable result.
///
/// ```text
/// (index, id, params, why: "unfinished" [held by host:pid] | the corruption)
/// ```
///
/// Source: docs/outputs.md ("Sweeps": `lash merge`).
#[derive(Clone, Debug, PartialEq)]
pub struct MissingPoint {
    /// Index in the grid (None for a corrupt file outside any manifest).
    pub index: Option<usize>,
    /// Id (directory name).
    pub id: String,
    /// Its parameters, if known from a manifest.
    pub params: Option<PointParams>,
    /// Why it has no result: "unfinished", "unfinished, claimed by host:pid", or what is
    /// wrong with its result.json.
    pub why: String,
}

/// The merged table of finished points.
///
/// ```text
/// columns = id, index, the parameters some point sets, status, error, every value name (sorted)
/// rows    = one per distinct point id, sorted by (index, id); finished points, then (when
///           asked for: MergedTable::with_missing) the unfinished and corrupt ones with status
///           `unfinished` / `corrupt` and the reason in `error`
/// ```
///
/// Source: docs/outputs.md ("Sweeps": `lash merge DIR...`).
#[derive(Clone, Debug, PartialEq)]
pub struct MergedTable {
    /// Column names.
    pub columns: Vec<String>,
    /// Cells, row by row (empty string for a missing value).
    pub rows: Vec<Vec<String>>,
    /// Points of the grids (manifests) with no result, or with a corrupt one.
    pub unfinished: Vec<MissingPoint>,
    /// Points whose result.json is corrupt.
    pub corrupt: Vec<MissingPoint>,
}

/// Reads the finished points under each directory (a sweep output directory, whose
/// subdirectories are points, or one point directory) and joins them. The points of the
/// directories' manifests ([`MANIFEST_FILE`]) that have no result anywhere are listed as
/// unfinished; result files that do not parse, or name another point, as corrupt.
pub(crate) fn merge(dirs: &[PathBuf]) -> Result<MergedTable, Error> {
    let mut records: BTreeMap<String, PointRecord> = BTreeMap::new();
    let mut expected: BTreeMap<String, ManifestPoint> = BTreeMap::new();
    let mut claims: BTreeMap<String, String> = BTreeMap::new();
    let mut corrupt_files: BTreeMap<String, String> = BTreeMap::new();
    for dir in dirs {
        if !dir.is_dir() {
            return Err(Error::Input(format!(
                "merge: {} is not a directory",
                dir.display()
            )));
        }
        let mf = dir.join(MANIFEST_FILE);
        if mf.is_file() {
            let bytes = std::fs::read(&mf).map_err(|e| Error::io(&mf, e))?;
            let m: Manifest = serde_json::from_slice(&bytes)
                .map_err(|e| Error::Input(format!("merge: {}: {e}", mf.display())))?;
            for p in m.points {
                expected.entry(p.id.clone()).or_insert(p);
            }
        }
        let point_dirs: Vec<PathBuf> = if dir.join(RESULT_FILE).is_file() {
            vec![dir.clone()]
        } else {
            let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
                .map_err(|e| Error::io(dir, e))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_dir())
                .collect();
            v.sort();
            v
        };
        for pd in point_dirs {
            let id = pd
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            match point_state(&pd, &id) {
                PointState::Finished(rec) => {
                    records.entry(rec.id.clone()).or_insert(*rec);
                }
                PointState::Missing => {
                    if let Some((c, age)) = claim::read_claim(&pd.join(claim::CLAIM_FILE)) {
                        let state = if claim::is_stale(&c, age) {
                            "stale claim of"
                        } else {
                            "claimed by"
                        };
                        claims.insert(id, format!("{state} {}", c.holder()));
                    }
                }
                PointState::Corrupt(why) => {
                    corrupt_files.insert(id, why);
                }
            }
        }
    }
    let mut corrupt = Vec::new();
    for (id, why) in corrupt_files {
        if records.contains_key(&id) {
            continue; // another directory holds a good copy
        }
        let m = expected.get(&id);
        corrupt.push(MissingPoint {
            index: m.map(|m| m.index),
            id,
            params: m.map(|m| m.params.clone()),
            why,
        });
    }
    let unfinished: Vec<MissingPoint> = expected
        .values()
        .filter(|m| !records.contains_key(&m.id) && !corrupt.iter().any(|c| c.id == m.id))
        .map(|m| MissingPoint {
            index: Some(m.index),
            id: m.id.clone(),
            params: Some(m.params.clone()),
            why: match claims.get(&m.id) {
                Some(c) => format!("unfinished, {c}"),
                None => "unfinished".into(),
            },
        })
        .collect();
    let mut unfinished = unfinished;
    unfinished.sort_by(|a, b| (a.index, &a.id).cmp(&(b.index, &b.id)));
    corrupt.sort_by(|a, b| (a.index, &a.id).cmp(&(b.index, &b.id)));
    let mut recs: Vec<PointRecord> = records.into_values().collect();
    recs.sort_by(|a, b| (a.index, &a.id).cmp(&(b.index, &b.id)));
    let param_maps: Vec<serde_json::Map<String, Value>> = recs
        .iter()
        .map(|r| match serde_json::to_value(&r.params) {
            Ok(Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        })
        .collect();
    let mut params: Vec<&str> = PARAM_COLUMNS
        .into_iter()
        .filter(|c| param_maps.iter().any(|m| m.contains_key(*c)))
        .collect();
    // The paths of `set`, after the named parameters, in sorted order.
    let set_paths: BTreeSet<&str> = param_maps
        .iter()
        .flat_map(|m| m.keys().map(String::as_str))
        .filter(|k| !PARAM_COLUMNS.contains(k))
        .collect();
    params.extend(set_paths);
    let value_names: BTreeSet<&String> = recs.iter().flat_map(|r| r.values.keys()).collect();
    let mut columns: Vec<String> = vec!["id".into(), "index".into()];
    columns.extend(params.iter().map(|s| s.to_string()));
    columns.push("status".into());
    columns.push("error".into());
    columns.extend(value_names.iter().map(|s| s.to_string()));
    let rows = recs
        .iter()
        .zip(&param_maps)
        .map(|(r, pm)| {
            let mut row = vec![r.id.clone(), r.index.to_string()];
            row.extend(params.iter().map(|c| cell(pm.get(*c))));
            row.push(
                match r.status {
                    PointStatus::Ok => "ok",
                    PointStatus::SolverFailed => "solver_failed",
                }
                .into(),
            );
            row.push(r.error.clone().unwrap_or_default());
            row.extend(value_names.iter().map(|c| cell(r.values.get(*c))));
            row
        })
        .collect();
    Ok(MergedTable {
        columns,
        rows,
        unfinished,
        corrupt,
    })
}

impl MergedTable {
    /// The table with a row for every unfinished and corrupt point (status `unfinished` or
    /// `corrupt`, the reason in `error`, the parameters where a manifest knows them, no
    /// values), after the finished rows.
    pub(crate) fn with_missing(mut self) -> MergedTable {
        let col = |n: &str| self.columns.iter().position(|c| c == n);
        let (st, er) = (col("status"), col("error"));
        // The parameter columns lie between `index` and `status`.
        let params: Vec<(usize, String)> = (2..st.unwrap_or(2).max(2))
            .map(|i| (i, self.columns[i].clone()))
            .collect();
        let mut extra = Vec::new();
        for (m, status) in self
            .unfinished
            .iter()
            .map(|m| (m, "unfinished"))
            .chain(self.corrupt.iter().map(|m| (m, "corrupt")))
        {
            let mut row = vec![String::new(); self.columns.len()];
            row[0] = m.id.clone();
            row[1] = m.index.map_or(String::new(), |i| i.to_string());
            if let Some(p) = m.params.as_ref().and_then(|p| serde_json::to_value(p).ok()) {
                for (i, c) in &params {
                    row[*i] = cell(p.get(c.as_str()));
                }
            }
            if let (Some(s), Some(e)) = (st, er) {
                row[s] = status.into();
                row[e] = m.why.clone();
            }
            extra.push(row);
        }
        self.rows.extend(extra);
        self
    }

    /// One line naming the points without a usable result: counts, then up to `max` of
    /// each kind by index and id.
    pub fn missing_summary(&self, max: usize) -> String {
        let list = |v: &[MissingPoint]| {
            let mut parts: Vec<String> = v
                .iter()
                .take(max)
                .map(|m| match m.index {
                    Some(i) => format!("#{i} {} ({})", m.id, m.why),
                    None => format!("{} ({})", m.id, m.why),
                })
                .collect();
            if v.len() > max {
                parts.push(format!("and {} more", v.len() - max));
            }
            parts.join("; ")
        };
        let mut s = Vec::new();
        if !self.unfinished.is_empty() {
            s.push(format!(
                "{} point(s) unfinished: {}",
                self.unfinished.len(),
                list(&self.unfinished)
            ));
        }
        if !self.corrupt.is_empty() {
            s.push(format!(
                "{} point(s) with a corrupt result.json: {}",
                self.corrupt.len(),
                list(&self.corrupt)
            ));
        }
        s.join("; ")
    }
}

fn cell(v: Option<&Value>) -> String {
    match v {
        None | Some(Value::Null) => String::new(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => other.to_string(),
    }
}

impl MergedTable {
    /// The table as CSV (RFC 4180 quoting).
    pub(crate) fn to_csv(&self) -> String {
        let q = |s: &str| {
            if s.contains([',', '"', '\n', '\r']) {
                format!("\"{}\"", s.replace('"', "\"\""))
            } else {
                s.to_string()
            }
        };
        let mut out = String::new();
        for row in std::iter::once(&self.columns).chain(&self.rows) {
            let cells: Vec<String> = row.iter().map(|c| q(c)).collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
        out
    }

    /// The table as a GitHub-flavoured markdown table (`|` escaped).
    pub(crate) fn to_markdown(&self) -> String {
        let esc = |s: &str| s.replace('|', "\\|").replace('\n', " ");
        let line = |r: &[String]| {
            let cells: Vec<String> = r.iter().map(|c| esc(c)).collect();
            format!("| {} |\n", cells.join(" | "))
        };
        let mut out = line(&self.columns);
        out.push_str(&format!("|{}\n", "---|".repeat(self.columns.len())));
        for r in &self.rows {
            out.push_str(&line(r));
        }
        out
    }

    /// Writes `merged.csv` (every column) and `merged.md` ([`MergedTable::report`] of
    /// `columns`) atomically into `dir` (created if needed); returns their paths.
    pub(crate) fn write(
        &self,
        dir: &Path,
        columns: &[String],
    ) -> Result<(PathBuf, PathBuf), Error> {
        let report = self.report(columns)?;
        io::create_dir(dir)?;
        let csv = dir.join("merged.csv");
        let md = dir.join("merged.md");
        io::write_atomic(&csv, self.to_csv().as_bytes())?;
        io::write_atomic(&md, report.as_bytes())?;
        Ok((csv, md))
    }

    /// The columns merged.md shows by default: `id`, `index`, the parameter columns but
    /// `scene_sha256`, `status`, `error`, and those of [`DEFAULT_METRICS`] the table has (the
    /// first four value columns if it has none of them).
    pub(crate) fn default_columns(&self) -> Vec<String> {
        let st = self.columns.iter().position(|c| c == "status");
        let values_from = st.map_or(self.columns.len(), |s| s + 2);
        let mut out: Vec<String> = self.columns[..values_from.min(self.columns.len())]
            .iter()
            .filter(|c| *c != "scene_sha256")
            .cloned()
            .collect();
        let values = &self.columns[values_from.min(self.columns.len())..];
        let metrics: Vec<&String> = DEFAULT_METRICS
            .iter()
            .filter_map(|m| values.iter().find(|c| c == m))
            .collect();
        if metrics.is_empty() {
            out.extend(values.iter().take(4).cloned());
        } else {
            out.extend(metrics.into_iter().cloned());
        }
        out
    }

    /// The quantiles of every metric ([`quantile`], type 7) over the points that
    /// finished ok: (column, n, [Q(0.05), Q(0.5), Q(0.95)]) for each value column that has a
    /// number in at least one of them, in column order; settings (`used.*`, `t_end`) left out.
    pub(crate) fn quantiles(&self) -> Vec<(String, usize, [f64; 3])> {
        let Some(st) = self.columns.iter().position(|c| c == "status") else {
            return Vec::new();
        };
        let ok: Vec<&Vec<String>> = self.rows.iter().filter(|r| r[st] == "ok").collect();
        let mut out = Vec::new();
        for (j, name) in self.columns.iter().enumerate().skip(st + 2) {
            if name.starts_with("used.") || name == "t_end" {
                continue;
            }
            let mut v: Vec<f64> = ok
                .iter()
                .filter_map(|r| r[j].parse::<f64>().ok())
                .filter(|x| x.is_finite())
                .collect();
            if v.is_empty() {
                continue;
            }
            v.sort_by(f64::total_cmp);
            let q = [0.05, 0.5, 0.95].map(|p| quantile(&v, p));
            out.push((name.clone(), v.len(), q));
        }
        out
    }

    /// merged.md: the table of `columns` (none: [`MergedTable::default_columns`]), then the
    /// quantiles of every metric. A column the table does not have is an error naming it.
    pub(crate) fn report(&self, columns: &[String]) -> Result<String, Error> {
        let cols = if columns.is_empty() {
            self.default_columns()
        } else {
            columns.to_vec()
        };
        let mut idx = Vec::new();
        for c in &cols {
            match self.columns.iter().position(|k| k == c) {
                Some(i) => idx.push(i),
                None => {
                    return Err(OptionError::new("columns")
                        .text(format!("merge: no column '{c}' to show with "))
                        .name("columns")
                        .text(format!(" (merged.csv has {})", self.columns.join(", ")))
                        .into())
                }
            }
        }
        let shown = MergedTable {
            columns: cols,
            rows: self
                .rows
                .iter()
                .map(|r| idx.iter().map(|&i| r[i].clone()).collect())
                .collect(),
            unfinished: Vec::new(),
            corrupt: Vec::new(),
        };
        let mut out = String::from("# Merged sweep\n\n");
        out.push_str(&format!(
            "{} point(s); {} of the {} columns shown (all of them are in merged.csv).\n\n",
            self.rows.len(),
            shown.columns.len(),
            self.columns.len()
        ));
        out.push_str(&shown.to_markdown());
        let q = self.quantiles();
        let n_ok = self
            .columns
            .iter()
            .position(|c| c == "status")
            .map_or(0, |st| self.rows.iter().filter(|r| r[st] == "ok").count());
        out.push_str(&format!(
            "\n## Quantiles of every metric over the {n_ok} point(s) that finished ok\n\n\
             Type 7 (linear interpolation between order statistics, the default of R and NumPy): \
             the n numbers of a column sorted, x₀ ≤ … ≤ x₍ₙ₋₁₎, h = (n − 1)·p, \
             Q(p) = x₍⌊h⌋₎ + (h − ⌊h⌋)·(x₍⌊h⌋+1₎ − x₍⌊h⌋₎); empty and non-numeric cells left out \
             (n counts the rest).\n\n"
        ));
        let table = MergedTable {
            columns: ["metric", "n", "5 %", "50 %", "95 %"]
                .map(String::from)
                .to_vec(),
            rows: q
                .into_iter()
                .map(|(name, n, [a, b, c])| {
                    vec![name, n.to_string(), number(a), number(b), number(c)]
                })
                .collect(),
            unfinished: Vec::new(),
            corrupt: Vec::new(),
        };
        out.push_str(&table.to_markdown());
        Ok(out)
    }
}

/// The metrics merged.md shows by default (those the table has), in this order.
pub(crate) const DEFAULT_METRICS: [&str; 6] = [
    "metrics.eps_max",
    "metrics.contact_force_max",
    "metrics.penetration_max",
    "metrics.energy.balance_error",
    "stats.steps",
    "wall_time_s",
];

/// The p-quantile of sorted numbers, type 7 of Hyndman & Fan (1996):
///
/// ```text
/// h = (n − 1)·p,  Q(p) = x[⌊h⌋] + (h − ⌊h⌋)·(x[⌊h⌋ + 1] − x[⌊h⌋])   (x 0-based, sorted)
/// ```
///
/// NaN for no numbers.
pub(crate) fn quantile(sorted: &[f64], p: f64) -> f64 {
    let Some(&last) = sorted.last() else {
        return f64::NAN;
    };
    let h = (sorted.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    if lo + 1 >= sorted.len() {
        return last;
    }
    sorted[lo] + (h - lo as f64) * (sorted[lo + 1] - sorted[lo])
}

/// A number for merged.md: 6 significant digits.
fn number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let a = x.abs();
    if (1e-3..1e6).contains(&a) {
        let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{x:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{x:.5e}")
    }
}
