//! `lash plot RUN_DIR COLUMN… [--x COLUMN] [--out FILE]`: any columns of a run's
//! trajectory against time or another column, as a PNG and an SVG with units on the axes.
//!
//! ```text
//! table   RUN_DIR/trajectory.csv (partial_trajectory.csv of a failed run: the rows up to
//!         the failure)
//! y       the columns, grouped by unit in the order given: one group → one plot, several →
//!         one panel per unit, stacked, sharing the x axis
//! x       t, or --x COLUMN (then the curve is drawn in row order: a phase portrait)
//! labels  "name, unit" (plain: underscores as spaces); a dimensionless column has no unit
//! files   FILE.svg and FILE.png (FILE given with or without .svg / .png); default
//!         RUN_DIR/plot_<columns joined by '+'>[_vs_<x>], characters other than letters,
//!         digits, '.', '-', '+' and '_' replaced by '_'
//! ```
//!
//! A plot file in a run directory belongs to the run it shows: a new run into the directory
//! replaces it ([`is_plot_file`], `report::run_file`). Source: docs/outputs.md ("`lash plot
//! RUN_DIR COLUMN…`").

use std::path::{Path, PathBuf};

use crate::animation::{unit, Table};
use crate::error::Error;
use crate::report::plot::{self, Axes, Panel, Series, SeriesStyle};
use crate::report::trajectory::{PARTIAL_TRAJECTORY_FILE, TRAJECTORY_FILE};
use crate::store::io::Written;

/// Prefix of the default file names of `lash plot`.
pub(crate) const PLOT_PREFIX: &str = "plot_";

/// Whether `name` is a file `lash plot` writes into a run directory by default.
pub(crate) fn is_plot_file(name: &str) -> bool {
    name.starts_with(PLOT_PREFIX) && (name.ends_with(".svg") || name.ends_with(".png"))
}

/// What to plot.
///
/// ```text
/// run_dir  columns (≥ 1)  [x]  [out]
/// ```
///
/// Source: module doc.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct PlotRequest {
    /// The run directory.
    pub run_dir: PathBuf,
    /// The columns drawn (y).
    pub columns: Vec<String>,
    /// The abscissa; None = `t`.
    pub x: Option<String>,
    /// The figure's path (with or without .svg / .png); None = the default in RUN_DIR.
    pub out: Option<PathBuf>,
}

/// What was plotted.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Plotted {
    /// The columns, in the order drawn.
    pub columns: Vec<String>,
    /// The abscissa.
    pub x: String,
    /// Panels (one per unit).
    pub panels: usize,
    /// Rows of the trajectory.
    pub rows: usize,
}

/// `name` with every character a file name should not hold replaced by `_`.
fn file_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-+".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The axis label of a column: its name in words and its unit.
fn label(name: &str) -> String {
    match unit(name) {
        "" => plot::plain(name),
        u => format!("{}, {u}", plot::plain(name)),
    }
}

/// A column by name, or an error that says why there is none.
fn column<'a>(table: &'a Table, name: &str) -> Result<&'a [f64], Error> {
    if let Some(c) = table.column(name) {
        return Ok(c);
    }
    if table.has(name) {
        return Err(Error::Input(format!(
            "column {name} has no values in this run (a column whose role the scene does \
             not declare is empty)"
        )));
    }
    Err(Error::Usage(format!(
        "trajectory.csv has no column '{name}'; its columns: {}",
        table.present().join(", ")
    )))
}

