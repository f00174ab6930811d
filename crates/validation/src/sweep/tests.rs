//! Tests of the sweep file, the runner and the merge.

use std::path::Path;

use lash_model::scene::{JointSpec, NormalSpec};
use lash_solver::{ControllerKind, Method};
use serde_json::Value;

use crate::error::Error;
use crate::run::case::sha256_hex;
use crate::store::io;

use super::merge::*;
use super::runner::*;
use super::spec::*;
use crate::progress::NoProgress;
use std::sync::atomic::{AtomicUsize, Ordering};

fn spec(dir: &Path, json: &str) -> Result<SweepSpec, Error> {
    std::fs::write(dir.join("base.json"), b"{\"scene\": true}").unwrap();
    let p = dir.join("sweep.json");
    std::fs::write(&p, json).unwrap();
    SweepSpec::load(&p)
}

const GRID: &str = r#"{"case": "base.json", "speed_rpm": [120, 150],
    "method": ["rk4", "dopri54", "bdf"], "step": [1e-4, 5e-5],
    "tolerance": [1e-6, 1e-8], "controller": ["pi", "h211"]}"#;

#[test]
fn shard_syntax() {
    assert_eq!(
        "1/4".parse::<Shard>().unwrap(),
        Shard { index: 1, count: 4 }
    );
    assert_eq!("0/1".parse::<Shard>().unwrap(), Shard::ALL);
    for bad in ["4/4", "0/0", "-1/2", "a/b", "1", "1/2/3", ""] {
        let e = bad.parse::<Shard>().unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::BadInput, "{bad}");
    }
    let s = Shard { index: 2, count: 3 };
    assert_eq!(
        (0..9).filter(|&i| s.contains(i)).collect::<Vec<_>>(),
        vec![2, 5, 8]
    );
    assert_eq!(s.to_string(), "2/3");
}

#[test]
fn grid_is_the_method_aware_product() {
    let d = tempfile::tempdir().unwrap();
    let pts = spec(d.path(), GRID).unwrap().points().unwrap();
    // Per speed: rk4 × 2 steps + dopri54 × 2 rtol × 2 controllers + bdf × 2 rtol = 8.
    assert_eq!(pts.len(), 16);
    assert!(pts.iter().enumerate().all(|(i, p)| p.index == i));
    let first = &pts[0].params;
    assert_eq!(first.speed_rpm, Some(120.0));
    assert_eq!(
        (first.method, first.step, first.rtol),
        (Some(Method::Rk4), Some(1e-4), None)
    );
    let p3 = &pts[3].params;
    assert_eq!(
        (p3.method, p3.rtol, p3.controller, p3.step),
        (
            Some(Method::Dopri54),
            Some(1e-6),
            Some(ControllerKind::H211),
            None
        )
    );
    let p7 = &pts[7].params;
    assert_eq!(
        (p7.method, p7.rtol, p7.controller),
        (Some(Method::Bdf), Some(1e-8), None)
    );
    assert_eq!(pts[8].params.speed_rpm, Some(150.0));
    assert_eq!(first.case, "base");
    assert_eq!(
        first.scene_sha256.as_deref(),
        Some(sha256_hex(b"{\"scene\": true}").as_str())
    );
}

#[test]
fn id_is_sha256_of_sorted_canonical_json() {
    let p = PointParams {
        case: "c".into(),
        scene_sha256: None,
        speed_rpm: Some(150.0),
        clearance: Some(1e-4),
        viscosity: None,
        stiffness: None,
        method: Some(Method::Dopri54),
        rtol: None,
        step: None,
        controller: Some(ControllerKind::H211),
        set: Default::default(),
    };
    let canon = r#"{"case":"c","clearance":0.0001,"controller":"h211","method":"dopri54","speed_rpm":150.0}"#;
    assert_eq!(p.canonical_json(), canon);
    // A scene field set by path is a key of its own, sorted with the others.
    let mut q = p.clone();
    q.set
        .insert("joints[1].friction.mu".into(), serde_json::json!(0.2));
    let canon_q = r#"{"case":"c","clearance":0.0001,"controller":"h211","joints[1].friction.mu":0.2,"method":"dopri54","speed_rpm":150.0}"#;
    assert_eq!(q.canonical_json(), canon_q);
    assert_eq!(q.id(), &sha256_hex(canon_q.as_bytes())[..16]);
    let back: PointParams = serde_json::from_str(canon_q).unwrap();
    assert_eq!(back, q);
    assert_eq!(p.id(), &sha256_hex(canon.as_bytes())[..16]);
    // The same numbers written differently give the same id; another value another id.
    let q: PointParams = serde_json::from_str(
        r#"{"speed_rpm": 1.5e2, "method": "dopri54", "clearance": 1e-4, "controller": "h211", "case": "c"}"#,
    )
    .unwrap();
    assert_eq!(q.id(), p.id());
    let r = PointParams {
        speed_rpm: Some(150.0000001),
        ..p.clone()
    };
    assert_ne!(r.id(), p.id());
}

