//! `lash study paper --robustness`: the paper's claims under the modelling choices the paper
//! leaves open, one choice varied at a time from the study's baseline.
//!
//! ```text
//! baseline      the study (eps_cap 0.99, long Gümbel film, c_max as in the scenes, two
//!               revolutions; the periodicity claim at steady state), study settings only
//! variants      eps_cap ∈ {0.999, 0.9999, none};  film ∈ {long Sommerfeld, short Ocvirk};
//!               contact damping c_max × {0.1, 10};  run length ∈ {two revolutions for every
//!               claim, steady state for every case}  (one factor at a time)
//! runs          every case × realisation of every variant through the study's job runner:
//!               cached in DIR/cache (resumable), identical runs done once (a film variant
//!               leaves the dry cases as they are), progress per run
//! verdicts      claims::evaluate_with on each variant's ensembles, with the margin of each
//! robust        a claim whose verdict is the same under every variant; fragile otherwise,
//!               with the variants that flip it and their numbers
//! files         DIR/robustness.md, then DIR/robustness.json (atomically)
//! ```
//!
//! Steady state for every case: a case with a clearance joint runs until its section settles
//! (the study's [`crate::studies::paper::Plan::steady`]); a dry joint is chaotic and runs to the cap. The ideal
//! mechanism is periodic from its start and keeps its two revolutions.
//!
//! Source: docs/model.md §3, §4, §6; the study (`super`); [`crate::run::steady`].

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use lash_model::laws::FilmModel;
use lash_model::scene::{JointSpec, NormalSpec};
use lash_model::Scene;

use crate::error::Error;
use crate::progress::Progress;
use crate::run::press::{Kind, RunKey};
use crate::store::cache::{RunCache, CACHE_DIR};
use crate::store::io;
use crate::studies::paper::claims::{self, Cases, Claim, Number, Thresholds, Verdict};
use crate::studies::paper::plan::{study_cases, Plan, Setting, LUB_CLEARANCES};
use crate::studies::paper::runner::Job;
use crate::studies::paper::runner::{run_jobs, spread, JobOut};
use crate::studies::paper::stats::Ensemble;

/// File name of the robustness table (markdown).
pub(crate) const MD_FILE: &str = "robustness.md";
/// File name of the machine-readable robustness results.
pub(crate) const JSON_FILE: &str = "robustness.json";

/// Run length of a variant.
///
/// ```text
/// Study = two revolutions, the periodicity claim at steady state;
/// TwoRevolutions = every claim after two revolutions;  SteadyState = every case until periodic
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum RunLength {
    /// As the study.
    Study,
    /// Two revolutions for every claim.
    TwoRevolutions,
    /// Every case until periodic.
    SteadyState,
}

/// The one modelling choice a variant changes.
///
/// ```text
/// eps_cap of every film (null: no cap) | film model | c_max × factor of every impact law |
/// run length
/// ```
///
/// Source: docs/model.md §3.1 (c_max), §4 (eps_cap, film models).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Choice {
    /// The baseline.
    Baseline,
    /// The film's eccentricity cap (None: no cap).
    EpsCap(Option<f64>),
    /// The film model.
    Film(FilmModel),
    /// The contact damping c_max multiplied by this factor.
    CMaxTimes(f64),
    /// The run length.
    Length(RunLength),
}

/// A variant of the study.
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Variant {
    /// Name (the key of robustness.json's verdicts).
    pub name: String,
    /// The factor varied ("baseline", "eps_cap", "film", "c_max", "run_length").
    pub factor: String,
    /// The choice.
    pub choice: Choice,
}

impl Variant {
    fn new(name: &str, factor: &str, choice: Choice) -> Variant {
        Variant {
            name: name.into(),
            factor: factor.into(),
            choice,
        }
    }

    /// The run length of this variant.
    pub(crate) fn length(&self) -> RunLength {
        match self.choice {
            Choice::Length(l) => l,
            _ => RunLength::Study,
        }
    }

    /// The case scene under this variant's choice.
    pub(crate) fn apply(&self, scene: &Scene) -> Scene {
        let mut s = scene.clone();
        for j in s.joints.iter_mut() {
            if let JointSpec::Clearance(c) = j {
                match self.choice {
                    Choice::EpsCap(cap) => {
                        if let Some(f) = c.film.as_mut() {
                            f.eps_cap = cap;
                        }
                    }
                    Choice::Film(m) => {
                        if let Some(f) = c.film.as_mut() {
                            f.model = m;
                        }
                    }
                    Choice::CMaxTimes(k) => {
                        if let NormalSpec::Impact(i) = &mut c.normal {
                            i.c_max *= k;
                        }
                    }
                    Choice::Baseline | Choice::Length(_) => {}
                }
            }
        }
        s
    }
}

