//! Wall time and peak memory of `lash run` against the size of the mechanism (issue 23, "a
//! cost that grows linearly with the mechanism"; BENCHMARKS.md, "Scaling with the number of
//! bodies").
//!
//! ```text
//! cargo build --release -p lash-cli
//! cargo run --release -p lash-benches --example scaling -- [chain N…] [free N…] [clearance N…]
//!     [crossover N…] [kkt-crossover N…] [--lash PATH]…
//! chain N      N pendulum links (0.1 m, 1 kg) pinned end to end, the first to the ground,
//!              released horizontal under gravity: 2N revolute equations; --t-end 1e-3
//! free N       N free bodies (1 kg, 0.1 kg m²) moving up under gravity, no joint; t_end 0.01
//! clearance N  a chain of N links whose N − 1 elbows are dry revolute clearance joints (the
//!              README pendulum's elbow: c = 1 mm, impact law, Coulomb friction); --t-end 0.1
//! ```
//! crossover N  in this process, not through `lash run`: the `free N` scene's mechanism
//!              integrated by bdf to t = 0.01 s on dense and on sparse matrices
//!              (SolverOptions::linear_algebra, lash_solver::linear_algebra), the integration
//!              alone timed (best of 3), with the steps and LU factorisations of each: where
//!              the sparse path starts to win (SPARSE_FROM)
//! kkt-crossover N  the same for the `chain N` scene (one cluster, the augmented Lagrangian
//!              by `auto`) on dense matrices and on the `kkt` path (lash_solver::kkt): where
//!              the sparse KKT Newton starts to win (KKT_FROM)
//! Without arguments: chain 30 100 200 300, free 100 300 1000, clearance 10 25 50. Each case
//! is one `lash run` at default settings (method bdf) in a child process, its scene written to
//! a temporary directory; the table gives its exit code, the wall time of the whole process,
//! the time the run itself reports (summary.json `wall_time_s`: set-up is the difference) and
//! the peak resident memory (VmHWM of /proc/<pid>/status, polled every 5 ms until the child
//! exits: a peak in its last 5 ms may be missed). The `lash` binary is the one next to this
//! example's directory (target/release/lash), or each `--lash PATH` given: with several, every
//! case runs with each binary in turn (old and new side by side in one session), one row each,
//! the binary's path in a column of its own.
//!
//! `--figure STEM` also writes STEM.csv (one row per case and binary: kind, N, n = dim y,
//! exit code, wall time, CPU time and peak RSS) and STEM.svg: CPU time and peak RSS of the
//! last `--lash` binary's runs that exited 0 against N, log–log, one line per kind, with
//! lines of slope 1 and 2 through the smallest case for reference (plotters, the font shipped
//! with lash-validation). CPU time is utime + stime of /proc/<pid>/stat (every thread),
//! polled with the memory: it misses at most the child's last 5 ms; it is the figure's time
//! because the wall time of a shared machine is the load's.

use std::io::Write;
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

/// A chain of `n` links; `clearance`: every joint but the ground pin is a clearance joint.
fn chain(n: usize, clearance: bool) -> String {
    let l = 0.1;
    let mut bodies = Vec::new();
    let mut joints = vec![
        r#"{"type": "revolute", "name": "j0", "a": {"body": "l0", "point": "A"},
            "b": {"body": "ground", "at": [0.0, 0.0]}}"#
            .to_string(),
    ];
    for i in 0..n {
        bodies.push(format!(
            r#"{{"name": "l{i}", "mass": 1.0, "inertia": {}, "position": [{}, 0.0],
                "points": {{"A": [{}, 0.0], "B": [{}, 0.0]}}}}"#,
            l * l / 12.0,
            l * i as f64 + l / 2.0,
            -l / 2.0,
            l / 2.0
        ));
        if i == 0 {
            continue;
        }
        joints.push(if clearance {
            format!(
                r#"{{"type": "clearance", "name": "j{i}",
                    "bearing": {{"body": "l{}", "point": "B", "radius": 0.01}},
                    "journal": {{"body": "l{i}", "point": "A", "radius": 0.009}},
                    "normal": {{"law": "impact", "k": 1e9, "c_max": 2000.0, "d_max": 1e-5}},
                    "friction": {{"law": "coulomb", "mu": 0.1, "v0": 1e-4, "v1": 2e-4}}}}"#,
                i - 1
            )
        } else {
            format!(
                r#"{{"type": "revolute", "name": "j{i}", "a": {{"body": "l{}", "point": "B"}},
                    "b": {{"body": "l{i}", "point": "A"}}}}"#,
                i - 1
            )
        });
    }
    format!(
        r#"{{"bodies": [{}], "joints": [{}], "gravity": [0.0, -9.81], "t_end": 1.0}}"#,
        bodies.join(", "),
        joints.join(", ")
    )
}