#[test]
fn bad_sweep_files_name_the_problem() {
    let d = tempfile::tempdir().unwrap();
    let msg = |j: &str| spec(d.path(), j).unwrap_err().to_string();
    assert!(msg(r#"{"case": "base.json", "speed": [1]}"#).contains("unknown field `speed`"));
    assert!(
        msg(r#"{"case": "base.json", "clearance": []}"#).contains("'clearance' is an empty list")
    );
    assert!(msg(r#"{"case": "base.json", "clearance": [0]}"#)
        .contains("clearance[0] must be finite and > 0"));
    assert!(msg(r#"{"case": "base.json", "method": ["rk4"]}"#)
        .contains("rk4 is fixed-step and needs a 'step' list"));
    assert!(
        msg(r#"{"case": "base.json", "method": ["bdf"], "controller": ["pi"]}"#)
            .contains("'controller' needs")
    );
    assert!(msg(r#"{"case": "base.json", "step": [1e-4], "rtol": [1e-6]}"#).contains("not both"));
    assert!(msg(r#"{"case": "base.json", "rtol": [2]}"#).contains("every rtol must be in"));
    assert!(
        msg(r#"{"case": "base.json", "method": ["euler"]}"#).contains("unknown variant `euler`")
    );
    assert!(msg(r#"{"case": "nope.json"}"#).contains("not found"));
    assert!(msg(r#"{"case": "base.json", "speed_rpm": [1, 1]}"#).contains("twice"));
    let e = SweepSpec::load(&d.path().join("absent.json")).unwrap_err();
    assert_eq!(e.kind(), crate::ErrorKind::BadInput);
}

/// Runs `pts` one at a time (so exactly the first `k` finish) with `run`, then stops: every
/// later point fails as if its process were killed.
pub(super) fn run_stopped_after<F>(pts: &[SweepPoint], root: &Path, k: usize, run: F) -> SweepReport
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    let calls = AtomicUsize::new(0);
    let opts = SweepOptions {
        jobs: Some(1),
        ..Default::default()
    };
    run_sweep(
        pts,
        root,
        &opts,
        |p, dir| {
            if calls.fetch_add(1, Ordering::SeqCst) >= k {
                Err(Error::Internal("killed".into()))
            } else {
                run(p, dir)
            }
        },
        &NoProgress,
    )
    .unwrap()
}

/// A fake runner: slider_acc_max = speed², and counts its calls.
fn fake(p: &SweepPoint, dir: &Path, calls: &AtomicUsize) -> Result<PointResult, Error> {
    calls.fetch_add(1, Ordering::SeqCst);
    io::write_atomic(&dir.join("summary.json"), b"{}")?;
    let s = p.params.speed_rpm.unwrap_or(0.0);
    Ok(PointResult::flatten(&serde_json::json!({
        "metrics": {"slider_acc_max": s * s}, "stats": {"rhs_evals": p.index}
    })))
}

#[test]
fn shards_partition_the_grid_and_merge_joins_them() {
    let d = tempfile::tempdir().unwrap();
    let pts = spec(d.path(), GRID).unwrap().points().unwrap();
    let calls = AtomicUsize::new(0);
    let mut roots = vec![];
    for i in 0..3 {
        let root = d.path().join(format!("shard{i}"));
        let opts = SweepOptions {
            jobs: Some(2),
            shard: Shard { index: i, count: 3 },
        };
        let r = run_sweep(
            &pts,
            &root,
            &opts,
            |p, dir| fake(p, dir, &calls),
            &NoProgress,
        )
        .unwrap();
        let expect = (0..16).filter(|k| k % 3 == i).count();
        assert_eq!((r.selected, r.ok, r.skipped), (expect, expect, 0));
        roots.push(root);
    }
    assert_eq!(calls.load(Ordering::SeqCst), 16);
    let t = merge(&roots).unwrap();
    assert_eq!(t.rows.len(), 16);
    assert!(t.unfinished.is_empty() && t.corrupt.is_empty());
    let col = |n: &str| t.columns.iter().position(|c| c == n).unwrap();
    for (k, row) in t.rows.iter().enumerate() {
        assert_eq!(row[col("index")], k.to_string());
        assert_eq!(row[col("id")], pts[k].id);
        assert_eq!(row[col("stats.rhs_evals")], k.to_string());
        let s: f64 = row[col("speed_rpm")].parse().unwrap();
        let a: f64 = row[col("metrics.slider_acc_max")].parse().unwrap();
        assert_eq!(a, s * s);
    }
    // Parameters no point sets are not columns.
    assert!(!t.columns.iter().any(|c| c == "viscosity"));
    let csv = t.to_csv();
    assert_eq!(csv.lines().count(), 17);
    assert!(csv.starts_with("id,index,case,scene_sha256,speed_rpm,method,rtol,step,controller,status,error,metrics.slider_acc_max,stats.rhs_evals\n"));
    let md = t.to_markdown();
    assert_eq!(md.lines().count(), 18);
    assert_eq!(
        md.lines().nth(1).unwrap().matches("---|").count(),
        t.columns.len()
    );
    // Merging the same shard twice does not duplicate rows.
    assert_eq!(
        merge(&[roots[0].clone(), roots[0].clone()])
            .unwrap()
            .rows
            .len(),
        6
    );
    let (c, m) = t.write(&d.path().join("merged"), &[]).unwrap();
    assert_eq!(std::fs::read_to_string(c).unwrap(), csv);
    assert_eq!(std::fs::read_to_string(m).unwrap(), t.report(&[]).unwrap());
}

/// Type 7 quantiles against NumPy's default: numpy.percentile([1, 2, 3, 4, 10], [5, 50, 95])
/// = [1.2, 3, 8.8] (h = 4p: 0.2, 2, 3.8), and the ends of one and two numbers.
#[test]
fn quantiles_are_type_7() {
    let v = [1.0, 2.0, 3.0, 4.0, 10.0];
    assert!((quantile(&v, 0.05) - 1.2).abs() < 1e-15);
    assert_eq!(quantile(&v, 0.5), 3.0);
    assert!((quantile(&v, 0.95) - 8.8).abs() < 1e-14);
    assert_eq!((quantile(&v, 0.0), quantile(&v, 1.0)), (1.0, 10.0));
    assert_eq!(quantile(&[7.0], 0.05), 7.0);
    assert_eq!(quantile(&[0.0, 1.0], 0.95), 0.95);
    assert!(quantile(&[], 0.5).is_nan());
}

/// merged.md: by default the parameters, status, error and the default metrics the table has
/// (here none, so the first four values), then the quantiles of every metric over the ok
/// points; `columns` chooses the table's columns, and an unknown one is an error naming it.
#[test]
fn merged_md_is_short_by_default_and_has_the_quantiles() {
    let d = tempfile::tempdir().unwrap();
    let pts = spec(d.path(), GRID).unwrap().points().unwrap();
    let root = d.path().join("out");
    let calls = AtomicUsize::new(0);
    run_sweep(
        &pts,
        &root,
        &SweepOptions::default(),
        |p, dir| fake(p, dir, &calls),
        &NoProgress,
    )
    .unwrap();
    let t = merge(std::slice::from_ref(&root)).unwrap();
    assert_eq!(
        t.default_columns(),
        [
            "id",
            "index",
            "case",
            "speed_rpm",
            "method",
            "rtol",
            "step",
            "controller",
            "status",
            "error",
            "metrics.slider_acc_max",
            "stats.rhs_evals"
        ]
    );
    // slider_acc_max = speed²: 8 points at 120 rpm (14 400), 8 at 150 (22 500); h = 15p:
    // Q(0.05) = x[0] (h = 0.75 between equal values), Q(0.5) = (x[7] + x[8])/2, Q(0.95) = x[15].
    // rhs_evals = index 0 … 15: Q(p) = 15p.
    let q = t.quantiles();
    assert_eq!(q.len(), 2);
    assert_eq!(
        q[0],
        (
            "metrics.slider_acc_max".into(),
            16,
            [14400.0, 18450.0, 22500.0]
        )
    );
    assert_eq!(q[1].0, "stats.rhs_evals");
    for (got, want) in q[1].2.iter().zip([0.75, 7.5, 14.25]) {
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
    let md = t.report(&[]).unwrap();
    assert!(
        md.contains("| metrics.slider_acc_max | 16 | 14400 | 18450 | 22500 |"),
        "{md}"
    );
    assert!(
        md.contains("| stats.rhs_evals | 16 | 0.75 | 7.5 | 14.25 |"),
        "{md}"
    );
    assert!(!md.contains("scene_sha256"));
    let cols = ["index".to_string(), "metrics.slider_acc_max".to_string()];
    let md = t.report(&cols).unwrap();
    assert!(
        md.contains("| index | metrics.slider_acc_max |\n|---|---|\n| 0 | 14400.0 |"),
        "{md}"
    );
    let e = t.report(&["nope".to_string()]).unwrap_err();
    assert_eq!(e.kind(), crate::ErrorKind::BadInput);
    assert!(e.to_string().contains("no column 'nope'"), "{e}");
}

#[test]
fn rerun_resumes_after_an_interruption() {
    let d = tempfile::tempdir().unwrap();
    let pts = spec(d.path(), GRID).unwrap().points().unwrap();
    let root = d.path().join("out");
    let k = 5;
    let r = run_stopped_after(&pts, &root, k, |p, dir| fake(p, dir, &AtomicUsize::new(0)));
    assert_eq!((r.ok, r.failed.len()), (k, 16 - k));
    let t = merge(std::slice::from_ref(&root)).unwrap();
    assert_eq!((t.rows.len(), t.unfinished.len()), (k, 16 - k));
    let e = r.into_result().unwrap_err();
    assert_eq!(e.kind(), crate::ErrorKind::Bug);
    assert!(
        e.to_string()
            .contains("11 sweep point(s) failed; first, point 5: internal error: killed"),
        "{e}"
    );
    // The rerun runs only the unfinished points.
    let calls2 = AtomicUsize::new(0);
    let opts = SweepOptions {
        jobs: Some(2),
        ..Default::default()
    };
    let r = run_sweep(
        &pts,
        &root,
        &opts,
        |p, dir| fake(p, dir, &calls2),
        &NoProgress,
    )
    .unwrap();
    assert_eq!((r.skipped, r.ok), (k, 16 - k));
    assert_eq!(calls2.load(Ordering::SeqCst), 16 - k);
    assert_eq!(merge(&[root]).unwrap().rows.len(), 16);
}

#[test]
fn solver_failures_are_results_not_retried() {
    let d = tempfile::tempdir().unwrap();
    let pts = spec(d.path(), GRID).unwrap().points().unwrap();
    let root = d.path().join("out");
    let runner = |p: &SweepPoint, dir: &Path| {
        if p.params.method == Some(Method::Rk4) {
            Err(Error::Solver(lash_solver::SolveError::NonFiniteState {
                t: 0.5,
                y: vec![1.0],
            }))
        } else {
            fake(p, dir, &AtomicUsize::new(0))
        }
    };
    let r = run_sweep(&pts, &root, &SweepOptions::default(), runner, &NoProgress).unwrap();
    assert_eq!((r.ok, r.solver_failed), (12, 4));
    let r = run_sweep(&pts, &root, &SweepOptions::default(), runner, &NoProgress).unwrap();
    assert_eq!((r.skipped, r.ok, r.solver_failed), (16, 0, 0));
    let t = merge(&[root]).unwrap();
    let st = t.columns.iter().position(|c| c == "status").unwrap();
    let er = t.columns.iter().position(|c| c == "error").unwrap();
    let failed: Vec<&Vec<String>> = t.rows.iter().filter(|r| r[st] == "solver_failed").collect();
    assert_eq!(failed.len(), 4);
    assert!(failed[0][er].starts_with("solver failed: non-finite"));
}

#[test]
fn csv_quotes_and_markdown_escapes() {
    let t = MergedTable {
        columns: vec!["a".into(), "b".into()],
        rows: vec![vec!["x,y".into(), "say \"hi\" | there".into()]],
        unfinished: vec![],
        corrupt: vec![],
    };
    assert_eq!(t.to_csv(), "a,b\n\"x,y\",\"say \"\"hi\"\" | there\"\n");
    assert_eq!(
        t.to_markdown(),
        "| a | b |\n|---|---|\n| x,y | say \"hi\" \\| there |\n"
    );
}

fn params() -> PointParams {
    PointParams {
        case: "x".into(),
        scene_sha256: None,
        speed_rpm: None,
        clearance: None,
        viscosity: None,
        stiffness: None,
        method: None,
        rtol: None,
        step: None,
        controller: None,
        set: Default::default(),
    }
}

#[test]
fn point_parameters_land_in_the_scene() {
    use lash_model::cases::{press_scene, PressJoint};
    let mut s = press_scene(PressJoint::Lubricated, 150.0, 1e-4);
    let p = PointParams {
        speed_rpm: Some(180.0),
        clearance: Some(3e-4),
        viscosity: Some(0.2),
        stiffness: Some(1e10),
        ..params()
    };
    apply_params(&mut s, &p).unwrap();
    let mut seen = 0;
    for j in &s.joints {
        match j {
            JointSpec::Driver(d) => {
                assert_eq!((d.rpm, d.omega), (Some(180.0), None));
                seen += 1;
            }
            JointSpec::Clearance(c) => {
                assert!((c.bearing.radius - c.journal.radius - 3e-4).abs() < 1e-15);
                assert_eq!(c.film.as_ref().unwrap().viscosity, 0.2);
                let NormalSpec::Impact(i) = &c.normal else {
                    panic!()
                };
                assert_eq!(i.k, Some(1e10));
                seen += 1;
            }
            _ => {}
        }
    }
    assert_eq!(seen, 2);
    s.validate().unwrap();
    // A dry scene has no film to take a viscosity; an ideal one no clearance joint.
    let mut dry = press_scene(PressJoint::Dry, 150.0, 1e-4);
    let e = apply_params(
        &mut dry,
        &PointParams {
            viscosity: Some(0.2),
            ..params()
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("viscosity needs a lubricated"),
        "{e}"
    );
    let mut ideal = press_scene(PressJoint::Ideal, 150.0, 0.0);
    assert!(apply_params(
        &mut ideal,
        &PointParams {
            clearance: Some(1e-4),
            ..params()
        }
    )
    .is_err());
    // Solver parameters leave the scene alone.
    let before = ideal.clone();
    apply_params(
        &mut ideal,
        &PointParams {
            method: Some(Method::Bdf),
            rtol: Some(1e-6),
            ..params()
        },
    )
    .unwrap();
    assert_eq!(ideal, before);
}

#[test]
fn flatten_uses_dotted_names() {
    let r =
        PointResult::flatten(&serde_json::json!({"a": {"b": 1, "c": null}, "d": [1, 2], "e": "s"}));
    let keys: Vec<&String> = r.values.keys().collect();
    assert_eq!(keys, ["a.b", "a.c", "d", "e"]);
    assert_eq!(r.values["d"], Value::String("[1,2]".into()));
    // Per-joint records (summary.json's law_range) become one column per joint and field;
    // an array that is not all records stays JSON text.
    let r = PointResult::flatten(&serde_json::json!({
        "law_range": [{"joint": "j1", "depth_max": -1e-5}, {"joint": "pj", "depth_max": 2e-6}],
        "mixed": [{"joint": "j1"}, 3]
    }));
    let keys: Vec<&String> = r.values.keys().collect();
    assert_eq!(
        keys,
        [
            "law_range[j1].depth_max",
            "law_range[j1].joint",
            "law_range[pj].depth_max",
            "law_range[pj].joint",
            "mixed"
        ]
    );
    assert_eq!(r.values["law_range[pj].depth_max"], serde_json::json!(2e-6));
}