/// The variants of `lash study paper --robustness`, baseline first (module doc).
pub(crate) fn variants() -> Vec<Variant> {
    vec![
        Variant::new("baseline", "baseline", Choice::Baseline),
        Variant::new("eps_cap=0.999", "eps_cap", Choice::EpsCap(Some(0.999))),
        Variant::new("eps_cap=0.9999", "eps_cap", Choice::EpsCap(Some(0.9999))),
        Variant::new("eps_cap=none", "eps_cap", Choice::EpsCap(None)),
        Variant::new(
            "film=long_sommerfeld",
            "film",
            Choice::Film(FilmModel::LongSommerfeld),
        ),
        Variant::new(
            "film=short_ocvirk",
            "film",
            Choice::Film(FilmModel::ShortOcvirk),
        ),
        Variant::new("c_max×0.1", "c_max", Choice::CMaxTimes(0.1)),
        Variant::new("c_max×10", "c_max", Choice::CMaxTimes(10.0)),
        Variant::new(
            "two_revolutions",
            "run_length",
            Choice::Length(RunLength::TwoRevolutions),
        ),
        Variant::new(
            "steady_state",
            "run_length",
            Choice::Length(RunLength::SteadyState),
        ),
    ]
}

/// A claim's verdict under one variant.
///
/// Source: [`claims::Claim`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Cell {
    /// The verdict.
    pub verdict: Verdict,
    /// Its relative margin ([`Claim::margin`]).
    pub margin: f64,
    /// The numbers it rests on.
    pub numbers: Vec<Number>,
}

/// One claim across the variants.
///
/// ```text
/// robust ⇔ the verdict is the baseline's under every variant;  flipped_by = the others
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct ClaimRobustness {
    /// Claim id (P1, …, M4).
    pub id: String,
    /// The claim.
    pub statement: String,
    /// Its criterion.
    pub criterion: String,
    /// Same verdict under every variant.
    pub robust: bool,
    /// The variants whose verdict differs from the baseline's.
    pub flipped_by: Vec<String>,
    /// Verdict, margin and numbers per variant name.
    pub cells: BTreeMap<String, Cell>,
}

/// The content of robustness.json.
///
/// ```text
/// { version, plan, thresholds, variants[], claims: {id: {variant: "holds" | "does_not_hold"}},
///   details[], runs, timing_s }
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RobustnessResult {
    /// lash version.
    pub(crate) version: String,
    /// The study's plan (only its study settings, realisations and steady state are used).
    pub(crate) plan: Plan,
    /// The thresholds of the claims.
    pub(crate) thresholds: Thresholds,
    /// The variants, baseline first.
    pub(crate) variants: Vec<Variant>,
    /// Verdicts: claim id → variant name → "holds" | "does_not_hold".
    pub(crate) claims: BTreeMap<String, BTreeMap<String, String>>,
    /// Each claim across the variants, in the order of the study.
    pub(crate) details: Vec<ClaimRobustness>,
    /// Distinct runs (after removing identical ones).
    pub(crate) runs: usize,
    /// Wall time, s.
    pub(crate) timing_s: f64,
}

/// The runs of every variant, as the claims read them (one [`Cases`] per variant).
pub(crate) type VariantCases = Vec<Cases>;

