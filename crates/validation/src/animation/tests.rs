//! The geometry the animation page receives, checked against the run's trajectory.csv: the
//! frames are rows of it, the poses its columns (to the page's 7 digits), the pins of ideal
//! joints close (to the run's constraint violation), ground pivots stay put, each clearance
//! joint's journal sits at the bearing plus e, the film force has the trajectory's magnitude,
//! and the panel's band holds every row between two frames.

use std::path::{Path, PathBuf};

use super::{AnimationOptions, Table, ANIMATION_FILE, SCENE_FILE};
use crate::commands::run::{run, RunOptions};
use crate::commands::viz::{animate, animate_in_memory, AnimateOptions};
use crate::progress::NoProgress;
use serde_json::Value;

fn case(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
        .to_string_lossy()
        .into_owned()
}

/// Runs `scene` into `dir` and animates it; returns the page's data and the trajectory.
fn run_and_animate(scene: &str, dir: &Path, o: AnimationOptions) -> (Value, Table, String) {
    run(
        &RunOptions {
            case: case(scene),
            out: Some(dir.to_path_buf()),
            ..Default::default()
        },
        &NoProgress,
    )
    .unwrap();
    let w = animate(&AnimateOptions {
        run_dir: dir.to_path_buf(),
        trace: o.trace,
        column: o.column,
        max_frames: o.max_frames,
        out: None,
    })
    .unwrap();
    assert_eq!(w.files, vec![dir.join(ANIMATION_FILE)]);
    let html = std::fs::read_to_string(dir.join(ANIMATION_FILE)).unwrap();
    assert_eq!(w.result.bytes, html.len());
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    (
        data_of(&html),
        Table::from_csv(&csv, "trajectory.csv").unwrap(),
        html,
    )
}

