//! The engine's commands: plain options in, typed results and written files out. Each front
//! end (the `lash` command line, a Python binding) fills the options and shows the results;
//! nothing here parses arguments, prints or knows about terminals.
//!
//! ```text
//! default_run(out, progress)            → Written<Headline>     (module headline)
//! run(RunOptions, progress)             → Written<RunResult>    summary.json, trajectory.csv
//!                                                               (streamed), figures; on a
//!                                                               solver failure failure.json,
//!                                                               partial_trajectory.csv
//! study_paper(StudyOptions, progress)   → Written<StudyResult>  figures, report.md, study.json
//! compare(CompareOptions, progress)     → Written<Comparison>   compare.md, compare.json
//! work_precision(WorkPrecisionOptions, progress) → Written<WorkPrecisionResult>
//! sweep(SweepRunOptions, progress)      → SweepOutcome          one result.json per point
//! merge(MergeOptions)                   → Merged                merged.csv, merged.md
//! stiffness(StiffnessOptions, progress) → Written<StiffnessResult>
//! poincare(PoincareOptions, progress)   → Written<PoincareResult>
//! extremes(ExtremesOptions, progress)   → Written<Matrix>       extremes.md, extremes.json
//! animate(AnimateOptions)               → Written<Animated>     RUN_DIR/animation.html
//! animate_in_memory(scene, columns, title, AnimateOptions) → String   the same page, in memory
//! plot(PlotOptions)                     → Written<()>           a figure of trajectory columns
//! out = the option, else default_out(COMMAND, case name) = out/COMMAND/NAME
//! ```
//!
//! Progress ([`Progress`]) gets the notes a command makes while it works (the reference of a
//! comparison, a derived RK4 step, runs reused from a cache) and every long command's work
//! as batches of items (a sweep's points, a study's runs, the extremes matrix's references
//! and runs, a comparison's reference and runs, a diagnostic's phases). A stop request
//! (`lash_solver::interrupt`, raised by SIGINT or SIGTERM in `lash`) ends every command with
//! [`Error::Interrupted`]: the item in flight abandoned, finished items kept (a sweep's
//! points, the study's and the extremes matrix's caches of finished runs). Errors are typed ([`Error`]); those about options name them by the engine's names.
//!
//! Source: docs/outputs.md ("Files each command writes"); ARCHITECTURE.md ("Invariants": one
//! engine behind every front end, knowing no command line).

use std::path::PathBuf;

pub(crate) mod compare;
pub(crate) mod diagnose;
pub(crate) mod run;
pub(crate) mod study;
pub(crate) mod sweep;
pub(crate) mod viz;

/// Default output directory of a command for a case: `out/COMMAND/NAME` (a `:` in a built-in
/// name becomes `_`).
pub(crate) fn default_out(command: &str, name: &str) -> PathBuf {
    PathBuf::from("out")
        .join(command)
        .join(name.replace(':', "_"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_out_is_per_command_and_case() {
        assert_eq!(
            default_out("run", "testset:hires"),
            PathBuf::from("out/run/testset_hires")
        );
    }
}
