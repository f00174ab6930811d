//! `lash study paper` (and its robustness) and `lash extremes`: the studies.
//!
//! Source: docs/outputs.md ("`lash study paper`", "`lash extremes`").

use std::path::PathBuf;

use crate::commands::default_out;
use crate::error::{Error, OptionError};
use crate::progress::Progress;
use crate::store::cache::{RunCache, CACHE_DIR};
use crate::store::io::Written;
use crate::studies::extremes::outcome::Matrix;
use crate::studies::extremes::{self};
use crate::studies::paper::plan::Plan as StudyPlan;
use crate::studies::paper::result::StudyResult;
use crate::studies::paper::result::JSON_FILE;
use crate::studies::paper::result::REPORT_FILE;
use crate::studies::paper::runner::run_and_write_with;

/// What to study.
///
/// ```text
/// paper = the paper's speeds (120–200 rpm) and clearances (0.1–0.5 mm), dry and lubricated
/// ```
///
/// Source: docs/model.md §6.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StudyOptions {
    /// Output directory; None = `out/study/paper`.
    pub out: Option<PathBuf>,
    /// Run the robustness study instead (`studies::robustness`): robustness.md and
    /// robustness.json in the same directory, sharing its cache of runs.
    pub robustness: bool,
    /// What to run; None = the paper's plan ([`study::Plan::paper`](crate::study::Plan::paper)):
    /// a library caller may run fewer realisations or other tolerances.
    pub plan: Option<StudyPlan>,
}

/// Runs the paper's study (module `study`): figures, report.md and study.json in the output
/// directory ([`StudyResult::describe`] says it in one line); each run as an item of
/// `progress`; finished runs are kept in DIR/cache/ and reused by a rerun.
pub fn study_paper(
    o: &StudyOptions,
    progress: &dyn Progress,
) -> Result<Written<StudyResult>, Error> {
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("study", "paper"));
    let plan = o.plan.unwrap_or_else(StudyPlan::paper);
    let r = run_and_write_with(&plan, &out, progress)?;
    let files = vec![out.join(REPORT_FILE), out.join(JSON_FILE)];
    Ok(Written {
        result: r,
        dir: out,
        files,
    })
}

/// `lash study paper --robustness`: the claims under the modelling choices the paper leaves
/// open (`studies::robustness`), written to the study's directory.
pub fn study_robustness(
    o: &StudyOptions,
    progress: &dyn Progress,
) -> Result<Written<crate::studies::robustness::RobustnessResult>, Error> {
    let out = o
        .out
        .clone()
        .unwrap_or_else(|| default_out("study", "paper"));
    let plan = o.plan.unwrap_or_else(StudyPlan::paper);
    let r = crate::studies::robustness::run_and_write(
        &plan,
        &crate::studies::robustness::variants(),
        &crate::studies::paper::claims::Thresholds::paper(),
        &out,
        progress,
    )?;
    let files = vec![
        out.join(crate::studies::robustness::MD_FILE),
        out.join(crate::studies::robustness::JSON_FILE),
    ];
    Ok(Written {
        result: r,
        dir: out,
        files,
    })
}

/// What to run: the extremes matrix.
///
/// ```text
/// [quick] [jobs] [max_steps] [max_wall_time] [out]
/// ```
///
/// Source: docs/outputs.md ("`lash extremes`"); module `extremes`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExtremesOptions {
    /// The quick subset (3 scenes × every method × 3 tolerances).
    pub quick: bool,
    /// Parallel runs (≥ 1, capped at the available parallelism); None = 1 (the wall-clock
    /// budget is per run).
    pub jobs: Option<usize>,
    /// Step budget of every run (attempts); None = the plan's.
    pub max_steps: Option<usize>,
    /// Wall-clock budget of every run, s; None = the plan's.
    pub max_wall_time: Option<f64>,
    /// Scenes of the catalogue to run, by stem (in the order given); None = the plan's.
    pub scenes: Option<Vec<String>>,
    /// Relative tolerances of the adaptive methods, each in (0, 1); None = the plan's.
    pub tolerances: Option<Vec<f64>>,
    /// Output directory; None = `out/extremes` (`out/extremes-quick` when quick).
    pub out: Option<PathBuf>,
}

/// Runs the extremes matrix (or its quick subset) and writes extremes.md and extremes.json
/// (in that order in `files`); each reference and run is an item of `progress`. Finished
/// references and runs are kept in DIR/cache/ and reused by a rerun (`extremes::runner::run_cached`).
/// A run that ended in an outcome that is not allowed is in the result, not an error: see
/// [`Matrix::check`].
pub fn extremes(o: &ExtremesOptions, progress: &dyn Progress) -> Result<Written<Matrix>, Error> {
    let mut plan = if o.quick {
        extremes::plan::Plan::quick()
    } else {
        extremes::plan::Plan::full()
    };
    if let Some(n) = o.max_steps {
        plan.budget.max_steps = n;
    }
    if let Some(w) = o.max_wall_time {
        plan.budget.max_wall_time = w;
    }
    if let Some(v) = &o.scenes {
        if v.is_empty() {
            return Err(OptionError::leading("scenes", " lists no scene").into());
        }
        plan.scenes = v.clone();
    }
    if let Some(v) = &o.tolerances {
        if let Some(bad) = v.iter().find(|r| !(**r > 0.0 && **r < 1.0)) {
            return Err(OptionError::leading(
                "tolerances",
                format!(" must each be in (0, 1), got {bad}"),
            )
            .into());
        }
        if v.is_empty() {
            return Err(OptionError::leading("tolerances", " lists no tolerance").into());
        }
        plan.tolerances = v.clone();
    }
    plan.jobs = o.jobs.unwrap_or(1);
    let out = o.out.clone().unwrap_or_else(|| {
        PathBuf::from("out").join(if o.quick {
            "extremes-quick"
        } else {
            "extremes"
        })
    });
    crate::store::claim::remove_dead_temporaries(&out);
    let cache = RunCache::new(&out.join(CACHE_DIR));
    let m = extremes::runner::run_cached(&plan, Some(&cache), progress)?;
    let files = m.write(&out)?;
    Ok(Written {
        result: m,
        dir: out,
        files,
    })
}