/// `n` free bodies under gravity.
fn free(n: usize) -> String {
    let bodies: Vec<String> = (0..n)
        .map(|i| {
            format!(
                r#"{{"name": "b{i}", "mass": 1.0, "inertia": 0.1, "position": [{i}.0, 0.0],
                    "velocity": [0.0, 1.0]}}"#
            )
        })
        .collect();
    format!(
        r#"{{"bodies": [{}], "gravity": [0.0, -9.81], "t_end": 0.01}}"#,
        bodies.join(", ")
    )
}

/// Peak resident memory of a live process (kB), from /proc/<pid>/status.
fn vm_hwm(pid: u32) -> Option<u64> {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// CPU time (user + system, every thread) of a live process (s), from /proc/<pid>/stat.
fn cpu_time(pid: u32) -> Option<f64> {
    let s = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command name (which may hold spaces), from its closing parenthesis:
    // state is field 3, utime 14 and stime 15 (proc(5)).
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    // USER_HZ is 100 on every Linux configuration lash runs on (sysconf(_SC_CLK_TCK)).
    Some(ticks / 100.0)
}

/// One measured case (a row of the CSV).
struct Measured {
    kind: String,
    bodies: usize,
    binary: Option<String>,
    exit: Option<i32>,
    wall: f64,
    cpu: f64,
    rss_mb: f64,
}

/// One case: exit code, wall time of the process (s), the run's own wall time (s), peak
/// memory (MB); printed as a table row and returned with the CPU time.
fn measure(
    lash: &PathBuf,
    label: Option<&str>,
    dir: &std::path::Path,
    name: &str,
    scene: &str,
    t_end: Option<&str>,
) -> Measured {
    let binary = label.map(str::to_string);
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, scene).expect("write the scene");
    let out = dir.join(name);
    let mut cmd = Command::new(lash);
    cmd.arg("run").arg(&path).arg("--out").arg(&out);
    if let Some(t) = t_end {
        cmd.args(["--t-end", t]);
    }
    let start = Instant::now();
    let mut child = cmd
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn lash");
    let mut peak = 0;
    let mut cpu = 0.0f64;
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait for lash") {
            break s;
        }
        peak = peak.max(vm_hwm(child.id()).unwrap_or(0));
        cpu = cpu.max(cpu_time(child.id()).unwrap_or(0.0));
        std::thread::sleep(Duration::from_millis(5));
    };
    let wall = start.elapsed().as_secs_f64();
    let run = std::fs::read_to_string(out.join("summary.json"))
        .ok()
        .and_then(|s| {
            let k = s.find("\"wall_time_s\":")?;
            let rest = s[k + 14..].trim_start();
            let end = rest.find([',', '\n', '}'])?;
            rest[..end].trim().parse::<f64>().ok()
        });
    let run = run.map_or_else(|| "—".to_string(), |v| format!("{v:.2}"));
    let label = label.map_or_else(String::new, |l| format!(" {l} |"));
    println!(
        "| {name} |{label} {} | {wall:.2} | {run} | {:.0} |",
        status
            .code()
            .map_or_else(|| "signal".into(), |c| c.to_string()),
        peak as f64 / 1024.0
    );
    std::io::stdout().flush().ok();
    Measured {
        kind: String::new(),
        bodies: 0,
        binary,
        exit: status.code(),
        wall,
        cpu,
        rss_mb: peak as f64 / 1024.0,
    }
}

/// STEM.csv of the module doc.
fn write_figure(stem: &std::path::Path, rows: &[Measured]) {
    let mut csv = String::from("kind,bodies,n,binary,exit,wall_s,cpu_s,peak_rss_mb\n");
    for r in rows {
        csv += &format!(
            "{},{},{},{},{},{:.4},{:.4},{:.1}\n",
            r.kind,
            r.bodies,
            6 * r.bodies,
            r.binary.as_deref().unwrap_or(""),
            r.exit.map_or_else(|| "signal".into(), |c| c.to_string()),
            r.wall,
            r.cpu,
            r.rss_mb
        );
    }
    let name = |suffix: &str| {
        let mut s = stem.as_os_str().to_owned();
        s.push(suffix);
        PathBuf::from(s)
    };
    if let Some(dir) = stem.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).expect("the figure's directory");
    }
    std::fs::write(name(".csv"), csv).expect("write the CSV");
    println!("wrote {}.csv", stem.display());
    let last = rows.last().and_then(|r| r.binary.clone());
    let newest: Vec<&Measured> = rows
        .iter()
        .filter(|r| r.binary == last && r.exit == Some(0))
        .collect();
    match draw_figure(&name(".svg"), &newest) {
        Ok(()) => println!("wrote {}.svg", stem.display()),
        Err(e) => eprintln!("the figure was not drawn: {e}"),
    }
}