/// Draws the columns (module doc).
pub(crate) fn plot_columns(o: &PlotRequest) -> Result<Written<Plotted>, Error> {
    if o.columns.is_empty() {
        return Err(Error::Usage("give at least one column to plot".into()));
    }
    let dir = &o.run_dir;
    if !dir.is_dir() {
        return Err(Error::Input(format!(
            "run directory {} not found",
            dir.display()
        )));
    }
    let (path, partial) = match dir.join(TRAJECTORY_FILE) {
        p if p.is_file() => (p, false),
        _ if dir.join(PARTIAL_TRAJECTORY_FILE).is_file() => {
            (dir.join(PARTIAL_TRAJECTORY_FILE), true)
        }
        _ => {
            return Err(Error::Input(format!(
                "{} has no {TRAJECTORY_FILE}: not a run directory",
                dir.display()
            )))
        }
    };
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let table = Table::from_csv(&text, &path.display().to_string())?;
    let x_name = o.x.clone().unwrap_or_else(|| "t".into());
    let x = column(&table, &x_name)?;
    let mut ys = Vec::new();
    for c in &o.columns {
        if ys.iter().any(|(n, _): &(&str, _)| n == c) {
            return Err(Error::Usage(format!("column {c} is given twice")));
        }
        ys.push((c.as_str(), column(&table, c)?));
    }
    let stem = match &o.out {
        Some(f) => match f.extension().and_then(|e| e.to_str()) {
            Some("svg") | Some("png") => f.with_extension(""),
            Some(e) => {
                return Err(Error::Usage(format!(
                    "the figure is written as SVG and PNG: give {} without .{e}, or with \
                     .svg or .png",
                    f.display()
                )))
            }
            None => f.clone(),
        },
        None => {
            let mut s = format!("{PLOT_PREFIX}{}", file_safe(&o.columns.join("+")));
            if o.x.is_some() {
                s.push_str(&format!("_vs_{}", file_safe(&x_name)));
            }
            dir.join(s)
        }
    };
    if let Some(parent) = stem.parent().filter(|p| !p.as_os_str().is_empty()) {
        if !parent.is_dir() {
            return Err(Error::Input(format!(
                "directory {} of the figure not found",
                parent.display()
            )));
        }
    }
    // Groups of one unit, in the order the columns were given.
    type Group<'a> = (&'static str, Vec<(&'a str, &'a [f64])>);
    let mut groups: Vec<Group<'_>> = Vec::new();
    for &(n, v) in &ys {
        let u = unit(n);
        match groups.iter_mut().find(|g| g.0 == u) {
            Some(g) => g.1.push((n, v)),
            None => groups.push((u, vec![(n, v)])),
        }
    }
    let case = run_case(dir);
    let what = if partial {
        " (up to the solver's failure)"
    } else {
        ""
    };
    let title = format!(
        "{}: {} against {}{what}",
        plot::plain(&case),
        o.columns
            .iter()
            .map(|c| plot::plain(c))
            .collect::<Vec<_>>()
            .join(", "),
        plot::plain(&x_name)
    );
    let x_label = label(&x_name);
    let names: Vec<Vec<String>> = groups
        .iter()
        .map(|g| g.1.iter().map(|(n, _)| plot::plain(n)).collect())
        .collect();
    let series: Vec<Vec<Series<'_>>> = groups
        .iter()
        .zip(&names)
        .map(|(g, ns)| {
            g.1.iter()
                .zip(ns)
                .map(|(&(_, v), n)| Series {
                    name: n,
                    x,
                    y: v,
                    style: SeriesStyle::Line,
                })
                .collect()
        })
        .collect();
    let y_labels: Vec<String> = groups
        .iter()
        .map(|g| match (g.1.len(), g.0) {
            (1, _) => label(g.1[0].0),
            (_, "") => "value (dimensionless)".to_string(),
            (_, u) => format!("value, {u}"),
        })
        .collect();
    let titles: Vec<String> = groups
        .iter()
        .map(|g| {
            g.1.iter()
                .map(|(n, _)| plot::plain(n))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .collect();
    let w = if groups.len() == 1 {
        plot::line_plot(
            &stem,
            &Axes {
                title: &title,
                x_label: &x_label,
                y_label: &y_labels[0],
            },
            &series[0],
        )?
    } else {
        let panels: Vec<Panel<'_>> = series
            .iter()
            .zip(&y_labels)
            .zip(&titles)
            .map(|((s, y), t)| Panel {
                axes: Axes {
                    title: t,
                    x_label: &x_label,
                    y_label: y,
                },
                series: s,
                log_y: false,
            })
            .collect();
        plot::panels_plot(&stem, &title, &panels)?
    };
    Ok(Written {
        result: Plotted {
            columns: o.columns.clone(),
            x: x_name,
            panels: groups.len(),
            rows: table.rows(),
        },
        dir: dir.clone(),
        files: vec![w.svg, w.png],
    })
}

/// The case of a run directory: summary.json's `case`, else the directory's name.
fn run_case(dir: &Path) -> String {
    std::fs::read(dir.join(crate::report::summary::SUMMARY_FILE))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|v| v.get("case").and_then(|c| c.as_str()).map(str::to_string))
        .unwrap_or_else(|| {
            dir.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "run".into())
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run_dir(d: &Path) -> PathBuf {
        let dir = d.join("run");
        std::fs::create_dir(&dir).unwrap();
        let mut csv = String::from("t,crank_angle,slider_x,rod.theta,rod.omega,x.force\n");
        for i in 0..=200 {
            let t = i as f64 * 0.01;
            csv.push_str(&format!(
                "{t},{},,{},{},{}\n",
                6.0 * t,
                (3.0 * t).sin(),
                3.0 * (3.0 * t).cos(),
                10.0 * t
            ));
        }
        std::fs::write(dir.join(TRAJECTORY_FILE), csv).unwrap();
        dir
    }

    #[test]
    fn one_unit_one_plot_several_units_panels() {
        let d = tempfile::tempdir().unwrap();
        let dir = run_dir(d.path());
        let w = plot_columns(&PlotRequest {
            run_dir: dir.clone(),
            columns: vec!["rod.theta".into(), "crank_angle".into()],
            ..Default::default()
        })
        .unwrap();
        assert_eq!(w.result.panels, 1);
        assert_eq!(w.files[1], dir.join("plot_rod.theta+crank_angle.png"));
        let svg = std::fs::read_to_string(&w.files[0]).unwrap();
        assert!(
            svg.contains("value, rad") && svg.contains("t, s"),
            "units on the axes"
        );
        assert!(is_plot_file("plot_rod.theta+crank_angle.png"));
        let w = plot_columns(&PlotRequest {
            run_dir: dir.clone(),
            columns: vec!["rod.theta".into(), "rod.omega".into(), "x.force".into()],
            x: Some("crank_angle".into()),
            out: Some(d.path().join("fig.png")),
        })
        .unwrap();
        assert_eq!(w.result.panels, 3);
        assert_eq!(w.files[0], d.path().join("fig.svg"));
        let svg = std::fs::read_to_string(&w.files[0]).unwrap();
        for l in [
            "rod.theta, rad",
            "rod.omega, rad/s",
            "x.force, N",
            "crank angle, rad",
        ] {
            assert!(svg.contains(l), "{l}");
        }
    }

    #[test]
    fn bad_requests_say_what_is_wrong() {
        let d = tempfile::tempdir().unwrap();
        let dir = run_dir(d.path());
        let o = |c: &str| PlotRequest {
            run_dir: dir.clone(),
            columns: vec![c.into()],
            ..Default::default()
        };
        let e = plot_columns(&o("rocker.theta")).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("trajectory.csv has no column 'rocker.theta'; its columns: t,"),
            "{e}"
        );
        assert_eq!(e.kind(), crate::ErrorKind::BadInput);
        let e = plot_columns(&o("slider_x")).unwrap_err();
        assert!(e.to_string().contains("slider_x has no values"), "{e}");
        let mut p = o("rod.theta");
        p.out = Some(d.path().join("f.pdf"));
        assert!(plot_columns(&p).unwrap_err().to_string().contains(".pdf"));
        p.out = None;
        p.run_dir = d.path().join("none");
        assert!(plot_columns(&p)
            .unwrap_err()
            .to_string()
            .contains("not found"));
        p.run_dir = dir.clone();
        p.columns.clear();
        assert!(plot_columns(&p).is_err());
        // Nothing was written by the failures.
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    }
}
