//! The figures' tests: palette PNGs, ticks that fit, data inside the plot area.

use std::path::Path;

use plotters::prelude::*;

use super::axes::*;
use super::orbit::*;
use super::panels::*;
use super::render::*;
use super::style::*;
use super::ticks::*;
use super::xy::*;

/// Decodes a PNG; returns (width, height, RGB(A) bytes, bytes per pixel).
fn decode(p: &Path) -> (u32, u32, Vec<u8>, usize) {
    let mut dec = png::Decoder::new(std::fs::File::open(p).unwrap());
    dec.set_transformations(png::Transformations::EXPAND);
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf, info.color_type.samples())
}

#[test]
fn palette_png_keeps_the_frequent_colours_exactly() {
    // 60 frequent colours (10 pixels each) and 300 rare shades one step off them (more
    // colours than a palette holds): the frequent ones survive exactly, each rare one maps
    // to a colour at most one step away.
    let (w, h) = (900u32, 1u32);
    let base = |k: usize| [(4 * k) as u8, (255 - 4 * k) as u8, 100];
    let mut rgb = Vec::new();
    for k in 0..60 {
        for _ in 0..10 {
            rgb.extend_from_slice(&base(k));
        }
    }
    for j in 0..300 {
        let mut c = base(j % 60);
        c[2] = 101 + (j / 60) as u8 % 2;
        c[0] += (j / 120) as u8;
        rgb.extend_from_slice(&c);
    }
    assert_eq!(rgb.len(), (3 * w * h) as usize);
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("p.png");
    std::fs::write(&p, palette_png(&rgb, (w, h)).unwrap()).unwrap();
    let img = decode(&p);
    assert_eq!((img.0, img.1, img.3), (w, h, 3));
    assert_eq!(&img.2[..1800], &rgb[..1800], "frequent colours exact");
    let worst = img.2[1800..]
        .chunks(3)
        .zip(rgb[1800..].chunks(3))
        .map(|(a, b)| {
            (0..3)
                .map(|k| (i32::from(a[k]) - i32::from(b[k])).abs())
                .sum::<i32>()
        })
        .max()
        .unwrap();
    assert!(worst <= 3, "{worst}");
}

/// Number of pixels darker than light grey in rows [y0, y1).
fn dark_pixels(img: &(u32, u32, Vec<u8>, usize), y0: u32, y1: u32) -> usize {
    let (w, _, buf, bpp) = img;
    (y0..y1)
        .flat_map(|y| (0..*w).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let i = ((y * w + x) as usize) * bpp;
            buf[i..i + 3].iter().map(|&v| v as u32).sum::<u32>() < 3 * 160
        })
        .count()
}

fn demo_series() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let deg: Vec<f64> = (0..=360).map(|k| k as f64).collect();
    let a: Vec<f64> = deg.iter().map(|d| -3.86 * d.to_radians().cos()).collect();
    let ideal: Vec<f64> = deg.iter().map(|d| -3.80 * d.to_radians().cos()).collect();
    (deg, a, ideal)
}

#[test]
fn line_plot_writes_svg_and_png_with_text() {
    let d = tempfile::tempdir().unwrap();
    let (deg, a, ideal) = demo_series();
    let w = line_plot(
        &d.path().join("slider_acc"),
        &Axes {
            title: "Slider acceleration, 150 rpm",
            x_label: "crank angle θ, °",
            y_label: "ẍ, m/s²",
        },
        &[
            Series {
                name: "lash",
                x: &deg,
                y: &a,
                style: SeriesStyle::Line,
            },
            Series {
                name: "ideal",
                x: &deg,
                y: &ideal,
                style: SeriesStyle::Dashed,
            },
        ],
    )
    .unwrap();
    let svg = std::fs::read_to_string(&w.svg).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("Slider acceleration, 150 rpm"));
    assert!(svg.contains("crank angle θ, °") && svg.contains("\nideal\n"));
    let img = decode(&w.png);
    assert_eq!((img.0, img.1), FIGURE_SIZE);
    // The title band (above the plot) holds the caption's glyphs and nothing else.
    assert!(dark_pixels(&img, 0, 40) > 200, "no title text rendered");
    // The curves: many dark or coloured pixels overall.
    assert!(dark_pixels(&img, 40, FIGURE_SIZE.1) > 5000);
    // No temporary file left behind.
    let n = std::fs::read_dir(d.path()).unwrap().count();
    assert_eq!(n, 2);
}