/// The font the figures use (lash-validation's, DejaVu Sans).
static FONT: &[u8] = include_bytes!("../../crates/validation/assets/DejaVuSans.ttf");

/// STEM.svg of the module doc from the runs in `rows`.
fn draw_figure(
    path: &std::path::Path,
    rows: &[&Measured],
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| "the font could not be registered")?;
    if rows.is_empty() {
        return Err("no run exited 0".into());
    }
    let root = SVGBackend::new(path, (1100, 460)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(550);
    type Get = fn(&Measured) -> f64;
    let panels: [(_, &str, Get); 2] = [
        (left, "CPU time of `lash run` (s)", |m| m.cpu),
        (right, "peak resident memory (MB)", |m| m.rss_mb),
    ];
    let kinds = [
        ("chain", "chain of N links", RGBColor(31, 119, 180)),
        ("free", "N free bodies", RGBColor(214, 39, 40)),
        (
            "clearance",
            "N links, N − 1 clearance joints",
            RGBColor(44, 160, 44),
        ),
    ];
    for (area, title, get) in panels {
        let xs = rows.iter().map(|m| m.bodies as f64);
        let ys = rows.iter().map(|m| get(m).max(1e-3));
        let (x0, x1) = xs.fold((f64::INFINITY, 0.0_f64), |(a, b), x| (a.min(x), b.max(x)));
        let (y0, y1) = ys.fold((f64::INFINITY, 0.0_f64), |(a, b), y| (a.min(y), b.max(y)));
        // Whole decades of time and memory around the data.
        let decade = |v: f64, up: bool| {
            let e = v.log10();
            10f64.powf(if up { e.ceil() } else { e.floor() })
        };
        let (x0, x1) = (x0 / 1.5, x1 * 1.5);
        let (y0, y1) = (decade(y0 / 1.2, false), decade(y1 * 1.2, true));
        let mut chart = ChartBuilder::on(&area)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("bodies N")
            .x_label_formatter(&|v| format!("{v}"))
            .y_label_formatter(&|v| format!("{v}"))
            .light_line_style(BLACK.mix(0.05))
            .label_style(("sans-serif", 13))
            .draw()?;
        for (kind, label, color) in kinds {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|m| m.kind == kind)
                .map(|m| (m.bodies as f64, get(m).max(1e-3)))
                .collect();
            if pts.is_empty() {
                continue;
            }
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))?;
        }
        // Slopes 1 and 2 through the smallest case (linear and quadratic growth).
        let first = rows
            .iter()
            .map(|m| (m.bodies as f64, get(m).max(1e-3)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("rows is not empty");
        for (k, shade) in [(1.0, 0.6), (2.0, 0.35)] {
            let grey = BLACK.mix(shade);
            // To the edge of the plot: the right side or the top, whichever comes first.
            let x_end = x1.min(first.0 * (y1 / first.1).powf(1.0 / k));
            let end = (x_end, first.1 * (x_end / first.0).powf(k));
            chart
                .draw_series(LineSeries::new(vec![first, end], grey.stroke_width(1)))?
                .label(format!("slope {k}"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 12))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()?;
    }
    root.present()?;
    Ok(())
}

/// The `crossover N` case (module doc): one table row; `kkt`: the `kkt-crossover N` case.
fn crossover(n: usize, kkt: bool) {
    use lash_solver::{LinearAlgebra, Method, OdeSystem, Output, Problem, SolverOptions};
    let (json, other) = if kkt {
        (chain(n, false), LinearAlgebra::Kkt)
    } else {
        (free(n), LinearAlgebra::Sparse)
    };
    let scene = lash_model::Scene::from_json_str(&json).expect("the scene");
    let mech = lash_model::Mechanism::from_scene(&scene).expect("its mechanism");
    let y0 = mech.initial_state();
    let mut row = format!("| {n} | {} |", mech.dim());
    for la in [LinearAlgebra::Dense, other] {
        let mut o = SolverOptions::with_method(Method::Bdf);
        o.output = Output::Final;
        o.linear_algebra = la;
        let mut best = f64::INFINITY;
        let mut stats = None;
        for _ in 0..3 {
            let start = Instant::now();
            let sol = Problem::new(&mech, &o)
                .and_then(|p| p.solve((0.0, 0.01), &y0))
                .expect("the integration");
            best = best.min(start.elapsed().as_secs_f64());
            stats = Some(sol.stats);
        }
        let st = stats.expect("three runs");
        row += &format!(" {best:.4} | {} | {} |", st.accepted, st.lu_factorizations);
    }
    println!("{row}");
    std::io::stdout().flush().ok();
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let first = args.first().map(String::as_str);
    if first == Some("crossover") || first == Some("kkt-crossover") {
        let kkt = first == Some("kkt-crossover");
        println!(
            "| N | n | dense (s) | steps | LUs | {} (s) | steps | LUs |\n\
             |---|---|---|---|---|---|---|---|",
            if kkt { "kkt" } else { "sparse" }
        );
        for a in &args[1..] {
            match a.parse::<usize>() {
                Ok(n) if n >= 1 => crossover(n, kkt),
                _ => {
                    eprintln!("usage: scaling crossover N… (N ≥ 1)");
                    std::process::exit(2);
                }
            }
        }
        return;
    }
    let mut cases: Vec<(String, usize)> = Vec::new();
    let mut kind = None;
    let mut lashes: Vec<PathBuf> = Vec::new();
    let mut figure: Option<PathBuf> = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--figure" => match it.next() {
                Some(p) => figure = Some(PathBuf::from(p)),
                None => {
                    eprintln!("--figure needs a path stem (e.g. docs/figures/scaling)");
                    std::process::exit(2);
                }
            },
            "--lash" => match it.next() {
                Some(p) => lashes.push(PathBuf::from(p)),
                None => {
                    eprintln!("--lash needs the path of a lash binary");
                    std::process::exit(2);
                }
            },
            "chain" | "free" | "clearance" => kind = Some(a.clone()),
            n => match (kind.clone(), n.parse::<usize>()) {
                (Some(k), Ok(n)) if n >= 1 => cases.push((k, n)),
                _ => {
                    eprintln!(
                        "usage: scaling [chain N…] [free N…] [clearance N…] (N ≥ 1) \
                         [--lash PATH]… [--figure STEM]"
                    );
                    std::process::exit(2);
                }
            },
        }
    }
    if cases.is_empty() {
        for n in [30, 100, 200, 300] {
            cases.push(("chain".into(), n));
        }
        for n in [100, 300, 1000] {
            cases.push(("free".into(), n));
        }
        for n in [10, 25, 50] {
            cases.push(("clearance".into(), n));
        }
    }
    if lashes.is_empty() {
        let exe = std::env::current_exe().expect("the example's path");
        lashes.push(
            exe.parent()
                .and_then(|p| p.parent())
                .map(|p| p.join("lash"))
                .expect("target/release"),
        );
    }
    for lash in &lashes {
        if !lash.exists() {
            eprintln!(
                "{} not found: cargo build --release -p lash-cli first",
                lash.display()
            );
            std::process::exit(2);
        }
    }
    let several = lashes.len() > 1;
    let dir = std::env::temp_dir().join(format!("lash-scaling-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    if several {
        println!("| case | lash | exit | wall (s) | run (s) | peak RSS (MB) |");
        println!("|---|---|---|---|---|---|");
    } else {
        println!("| case | exit | wall (s) | run (s) | peak RSS (MB) |");
        println!("|---|---|---|---|---|");
    }
    let mut rows = Vec::new();
    for (k, n) in cases {
        let (scene, t_end) = match k.as_str() {
            "chain" => (chain(n, false), Some("1e-3")),
            "free" => (free(n), None),
            _ => (chain(n, true), Some("0.1")),
        };
        for (i, lash) in lashes.iter().enumerate() {
            let label = several.then(|| lash.display().to_string());
            // A directory per binary: each run writes its own output.
            let sub = dir.join(i.to_string());
            std::fs::create_dir_all(&sub).expect("a temporary directory");
            let mut m = measure(
                lash,
                label.as_deref(),
                &sub,
                &format!("{k}{n}"),
                &scene,
                t_end,
            );
            (m.kind, m.bodies) = (k.clone(), n);
            rows.push(m);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    if let Some(stem) = figure {
        write_figure(&stem, &rows);
    }
}
