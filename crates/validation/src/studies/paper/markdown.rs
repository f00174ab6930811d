//! report.md of `lash study paper`: settings, verdicts, metrics per case, each claim with its
//! quoted source and numbers, the convergence check and the timings.
//!
//! ```text
//! # title · settings · verdict summary · metrics tables · claims · docs/model.md checks ·
//! convergence (study and loose settings against the reference) · solver work and timing ·
//! figures
//! ```
//!
//! Source: docs/outputs.md ("`lash study paper`": a metrics table per case, each claim:
//! statement, quoted source sentence, numbers, HOLDS / DOES NOT HOLD).

use std::fmt::Write as _;

use crate::report::metrics::Metrics;
use crate::run::press::Kind;
use crate::studies::paper::claims::{self, Claim, Origin};
use crate::studies::paper::plan::Setting;
use crate::studies::paper::result::{CaseResult, StudyResult};
use crate::studies::paper::stats::{CaseStats, Ensemble};

/// Text for a table cell: `|` escaped.
pub(crate) fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// A statistic of one realisation.
type Stat = fn(&CaseStats) -> Option<f64>;

/// A number with four significant digits, plain or scientific.
pub(crate) fn sig(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-2..1e5).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.digits$}")
    } else {
        // 4 significant digits, trailing zeros of the mantissa dropped: 1e-10, 1.25e-4.
        let t = format!("{v:.3e}");
        match t.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => t,
        }
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(|| "—".into(), sig)
}

fn mean_range(e: &Ensemble, f: impl Fn(&CaseStats) -> Option<f64>) -> String {
    let v: Vec<f64> = e.members.iter().filter_map(&f).collect();
    if v.is_empty() {
        return "—".into();
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    if v.len() == 1 {
        return sig(mean);
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if lo == hi {
        sig(mean)
    } else {
        format!("{} [{} – {}]", sig(mean), sig(lo), sig(hi))
    }
}

fn mean_of(e: &Ensemble, f: impl Fn(&CaseStats) -> Option<f64>) -> Option<f64> {
    let v: Vec<f64> = e.members.iter().filter_map(&f).collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// (mean₁ − mean₂) / sqrt(s₁²/n₁ + s₂²/n₂); None without two realisations on each side or
/// with no spread at all.
fn z_score(a: &Ensemble, b: &Ensemble, f: &dyn Fn(&CaseStats) -> Option<f64>) -> Option<f64> {
    let moments = |e: &Ensemble| {
        let v: Vec<f64> = e.members.iter().filter_map(f).collect();
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
        (v.len(), m, var)
    };
    let (na, ma, va) = moments(a);
    let (nb, mb, vb) = moments(b);
    if na < 2 || nb < 2 {
        return None;
    }
    let se = (va / na as f64 + vb / nb as f64).sqrt();
    if se > 0.0 {
        Some((ma - mb) / se)
    } else if ma == mb {
        Some(0.0)
    } else {
        None
    }
}

fn kind(c: &CaseResult) -> &'static str {
    match c.kind {
        Kind::Dry => "dry",
        Kind::Lubricated => "lubricated",
        Kind::Ideal => "ideal",
    }
}

fn metrics_table(out: &mut String, r: &StudyResult) {
    let _ = writeln!(
        out,
        "| case | slider_acc_max | slider_acc_min | slider_acc_rms_dev_ideal | eps_max | \
         contact_onsets | contact_force_max | penetration_max | film_force_max | \
         film_thickness_min | slider_x_end | constraint_violation_max |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for c in &r.cases {
        let m: &Metrics = &c.study.members[0].metrics;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.name,
            opt(m.slider_acc_max),
            opt(m.slider_acc_min),
            opt(m.slider_acc_rms_dev_ideal),
            opt(m.eps_max),
            m.contact_onsets
                .map_or_else(|| "—".into(), |n| n.to_string()),
            opt(m.contact_force_max),
            opt(m.penetration_max),
            opt(m.film_force_max),
            opt(m.film_thickness_min),
            opt(m.slider_x_end),
            sig(m.constraint_violation_max),
        );
    }
}

fn ensemble_table(out: &mut String, r: &StudyResult) {
    let _ = writeln!(
        out,
        "| case | slider_acc_rms_dev_ideal | slider_acc_max | slider_acc_min | eps_max | \
         contact_onsets | penetration_max | contact_force_max | acc_spread |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|");
    for c in &r.cases {
        let e = &c.study;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.name,
            mean_range(e, |s| s.metrics.slider_acc_rms_dev_ideal),
            mean_range(e, |s| s.metrics.slider_acc_max),
            mean_range(e, |s| s.metrics.slider_acc_min),
            mean_range(e, |s| s.metrics.eps_max),
            mean_range(e, |s| s.metrics.contact_onsets.map(|n| n as f64)),
            mean_range(e, |s| s.metrics.penetration_max),
            mean_range(e, |s| s.metrics.contact_force_max),
            sig(e.acc_spread),
        );
    }
}