#[test]
fn loglog_plot_accepts_positive_data_only() {
    let d = tempfile::tempdir().unwrap();
    let cost = [1e3, 1e4, 1e5];
    let err = [1e-3, 1e-6, 1e-9];
    let w = loglog_plot(
        &d.path().join("wp"),
        &Axes {
            title: "Work–precision",
            x_label: "RHS evaluations",
            y_label: "error",
        },
        &[Series {
            name: "dopri54",
            x: &cost,
            y: &err,
            style: SeriesStyle::LinePoints,
        }],
    )
    .unwrap();
    let img = decode(&w.png);
    assert_eq!((img.0, img.1), FIGURE_SIZE);
    assert!(std::fs::read_to_string(&w.svg).unwrap().contains("dopri54"));
    let zero = [0.0, 1e-6, 1e-9];
    let e = loglog_plot(
        &d.path().join("bad"),
        &Axes {
            title: "",
            x_label: "",
            y_label: "",
        },
        &[Series {
            name: "s",
            x: &cost,
            y: &zero,
            style: SeriesStyle::Points,
        }],
    )
    .unwrap_err();
    assert!(e.to_string().contains("log axis"), "{e}");
    assert!(!d.path().join("bad.png").exists() && !d.path().join("bad.svg").exists());
}

#[test]
fn orbit_plot_is_square_and_shows_the_circle() {
    let d = tempfile::tempdir().unwrap();
    let th: Vec<f64> = (0..2001).map(|k| k as f64 * 0.01).collect();
    let ex: Vec<f64> = th
        .iter()
        .map(|t| 0.6 * t.cos() + 0.1 * (3.0 * t).sin())
        .collect();
    let ey: Vec<f64> = th.iter().map(|t| 0.6 * t.sin()).collect();
    let w = orbit_plot(&d.path().join("orbit"), "Journal orbit", &ex, &ey).unwrap();
    let img = decode(&w.png);
    assert_eq!((img.0, img.1), ORBIT_SIZE);
    assert!(dark_pixels(&img, 0, 35) > 150, "no title text rendered");
    assert!(std::fs::read_to_string(&w.svg)
        .unwrap()
        .contains("clearance circle"));
}

#[test]
fn panels_plot_stacks_log_and_linear_panels() {
    let d = tempfile::tempdir().unwrap();
    let x: Vec<f64> = (0..=72).map(|k| 10.0 * k as f64).collect();
    let rho: Vec<f64> = x
        .iter()
        .map(|a| 1e3 * (2.0 + a.to_radians().cos()))
        .collect();
    let h: Vec<f64> = rho.iter().map(|r| 2.785 / r).collect();
    let a = Axes {
        title: "spectral radius",
        x_label: "crank angle, °",
        y_label: "|λ|, 1/s",
    };
    let b = Axes {
        title: "RK4 limit",
        x_label: "crank angle, °",
        y_label: "h, s",
    };
    let s1 = [Series {
        name: "|λ|max",
        x: &x,
        y: &rho,
        style: SeriesStyle::Line,
    }];
    let s2 = [Series {
        name: "2.785/|λ|",
        x: &x,
        y: &h,
        style: SeriesStyle::Line,
    }];
    let w = panels_plot(
        &d.path().join("st"),
        "Stiffness",
        &[
            Panel {
                axes: a,
                series: &s1,
                log_y: true,
            },
            Panel {
                axes: b,
                series: &s2,
                log_y: false,
            },
        ],
    )
    .unwrap();
    let img = decode(&w.png);
    assert_eq!((img.0, img.1), (PANEL_WIDTH, 2 * PANEL_HEIGHT + 40));
    assert!(dark_pixels(&img, 0, 40) > 100, "no title text rendered");
    // Each panel draws its own axes, labels and curve.
    assert!(dark_pixels(&img, 40, 40 + PANEL_HEIGHT) > 3000);
    assert!(dark_pixels(&img, 40 + PANEL_HEIGHT, 40 + 2 * PANEL_HEIGHT) > 3000);
    let svg = std::fs::read_to_string(&w.svg).unwrap();
    assert!(svg.contains("spectral radius") && svg.contains("RK4 limit"));
    // A log panel refuses y ≤ 0, a linear x axis accepts x = 0.
    let zero = [0.0; 73];
    let bad = [Series {
        name: "z",
        x: &x,
        y: &zero,
        style: SeriesStyle::Line,
    }];
    let e = panels_plot(
        &d.path().join("bad"),
        "t",
        &[Panel {
            axes: a,
            series: &bad,
            log_y: true,
        }],
    )
    .unwrap_err();
    assert!(e.to_string().contains("log axis"), "{e}");
    assert!(panels_plot(&d.path().join("none"), "t", &[]).is_err());
}

