//! The analysis of one case: the reference run sampled, the limit measured from the predicted
//! one, the report built.
//!
//! Source: the module doc of `diagnostics::stiffness`.

use std::time::Instant;

use lash_model::Mechanism;
use lash_solver::analysis::stiffness::StiffnessOptions;
use lash_solver::{Method, OdeSystem, SolverOptions};

use crate::diagnostics::stiffness::report::build_report;
use crate::diagnostics::stiffness::report::predicted_min;
use crate::diagnostics::stiffness::report::StiffnessResult;
use crate::diagnostics::stiffness::sample::measure_limit;
use crate::diagnostics::stiffness::sample::phi_max;
use crate::diagnostics::stiffness::sample::sample_along;
use crate::diagnostics::stiffness::sample::Measurement;
use crate::diagnostics::stiffness::sample::Sampled;
use crate::diagnostics::stiffness::sample::StiffnessSettings;
use crate::diagnostics::stiffness::sample::MIN_SAMPLES;
use crate::error::{Error, OptionError};
use crate::progress::Progress;
use crate::run::plan::uniform_grid;
use crate::run::prepare::scene_error;
use crate::run::prepare::{Model, Prepared};
use crate::run::sample::Sampler;

/// Runs the analysis of a prepared case with solver options `opts` (the reference run);
/// `progress` gets its phases as items (the eigenvalues along the run, then the measured RK4
/// limit).
pub(crate) fn analyse(
    p: &Prepared,
    opts: &SolverOptions,
    settings: &StiffnessSettings,
    progress: &dyn Progress,
) -> Result<StiffnessResult, Error> {
    if settings.samples < MIN_SAMPLES {
        return Err(OptionError::leading(
            "samples",
            format!(" must be >= {MIN_SAMPLES}, got {}", settings.samples),
        )
        .into());
    }
    let t_span = p.t_span(settings.t_end)?;
    let times = uniform_grid(t_span.0, t_span.1, settings.samples);
    let sopts = StiffnessOptions::default();
    progress.started("phases", 1 + usize::from(settings.measure));
    let clock = Instant::now();
    let sampled_done = |n: usize| {
        progress.finished(
            &format!("reference run with the eigenvalues of ∂f/∂y at {n} points"),
            clock.elapsed().as_secs_f64(),
        );
        Instant::now()
    };
    let measured_done = |since: Instant| {
        if settings.measure {
            progress.finished(
                "RK4 step limit measured by bisection",
                since.elapsed().as_secs_f64(),
            );
        }
    };
    // The measured limit is the largest step that `lash run --method rk4` accepts: the probe
    // runs keep the case's own RK4 stability check (`rk4_instability_steps`, on for
    // mechanisms: h·ρ from the stages confirmed by the eigenvalues) on top of growth and the
    // constraint check, so that stiffness and run give one answer (issue 22). Without it the
    // bisection found spurious bounded solutions stable (8.9e-5 s where run stops at 2.3e-5 s).
    let rk4_base = |guess: f64| -> Result<SolverOptions, Error> {
        p.options_for(Method::Rk4, None, Some(guess), None)
    };
    let mut formulation = None;
    let (sampled, measurement, analytic) = match &p.model {
        Model::Mechanism(scene) => {
            let build = || Mechanism::from_scene(scene).map_err(|e| scene_error(&p.case, e));
            let mech = build()?;
            formulation = Some(mech.formulation_name().to_string());
            let sampler = Sampler::new(&mech, scene);
            let y0 = mech.initial_state();
            let angle = |t: f64, y: &[f64]| sampler.sample(t, y).crank_angle;
            let sampled = sample_along(&mech, t_span, &y0, opts, &times, &sopts, &angle)?;
            let since = sampled_done(sampled.points.len());
            let analytic = mech.has_jacobian();
            let phi_max = phi_max(p);
            let m = measure(&sampled, settings, |guess| {
                // A fresh mechanism: the probe runs start from the scene's initial hook state.
                let fresh = build()?;
                let valid = |t: f64, y: &[f64]| fresh.outputs(t, y).constraint_violation <= phi_max;
                measure_limit(
                    &fresh,
                    t_span,
                    &y0,
                    &rk4_base(guess)?,
                    guess,
                    &settings.probe,
                    &valid,
                )
            })?;
            measured_done(since);
            (sampled, m, analytic)
        }
        Model::TestSet(_) => {
            let prob = p
                .test_problem()
                .ok_or_else(|| Error::Internal("not a test problem".into()))?;
            let sys = &*prob.system;
            let none = |_: f64, _: &[f64]| None;
            let sampled = sample_along(sys, t_span, &prob.y0, opts, &times, &sopts, &none)?;
            let since = sampled_done(sampled.points.len());
            let m = measure(&sampled, settings, |guess| {
                measure_limit(
                    sys,
                    t_span,
                    &prob.y0,
                    &rk4_base(guess)?,
                    guess,
                    &settings.probe,
                    &|_, _| true,
                )
            })?;
            measured_done(since);
            (sampled, m, sys.has_jacobian())
        }
    };
    let mut report = build_report(p, opts, settings, t_span, &sampled, measurement, analytic)?;
    report.formulation = formulation;
    Ok(StiffnessResult {
        report,
        points: sampled.points,
    })
}

/// The measurement, started from the predicted limit (else the accuracy step), or a note.
fn measure<F>(sampled: &Sampled, settings: &StiffnessSettings, run: F) -> Result<Measurement, Error>
where
    F: FnOnce(f64) -> Result<Measurement, Error>,
{
    if !settings.measure {
        return Ok(Measurement {
            limit: None,
            note: Some("not measured (measure off)".into()),
            brackets: 0,
            wall_time_s: 0.0,
        });
    }
    let guess = predicted_min(&sampled.points)
        .map(|(_, h)| h)
        .or_else(|| sampled.median_step());
    match guess {
        Some(g) => run(g),
        None => Ok(Measurement {
            limit: None,
            note: Some("not measured: no step to start the bracket from".into()),
            brackets: 0,
            wall_time_s: 0.0,
        }),
    }
}