fn deviations_table(out: &mut String, r: &StudyResult) {
    let _ = writeln!(
        out,
        "| case | x_dev_max, m | x_dev_bdc, m | v_dev_max, m/s | a_dev_max, m/s² | \
         a_dev_dead_centres, m/s² | a_ideal_peak, m/s² | x_dev_rel | v_dev_rel | a_dev_rel | \
         fluctuation_sectors | contact_fraction | orbit_closure |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for c in &r.cases {
        let e = &c.study;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.name,
            mean_range(e, |s| Some(s.dev.x_dev_max)),
            mean_range(e, |s| Some(s.dev.x_dev_bdc)),
            mean_range(e, |s| Some(s.dev.v_dev_max)),
            mean_range(e, |s| Some(s.dev.a_dev_max)),
            mean_range(e, |s| Some(s.dev.a_dev_dead_centres)),
            sig(e.members[0].dev.a_ideal_peak),
            mean_range(e, |s| Some(s.dev.x_dev_rel)),
            mean_range(e, |s| Some(s.dev.v_dev_rel)),
            mean_range(e, |s| Some(s.dev.a_dev_rel)),
            mean_range(e, |s| Some(s.dev.fluctuation_sectors as f64)),
            mean_range(e, |s| s.dev.contact_fraction),
            mean_range(e, |s| s.dev.orbit_closure),
        );
    }
}

fn claim_section(out: &mut String, c: &Claim, others: &[(f64, &Claim)]) {
    let _ = writeln!(
        out,
        "### {} — {} ({})\n",
        c.id,
        c.verdict.as_str(),
        c.figure
    );
    let _ = writeln!(out, "**Claim.** {}\n", c.statement);
    let src = if c.origin == Origin::Paper {
        "Paper, §4"
    } else {
        "docs/model.md"
    };
    let _ = writeln!(out, "**Source ({src}).** \"{}\"\n", c.source);
    let _ = writeln!(out, "**Criterion.** {}\n", c.criterion);
    if !c.note.is_empty() {
        let _ = writeln!(out, "**Note.** {}\n", c.note);
    }
    let _ = writeln!(
        out,
        "| number | value (mean) | min over realisations | max over realisations |"
    );
    let _ = writeln!(out, "|---|---|---|---|");
    for n in &c.numbers {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} |",
            n.label,
            sig(n.value),
            opt(n.min),
            opt(n.max)
        );
    }
    let _ = write!(
        out,
        "\n**Verdict: {}** on the ensemble means; the criterion holds in {} of {} realisations",
        c.verdict.as_str(),
        c.realisations_holding,
        c.realisations
    );
    for (rtol, o) in others {
        let _ = write!(
            out,
            "; at rtol {}: {} ({} of {})",
            sig(*rtol),
            o.verdict.as_str(),
            o.realisations_holding,
            o.realisations
        );
    }
    out.push_str(".\n\n");
}