#[test]
fn orbits_plot_draws_points_as_markers() {
    let d = tempfile::tempdir().unwrap();
    let ex = [0.1, 0.5, -0.3];
    let ey = [0.2, -0.4, 0.6];
    let w = orbits_plot(
        &d.path().join("sec"),
        "Poincaré section",
        &[Series {
            name: "once per revolution",
            x: &ex,
            y: &ey,
            style: SeriesStyle::Points,
        }],
    )
    .unwrap();
    let svg = std::fs::read_to_string(&w.svg).unwrap();
    // One marker per point, and one in the legend.
    assert_eq!(svg.matches("<circle").count(), 4, "one marker per point");
}

#[test]
fn bad_data_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let ax = Axes {
        title: "t",
        x_label: "x",
        y_label: "y",
    };
    let e = line_plot(
        &d.path().join("a"),
        &ax,
        &[Series {
            name: "s",
            x: &[1.0, 2.0],
            y: &[1.0],
            style: SeriesStyle::Line,
        }],
    )
    .unwrap_err();
    assert!(e.to_string().contains("2 x and 1 y"));
    let e = line_plot(
        &d.path().join("a"),
        &ax,
        &[Series {
            name: "s",
            x: &[1.0],
            y: &[f64::NAN],
            style: SeriesStyle::Line,
        }],
    )
    .unwrap_err();
    assert!(e.to_string().contains("non-finite"));
    assert!(line_plot(&d.path().join("a"), &ax, &[]).is_err());
    assert!(orbit_plot(&d.path().join("o"), "t", &[0.1], &[]).is_err());
}

/// Pixels of a data colour (saturated: max − min channel > 60; text, axes and grid are
/// grey) that lie in no plot area and no legend of the layout.
fn strays(w: &Written) -> (usize, usize, Vec<(u32, u32)>) {
    let (width, height, buf, bpp) = decode(&w.png);
    let inside = |r: &PixelRect, x: u32, y: u32| {
        (x as i32) >= r[0] && (x as i32) < r[2] && (y as i32) >= r[1] && (y as i32) < r[3]
    };
    let (mut data, mut out) = (0, Vec::new());
    for y in 0..height {
        for x in 0..width {
            let i = ((y * width + x) as usize) * bpp;
            let (mx, mn) = (
                buf[i..i + 3].iter().max().unwrap(),
                buf[i..i + 3].iter().min().unwrap(),
            );
            if mx - mn <= 60 {
                continue;
            }
            if w.layout.plots.iter().any(|r| inside(r, x, y)) {
                data += 1;
            } else if !w.layout.legends.iter().any(|r| inside(r, x, y)) {
                out.push((x, y));
            }
        }
    }
    (data, out.len(), out.into_iter().take(8).collect())
}

