//! End-to-end: `lash study paper --out DIR` runs the paper's §4 and writes figures, report.md
//! and study.json whose verdicts follow from the numbers stored beside them.

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

use lash_validation::study::{
    CaseResult, CaseStats, Claim, Ensemble, Kind, Setting, StudyResult, Verdict,
};

/// The study's cases, in the order study.json lists them: the speed and clearance studies,
/// dry then lubricated, then the ideal mechanism (docs/model.md §6).
const CASES: [&str; 18] = [
    "dry_120rpm_c0.1",
    "dry_150rpm_c0.1",
    "dry_180rpm_c0.1",
    "dry_200rpm_c0.1",
    "dry_150rpm_c0.2",
    "dry_150rpm_c0.3",
    "dry_150rpm_c0.5",
    "lubricated_120rpm_c0.1",
    "lubricated_150rpm_c0.1",
    "lubricated_180rpm_c0.1",
    "lubricated_200rpm_c0.1",
    "lubricated_150rpm_c0.2",
    "lubricated_150rpm_c0.3",
    "lubricated_150rpm_c0.5",
    "ideal_120rpm",
    "ideal_150rpm",
    "ideal_180rpm",
    "ideal_200rpm",
];
/// The speed study (0.1 mm), dry and lubricated, in increasing speed.
const DRY_SPEEDS: [&str; 4] = [CASES[0], CASES[1], CASES[2], CASES[3]];
const LUB_SPEEDS: [&str; 4] = [CASES[7], CASES[8], CASES[9], CASES[10]];
/// The clearance study (150 rpm), dry and lubricated, in increasing clearance.
const DRY_CLEARANCES: [&str; 4] = [CASES[1], CASES[4], CASES[5], CASES[6]];
const LUB_CLEARANCES: [&str; 4] = [CASES[8], CASES[11], CASES[12], CASES[13]];
/// The study's three solver settings.
const SETTINGS: [Setting; 3] = [Setting::Study, Setting::Reference, Setting::Loose];

/// A case's realisations at one of the settings.
fn ensemble(c: &CaseResult, s: Setting) -> &Ensemble {
    match s {
        Setting::Study => &c.study,
        Setting::Reference => &c.reference,
        Setting::Loose => &c.loose,
    }
}

/// A verdict as study.json and the report spell it (HOLDS, DOES NOT HOLD).
fn spelled(v: Verdict) -> String {
    serde_json::to_value(v)
        .unwrap()
        .as_str()
        .unwrap()
        .to_string()
}
/// Claims: P1–P25 from the paper, M1–M4 from docs/model.md.
const CLAIMS: usize = 29;
/// Figures drawn after the paper's Figures 5–16, one file pair per panel (the engine's own
/// test pins the same count).
const FIGURES: usize = 44;

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.collect();
    v.iter().sum::<f64>() / v.len() as f64
}

fn ensemble_mean(r: &StudyResult, case: &str, f: impl Fn(&CaseStats) -> f64) -> f64 {
    let c = r.cases.iter().find(|c| c.name == case).unwrap();
    mean(c.study.members.iter().map(f))
}

/// HOLDS for true.
fn verdict(holds: bool) -> Verdict {
    if holds {
        Verdict::Holds
    } else {
        Verdict::DoesNotHold
    }
}

fn verdict_of(r: &StudyResult, id: &str) -> Verdict {
    r.claims.iter().find(|c| c.id == id).unwrap().verdict
}

/// The same claims: equal text, verdicts and counts; numbers equal up to the last bit that
/// serde_json's default float parser may change (it is not correctly rounded).
fn same_claims(a: &[Claim], b: &[Claim]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(
            (&x.id, &x.statement, &x.source, &x.criterion, x.verdict),
            (&y.id, &y.statement, &y.source, &y.criterion, y.verdict)
        );
        assert_eq!(
            (x.realisations_holding, x.realisations),
            (y.realisations_holding, y.realisations),
            "{}",
            x.id
        );
        assert_eq!(x.numbers.len(), y.numbers.len(), "{}", x.id);
        let close = |p: f64, q: f64| (p - q).abs() <= 1e-14 * p.abs().max(q.abs());
        for (n, m) in x.numbers.iter().zip(&y.numbers) {
            assert_eq!(n.label, m.label, "{}", x.id);
            assert!(
                close(n.value, m.value),
                "{} {}: {} {}",
                x.id,
                n.label,
                n.value,
                m.value
            );
            for (p, q) in [(n.min, m.min), (n.max, m.max)] {
                assert_eq!(p.is_some(), q.is_some(), "{} {}", x.id, n.label);
                if let (Some(p), Some(q)) = (p, q) {
                    assert!(close(p, q), "{} {}: {p} {q}", x.id, n.label);
                }
            }
        }
    }
}

