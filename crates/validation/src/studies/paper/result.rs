//! What the study measured: every case at every setting, the claims judged on it, the
//! figures and the times — the content of study.json.
//!
//! Source: docs/outputs.md ("`lash study paper`").

use std::path::Path;

use lash_solver::Stats;

use crate::error::Error;
use crate::run::press::{Kind, PressCase, RunKey};
use crate::run::steady::UntilPeriodic;
use crate::studies::paper::claims;
use crate::studies::paper::claims::Claim;
use crate::studies::paper::claims::Origin;
use crate::studies::paper::claims::Verdict;
use crate::studies::paper::plan::Plan;
use crate::studies::paper::plan::Setting;
use crate::studies::paper::stats::Ensemble;

/// File name of the markdown report.
pub(crate) const REPORT_FILE: &str = "report.md";
/// File name of the machine-readable results.
pub(crate) const JSON_FILE: &str = "study.json";
/// Folder of the figures inside the output directory.
pub(crate) const FIGURES_DIR: &str = "figures";

impl CaseResult {
    /// The realisations at `which` settings.
    pub(crate) fn ensemble(&self, which: Setting) -> &Ensemble {
        match which {
            Setting::Study => &self.study,
            Setting::Reference => &self.reference,
            Setting::Loose => &self.loose,
        }
    }
}

/// What the solver did for the paper's realisation (k = 0) at the study's settings, and the
/// wall time of all runs of the case.
///
/// ```text
/// stats, events of realisation 0;  wall_time_s of realisation 0;  total_wall_time_s = Σ runs
/// ```
///
/// Source: `lash_solver::Stats`; docs/outputs.md (`wall_time_s`, `events`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolverRecord {
    /// The solver's counters.
    pub stats: Stats,
    /// Events located during the whole run.
    pub events: usize,
    /// Wall time of the integration alone, s.
    pub wall_time_s: f64,
    /// Wall time of every run of this case (all realisations, both settings), s.
    pub total_wall_time_s: f64,
}

/// Everything measured for one case.
///
/// ```text
/// name, kind, rpm, c;  study = Ensemble at Plan::settings;  reference, loose = at
/// Plan::reference, Plan::loose
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaseResult {
    /// Case name (file stem in cases/press/).
    pub name: String,
    /// Dry, lubricated or ideal.
    pub kind: Kind,
    /// Crank speed, rpm.
    pub rpm: f64,
    /// Radial clearance, m (null for the ideal mechanism).
    pub clearance_m: Option<f64>,
    /// Realisations at the study's settings.
    pub study: Ensemble,
    /// The same realisations at the reference settings.
    pub reference: Ensemble,
    /// The same realisations at the loose settings.
    pub loose: Ensemble,
    /// max_i |ẍ(t_i) at the study's settings − ẍ(t_i) at the reference settings| of the
    /// paper's realisation over the last revolution, m/s².
    pub acc_tolerance_diff: f64,
    /// Solver counters and times.
    pub solver: SolverRecord,
    /// The same realisations run until the orbit settles (the cases of the periodicity claim;
    /// null for the others).
    pub steady: Option<SteadyRuns>,
}

/// A case's realisations run until periodic (`crate::run::steady`) at the three settings.
///
/// ```text
/// run until |s_k − s_{k−1}| < tol·c (section once per revolution), at most max_revolutions;
/// statistics of the last revolution, as for the two-revolution runs
/// ```
///
/// Source: `crate::run::steady`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SteadyRuns {
    /// The request.
    pub until: UntilPeriodic,
    /// Revolutions run by each realisation at the study's settings.
    pub revolutions: Vec<usize>,
    /// Whether each realisation settled within the cap (study's settings).
    pub settled: Vec<bool>,
    /// Realisations at the study's settings.
    pub study: Ensemble,
    /// At the reference settings.
    pub reference: Ensemble,
    /// At the loose settings.
    pub loose: Ensemble,
}

/// A written figure.
///
/// ```text
/// id "fig06a" → figures/fig06a.svg, figures/fig06a.png
/// ```
///
/// Source: the paper's Figures 5–16 (panel letters as in the paper; panel (c) of the
/// displacement figures is added: x − x_ideal).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FigureRecord {
    /// File stem, e.g. `fig06a`.
    pub id: String,
    /// Figure title.
    pub title: String,
    /// Cases drawn.
    pub cases: Vec<String>,
}

/// Wall times of the study, s.
///
/// ```text
/// total = runs + figures + writing
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Timing {
    /// All integrations and statistics (parallel).
    pub runs_s: f64,
    /// Rendering of the figures (parallel).
    pub figures_s: f64,
    /// The whole command.
    pub total_s: f64,
    /// Worker threads used.
    pub threads: usize,
}

/// The content of study.json.
///
/// ```text
/// { version, plan, cases[], claims[] (study settings), reference_claims[],
///   loose_claims[] (the other settings), verdicts_agree, figures[], timing }
/// ```
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StudyResult {
    /// lash version string.
    pub version: String,
    /// What was run.
    pub plan: Plan,
    /// The cases, in the order of `case_names`.
    pub cases: Vec<CaseResult>,
    /// The claims judged on the study's settings.
    pub claims: Vec<Claim>,
    /// The same claims judged on the reference settings.
    pub reference_claims: Vec<Claim>,
    /// The same claims judged on the loose settings.
    pub loose_claims: Vec<Claim>,
    /// True when every claim has the same verdict at the study's and the reference settings.
    pub verdicts_agree: bool,
    /// The figures written.
    pub figures: Vec<FigureRecord>,
    /// Wall times.
    pub timing: Timing,
}

impl StudyResult {
    /// The claims judged again on the statistics stored here at one of the settings (what
    /// `claims`, `reference_claims` and `loose_claims` hold, recomputed: a check that every
    /// verdict follows from the stored numbers). Errors: a case or a statistic missing.
    pub fn judge(&self, which: Setting) -> Result<Vec<Claim>, Error> {
        claims::evaluate(&self.ensembles(which)?)
    }

    /// The ensembles at one of the settings, by press case (each name parsed back: a case
    /// that is not a press case is an input error); the steady-state runs under the case's
    /// `RunKey::steady_state`.
    pub(crate) fn ensembles(&self, which: Setting) -> Result<claims::Cases, Error> {
        let mut m = claims::Cases::new();
        for c in &self.cases {
            let case: PressCase = c
                .name
                .parse()
                .map_err(|e| Error::Input(format!("study: {e}")))?;
            m.insert(RunKey::runs(case), c.ensemble(which).clone());
            if let Some(st) = &c.steady {
                let e = match which {
                    Setting::Study => &st.study,
                    Setting::Reference => &st.reference,
                    Setting::Loose => &st.loose,
                };
                m.insert(RunKey::steady_state(case), e.clone());
            }
        }
        Ok(m)
    }
}

impl StudyResult {
    /// One line of results of the paper's study written to `out`: cases, realisations, times,
    /// how many of the paper's claims hold, where the report is.
    pub fn describe(&self, out: &Path) -> String {
        let paper: Vec<&Claim> = self
            .claims
            .iter()
            .filter(|c| c.origin == Origin::Paper)
            .collect();
        let holding = paper.iter().filter(|c| c.verdict == Verdict::Holds).count();
        format!(
            "study paper: {} cases × {} realisations, runs {:.1} s, figures {:.1} s; {} of {} paper claims hold; report {}",
            self.cases.len(),
            self.plan.realisations,
            self.timing.runs_s,
            self.timing.figures_s,
            holding,
            paper.len(),
            out.join(REPORT_FILE).display()
        )
    }
}