/// z of the dry cases between settings `a` and `b`; returns the largest |z|.
fn z_table(out: &mut String, r: &StudyResult, a: Setting, b: Setting) -> f64 {
    let _ = writeln!(
        out,
        "| case | z slider_acc_rms_dev_ideal | z slider_acc_max | z slider_acc_min | z eps_max | \
         z contact_force_max | z contact_onsets |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|");
    let mut z_max: f64 = 0.0;
    for c in r.cases.iter().filter(|c| c.kind == Kind::Dry) {
        let stats: [Stat; 6] = [
            |s| s.metrics.slider_acc_rms_dev_ideal,
            |s| s.metrics.slider_acc_max,
            |s| s.metrics.slider_acc_min,
            |s| s.metrics.eps_max,
            |s| s.metrics.contact_force_max,
            |s| s.metrics.contact_onsets.map(|n| n as f64),
        ];
        let zs: Vec<String> = stats
            .iter()
            .map(|f| match z_score(c.ensemble(a), c.ensemble(b), f) {
                Some(z) => {
                    z_max = z_max.max(z.abs());
                    format!("{z:.2}")
                }
                None => "—".into(),
            })
            .collect();
        let _ = writeln!(out, "| {} | {} |", c.name, zs.join(" | "));
    }
    let _ = writeln!(out, "\nLargest |z|: {z_max:.2}.\n");
    z_max
}

/// The largest relative change of the lubricated cases' statistics between `a` and `b`.
fn lubricated_change(r: &StudyResult, a: Setting, b: Setting) -> (f64, String) {
    let mut worst: (f64, String) = (0.0, "—".into());
    for c in r.cases.iter().filter(|c| c.kind == Kind::Lubricated) {
        let stats: [(&str, Stat); 6] = [
            ("slider_acc_max", |s| s.metrics.slider_acc_max),
            ("slider_acc_min", |s| s.metrics.slider_acc_min),
            ("slider_acc_rms_dev_ideal", |s| {
                s.metrics.slider_acc_rms_dev_ideal
            }),
            ("eps_max", |s| s.metrics.eps_max),
            ("film_force_max", |s| s.metrics.film_force_max),
            ("a_dev_max", |s| Some(s.dev.a_dev_max)),
        ];
        for (name, f) in stats {
            if let (Some(x), Some(y)) = (mean_of(c.ensemble(a), f), mean_of(c.ensemble(b), f)) {
                let d = if y != 0.0 {
                    (x - y).abs() / y.abs()
                } else {
                    0.0
                };
                if d > worst.0 {
                    worst = (d, format!("{} {name}", c.name));
                }
            }
        }
    }
    worst
}

fn changed_verdicts(a: &[Claim], b: &[Claim]) -> String {
    let changed: Vec<&str> = a
        .iter()
        .zip(b)
        .filter(|(x, y)| x.verdict != y.verdict)
        .map(|(x, _)| x.id.as_str())
        .collect();
    if changed.is_empty() {
        "identical for every claim".into()
    } else {
        format!("different for {}", changed.join(", "))
    }
}