/// Runs every variant (module doc) and returns each variant's ensembles. Runs go through the
/// study's job runner with `cache` and `progress`.
pub(crate) fn run_variants(
    plan: &Plan,
    variants: &[Variant],
    cache: &RunCache,
    progress: &dyn Progress,
) -> Result<(VariantCases, usize), Error> {
    if plan.realisations == 0 {
        return Err(Error::Usage("study: at least one realisation".into()));
    }
    let names = study_cases();
    let mut jobs = Vec::new();
    // (variant, case, steady) of each job.
    let mut tags = Vec::new();
    for (vi, v) in variants.iter().enumerate() {
        for (i, &name) in names.iter().enumerate() {
            let scene = v.apply(&name.scene());
            let kind = name.kind();
            let members = if kind == Kind::Ideal {
                1
            } else {
                plan.realisations
            };
            let steady = Some(plan.steady);
            let lengths: Vec<Option<_>> = match v.length() {
                RunLength::Study if LUB_CLEARANCES.contains(&name) => {
                    vec![None, steady]
                }
                RunLength::SteadyState if kind != Kind::Ideal => vec![steady],
                _ => vec![None],
            };
            for until in lengths {
                for member in 0..members {
                    jobs.push(Job {
                        case: i,
                        press: name,
                        scene: scene.clone(),
                        setting: Setting::Study,
                        member,
                        until,
                    });
                    tags.push((vi, i, until.is_some()));
                }
            }
        }
    }
    let (outs, distinct) = run_jobs(&jobs, plan, cache, progress, "robustness")?;
    let mut all = Vec::new();
    for (vi, v) in variants.iter().enumerate() {
        let mut cases = Cases::new();
        for (i, &name) in names.iter().enumerate() {
            let ensemble = |steady: bool| {
                let mut m: Vec<(usize, &JobOut)> = jobs
                    .iter()
                    .zip(&outs)
                    .zip(&tags)
                    .filter(|(_, t)| **t == (vi, i, steady))
                    .map(|((j, o), _)| (j.member, o))
                    .collect();
                m.sort_by_key(|x| x.0);
                (!m.is_empty()).then(|| Ensemble {
                    members: m.iter().map(|(_, o)| o.stats.clone()).collect(),
                    acc_spread: spread(&m.iter().map(|(_, o)| &o.acc).collect::<Vec<_>>()),
                })
            };
            let (two, steady) = (ensemble(false), ensemble(true));
            match (v.length(), two, steady) {
                (RunLength::SteadyState, _, Some(s)) => {
                    cases.insert(RunKey::runs(name), s);
                }
                (_, Some(t), s) => {
                    cases.insert(RunKey::runs(name), t);
                    if let Some(s) = s {
                        cases.insert(RunKey::steady_state(name), s);
                    }
                }
                _ => {
                    return Err(Error::Internal(format!(
                        "robustness: no runs of {name} under {}",
                        v.name
                    )))
                }
            }
        }
        all.push(cases);
    }
    Ok((all, distinct))
}

/// The verdicts of every claim under every variant with thresholds `th` (baseline first).
pub(crate) fn judge(
    variants: &[Variant],
    cases: &[Cases],
    th: &Thresholds,
) -> Result<Vec<ClaimRobustness>, Error> {
    let per: Vec<Vec<Claim>> = cases
        .iter()
        .map(|c| claims::evaluate_with(c, th))
        .collect::<Result<_, _>>()?;
    let base = per
        .first()
        .ok_or_else(|| Error::Internal("robustness: no variants".into()))?;
    Ok(base
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let mut cells = BTreeMap::new();
            let mut flipped_by = Vec::new();
            for (v, claims) in variants.iter().zip(&per) {
                let c = &claims[k];
                if c.verdict != b.verdict {
                    flipped_by.push(v.name.clone());
                }
                cells.insert(
                    v.name.clone(),
                    Cell {
                        verdict: c.verdict,
                        margin: c.margin,
                        numbers: c.numbers.clone(),
                    },
                );
            }
            ClaimRobustness {
                id: b.id.clone(),
                statement: b.statement.clone(),
                criterion: b.criterion.clone(),
                robust: flipped_by.is_empty(),
                flipped_by,
                cells,
            }
        })
        .collect())
}

fn verdict_word(v: Verdict) -> &'static str {
    match v {
        Verdict::Holds => "holds",
        Verdict::DoesNotHold => "does_not_hold",
    }
}

/// Runs the robustness study and writes `out/robustness.md`, then `out/robustness.json`;
/// finished runs go to `out/cache` (shared with `lash study paper --out` the same folder, whose
/// study-setting runs it reuses).
pub(crate) fn run_and_write(
    plan: &Plan,
    variants: &[Variant],
    th: &Thresholds,
    out: &Path,
    progress: &dyn Progress,
) -> Result<RobustnessResult, Error> {
    let clock = Instant::now();
    crate::store::claim::remove_dead_temporaries(out);
    let cache = RunCache::new(&out.join(CACHE_DIR));
    let (cases, runs) = run_variants(plan, variants, &cache, progress)?;
    let details = judge(variants, &cases, th)?;
    let claims = details
        .iter()
        .map(|d| {
            (
                d.id.clone(),
                d.cells
                    .iter()
                    .map(|(v, c)| (v.clone(), verdict_word(c.verdict).to_string()))
                    .collect(),
            )
        })
        .collect();
    let r = RobustnessResult {
        version: env!("CARGO_PKG_VERSION").to_string(),
        plan: *plan,
        thresholds: *th,
        variants: variants.to_vec(),
        claims,
        details,
        runs,
        timing_s: clock.elapsed().as_secs_f64(),
    };
    io::create_dir(out)?;
    io::write_atomic(&out.join(MD_FILE), markdown(&r).as_bytes())?;
    io::write_json_atomic(&out.join(JSON_FILE), &r)?;
    Ok(r)
}