/// A dry joint's contact force: zero, with spikes of one or two samples up to 3e4 N, on
/// 2001 samples of 0…720° (several samples per pixel column).
fn spiky() -> (Vec<f64>, Vec<f64>) {
    let x: Vec<f64> = (0..=2000).map(|k| 0.36 * k as f64).collect();
    let y: Vec<f64> = (0..=2000)
        .map(|k| match k % 97 {
            0 => 3e4 * (1.0 + (k as f64).sin()) / 2.0,
            1 => 1.5e4,
            5..=9 => 2e3 * ((k % 7) as f64),
            _ => 0.0,
        })
        .collect();
    (x, y)
}

/// Every figure kind, drawn from data that provokes strokes past the axes (spikes of one
/// sample, many samples per pixel, steep reversals, markers at the ends of the range):
/// no pixel of a data series lies outside the plot areas (legends aside), and the series
/// are drawn inside them.
#[test]
fn no_data_pixel_lies_outside_the_axes() {
    let d = tempfile::tempdir().unwrap();
    let (x, y) = spiky();
    let wave: Vec<f64> = x.iter().map(|a| 1e4 * a.to_radians().sin()).collect();
    let few_x = [0.0, 180.0, 360.0, 720.0];
    let few_y = [0.0, 3e4, -1e4, 2e4];
    let ax = Axes {
        title: "Clearance joint forces",
        x_label: "crank angle θ, °",
        y_label: "force, N",
    };
    let line = line_plot(
        &d.path().join("line"),
        &ax,
        &[
            Series {
                name: "contact",
                x: &x,
                y: &y,
                style: SeriesStyle::Line,
            },
            Series {
                name: "ideal",
                x: &x,
                y: &wave,
                style: SeriesStyle::Dashed,
            },
            Series {
                name: "marked",
                x: &few_x,
                y: &few_y,
                style: SeriesStyle::LinePoints,
            },
            Series {
                name: "points",
                x: &few_x,
                y: &few_y,
                style: SeriesStyle::Points,
            },
        ],
    )
    .unwrap();
    // Work–precision: errors over 16 decades, costs over 6, zigzags.
    let cost: Vec<f64> = (0..12).map(|k| 10f64.powf(2.0 + 0.5 * k as f64)).collect();
    let err: Vec<f64> = (0..12)
        .map(|k| 10f64.powf(-(k as f64) * 1.4 + if k % 2 == 0 { 0.8 } else { 0.0 }))
        .collect();
    let err2: Vec<f64> = err.iter().map(|e| e * 3.0).collect();
    let wp = loglog_plot(
        &d.path().join("wp"),
        &Axes {
            title: "Work–precision",
            x_label: "RHS evaluations",
            y_label: "error",
        },
        &[
            Series {
                name: "dop853",
                x: &cost,
                y: &err,
                style: SeriesStyle::LinePoints,
            },
            Series {
                name: "bdf",
                x: &cost,
                y: &err2,
                style: SeriesStyle::DashedPoints,
            },
        ],
    )
    .unwrap();
    // Stiffness: |λ| jumping between 5 and 1e3 with single-sample spikes to 5e4.
    let rho: Vec<f64> = y
        .iter()
        .map(|v| if *v > 0.0 { 5e4 * v / 3e4 + 5.0 } else { 1e3 })
        .collect();
    let h: Vec<f64> = rho.iter().map(|r| 2.785 / r).collect();
    let s1 = [Series {
        name: "|λ|max",
        x: &x,
        y: &rho,
        style: SeriesStyle::Line,
    }];
    let s2 = [
        Series {
            name: "limit",
            x: &x,
            y: &h,
            style: SeriesStyle::Line,
        },
        Series {
            name: "force",
            x: &x,
            y: &y,
            style: SeriesStyle::Dashed,
        },
    ];
    let panels = panels_plot(
        &d.path().join("panels"),
        "Stiffness",
        &[
            Panel {
                axes: Axes {
                    title: "spectral radius",
                    x_label: "crank angle, °",
                    y_label: "|λ|, 1/s",
                },
                series: &s1,
                log_y: true,
            },
            Panel {
                axes: Axes {
                    title: "RK4 limit",
                    x_label: "crank angle, °",
                    y_label: "h, s",
                },
                series: &s2[..1],
                log_y: true,
            },
            Panel {
                axes: Axes {
                    title: "force",
                    x_label: "crank angle, °",
                    y_label: "N",
                },
                series: &s2[1..],
                log_y: false,
            },
        ],
    )
    .unwrap();
    // A dry orbit: through the clearance circle to 2.3 c with sharp turns, and a section.
    let (ex, ey): (Vec<f64>, Vec<f64>) = (0..2001)
        .map(|k| {
            let a = k as f64 * 0.05;
            let r = if k % 50 < 2 {
                2.3
            } else {
                0.6 + 0.4 * (3.0 * a).sin()
            };
            (r * a.cos(), r * a.sin())
        })
        .unzip();
    let orbit = orbits_plot(
        &d.path().join("orbit"),
        "Journal centre orbit",
        &[
            Series {
                name: "orbit",
                x: &ex,
                y: &ey,
                style: SeriesStyle::Line,
            },
            Series {
                name: "section",
                x: &ex[..40],
                y: &ey[..40],
                style: SeriesStyle::Points,
            },
        ],
    )
    .unwrap();
    for (name, w) in [
        ("line", &line),
        ("wp", &wp),
        ("panels", &panels),
        ("orbit", &orbit),
    ] {
        // LASH_FIGURE_SHOTS=DIR keeps the PNGs to look at.
        if let Some(dir) = std::env::var_os("LASH_FIGURE_SHOTS") {
            std::fs::copy(&w.png, Path::new(&dir).join(format!("{name}.png"))).unwrap();
        }
        let (data, n, first) = strays(w);
        assert_eq!(
            n, 0,
            "{name}: {n} data pixels outside the axes, e.g. {first:?}"
        );
        assert!(
            data > 1000,
            "{name}: only {data} data pixels inside the axes"
        );
    }
    assert_eq!(panels.layout.plots.len(), 3);
}