fn convergence(out: &mut String, r: &StudyResult) {
    let p = &r.plan;
    let (s, f, l) = (p.settings.rtol, p.reference.rtol, p.loose.rtol);
    let _ = writeln!(
        out,
        "Every realisation was also run at rtol {} (atol {}, the reference) and at rtol {} \
         (atol {}, loose). Values are ensemble means [min – max over the realisations]. \
         `Δ pointwise` is max |ẍ(rtol {}) − ẍ(rtol {})| of the paper's realisation over the \
         last revolution: large for the chaotic dry cases (docs/model.md §9), so those are \
         compared through statistics only.\n",
        sig(f),
        sig(p.reference.atol),
        sig(l),
        sig(p.loose.atol),
        sig(s),
        sig(f)
    );
    let _ = writeln!(
        out,
        "| case | RMS dev, rtol {0} | RMS dev, rtol {1} | RMS dev, rtol {2} | eps_max, rtol {0} | \
         eps_max, rtol {1} | eps_max, rtol {2} | contact_onsets, rtol {0} | contact_onsets, \
         rtol {1} | Δ pointwise, m/s² |",
        sig(s),
        sig(f),
        sig(l)
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|");
    for c in &r.cases {
        let (a, b, lo) = (&c.study, &c.reference, &c.loose);
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.name,
            mean_range(a, |s| s.metrics.slider_acc_rms_dev_ideal),
            mean_range(b, |s| s.metrics.slider_acc_rms_dev_ideal),
            mean_range(lo, |s| s.metrics.slider_acc_rms_dev_ideal),
            mean_range(a, |s| s.metrics.eps_max),
            mean_range(b, |s| s.metrics.eps_max),
            mean_range(lo, |s| s.metrics.eps_max),
            mean_range(a, |s| s.metrics.contact_onsets.map(|n| n as f64)),
            mean_range(b, |s| s.metrics.contact_onsets.map(|n| n as f64)),
            sig(c.acc_tolerance_diff),
        );
    }
    let _ = writeln!(
        out,
        "\nDry cases (chaotic): the ensembles at two settings are samples of one distribution \
         when the settings are converged. z = (mean₁ − mean₂) / sqrt(s₁²/n₁ + s₂²/n₂), s the \
         realisations' standard deviation; |z| up to about 3 is what two samples of one \
         distribution give, larger |z| is a systematic difference.\n"
    );
    let _ = writeln!(
        out,
        "rtol {} against rtol {} (the study's setting):\n",
        sig(s),
        sig(f)
    );
    let z_study = z_table(out, r, Setting::Study, Setting::Reference);
    let _ = writeln!(
        out,
        "rtol {} against rtol {} (the loose setting):\n",
        sig(l),
        sig(f)
    );
    let z_loose = z_table(out, r, Setting::Loose, Setting::Reference);
    let (ws, wsn) = lubricated_change(r, Setting::Study, Setting::Reference);
    let (wl, wln) = lubricated_change(r, Setting::Loose, Setting::Reference);
    let _ = writeln!(
        out,
        "Lubricated cases (not chaotic): the largest relative change of slider_acc_max, \
         slider_acc_min, slider_acc_rms_dev_ideal, eps_max, film_force_max or a_dev_max \
         (ensemble means) against rtol {}: {} at rtol {} ({wsn}), {} at rtol {} ({wln}).\n",
        sig(f),
        sig(ws),
        sig(s),
        sig(wl),
        sig(l)
    );
    let _ = writeln!(
        out,
        "**Summary.** Against rtol {}: rtol {} has largest |z| {:.2} on the dry statistics and \
         verdicts {}; rtol {} has largest |z| {:.2} and verdicts {}.\n",
        sig(f),
        sig(s),
        z_study,
        changed_verdicts(&r.claims, &r.reference_claims),
        sig(l),
        z_loose,
        changed_verdicts(&r.loose_claims, &r.reference_claims),
    );
}