impl RobustnessResult {
    /// One line: robust and fragile claims, where the table is.
    pub fn describe(&self, out: &Path) -> String {
        let fragile: Vec<&str> = self
            .details
            .iter()
            .filter(|d| !d.robust)
            .map(|d| d.id.as_str())
            .collect();
        format!(
            "study paper (robustness): {} variants, {} distinct runs, {:.1} s; {} of {} claims robust, fragile: {}; table {}",
            self.variants.len(),
            self.runs,
            self.timing_s,
            self.details.len() - fragile.len(),
            self.details.len(),
            if fragile.is_empty() { "none".to_string() } else { fragile.join(", ") },
            out.join(MD_FILE).display()
        )
    }
}

/// robustness.md: thresholds, the claims × variants table (verdict and margin), and for each
/// fragile claim the variants that flip it with their numbers.
pub(crate) fn markdown(r: &RobustnessResult) -> String {
    let th = &r.thresholds;
    let mut s = String::new();
    s.push_str("# The paper's claims under model uncertainty\n\n");
    s.push_str(&format!(
        "One modelling choice varied at a time from the study's baseline (eps_cap 0.99, long \
         Gümbel film, the scenes' contact damping, two revolutions with the periodicity claim \
         P25 at steady state); {} realisations per clearance case at the study's settings \
         (BDF, rtol {:e}); steady state = until the once-per-revolution section moves by less \
         than {} c, at most {} revolutions. {} distinct runs, {:.1} s.\n\n",
        r.plan.realisations,
        r.plan.settings.rtol,
        r.plan.steady.tol,
        r.plan.steady.max_revolutions,
        r.runs,
        r.timing_s
    ));
    s.push_str(&format!(
        "Thresholds: little = {} of the stroke; scarcely = {} and obvious = {} of the ideal \
         peak acceleration; near the boundary ε ≥ {}; not chaotic: spread < {} of the peak; \
         periodic: closure < {} c; marked growth × {}; a fluctuating sector exceeds {} of the \
         peak.\n\n",
        th.little,
        th.scarcely,
        th.obvious,
        th.near_boundary,
        th.not_chaotic,
        th.periodic,
        th.marked_growth,
        crate::studies::paper::stats::SECTOR_FLUCTUATION
    ));
    s.push_str(
        "Each cell: ✓ holds / ✗ does not hold, and the verdict's relative margin (the \
         smallest (b − a)/max(|a|, |b|) over the criterion's comparisons a < b; negative: by \
         how much the worst comparison fails).\n\n",
    );
    s.push_str("| claim | robust |");
    for v in &r.variants {
        s.push_str(&format!(" {} |", v.name));
    }
    s.push_str("\n|---|---|");
    for _ in &r.variants {
        s.push_str("---|");
    }
    s.push('\n');
    for d in &r.details {
        s.push_str(&format!(
            "| {} | {} |",
            d.id,
            if d.robust { "robust" } else { "**fragile**" }
        ));
        for v in &r.variants {
            let c = &d.cells[&v.name];
            let mark = if c.verdict == Verdict::Holds {
                "✓"
            } else {
                "✗"
            };
            s.push_str(&format!(" {mark} {:+.3} |", c.margin));
        }
        s.push('\n');
    }
    s.push_str("\n## Fragile claims\n\n");
    let base = r
        .variants
        .first()
        .map(|v| v.name.clone())
        .unwrap_or_default();
    for d in r.details.iter().filter(|d| !d.robust) {
        let b = &d.cells[&base];
        s.push_str(&format!(
            "### {} — {}\n\nCriterion: {}\n\nBaseline: {} (margin {:+.3}).\n\n",
            d.id,
            d.statement,
            d.criterion,
            b.verdict.as_str(),
            b.margin
        ));
        for v in &d.flipped_by {
            let c = &d.cells[v];
            s.push_str(&format!(
                "- **{v}**: {} (margin {:+.3}). Numbers (baseline → {v}):\n",
                c.verdict.as_str(),
                c.margin
            ));
            for n in &c.numbers {
                let was = b
                    .numbers
                    .iter()
                    .find(|m| m.label == n.label)
                    .map_or("—".to_string(), |m| format!("{:.4e}", m.value));
                s.push_str(&format!("  - {}: {was} → {:.4e}\n", n.label, n.value));
            }
        }
        s.push('\n');
    }
    s
}
