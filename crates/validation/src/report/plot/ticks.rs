//! Tick positions and labels: 1-2-5 steps on linear axes, every decade labelled on log
//! axes, labels that fit without overlapping.

/// Tick label on a log axis: `1e-4` for powers of ten, else one significant digit (`3e-4`).
pub(super) fn tick_log(v: f64) -> String {
    let e = v.log10().round();
    if (v / 10f64.powf(e) - 1.0).abs() < 1e-9 {
        format!("1e{e}")
    } else {
        format!("{v:.0e}")
    }
}

/// Gap between two tick labels along an axis, px.
pub(super) const LABEL_GAP: f64 = 10.0;

/// Whether labels at `ticks` (positions along the axis in px from `pos`) fit without
/// overlapping: neighbours apart by at least half their widths (x axis) or their height
/// (y axis) plus a gap.
pub(super) fn labels_fit(
    ticks: &[f64],
    pos: &dyn Fn(f64) -> f64,
    label: &dyn Fn(f64) -> String,
    horizontal: bool,
    measure: &dyn Fn(&str) -> (u32, u32),
) -> bool {
    let sizes: Vec<(f64, f64)> = ticks
        .iter()
        .map(|&v| {
            let (w, h) = measure(&label(v));
            (f64::from(w), f64::from(h))
        })
        .collect();
    ticks.windows(2).zip(sizes.windows(2)).all(|(t, s)| {
        let room = (pos(t[1]) - pos(t[0])).abs();
        let need = if horizontal {
            0.5 * (s[0].0 + s[1].0) + LABEL_GAP
        } else {
            0.5 * (s[0].1 + s[1].1) + 0.5 * LABEL_GAP
        };
        room >= need
    })
}

/// The multiples k·step in [lo, hi] (values within 1e-9 step of 0 as 0, of an end as it).
pub(super) fn multiples(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let (a, b) = (
        (lo / step - 1e-9).ceil() as i64,
        (hi / step + 1e-9).floor() as i64,
    );
    (a..=b)
        .map(|k| {
            let v = k as f64 * step;
            if v.abs() < 1e-9 * step {
                0.0
            } else {
                // k·step may round a few ulps past an end it belongs to.
                v.clamp(lo, hi)
            }
        })
        .collect()
}

/// Label of a linear tick on an axis of tick spacing `step`: as many decimals as the step
/// needs (1-2-5 steps have one significant digit), scientific when tiny or huge.
pub(super) fn tick_at(v: f64, step: f64) -> String {
    if v == 0.0 || v.abs() < 1e-9 * step {
        return "0".into();
    }
    let a = v.abs();
    let e_step = step.log10().floor();
    if (1e-3..1e5).contains(&a) {
        let d = (-e_step).max(0.0) as usize;
        format!("{v:.d$}")
    } else {
        let d = (a.log10().floor() - e_step).max(0.0) as usize;
        format!("{v:.d$e}")
    }
}

/// Ticks of a linear axis [lo, hi] of `len` px: the finest 1-2-5 step (at most 12 ticks)
/// whose labels fit ([`labels_fit`]); light lines at a fifth (a quarter for a step of 2) of
/// it. Returns (ticks, light lines, step).
pub(super) fn linear_ticks(
    lo: f64,
    hi: f64,
    len: f64,
    horizontal: bool,
    measure: &dyn Fn(&str) -> (u32, u32),
) -> (Vec<f64>, Vec<f64>, f64) {
    let span = hi - lo;
    let pos = |v: f64| (v - lo) / span * len;
    let mut p = 10f64.powf((span / 12.0).log10().floor());
    for _ in 0..40 {
        for m in [1.0, 2.0, 5.0] {
            let step = m * p;
            let t = multiples(lo, hi, step);
            if t.len() > 12 || t.len() < 2 {
                continue;
            }
            if labels_fit(&t, &pos, &|v| tick_at(v, step), horizontal, measure) {
                let sub = if m == 2.0 { step / 4.0 } else { step / 5.0 };
                return (t, multiples(lo, hi, sub), step);
            }
        }
        p *= 10.0;
    }
    // Nothing fits (an axis a few pixels long): its two ends.
    (vec![lo, hi], Vec::new(), span)
}

/// Label of a log-axis tick: `1e-4`, `2e-4` for m·10^k, else as on a linear axis of
/// spacing `step`.
pub(super) fn log_label(v: f64, step: Option<f64>) -> String {
    match step {
        None => tick_log(v),
        Some(s) => tick_at(v, s),
    }
}

/// Ticks of a log axis [lo, hi] (lo > 0) of `len` px, the first that fits: 1, 2, 5 × 10^k;
/// the decades with 2 and 5 × 10^k only at the partial ends (so that no end of the axis goes
/// unlabelled); the decades alone; every second, third … decade (too many decades to label
/// each). An axis spanning too little for two such ticks gets 1 … 9 × 10^k, or linear ticks.
/// Light lines at 1 … 9 × 10^k. Returns (ticks, light lines, the linear step if linear).
#[allow(clippy::type_complexity)]
pub(super) fn log_ticks(
    lo: f64,
    hi: f64,
    len: f64,
    horizontal: bool,
    measure: &dyn Fn(&str) -> (u32, u32),
) -> (Vec<f64>, Vec<f64>, Option<f64>) {
    let (a, b) = (lo.log10(), hi.log10());
    let pos = |v: f64| (v.log10() - a) / (b - a) * len;
    let inside = |v: f64| v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12);
    let (k0, k1) = (a.floor() as i32, b.ceil() as i32);
    let of = |m: f64, k: i32| {
        // m · 10^k, exactly for the decades.
        let p = format!("1e{k}").parse::<f64>().unwrap_or(f64::NAN);
        m * p
    };
    let with = |mults: &[f64]| -> Vec<f64> {
        (k0..=k1)
            .flat_map(|k| mults.iter().map(move |&m| of(m, k)))
            .filter(|&v| inside(v))
            .collect()
    };
    let light = with(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    let decades = with(&[1.0]);
    let fits =
        |t: &[f64]| t.len() >= 2 && labels_fit(t, &pos, &|v| tick_log(v), horizontal, measure);
    let dense = with(&[1.0, 2.0, 5.0]);
    if fits(&dense) {
        return (dense, light, None);
    }
    if let (Some(&first), Some(&last)) = (decades.first(), decades.last()) {
        let ends: Vec<f64> = dense
            .iter()
            .copied()
            .filter(|&v| v < first || v > last || decades.contains(&v))
            .collect();
        if fits(&ends) {
            return (ends, light, None);
        }
        if fits(&decades) {
            return (decades, light, None);
        }
        for every in 2..=decades.len().max(2) {
            let some: Vec<f64> = decades.iter().copied().step_by(every).collect();
            if fits(&some) {
                return (some, light, None);
            }
        }
    }
    let all = light.clone();
    if fits(&all) {
        return (all, light, None);
    }
    // Less than a decade with too few round values: linear ticks on the log axis.
    let (t, _, step) = linear_ticks(lo, hi, len, horizontal, measure);
    let lin_pos = |v: f64| pos(v);
    if t.len() >= 2 && labels_fit(&t, &lin_pos, &|v| tick_at(v, step), horizontal, measure) {
        return (t, light, Some(step));
    }
    (vec![lo, hi], light, Some(hi - lo))
}

// ---------------------------------------------------------------------------------------------
// Axes
// ---------------------------------------------------------------------------------------------