/// Tick labels, measured with the figures' font, never overlap, never repeat, number at
/// least two, and on a log axis every decade in range is labelled whenever the decades'
/// labels fit (and at least one label falls in each partial decade at the ends, when
/// 1-2-5 labels fit): the "5e-16e-17e-18e-19e-11e0" and its unlabelled decade.
#[test]
fn tick_labels_fit_and_decades_are_labelled() {
    ensure_font().unwrap();
    let mut buf = vec![0u8; 3 * 64 * 64];
    let area = BitMapBackend::with_buffer(&mut buf, (64, 64)).into_drawing_area();
    let measure = measurer(&area, 15);
    let check = |t: &[f64],
                 pos: &dyn Fn(f64) -> f64,
                 label: &dyn Fn(f64) -> String,
                 h: bool,
                 what: &str| {
        assert!(t.len() >= 2, "{what}: {t:?}");
        let labels: Vec<String> = t.iter().map(|&v| label(v)).collect();
        for w in labels.windows(2) {
            assert_ne!(w[0], w[1], "{what}: {labels:?}");
        }
        for (i, pair) in t.windows(2).enumerate() {
            let (a, b) = (measure(&labels[i]), measure(&labels[i + 1]));
            let room = (pos(pair[1]) - pos(pair[0])).abs();
            let need = if h {
                0.5 * f64::from(a.0 + b.0)
            } else {
                0.5 * f64::from(a.1 + b.1)
            };
            assert!(
                room > need,
                "{what}: {labels:?} overlap at {i} ({room} px for {need})"
            );
        }
    };
    for &(lo, hi) in &[
        (0.0, 360.0),
        (-3.86, 3.86),
        (-1500.0, 31500.0),
        (1e-9, 3e-9),
        (120_000.0, 125_000.0),
        (0.3650, 0.3651),
        (-2.7e-17, 4.1e-17),
        (0.0, 1e9),
    ] {
        for len in [120.0, 400.0, 760.0] {
            for h in [true, false] {
                let (t, _, step) = linear_ticks(lo, hi, len, h, &measure);
                let pos = |v: f64| (v - lo) / (hi - lo) * len;
                check(
                    &t,
                    &pos,
                    &|v| tick_at(v, step),
                    h,
                    &format!("[{lo}, {hi}] {len} px"),
                );
                assert!(t.iter().all(|v| *v >= lo && *v <= hi));
            }
        }
    }
    for &(lo, hi, len, h) in &[
        (3e-3, 2.4e-2, 680.0, true),
        (1e-17, 2.0, 520.0, false),
        (1e-17, 2.0, 680.0, true),
        (50.0, 4e8, 680.0, true),
        (0.3, 1.2, 680.0, true),
        (1.1, 1.3, 680.0, true),
        (1.1, 1.3, 300.0, false),
        (1e-300, 1e300, 680.0, true),
        (2e-6, 5e-4, 300.0, false),
    ] {
        let (t, _, step) = log_ticks(lo, hi, len, h, &measure);
        let pos = |v: f64| (v.log10() - lo.log10()) / (hi.log10() - lo.log10()) * len;
        let what = format!("log [{lo:e}, {hi:e}] {len} px");
        check(&t, &pos, &|v| log_label(v, step), h, &what);
        let decades: Vec<f64> = (lo.log10().ceil() as i32..=hi.log10().floor() as i32)
            .map(|k| format!("1e{k}").parse().unwrap())
            .collect();
        // Whether the decades' labels alone fit: a decade's length against the widest
        // (x) or tallest (y) of their labels and the gap.
        let per_decade = len / (hi.log10() - lo.log10());
        let need = decades
            .iter()
            .map(|&d| {
                let m = measure(&tick_log(d));
                if h {
                    f64::from(m.0) + LABEL_GAP
                } else {
                    f64::from(m.1) + 0.5 * LABEL_GAP
                }
            })
            .fold(0.0, f64::max);
        let every = decades.iter().all(|d| t.contains(d));
        assert_eq!(every, per_decade >= need, "{what}: {t:?}");
    }
    // The work-precision axis: 3e-3 … 2.4e-2 s labels its left decade too.
    let (t, _, _) = log_ticks(3e-3, 2.4e-2, 680.0, true, &measure);
    assert!(t.iter().any(|v| *v < 1e-2), "{t:?}");
}

