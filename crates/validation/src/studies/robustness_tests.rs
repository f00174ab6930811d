//! `lash study paper --robustness` on a quick configuration: one realisation per case at rtol
//! 1e-8 (the defaults of a run), runs until periodic capped at 12 revolutions, and three of the
//! variants (baseline, no cap, two revolutions). The verdicts come from the runs; the test
//! checks them against what the model must do, and that moving a threshold moves exactly the
//! verdicts that read it.

use std::sync::Mutex;

use crate::progress::Progress;
use crate::studies::paper::claims::{Thresholds, Verdict};
use crate::studies::paper::plan::Plan;
use crate::studies::robustness::{self, ClaimRobustness, Variant};

fn quick_plan() -> Plan {
    let mut p = Plan::paper();
    p.settings.rtol = 1e-8;
    p.settings.atol = 1e-10;
    p.realisations = 1;
    p.steady.max_revolutions = 12;
    p
}

fn quick_variants() -> Vec<Variant> {
    robustness::variants()
        .into_iter()
        .filter(|v| ["baseline", "eps_cap=none", "two_revolutions"].contains(&v.name.as_str()))
        .collect()
}

/// Counts the runs a study starts (items of its batch).
#[derive(Default)]
struct Count(Mutex<Vec<usize>>);
impl Progress for Count {
    fn started(&self, _: &str, total: usize) {
        self.0.lock().unwrap().push(total);
    }
}

fn claim<'a>(d: &'a [ClaimRobustness], id: &str) -> &'a ClaimRobustness {
    d.iter().find(|c| c.id == id).unwrap()
}

/// The largest value among a cell's numbers whose label ends with `suffix`.
fn largest(d: &ClaimRobustness, variant: &str, suffix: &str) -> f64 {
    d.cells[variant]
        .numbers
        .iter()
        .filter(|n| n.label.ends_with(suffix))
        .map(|n| n.value)
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn robustness_verdicts_come_from_the_runs_and_follow_the_thresholds() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rob");
    let (plan, variants, th) = (quick_plan(), quick_variants(), Thresholds::paper());
    let count = Count::default();
    let r = robustness::run_and_write(&plan, &variants, &th, &out, &count).unwrap();
    let d = &r.details;

    // Margins agree with the verdicts, in every cell (0: on the threshold, e.g. P4's eight
    // sectors of eight, which holds by "at least").
    for c in d {
        for (v, cell) in &c.cells {
            let ok = match cell.verdict {
                Verdict::Holds => cell.margin >= 0.0,
                Verdict::DoesNotHold => cell.margin <= 0.0,
            };
            assert!(ok, "{} under {v}: margin {}", c.id, cell.margin);
        }
    }

    // P23 (ε_max < 1 at every clearance): the cap 0.99 lets the 0.5 mm journal through to
    // contact (docs/model.md §4, the cap rule); without a cap the film alone holds it off.
    let p23 = claim(d, "P23");
    let eps = |v: &str| largest(p23, v, "c0.5 eps_max");
    assert!(eps("baseline") > 1.0, "{}", eps("baseline"));
    assert!(eps("eps_cap=none") < 1.0, "{}", eps("eps_cap=none"));
    assert_eq!(p23.cells["baseline"].verdict, Verdict::DoesNotHold);
    assert_eq!(p23.cells["eps_cap=none"].verdict, Verdict::Holds);
    assert!(!p23.robust && p23.flipped_by.contains(&"eps_cap=none".to_string()));

    // P25 (periodic orbit): after two revolutions the 0.1 mm journal is still sinking (its
    // orbit closes to 0.53 c, far above the 0.05 c of the claim); run until its section moves
    // by less than 0.01 c a revolution, every orbit closes within 0.05 c.
    let p25 = claim(d, "P25");
    let steady = largest(p25, "baseline", "orbit_closure");
    let two = largest(p25, "two_revolutions", "orbit_closure");
    assert!(steady < 0.05 && two > 0.2, "{steady} {two}");
    assert_eq!(p25.cells["baseline"].verdict, Verdict::Holds);
    assert_eq!(p25.cells["two_revolutions"].verdict, Verdict::DoesNotHold);

    // Moving the periodicity threshold just above the two-revolution closure makes P25 hold
    // there too, with a margin of about 1 %, and changes no other verdict; just below the
    // steady closure it fails at baseline.
    let cases = robustness::run_variants(
        &plan,
        &variants,
        &crate::store::cache::RunCache::new(&out.join("cache")),
        &count,
    )
    .unwrap()
    .0;
    let again = robustness::judge(&variants, &cases, &th).unwrap();
    assert_eq!(&again, d, "judged again from the cache: the same");
    let loose = Thresholds {
        periodic: 1.01 * two,
        ..th
    };
    let l = robustness::judge(&variants, &cases, &loose).unwrap();
    let c = &claim(&l, "P25").cells["two_revolutions"];
    assert_eq!(c.verdict, Verdict::Holds);
    assert!((c.margin - 0.01 / 1.01).abs() < 1e-12, "{}", c.margin);
    assert!(claim(&l, "P25").robust);
    for (a, b) in l.iter().zip(d) {
        if a.id != "P25" {
            assert_eq!(a.cells, b.cells, "{}", a.id);
        }
    }
    let strict = Thresholds {
        periodic: 0.99 * steady,
        ..th
    };
    let s = robustness::judge(&variants, &cases, &strict).unwrap();
    assert_eq!(
        claim(&s, "P25").cells["baseline"].verdict,
        Verdict::DoesNotHold
    );
    // The "not chaotic" threshold at 0 fails P24 everywhere (a spread is never negative).
    let none = Thresholds {
        not_chaotic: 0.0,
        ..th
    };
    let n = robustness::judge(&variants, &cases, &none).unwrap();
    assert!(claim(&n, "P24")
        .cells
        .values()
        .all(|c| c.verdict == Verdict::DoesNotHold));

    // The files: robustness.json in the documented shape, robustness.md with the table.
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join(robustness::JSON_FILE)).unwrap()).unwrap();
    let names: Vec<&str> = json["variants"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["baseline", "eps_cap=none", "two_revolutions"]);
    assert_eq!(json["claims"]["P23"]["baseline"], "does_not_hold");
    assert_eq!(json["claims"]["P23"]["eps_cap=none"], "holds");
    assert_eq!(json["claims"].as_object().unwrap().len(), d.len());
    let md = std::fs::read_to_string(out.join(robustness::MD_FILE)).unwrap();
    assert!(md.contains("| claim | robust | baseline | eps_cap=none | two_revolutions |"));
    assert!(md.contains("### P23"));

    // Resuming: the same command again runs nothing (every run is in the cache).
    let before = count.0.lock().unwrap().clone();
    assert!(before[0] > 0 && before[1] == 0, "{before:?}");
    let r2 = robustness::run_and_write(&plan, &variants, &th, &out, &count).unwrap();
    assert_eq!(count.0.lock().unwrap().last(), Some(&0));
    assert_eq!(r2.details, r.details);
}