/// The JSON the page parses (its `lash-data` script element).
fn data_of(html: &str) -> Value {
    let open = r#"<script id="lash-data" type="application/json">"#;
    let from = html.find(open).unwrap() + open.len();
    let to = from + html[from..].find("</script>").unwrap();
    serde_json::from_str(&html[from..to]).unwrap()
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn pair(v: &Value) -> [f64; 2] {
    [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()]
}

/// |a − b| within the page's rounding to 7 significant digits.
fn close7(a: f64, b: f64) -> bool {
    (a - b).abs() <= 5.000001e-7 * b.abs()
}

/// A place on frame f, as the page computes it: r + A(θ) s, or s on the ground.
fn place(d: &Value, f: usize, a: &Value) -> [f64; 2] {
    let s = pair(&a["s"]);
    match a["body"].as_u64() {
        None => s,
        Some(k) => {
            let b = &d["bodies"][k as usize];
            let (x, y, th) = (
                b["x"][f].as_f64().unwrap(),
                b["y"][f].as_f64().unwrap(),
                b["theta"][f].as_f64().unwrap(),
            );
            let (sn, cs) = th.sin_cos();
            [x + cs * s[0] - sn * s[1], y + sn * s[0] + cs * s[1]]
        }
    }
}

/// The checks every page must pass against its trajectory (module doc).
fn check_against_trajectory(d: &Value, tab: &Table) {
    let rows = tab.rows();
    let stride = d["stride"].as_u64().unwrap() as usize;
    let t = nums(&d["t"]);
    // Frames: rows 0, s, 2s, …, and the last, their times exact.
    let mut want: Vec<usize> = (0..rows).step_by(stride).collect();
    if *want.last().unwrap() != rows - 1 {
        want.push(rows - 1);
    }
    assert_eq!(t.len(), want.len());
    for (f, &i) in want.iter().enumerate() {
        assert_eq!(t[f].to_bits(), tab.t()[i].to_bits(), "frame {f}");
    }
    // Poses: the trajectory's columns to 7 digits.
    for b in d["bodies"].as_array().unwrap() {
        let name = b["name"].as_str().unwrap();
        for q in ["x", "y", "theta"] {
            let col = tab.column(&format!("{name}.{q}")).unwrap();
            for (f, v) in nums(&b[q]).iter().enumerate() {
                assert!(close7(*v, col[want[f]]), "{name}.{q} frame {f}: {v}");
            }
        }
    }
    // Length scale of the rounding: |x| ≤ L everywhere, |θ| ≤ Θ.
    let view = nums(&d["view"]);
    let l = view.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let th_max = d["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|b| nums(&b["theta"]))
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let round = 5e-7 * (2.0 * l + th_max * l);
    // Ideal pins close to within the run's constraint violation (plus rounding), and a pin to
    // the ground stays at its location.
    let phi = tab.column("constraint_violation").unwrap();
    for p in d["pins"].as_array().unwrap() {
        for f in 0..t.len() {
            let (a, b) = (place(d, f, &p["a"]), place(d, f, &p["b"]));
            let gap = (a[0] - b[0]).hypot(a[1] - b[1]);
            assert!(
                gap <= phi[want[f]] + round,
                "pin {} frame {f}: the sides are {gap:e} m apart, ‖Φ‖ = {:e}",
                p["name"],
                phi[want[f]]
            );
        }
    }
    // Clearance joints: the journal's centre is the bearing's plus e = (e/c)·c, and e/c is
    // the trajectory's.
    for c in d["clearance"].as_array().unwrap() {
        let name = c["name"].as_str().unwrap();
        let cl = c["c"].as_f64().unwrap();
        let (ex, ey) = (nums(&c["ex"]), nums(&c["ey"]));
        let (tx, ty) = (
            tab.column(&format!("{name}.ex_over_c")).unwrap(),
            tab.column(&format!("{name}.ey_over_c")).unwrap(),
        );
        for f in 0..t.len() {
            assert!(close7(ex[f], tx[want[f]]) && close7(ey[f], ty[want[f]]));
            let (jb, bb) = (place(d, f, &c["journal"]), place(d, f, &c["bearing"]));
            let e = [jb[0] - bb[0], jb[1] - bb[1]];
            let err = (e[0] - ex[f] * cl).hypot(e[1] - ey[f] * cl);
            assert!(err <= 2.0 * round, "{name} frame {f}: e off by {err:e} m");
        }
        // Forces: the trajectory's, and the film's magnitude too.
        for (q, key) in [("contact_force", "fn"), ("friction_force", "ft")] {
            let col = tab.column(&format!("{name}.{q}")).unwrap();
            for (f, v) in nums(&c[key]).iter().enumerate() {
                assert!(close7(*v, col[want[f]]), "{name}.{q} frame {f}");
            }
        }
        let film = tab.column(&format!("{name}.film_force")).unwrap();
        if c["film_r"].is_null() {
            assert!(film.iter().all(|v| *v == 0.0), "a dry joint has no film");
        } else {
            let (fr, ft) = (nums(&c["film_r"]), nums(&c["film_t"]));
            for f in 0..t.len() {
                let m = fr[f].hypot(ft[f]);
                assert!(
                    (m - film[want[f]]).abs() <= 1e-6 * film[want[f]] + 1e-12,
                    "{name} frame {f}: |film| {m} against {}",
                    film[want[f]]
                );
            }
        }
    }
    // The panel: every filled column but t; with a stride, a band holding every row.
    let series = d["series"].as_array().unwrap();
    let present: Vec<&str> = tab.present().into_iter().filter(|n| *n != "t").collect();
    let names: Vec<&str> = series.iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(names, present);
    for s in series {
        let col = tab.column(s["name"].as_str().unwrap()).unwrap();
        let v = nums(&s["v"]);
        for f in 0..t.len() {
            assert!(close7(v[f], col[want[f]]));
        }
        if stride > 1 {
            let (lo, hi) = (nums(&s["lo"]), nums(&s["hi"]));
            for f in 1..t.len() {
                for &x in &col[want[f - 1]..=want[f]] {
                    assert!(
                        lo[f] <= x + 5e-7 * x.abs() && x <= hi[f] + 5e-7 * x.abs(),
                        "{} frame {f}: {x} outside [{}, {}]",
                        s["name"],
                        lo[f],
                        hi[f]
                    );
                }
            }
        } else {
            assert!(s["lo"].is_null() && s["hi"].is_null());
        }
    }
    // The view holds every body's points on every frame.
    for (k, b) in d["bodies"].as_array().unwrap().iter().enumerate() {
        for f in 0..t.len() {
            for p in b["points"].as_array().unwrap() {
                let a = serde_json::json!({"body": k, "s": p["s"]});
                let q = place(d, f, &a);
                assert!(
                    q[0] >= view[0] && q[0] <= view[1] && q[1] >= view[2] && q[1] <= view[3],
                    "{} at {q:?} outside {view:?}",
                    b["name"]
                );
            }
        }
    }
}

#[test]
fn the_fourbar_page_matches_its_trajectory() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("fb");
    let (data, tab, html) = run_and_animate(
        "cases/examples/fourbar_clearance.json",
        &dir,
        AnimationOptions::default(),
    );
    // 2 revolutions at 2000 rows each: 4001 rows, every second one a frame (2500 at most).
    assert_eq!((tab.rows(), data["stride"].as_u64()), (4001, Some(2)));
    check_against_trajectory(&data, &tab);
    // The ground pivots: the crank's O at (0, 0), the rocker's O at (0.4, 0).
    let pins = data["pins"].as_array().unwrap();
    let ground: Vec<[f64; 2]> = pins
        .iter()
        .filter(|p| p["b"]["body"].is_null())
        .map(|p| pair(&p["b"]["s"]))
        .collect();
    assert_eq!(ground, vec![[0.0, 0.0], [0.4, 0.0]]);
    // The drawn eccentricity: R_B / 2c = 10 → × 10; the dry joint has no film.
    let c = &data["clearance"][0];
    assert_eq!(
        (c["magnify"].as_f64(), c["film_r"].is_null()),
        (Some(10.0), true)
    );
    // Defaults: the coupler's path (it carries the journal), the contact force first.
    assert_eq!(
        (data["trace"].as_str(), data["column"].as_str()),
        (Some("coupler"), Some("contact_force"))
    );
    // The page in memory (Python's Run.animate) is the file's, from the same columns.
    let names: Vec<String> = tab.names().to_vec();
    let cols: Vec<Vec<f64>> = names
        .iter()
        .map(|n| {
            tab.column(n)
                .map(<[f64]>::to_vec)
                .unwrap_or_else(|| vec![f64::NAN; tab.rows()])
        })
        .collect();
    let scene = std::fs::read_to_string(dir.join(SCENE_FILE)).unwrap();
    let title = data["title"].as_str().unwrap();
    let mem = animate_in_memory(&scene, names, cols, title, &AnimateOptions::default()).unwrap();
    assert_eq!(mem, html);
}

#[test]
fn the_lubricated_press_page_has_the_films_force() {
    let d = tempfile::tempdir().unwrap();
    let (data, tab, _) = run_and_animate(
        "cases/press/lubricated_150rpm_c0.1.json",
        &d.path().join("lub"),
        AnimationOptions {
            trace: Some("rod.A".into()),
            column: Some("rod_slider.ex_over_c".into()),
            max_frames: Some(300),
        },
    );
    // 4001 rows in at most 300 frames: stride ⌈4000/299⌉ = 14, 286 frames (the last row too).
    assert_eq!(data["stride"].as_u64(), Some(14));
    assert_eq!(data["t"].as_array().unwrap().len(), 4000 / 14 + 2);
    check_against_trajectory(&data, &tab);
    let c = &data["clearance"][0];
    // R_B = 50 mm, c = 0.1 mm: R_B / 2c = 250 → × 200.
    assert_eq!(c["magnify"].as_f64(), Some(200.0));
    assert!(!c["film_r"].is_null());
    // The film carries the load (the journal never touches: no contact force), so its force
    // is never zero; the slide's guide is drawn.
    assert!(nums(&c["fn"]).iter().all(|v| *v == 0.0));
    assert!(nums(&c["film_r"])
        .iter()
        .zip(nums(&c["film_t"]))
        .all(|(r, t)| r.hypot(t) > 0.0));
    assert_eq!(
        data["guides"][0]["direction"],
        serde_json::json!([1.0, 0.0])
    );
    assert_eq!(data["trace"], "rod.A");
}

#[test]
fn the_pendulum_page_keeps_its_pivot() {
    let d = tempfile::tempdir().unwrap();
    let (data, tab, _) = run_and_animate(
        "cases/examples/pendulum.json",
        &d.path().join("p"),
        AnimationOptions::default(),
    );
    check_against_trajectory(&data, &tab);
    // link1's O is pinned at the origin on every frame (to ‖Φ‖ and rounding).
    let a = serde_json::json!({"body": 0, "s": [-0.25, 0.0]});
    let phi = tab.column("constraint_violation").unwrap();
    let stride = data["stride"].as_u64().unwrap() as usize;
    for f in 0..data["t"].as_array().unwrap().len() {
        let o = place(&data, f, &a);
        let row = (f * stride).min(tab.rows() - 1);
        assert!(o[0].hypot(o[1]) <= phi[row] + 2e-6, "frame {f}: {o:?}");
    }
    // Two links, bars: link1 between its two points, link2 (one point, the elbow, 0.25 m
    // from its centre of mass) from the elbow to the point's mirror image.
    assert_eq!(data["bodies"][0]["shape"], "bar");
    assert_eq!(data["bodies"][1]["shape"], "bar");
    assert_eq!(
        data["bodies"][1]["outline"],
        serde_json::json!([[-0.25, 0.0], [0.25, 0.0]])
    );
}

#[test]
fn a_scene_that_does_not_fit_the_trajectory_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let dir: PathBuf = d.path().join("lub");
    run_and_animate(
        "cases/press/lubricated_150rpm_c0.1.json",
        &dir,
        AnimationOptions::default(),
    );
    // The scene with another journal radius (summary.json removed, so its hash is not there
    // to catch it): the re-evaluated eccentricity differs from the trajectory's.
    let p = dir.join(SCENE_FILE);
    let s = std::fs::read_to_string(&p)
        .unwrap()
        .replace("0.0499", "0.0498");
    std::fs::write(&p, s).unwrap();
    std::fs::remove_file(dir.join("summary.json")).unwrap();
    let e = animate(&AnimateOptions {
        run_dir: dir.clone(),
        ..Default::default()
    })
    .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("trajectory.csv does not match scene.json: at t = "),
        "{e}"
    );
}
