//! `lash run --animate`, `lash animate`, `lash plot` end to end, and the page in a real
//! browser: headless Chromium driven over the DevTools protocol (its `--remote-debugging-pipe`,
//! JSON messages separated by NUL on file descriptors 3 and 4, here two FIFOs).
//!
//! The browser test needs Chromium (`LASH_CHROMIUM`, else `chromium`, `chromium-browser`,
//! `google-chrome` on PATH). Without one it is skipped with a printed reason, unless
//! `LASH_REQUIRE_BROWSER=1` (set by `.ci/run`): then a missing browser fails it. With
//! `LASH_BROWSER_SHOTS=DIR` its screenshots are kept in DIR (README's docs/animation.png is
//! `fourbar-scrubbed.png`).

mod common;

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use common::{lash, ok};
use serde_json::{json, Value};

fn case(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
        .to_string_lossy()
        .into_owned()
}

/// The issue's budget: one second of the clearance four-bar animates into at most 10 MB.
#[test]
fn one_second_of_the_fourbar_is_a_page_under_ten_megabytes() {
    let d = tempfile::tempdir().unwrap();
    let out = ok(
        &[
            "run",
            &case("cases/examples/fourbar_clearance.json"),
            "--t-end",
            "1",
            "--animate",
            "--out",
            "fb",
        ],
        d.path(),
    );
    let page = d.path().join("fb/animation.html");
    let bytes = std::fs::metadata(&page).unwrap().len();
    assert!(bytes <= 10_000_000, "{bytes} bytes");
    // 1 s at 60 rpm: 2001 rows, all of them frames (below the default 2500).
    assert!(out.contains("2001 frames)"), "{out}");
    let html = std::fs::read_to_string(&page).unwrap();
    // Self-contained: nothing is loaded from anywhere.
    for needle in ["src=", "href=", "http://", "https://", "@import", "url("] {
        assert!(!html.contains(needle), "the page refers to {needle}");
    }
    // The run keeps its scene, byte for byte.
    assert_eq!(
        std::fs::read(d.path().join("fb/scene.json")).unwrap(),
        std::fs::read(case("cases/examples/fourbar_clearance.json")).unwrap()
    );
}