#[test]
fn ranges() {
    assert_eq!(padded(0.0, 10.0), (-0.5, 10.5));
    assert_eq!(padded(2.0, 2.0), (1.9, 2.1));
    assert_eq!(padded(0.0, 0.0), (-1.0, 1.0));
    let (a, b) = padded_log(1e-8, 1e-4);
    assert!((a.log10() + 8.2).abs() < 1e-12 && (b.log10() + 3.8).abs() < 1e-12);
    // Equal aspect: data units per pixel equal in x and y.
    let (rx, ry) = equal_aspect(1.2, 600, 400);
    assert!((2.0 * rx / 600.0 - 2.0 * ry / 400.0).abs() < 1e-15 && ry == 1.2);
    let (rx, ry) = equal_aspect(1.2, 300, 500);
    assert!((2.0 * rx / 300.0 - 2.0 * ry / 500.0).abs() < 1e-15 && rx == 1.2);
    assert_eq!(tick_at(0.5, 0.5), "0.5");
    assert_eq!(tick_at(-2.2e-16, 0.5), "0");
    assert_eq!(tick_at(1e-6, 1e-6), "1e-6");
    assert_eq!(tick_at(1.2e-6, 2e-7), "1.2e-6");
    assert_eq!(tick_at(-120.0, 20.0), "-120");
    assert_eq!(tick_at(0.0002, 0.0001), "2e-4");
    assert_eq!(tick_at(0.002, 0.001), "0.002");
    // Ticks one step apart never print alike.
    assert_eq!(tick_at(120000.0, 5000.0), "1.20e5");
    assert_eq!(tick_at(125000.0, 5000.0), "1.25e5");
    assert_eq!(tick_log(1e-4), "1e-4");
    assert_eq!(tick_log(1000.0), "1e3");
    assert_eq!(tick_log(3e-4), "3e-4");
}