#[test]
fn study_paper_writes_consistent_results() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("paper");
    let o = Command::new(env!("CARGO_BIN_EXE_lash"))
        .args(["study", "paper", "--out"])
        .arg(&out)
        .output()
        .expect("run lash");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    assert!(stdout.starts_with("study paper: 18 cases"), "{stdout}");

    // study.json reads back into the typed result.
    let json = std::fs::read_to_string(out.join("study.json")).unwrap();
    let r: StudyResult = serde_json::from_str(&json).unwrap();
    let names: Vec<&str> = r.cases.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, CASES);
    for c in &r.cases {
        let n = if c.kind == Kind::Ideal {
            1
        } else {
            r.plan.realisations
        };
        for s in SETTINGS {
            assert_eq!(ensemble(c, s).members.len(), n, "{} {s:?}", c.name);
        }
    }

    // Every verdict follows from the numbers stored in study.json: judging the stored
    // statistics again gives the same claims, numbers and counts, at every setting.
    for (s, stored) in [
        (Setting::Study, &r.claims),
        (Setting::Reference, &r.reference_claims),
        (Setting::Loose, &r.loose_claims),
    ] {
        same_claims(&r.judge(s).unwrap(), stored);
    }
    assert_eq!(r.claims.len(), CLAIMS);
    let agree = r
        .claims
        .iter()
        .zip(&r.reference_claims)
        .all(|(a, b)| a.verdict == b.verdict);
    assert_eq!(r.verdicts_agree, agree);

    // Three verdicts recomputed here from the stored metrics, independently of the claims
    // module. P9: lubricated RMS deviation below dry at every speed.
    let rms = |s: &CaseStats| s.metrics.slider_acc_rms_dev_ideal.unwrap();
    let p9 = DRY_SPEEDS
        .iter()
        .zip(LUB_SPEEDS)
        .all(|(dry, lub)| ensemble_mean(&r, lub, rms) < ensemble_mean(&r, dry, rms));
    assert_eq!(verdict_of(&r, "P9"), verdict(p9));
    // P18: dry penetration strictly increasing with the clearance.
    let pen: Vec<f64> = DRY_CLEARANCES
        .iter()
        .map(|c| ensemble_mean(&r, c, |s| s.metrics.penetration_max.unwrap()))
        .collect();
    let p18 = pen.windows(2).all(|w| w[1] > w[0]);
    assert_eq!(verdict_of(&r, "P18"), verdict(p18));
    // P23: lubricated eps_max below 1 at every clearance.
    let p23 = LUB_CLEARANCES
        .iter()
        .all(|c| ensemble_mean(&r, c, |s| s.metrics.eps_max.unwrap()) < 1.0);
    assert_eq!(verdict_of(&r, "P23"), verdict(p23));

    // The stored metrics agree with each other: on the same grid δ = c (ε − 1), so
    // penetration_max = max(0, c (eps_max − 1)); film_thickness_min = c (1 − min(eps_max, 1)).
    for c in r.cases.iter().filter(|c| c.kind != Kind::Ideal) {
        let cl = c.clearance_m.unwrap();
        for m in SETTINGS.iter().flat_map(|&s| &ensemble(c, s).members) {
            let m = &m.metrics;
            let eps = m.eps_max.unwrap();
            let pen = m.penetration_max.unwrap();
            assert!(
                (pen - (cl * (eps - 1.0)).max(0.0)).abs() < 1e-12 * cl,
                "{}: δ_max {pen} vs c (ε_max − 1) = {}",
                c.name,
                cl * (eps - 1.0)
            );
            if c.kind == Kind::Lubricated {
                let h = m.film_thickness_min.unwrap();
                assert!(
                    (h - cl * (1.0 - eps.min(1.0))).abs() < 1e-12 * cl,
                    "{}",
                    c.name
                );
            } else {
                assert_eq!(m.film_thickness_min, None);
            }
        }
    }

    // report.md: every case, every claim with its verdict (heading and summary row).
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for c in &r.cases {
        assert!(
            report.contains(&format!("\n| {} | ", c.name)),
            "{} not in the report",
            c.name
        );
    }
    for c in &r.claims {
        let heading = format!("\n### {} — {} (", c.id, spelled(c.verdict));
        assert!(report.contains(&heading), "no '{heading}' in the report");
        let row = format!(
            "\n| {} | {} | {} | **{}** | ",
            c.id,
            c.figure.replace('|', "\\|"),
            c.statement.replace('|', "\\|"),
            spelled(c.verdict)
        );
        assert!(report.contains(&row), "no summary row for {}", c.id);
        assert!(report.contains(&c.source), "{}: source not quoted", c.id);
    }

    // Figures: an SVG and a PNG per record, nothing else, no temporary file.
    assert_eq!(r.figures.len(), FIGURES);
    let dir = out.join("figures");
    let files: BTreeSet<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    let want: BTreeSet<String> = r
        .figures
        .iter()
        .flat_map(|f| [format!("{}.svg", f.id), format!("{}.png", f.id)])
        .collect();
    assert_eq!(files, want);
    for id in ["fig05a", "fig06d", "fig07a", "fig12c", "fig16d"] {
        assert!(want.contains(&format!("{id}.png")), "{id}");
        assert!(
            report.contains(&format!("(figures/{id}.png)")),
            "{id} not linked"
        );
    }
    let top: BTreeSet<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    // cache/ holds the finished runs a stopped study resumes from.
    let expected: BTreeSet<String> = ["figures", "study.json", "report.md", "cache"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(top, expected);
    assert!(Path::new(&dir.join("fig06a.svg")).is_file());
}