#[test]
fn animate_and_plot_say_what_is_wrong() {
    let d = tempfile::tempdir().unwrap();
    let err = |args: &[&str]| {
        let o = lash(args, d.path());
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let e = err(&["run", "testset:rober", "--animate"]);
    assert!(e.contains("--animate needs a scene"), "{e}");
    assert!(
        !d.path().join("out").exists(),
        "nothing run, nothing written"
    );
    ok(
        &[
            "run",
            &case("cases/examples/pendulum.json"),
            "--t-end",
            "0.2",
            "--out",
            "p",
        ],
        d.path(),
    );
    let e = err(&["animate", "p", "--trace", "link3"]);
    assert!(
        e.contains("'link3' is no body or body point of the scene; choose one of link1, link1.O"),
        "{e}"
    );
    let e = err(&["animate", "nowhere"]);
    assert!(e.contains("run directory nowhere not found"), "{e}");
    let e = err(&["plot", "p", "rocker.theta"]);
    assert!(e.contains("no column 'rocker.theta'"), "{e}");
    let e = err(&["plot", "p", "slider_x"]);
    assert!(e.contains("slider_x has no values"), "{e}");
    let e = err(&["animate", "p", "--max-frames", "1"]);
    assert!(e.contains("max-frames must be a whole number >= 2"), "{e}");
    // A scene.json that is not the run's (edited) is refused: the summary's hash differs.
    let s = d.path().join("p/scene.json");
    let mut text = std::fs::read_to_string(&s).unwrap();
    text.push(' ');
    std::fs::write(&s, text).unwrap();
    let e = err(&["animate", "p"]);
    assert!(e.contains("is not the scene of this run"), "{e}");
    assert!(!d.path().join("p/animation.html").exists());
    // A plot of two columns and of one against another; a rerun of the run replaces them.
    let o = ok(&["plot", "p", "link2.theta", "link1.theta"], d.path());
    assert!(o.contains("plot_link2.theta+link1.theta.svg"), "{o}");
    ok(&["plot", "p", "link2.y", "--x", "link2.x"], d.path());
    assert!(d.path().join("p/plot_link2.y_vs_link2.x.png").is_file());
    ok(
        &[
            "run",
            &case("cases/examples/pendulum.json"),
            "--t-end",
            "0.1",
            "--out",
            "p",
        ],
        d.path(),
    );
    assert!(!d.path().join("p/plot_link2.y_vs_link2.x.png").exists());
}

// ------------------------------------------------------------------------------------------
// The browser
// ------------------------------------------------------------------------------------------

/// The Chromium to drive: `LASH_CHROMIUM`, else the first of the usual names on PATH.
fn find_chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("LASH_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    for name in [
        "chromium",
        "chromium-browser",
        "google-chrome",
        "google-chrome-stable",
    ] {
        for dir in std::env::split_paths(&path) {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Decodes standard base64 (the DevTools protocol's screenshots).
fn base64(s: &str) -> Vec<u8> {
    let val = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let bytes: Vec<u8> = s.bytes().filter(|&c| c != b'=' && c != b'\n').collect();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let mut n = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            n |= val(c) << (18 - 6 * i);
        }
        for i in 0..chunk.len() - 1 {
            out.push((n >> (16 - 8 * i)) as u8);
        }
    }
    out
}

/// An RGB screenshot.
struct Shot {
    w: usize,
    h: usize,
    rgb: Vec<u8>,
}

impl Shot {
    fn decode(png_bytes: &[u8]) -> Shot {
        let mut dec = png::Decoder::new(std::io::Cursor::new(png_bytes));
        dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut r = dec.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size()];
        let info = r.next_frame(&mut buf).unwrap();
        let bpp = info.color_type.samples();
        let rgb = buf[..info.buffer_size()]
            .chunks(bpp)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        Shot {
            w: info.width as usize,
            h: info.height as usize,
            rgb,
        }
    }

    fn px(&self, x: usize, y: usize) -> [u8; 3] {
        let i = 3 * (y.min(self.h - 1) * self.w + x.min(self.w - 1));
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }
}

fn dist(a: [u8; 3], b: [u8; 3]) -> u32 {
    (0..3).map(|k| u32::from(a[k].abs_diff(b[k]))).sum()
}

/// The view canvas's background (page.html: #fbfbf8).
const BACKGROUND: [u8; 3] = [251, 251, 248];

/// A headless Chromium on the DevTools protocol's pipe, with one page attached.
struct Browser {
    child: Child,
    to: std::fs::File,
    from: mpsc::Receiver<Value>,
    next: u64,
    events: Vec<Value>,
    session: Option<String>,
    _dir: tempfile::TempDir,
}

impl Browser {
    fn launch(exe: &Path) -> Browser {
        let dir = tempfile::tempdir().unwrap();
        let (fin, fout) = (dir.path().join("in"), dir.path().join("out"));
        for f in [&fin, &fout] {
            let st = Command::new("mkfifo").arg(f).status().unwrap();
            assert!(st.success(), "mkfifo {}", f.display());
        }
        let log = std::fs::File::create(dir.path().join("chromium.log")).unwrap();
        let child = Command::new("sh")
            .arg("-c")
            .arg(r#"exec "$0" "$@" 3<"$LASH_PIPE_IN" 4>"$LASH_PIPE_OUT""#)
            .arg(exe)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--disable-extensions",
                "--mute-audio",
                "--hide-scrollbars",
                "--force-device-scale-factor=1",
                "--remote-debugging-pipe",
            ])
            .arg(format!(
                "--user-data-dir={}",
                dir.path().join("profile").display()
            ))
            .env("LASH_PIPE_IN", &fin)
            .env("LASH_PIPE_OUT", &fout)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .expect("start chromium");
        // Opening a FIFO blocks until its other end opens: do it aside, with a deadline.
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let to = std::fs::OpenOptions::new().write(true).open(&fin);
            let from = std::fs::File::open(&fout);
            let _ = tx.send((to, from));
        });
        let (to, from) = match rx.recv_timeout(Duration::from_secs(60)) {
            Ok((Ok(t), Ok(f))) => (t, f),
            other => panic!("chromium did not open its pipe: {:?}", other.is_ok()),
        };
        let (etx, erx) = mpsc::channel();
        std::thread::spawn(move || {
            let mut r = BufReader::new(from);
            let mut buf = Vec::new();
            loop {
                buf.clear();
                match r.read_until(0, &mut buf) {
                    Ok(0) | Err(_) => return,
                    Ok(_) => {
                        if buf.last() == Some(&0) {
                            buf.pop();
                        }
                        if let Ok(v) = serde_json::from_slice::<Value>(&buf) {
                            if etx.send(v).is_err() {
                                return;
                            }
                        }
                    }
                }
            }
        });
        Browser {
            child,
            to,
            from: erx,
            next: 0,
            events: Vec::new(),
            session: None,
            _dir: dir,
        }
    }

    /// Sends a command (to the attached page unless `browser`) and waits for its result.
    fn send(&mut self, method: &str, params: Value, browser: bool) -> Value {
        self.next += 1;
        let id = self.next;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if let (false, Some(s)) = (browser, &self.session) {
            msg["sessionId"] = json!(s);
        }
        let mut bytes = serde_json::to_vec(&msg).unwrap();
        bytes.push(0);
        self.to.write_all(&bytes).unwrap();
        self.to.flush().unwrap();
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let v = self
                .from
                .recv_timeout(left)
                .unwrap_or_else(|_| panic!("no answer to {method}"));
            if v.get("id").and_then(Value::as_u64) == Some(id) {
                if let Some(e) = v.get("error") {
                    panic!("{method}: {e}");
                }
                return v["result"].clone();
            }
            self.events.push(v);
        }
    }

    fn call(&mut self, method: &str, params: Value) -> Value {
        self.send(method, params, false)
    }

    /// Opens `url` in a new page and attaches to it.
    fn open(&mut self, url: &str) {
        let t = self.send("Target.createTarget", json!({"url": "about:blank"}), true);
        let target = t["targetId"].as_str().unwrap().to_string();
        let a = self.send(
            "Target.attachToTarget",
            json!({"targetId": target, "flatten": true}),
            true,
        );
        self.session = Some(a["sessionId"].as_str().unwrap().to_string());
        for m in ["Page.enable", "Runtime.enable", "Network.enable"] {
            self.call(m, json!({}));
        }
        self.call(
            "Emulation.setDeviceMetricsOverride",
            json!({"width": 1280, "height": 1000, "deviceScaleFactor": 1, "mobile": false}),
        );
        self.call("Page.navigate", json!({ "url": url }));
        let deadline = Instant::now() + Duration::from_secs(60);
        while self.eval("!!(window.lash && window.lash.ready)") != json!(true) {
            assert!(Instant::now() < deadline, "the page never got ready");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// The value of a JavaScript expression on the page.
    fn eval(&mut self, expr: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": expr, "returnByValue": true, "awaitPromise": true}),
        );
        if let Some(e) = r.get("exceptionDetails") {
            panic!("{expr}: {e}");
        }
        r["result"]["value"].clone()
    }

    /// A screenshot; with `LASH_BROWSER_SHOTS=DIR` also kept as DIR/NAME.png.
    fn shot(&mut self, name: &str) -> Shot {
        // Two animation frames first, so that the page has painted what it set.
        self.eval("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))");
        let r = self.call("Page.captureScreenshot", json!({"format": "png"}));
        let png = base64(r["data"].as_str().unwrap());
        if let Some(dir) = std::env::var_os("LASH_BROWSER_SHOTS") {
            std::fs::write(Path::new(&dir).join(format!("{name}.png")), &png).unwrap();
        }
        Shot::decode(&png)
    }

    fn mouse(&mut self, kind: &str, x: f64, y: f64) {
        let buttons = if kind == "mouseReleased" { 0 } else { 1 };
        self.call(
            "Input.dispatchMouseEvent",
            json!({"type": kind, "x": x, "y": y, "button": "left", "buttons": buttons,
                   "clickCount": 1}),
        );
    }

    fn click(&mut self, x: f64, y: f64) {
        self.mouse("mousePressed", x, y);
        self.mouse("mouseReleased", x, y);
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        self.next += 1;
        let msg = format!("{{\"id\":{},\"method\":\"Browser.close\"}}\0", self.next);
        let _ = self.to.write_all(msg.as_bytes());
        let deadline = Instant::now() + Duration::from_secs(10);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        // Our own child, by its handle: it did not close in time.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn rect(v: &Value) -> [f64; 4] {
    let a = v.as_array().unwrap();
    [0, 1, 2, 3].map(|i| a[i].as_f64().unwrap())
}

/// Pixels of `a` and `b` inside `r` (x, y, w, h) that differ by more than 60 (sum of |ΔRGB|).
fn differing(a: &Shot, b: &Shot, r: [f64; 4]) -> usize {
    let (x0, y0) = (r[0].max(0.0) as usize, r[1].max(0.0) as usize);
    let (x1, y1) = ((r[0] + r[2]) as usize, (r[1] + r[3]) as usize);
    (y0..y1.min(a.h))
        .flat_map(|y| (x0..x1.min(a.w)).map(move |x| (x, y)))
        .filter(|&(x, y)| dist(a.px(x, y), b.px(x, y)) > 60)
        .count()
}

/// The page of one run in a real browser: it draws the mechanism (the canvas is not blank;
/// each body's box, from the page's own geometry, is drawn on), dragging the scrubber with
/// the mouse moves the bodies (the screenshots differ where they were and where they are),
/// Play animates, and nothing goes to the network or throws.
fn check_in_browser(b: &mut Browser, page: &Path, name: &str, bodies: &[&str]) {
    b.events.clear();
    b.open(&format!("file://{}", page.display()));
    let list = serde_json::to_string(bodies).unwrap();
    let probe = format!(
        "JSON.stringify((() => {{ const r = id => {{ const b = document.getElementById(id)\
         .getBoundingClientRect(); return [b.left, b.top, b.width, b.height]; }}; return {{ \
         view: r('view'), scrub: r('scrub'), play: r('play'), frame: lash.frame(), frames: \
         lash.frames, playing: lash.playing(), boxes: {list}.map(n => lash.boxOf(n)) }}; \
         }})())"
    );
    let p0: Value = serde_json::from_str(b.eval(&probe).as_str().unwrap()).unwrap();
    let view = rect(&p0["view"]);
    let frames = p0["frames"].as_u64().unwrap();
    assert_eq!(p0["frame"], 0);
    assert!(frames > 100, "{frames}");
    let a = b.shot(&format!("{name}-start"));
    // The canvas is not blank: a good share of it is drawn.
    let blank = Shot {
        w: a.w,
        h: a.h,
        rgb: std::iter::repeat_n(BACKGROUND, a.w * a.h)
            .flatten()
            .collect(),
    };
    let inner = [view[0] + 2.0, view[1] + 2.0, view[2] - 4.0, view[3] - 4.0];
    let drawn = differing(&a, &blank, inner);
    let area = (view[2] * view[3]) as usize;
    assert!(
        drawn > area / 100,
        "{}: {drawn} of {area} pixels drawn",
        page.display()
    );
    // Each body is drawn inside the view, where the page's geometry puts it.
    for (n, bx) in bodies.iter().zip(p0["boxes"].as_array().unwrap()) {
        let r = rect(bx);
        assert!(
            r[0] >= view[0]
                && r[1] >= view[1]
                && r[0] + r[2] <= view[0] + view[2]
                && r[1] + r[3] <= view[1] + view[3],
            "{n}'s box {r:?} outside the view {view:?}"
        );
        let on = differing(&a, &blank, r);
        assert!(
            on >= 20,
            "{}: {on} pixels drawn in {n}'s box {r:?}",
            page.display()
        );
    }
    // Drag the scrubber's thumb with the mouse from its start to 35 % of the track (not half
    // way: the press and the four-bar run two crank revolutions, and after one the crank is
    // back where it started).
    let s = rect(&p0["scrub"]);
    let (y, x_from, x_to) = (s[1] + s[3] / 2.0, s[0] + 6.0, s[0] + 0.35 * s[2]);
    b.mouse("mousePressed", x_from, y);
    for k in 1..=10 {
        b.mouse("mouseMoved", x_from + (x_to - x_from) * k as f64 / 10.0, y);
    }
    b.mouse("mouseReleased", x_to, y);
    let p1: Value = serde_json::from_str(b.eval(&probe).as_str().unwrap()).unwrap();
    let f1 = p1["frame"].as_u64().unwrap();
    assert!(
        f1 > frames / 5 && f1 < frames / 2,
        "the scrubber moved to frame {f1} of {frames}"
    );
    let c = b.shot(&format!("{name}-scrubbed"));
    let mut moved = 0;
    for (k, n) in bodies.iter().enumerate() {
        let (from, to) = (rect(&p0["boxes"][k]), rect(&p1["boxes"][k]));
        let change = (0..4).map(|i| (from[i] - to[i]).abs()).fold(0.0, f64::max);
        if change < 6.0 {
            continue;
        }
        moved += 1;
        let (was, is) = (differing(&a, &c, from), differing(&a, &c, to));
        assert!(
            was >= 20 && is >= 20,
            "{}: {n} moved from {from:?} to {to:?} but the screenshots differ in {was} and \
             {is} pixels there",
            page.display()
        );
    }
    assert!(moved >= 2, "{}: {moved} bodies moved", page.display());
    // Play: the frames advance and the drawing changes; Pause stops it.
    let pl = rect(&p1["play"]);
    b.click(pl[0] + pl[2] / 2.0, pl[1] + pl[3] / 2.0);
    std::thread::sleep(Duration::from_millis(700));
    let p2: Value = serde_json::from_str(b.eval(&probe).as_str().unwrap()).unwrap();
    assert_eq!(p2["playing"], true, "{}", page.display());
    assert_ne!(
        p2["frame"],
        p1["frame"],
        "{}: Play did not advance",
        page.display()
    );
    let e = b.shot(&format!("{name}-playing"));
    assert!(
        differing(&c, &e, view) > 50,
        "{}: playing changed nothing",
        page.display()
    );
    b.click(pl[0] + pl[2] / 2.0, pl[1] + pl[3] / 2.0);
    assert_eq!(b.eval("lash.playing()"), false);
    // Nothing but the page itself was requested, and no script error was thrown.
    for ev in &b.events {
        match ev["method"].as_str() {
            Some("Network.requestWillBeSent") => {
                let url = ev["params"]["request"]["url"].as_str().unwrap_or("");
                assert!(
                    url.starts_with("file://") || url.starts_with("data:"),
                    "the page requested {url}"
                );
            }
            Some("Runtime.exceptionThrown") => panic!("{}: {}", page.display(), ev["params"]),
            Some("Runtime.consoleAPICalled") if ev["params"]["type"] == "error" => {
                panic!("{}: console error {}", page.display(), ev["params"])
            }
            _ => {}
        }
    }
}

#[test]
fn the_page_draws_and_animates_in_a_real_browser() {
    let Some(exe) = find_chromium() else {
        let required = std::env::var("LASH_REQUIRE_BROWSER").is_ok_and(|v| v == "1");
        assert!(
            !required,
            "LASH_REQUIRE_BROWSER=1 but no Chromium found (set LASH_CHROMIUM or put \
             chromium on PATH)"
        );
        eprintln!(
            "skipped: no Chromium on this machine (LASH_CHROMIUM, or chromium on PATH); \
             .ci/run installs one"
        );
        return;
    };
    let d = tempfile::tempdir().unwrap();
    let runs = [
        (
            "cases/examples/pendulum.json",
            "pend",
            vec!["link1", "link2"],
        ),
        (
            "cases/examples/fourbar_clearance.json",
            "fourbar",
            vec!["crank", "coupler", "rocker"],
        ),
        (
            "cases/press/dry_150rpm_c0.1.json",
            "press",
            vec!["crank", "rod", "slider"],
        ),
    ];
    for (scene, dir, _) in &runs {
        ok(&["run", &case(scene), "--animate", "--out", dir], d.path());
    }
    let mut b = Browser::launch(&exe);
    let v = b.send("Browser.getVersion", json!({}), true);
    eprintln!("browser: {}", v["product"]);
    for (_, dir, bodies) in &runs {
        let page = d.path().join(dir).join("animation.html");
        check_in_browser(&mut b, &page, dir, bodies);
    }
}