/// The whole report.
pub(crate) fn report(r: &StudyResult) -> String {
    let mut out = String::new();
    let p = &r.plan;
    let _ = writeln!(out, "# The paper's case study (§4) with lash\n");
    let _ = writeln!(
        out,
        "Peng et al. 2025 (Lubricants 13(3) 124), §4: the slider-crank press at 120, 150, 180 \
         and 200 rpm with a 0.1 mm clearance, and at 150 rpm with 0.1, 0.2, 0.3 and 0.5 mm; dry \
         and lubricated rod–slider joint; the ideal mechanism beside. Parameters: docs/model.md §6 \
         (the scenes of `cases/press/`, as generated by `lash_model::cases::press_catalogue`). \
         Nothing was tuned. lash {}.\n",
        r.version
    );
    let _ = writeln!(
        out,
        "- Solver: {} at rtol {}, atol {}, {} event samples per step (an adaptive step can \
         otherwise hold a whole contact and skip it); every run repeated at rtol {} (reference) \
         and rtol {} (loose) for the convergence section.",
        p.settings.method.name(),
        sig(p.settings.rtol),
        sig(p.settings.atol),
        p.settings.event_samples,
        sig(p.reference.rtol),
        sig(p.loose.rtol)
    );
    let _ = writeln!(
        out,
        "- Two crank revolutions; everything is measured over the second (the 2001-point grid \
         of docs/outputs.md, `metrics`), x axes of the figures are the crank angle of that \
         revolution."
    );
    let _ = writeln!(
        out,
        "- Realisations: the dry cases are chaotic (docs/model.md §9), so every clearance case \
         runs {} times with the crank's initial angle moved by k·{} rad (k = 0..{}; k = 0 is the \
         paper's case and the one plotted and listed in the first table). The shift is physically \
         nothing (r·Δθ = {} m) but larger than the integration error, so the realisations are \
         distinct trajectories. Claims are judged on the ensemble means; each also says on how \
         many single realisations it holds. The ideal mechanism is deterministic and runs once.",
        p.realisations,
        sig(p.phase_step_rad),
        p.realisations - 1,
        sig(0.5 * r.cases[0].study.members[0].dev.stroke * p.phase_step_rad)
    );
    let _ = writeln!(
        out,
        "- The lubricated cases start with the journal centred (docs/model.md §6) and the film \
         lets it sink only slowly: `orbit_closure` (how far the last revolution's orbit is from \
         the previous one) says how settled each orbit is within the two revolutions."
    );
    let _ = writeln!(
        out,
        "- Thresholds used by the criteria: \"little effect\" on x: < {} % of the stroke 2r; \
         \"scarcely different\": max |ẍ − ẍ_ideal| < {} % of the ideal peak; \"obvious\": ≥ {} %; \
         a 45° sector \"fluctuates\" when max |ẍ − ẍ_ideal| > {} % of the ideal peak; \"near the \
         boundary\": ε ≥ {}; \"not chaotic\": realisation spread of ẍ < {} % of the ideal peak; \
         \"periodic\": max |e(t) − e(t − T)|/c < {}. Dead-centre windows: ±{}° of crank angle; \
         the bottom dead centre is θ ≡ 0 (slider farthest from the crank, x = r + l).\n",
        100.0 * claims::LITTLE,
        100.0 * claims::SCARCELY,
        100.0 * claims::OBVIOUS,
        100.0 * crate::studies::paper::stats::SECTOR_FLUCTUATION,
        claims::NEAR_BOUNDARY,
        100.0 * claims::NOT_CHAOTIC,
        claims::PERIODIC,
        crate::studies::paper::plan::DEAD_CENTRE_WINDOW_DEG
    );

    let _ = writeln!(out, "## Verdicts\n");
    let _ = writeln!(
        out,
        "| claim | figure | statement | verdict | realisations holding | verdict at rtol {} | \
         verdict at rtol {} |",
        sig(p.reference.rtol),
        sig(p.loose.rtol)
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|");
    for ((c, rc), lc) in r
        .claims
        .iter()
        .zip(&r.reference_claims)
        .zip(&r.loose_claims)
    {
        let _ = writeln!(
            out,
            "| {} | {} | {} | **{}** | {} / {} | {} | {} |",
            c.id,
            cell(&c.figure),
            cell(&c.statement),
            c.verdict.as_str(),
            c.realisations_holding,
            c.realisations,
            rc.verdict.as_str(),
            lc.verdict.as_str()
        );
    }
    let paper: Vec<&Claim> = r
        .claims
        .iter()
        .filter(|c| c.origin == Origin::Paper)
        .collect();
    let _ = writeln!(
        out,
        "\n{} of {} claims of the paper hold with the parameters of docs/model.md §6.\n",
        paper
            .iter()
            .filter(|c| c.verdict == claims::Verdict::Holds)
            .count(),
        paper.len()
    );

    let _ = writeln!(out, "## Metrics per case\n");
    let _ = writeln!(
        out,
        "Metrics (docs/outputs.md, `metrics`) of the paper's realisation (k = 0) at rtol {}, \
         last revolution (SI units; energy is not accounted by the study).\n",
        sig(p.settings.rtol)
    );
    metrics_table(&mut out, r);
    let _ = writeln!(
        out,
        "\nOver the {} realisations: mean [min – max]. `acc_spread` is the realisations' \
         pointwise spread max_i (max_k ẍ_k − min_k ẍ_k), m/s².\n",
        p.realisations
    );
    ensemble_table(&mut out, r);
    let _ = writeln!(
        out,
        "\nDeviations from the ideal mechanism at the same crank angle (mean [min – max] over \
         the realisations): `x_dev_bdc` within ±{0}° of the bottom dead centre, \
         `a_dev_dead_centres` within ±{0}° of either dead centre, `*_rel` = RMS(q − q_ideal) / \
         RMS(q_ideal − mean), `fluctuation_sectors` = 45° sectors with max |ẍ − ẍ_ideal| > {1} % \
         of the ideal peak, `contact_fraction` = share of the revolution with δ > 0, \
         `orbit_closure` = max |e(t) − e(t − T)|/c.\n",
        crate::studies::paper::plan::DEAD_CENTRE_WINDOW_DEG,
        100.0 * crate::studies::paper::stats::SECTOR_FLUCTUATION
    );
    deviations_table(&mut out, r);

    for (origin, title) in [
        (Origin::Paper, "\n## Claims of the paper\n"),
        (Origin::Model, "## Cross-checks of docs/model.md\n"),
    ] {
        let _ = writeln!(out, "{title}");
        for ((c, rc), lc) in r
            .claims
            .iter()
            .zip(&r.reference_claims)
            .zip(&r.loose_claims)
        {
            if c.origin == origin {
                claim_section(&mut out, c, &[(p.reference.rtol, rc), (p.loose.rtol, lc)]);
            }
        }
    }
    let _ = writeln!(out, "## Convergence\n");
    convergence(&mut out, r);

    let _ = writeln!(out, "## Solver work and timing\n");
    let _ = writeln!(
        out,
        "Paper's realisation at rtol {}: counters of `lash_solver::Stats`; `all runs` is the \
         wall time of every realisation at the three settings.\n",
        sig(p.settings.rtol)
    );
    let _ = writeln!(
        out,
        "| case | kind | rpm | c, mm | accepted steps | rejected | rhs evals | events | wall, s | all runs, s |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|");
    for c in &r.cases {
        let s = &c.solver.stats;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {:.3} | {:.3} |",
            c.name,
            kind(c),
            sig(c.rpm),
            opt(c.clearance_m.map(|m| m * 1e3)),
            s.accepted,
            s.rejected_error + s.rejected_newton,
            s.rhs_evals,
            c.solver.events,
            c.solver.wall_time_s,
            c.solver.total_wall_time_s
        );
    }
    let runs: usize = r
        .cases
        .iter()
        .map(|c| c.study.members.len() + c.reference.members.len() + c.loose.members.len())
        .sum();
    let _ = writeln!(
        out,
        "\n{runs} runs in {:.2} s, {} figures in {:.2} s, {:.2} s in all ({} threads).\n",
        r.timing.runs_s,
        r.figures.len(),
        r.timing.figures_s,
        r.timing.total_s,
        r.timing.threads
    );

    let _ = writeln!(out, "## Figures\n");
    let _ = writeln!(
        out,
        "One file per panel, as SVG and PNG in `figures/`: panels (a), (b) of Figures 5, 8, 11 \
         and 14 are the paper's displacement and velocity; panel (c) is added (x − x_ideal, \
         which the coinciding curves of (a) hide). Acceleration figures draw the ideal \
         mechanism dashed; orbit figures draw e/c inside the unit clearance circle.\n"
    );
    for f in &r.figures {
        let _ = writeln!(
            out,
            "- [{}](figures/{}.png) ([svg](figures/{}.svg)): {}",
            f.id, f.id, f.id, f.title
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_four_significant_digits() {
        assert_eq!(sig(0.0), "0");
        assert_eq!(sig(2.0843), "2.084");
        assert_eq!(sig(-12.2776), "-12.28");
        assert_eq!(sig(33306.96), "33307");
        assert_eq!(sig(0.07230111), "0.07230");
        assert_eq!(sig(1e-10), "1e-10");
        assert_eq!(sig(1.25e-4), "1.25e-4");
        assert_eq!(sig(-9.39303e-5), "-9.393e-5");
        assert_eq!(sig(123456.0), "1.235e5");
        assert_eq!(cell("|e|/c"), "\\|e\\|/c");
    }
}
