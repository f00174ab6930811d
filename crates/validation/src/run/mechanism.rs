//! A run of a mechanism (a scene): the observer that writes the trajectory's rows, samples
//! the metrics window and the extra times, searches the extrema on the dense output,
//! integrates the power terms and records the events; then the metrics and the summary.
//!
//! Source: docs/outputs.md (`metrics`, the energy balance); docs/model.md §1.8.

use lash_model::scene::JointSpec;
use lash_model::{LawRangeMonitor, Mechanism, Outputs, PowerTerms, Scene};
use lash_solver::{EventHit, OdeSystem, Solution, SolveError, WithQuadrature};

use crate::error::Error;
use crate::report::metrics::Window;
use crate::report::metrics::{
    self, DenseExtremes, EnergyTotals, EventQuantity, EventRecord, JointExtremes, Peaks, Sample,
    GRID_POINTS,
};
use crate::report::trajectory::{Columns, Header, TrajectorySink};
use crate::run::drive::checked_power;
use crate::run::drive::drive;
use crate::run::drive::empty_solution;
use crate::run::drive::finite_powers;
use crate::run::drive::Observer;
use crate::run::drive::PowerFn;
use crate::run::plan::check_times;
use crate::run::plan::options_within;
use crate::run::plan::plan_run;
use crate::run::plan::Grid;
use crate::run::plan::RunRequest;
use crate::run::prepare::scene_error;
use crate::run::prepare::Prepared;
use crate::run::prepare::QUADRATURE_PANEL_PER_PERIOD;
use crate::run::quadrature::{own_quadrature, step_ends, Own, Powers, Quadrature, TERMS};
use crate::run::result::RunResult;
use crate::run::sample::fixed_values;
use crate::run::sample::Sampler;
use crate::run::state_tolerance::state_tolerance;
use crate::run::window::{whole, CrankTrack, WindowPlan};

/// Output lists of a mechanism run, merged in time order.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum List {
    Window,
    Trajectory,
    Extra,
}

/// The observer of a mechanism run (module doc): rows into the sink, samples of the window
/// and at the extra times, the extrema over the dense output, the energy quadrature, events.
struct MechanismRun<'a> {
    mech: &'a Mechanism,
    sampler: Sampler<'a>,
    header: Header,
    sink: &'a mut dyn TrajectorySink,
    row: Vec<f64>,
    // The three output lists, merged lazily.
    wgrid: Vec<f64>,
    tgrid: Grid,
    extra_times: &'a [f64],
    idx: [usize; 3],
    t0: f64,
    t_end: f64,
    // The crank at the step ends (the first pass of a motor-driven crank's last revolution).
    track: Option<CrankTrack>,
    window: Vec<Sample>,
    extra: Vec<Sample>,
    // The absolute state (q, q̇) of the integrated bodies at the extra times (the same for
    // every formulation: docs/model.md §12), and the scene indices of those bodies.
    extra_states: Solution,
    int_bodies: Vec<usize>,
    rows: usize,
    // Extrema over the window's dense output [w0, w1].
    w0: f64,
    w1: f64,
    peaks: Peaks,
    cv_max: f64,
    has_slider: bool,
    n_clr: usize,
    // Energy.
    quad: Option<Quadrature>,
    power: Option<PowerFn<'a>>,
    // Events.
    names: Vec<(&'static str, Option<usize>)>,
    keep_events: bool,
    events: Vec<EventRecord>,
    ybuf: Vec<f64>,
    // The ranges of the clearance joints' laws, at every accepted step's end.
    laws: LawRangeMonitor,
    // The last output's evaluation (t, y, outputs): a row at the time of a window sample
    // (the same t and y) reuses it.
    last_output: Option<(f64, Vec<f64>, Outputs)>,
    // The evaluations at the quadrature's nodes of the current step inside the window
    // (t, outputs): the extrema's samples at the same times reuse them (the dense output is
    // the step's, so the same t is the same y).
    nodes: Vec<(f64, Outputs)>,
}

/// The power terms in the quadrature's order (Quadrature's `total`).
fn power_array(p: &PowerTerms) -> Powers {
    [
        p.driver,
        p.contact_damping,
        p.friction,
        p.film,
        p.load,
        p.motor,
        p.damper,
    ]
}

impl MechanismRun<'_> {
    fn next(&self) -> Option<(f64, List)> {
        let w = self.wgrid.get(self.idx[0]).map(|&t| (t, List::Window));
        let tr =
            (self.idx[1] < self.tgrid.n).then(|| (self.tgrid.time(self.idx[1]), List::Trajectory));
        let x = self.extra_times.get(self.idx[2]).map(|&t| (t, List::Extra));
        [w, tr, x]
            .into_iter()
            .flatten()
            .fold(None, |best: Option<(f64, List)>, c| match best {
                Some(b) if b.0 <= c.0 => Some(b),
                _ => Some(c),
            })
    }

    /// The quantities whose extrema the metrics take (module doc): slider a and −a, then per
    /// clearance joint ε, δ, F_N, |F_film|.
    fn quantities(&mut self, o: &Outputs) -> Result<Vec<f64>, Error> {
        let mut v = Vec::with_capacity(2 + 4 * self.n_clr);
        if self.has_slider {
            let a = o.slider_a.unwrap_or(f64::NAN);
            v.extend([a, -a]);
        }
        for c in &o.clearance {
            v.extend([c.eps, c.delta, c.contact_force, c.film_force.abs()]);
        }
        if v.iter().any(|x| !x.is_finite()) || !o.constraint_violation.is_finite() {
            return Err(Error::Internal(format!(
                "metrics: a non-finite output on the dense output: {v:?}, ‖Φ‖ = {}",
                o.constraint_violation
            )));
        }
        self.cv_max = self.cv_max.max(o.constraint_violation);
        Ok(v)
    }

    fn dense_extremes(&self, scene: &Scene) -> DenseExtremes {
        let m = self.peaks.max();
        let found = |x: f64| x.is_finite().then_some(x);
        let (slider_acc, off) = if self.has_slider {
            (found(-m[1]).zip(found(m[0])), 2)
        } else {
            (None, 0)
        };
        let joints = scene
            .joints
            .iter()
            .filter_map(|j| match j {
                JointSpec::Clearance(c) => Some(c),
                _ => None,
            })
            .enumerate()
            .map(|(k, c)| {
                let q = &m[off + 4 * k..off + 4 * k + 4];
                JointExtremes {
                    name: c.name.clone(),
                    clearance: c.bearing.radius - c.journal.radius,
                    lubricated: c.film.is_some(),
                    eps_max: q[0],
                    delta_max: q[1],
                    contact_force_max: q[2],
                    film_force_max: q[3],
                }
            })
            .collect();
        DenseExtremes {
            slider_acc,
            constraint_violation_max: self.cv_max,
            joints,
        }
    }
}

impl Observer for MechanismRun<'_> {
    fn next_time(&self) -> Option<f64> {
        // The metrics grid may start a few ulps before t0 (t_end − T): clamp into the run.
        self.next().map(|(t, _)| t.clamp(self.t0, self.t_end))
    }

    fn output(&mut self, _t: f64, y: &[f64]) -> Result<(), Error> {
        let Some((t_req, list)) = self.next() else {
            return Err(Error::Internal(
                "an output past the last requested time".into(),
            ));
        };
        let reuse = matches!(&self.last_output, Some((t, ys, _)) if *t == t_req && ys == y);
        if !reuse {
            let o = self.mech.outputs(t_req, y);
            let mut ys = self.last_output.take().map(|l| l.1).unwrap_or_default();
            ys.clear();
            ys.extend_from_slice(y);
            self.last_output = Some((t_req, ys, o));
        }
        let Some((_, _, o)) = &self.last_output else {
            return Err(Error::Internal("an output without its evaluation".into()));
        };
        let s = self.sampler.of_outputs(t_req, o);
        match list {
            List::Window => {
                self.window.push(s);
                self.idx[0] += 1;
            }
            List::Extra => {
                self.extra_states.t.push(t_req);
                let b = &o.bodies;
                let st = &mut self.extra_states.y;
                st.extend(
                    self.int_bodies
                        .iter()
                        .flat_map(|&k| [b[k].x, b[k].y, b[k].theta]),
                );
                st.extend(
                    self.int_bodies
                        .iter()
                        .flat_map(|&k| [b[k].vx, b[k].vy, b[k].omega]),
                );
                self.extra.push(s);
                self.idx[2] += 1;
            }
            List::Trajectory => {
                self.row.clear();
                self.row.extend(fixed_values(&s));
                o.column_values(&mut self.row);
                self.header.check(&self.row)?;
                self.sink.row(&self.row)?;
                self.rows += 1;
                self.idx[1] += 1;
            }
        }
        Ok(())
    }

    fn step(
        &mut self,
        ta: f64,
        tb: f64,
        cut: bool,
        y: &[f64],
        own: Option<Own>,
        dense: &dyn Fn(f64, &mut [f64]),
    ) -> Result<(), Error> {
        self.laws
            .observe(self.mech, tb, y)
            .map_err(|v| law_out_of_range(tb, y, &v))?;
        let in_window = tb >= self.w0 && ta <= self.w1;
        self.nodes.clear();
        if let (Some(q), Some(pw)) = (self.quad.as_mut(), self.power) {
            let buf = &mut self.ybuf;
            let mech = self.mech;
            let nodes = &mut self.nodes;
            let mut node = |t: f64| -> Result<Powers, Error> {
                dense(t, buf);
                let p = if in_window {
                    // One evaluation for the power and the extrema's sample at t.
                    let (o, p) = mech.outputs_and_power(t, buf);
                    nodes.push((t, o));
                    finite_powers(power_array(&p), t)
                } else {
                    checked_power(pw, t, buf)
                };
                p.map_err(|e| singular_or(mech, e, t, buf, (ta, tb)))
            };
            q.step(ta, tb, cut, own, &mut node)?;
        }
        if let Some(tr) = self.track.as_mut() {
            let o = self.mech.outputs(tb, y);
            if let (Some(phi), Some(rate)) = (o.crank_angle, o.crank_rate) {
                tr.push(tb, phi, rate);
            }
        }
        if in_window {
            let (a, b) = (ta.max(self.w0), tb.min(self.w1));
            let mut peaks = std::mem::replace(&mut self.peaks, Peaks::new(0));
            let mut buf = std::mem::take(&mut self.ybuf);
            let nodes = std::mem::take(&mut self.nodes);
            let r = peaks.step(a, b, &mut |t| {
                let fresh;
                let o = match nodes.iter().find(|n| n.0 == t) {
                    Some((_, o)) => o,
                    None => {
                        dense(t, &mut buf);
                        fresh = self.mech.outputs(t, &buf);
                        &fresh
                    }
                };
                self.quantities(o).map_err(|e| {
                    dense(t, &mut buf);
                    singular_or(self.mech, e, t, &buf, (ta, tb))
                })
            });
            self.nodes = nodes;
            self.ybuf = buf;
            self.peaks = peaks;
            r?;
        }
        Ok(())
    }

    fn event(&mut self, h: EventHit) {
        if !self.keep_events && h.t < self.w0 {
            return;
        }
        let (kind, joint) = self.names.get(h.index).copied().unwrap_or(("", None));
        let quantity = match kind {
            "contact" => EventQuantity::Penetration,
            "eps_cap" => EventQuantity::FilmCap,
            _ => EventQuantity::Other,
        };
        self.events.push(EventRecord {
            t: h.t,
            quantity,
            rising: h.rising,
            joint,
            index: h.index,
        });
    }
}

/// A non-finite output at a finite state inside an accepted step [ta, tb] (the dense output
/// at t): a singular configuration the step jumped over when the acceleration solve fails
/// there (exit 3), else `e` (a bug).
pub(crate) fn singular_or(
    mech: &Mechanism,
    e: Error,
    t: f64,
    y: &[f64],
    (ta, tb): (f64, f64),
) -> Error {
    if y.iter().all(|v| v.is_finite()) && !mech.acceleration_solvable(t, y) {
        // The same kind and wording as the formulations' check of accepted states
        // (`Mechanism::check_accepted`, docs/model.md §12.1): one error for one situation.
        Error::Solver(SolveError::StateRejected {
            t,
            y: y.to_vec(),
            kind: "singular_configuration",
            reason: format!(
                "singular configuration at t = {t:e} (rank of Φ_q drops inside the accepted \
                 step [{ta:e}, {tb:e}] s: the accelerations and the constraint forces have no \
                 unique value there; the step jumped over the configuration)"
            ),
        })
    } else {
        e
    }
}

/// A right-hand side that is not finite at a finite state where the accelerations have no
/// unique value (`SolveError::NonFiniteState` from a method that evaluates f at an accepted
/// state, RK4's stages, a start) is the singular configuration it is, with the same kind as
/// [`singular_or`]; any other error is returned unchanged.
pub(crate) fn singular_rhs(mech: &Mechanism, e: Error) -> Error {
    match e {
        Error::Solver(SolveError::NonFiniteState { t, y })
            if y.iter().all(|v| v.is_finite()) && !mech.acceleration_solvable(t, &y) =>
        {
            Error::Solver(SolveError::StateRejected {
                t,
                y,
                kind: "singular_configuration",
                reason: format!(
                    "singular configuration at t = {t:e} (rank of Φ_q drops at the state the \
                     integration reached: the accelerations and the constraint forces have no \
                     unique value there)"
                ),
            })
        }
        e => e,
    }
}

/// The solver failure of a state outside the range of a clearance joint's law (exit 3).
fn law_out_of_range(t: f64, y: &[f64], v: &lash_model::LawRangeViolation) -> Error {
    Error::Solver(SolveError::LawOutOfRange {
        t,
        y: y.to_vec(),
        reason: v.to_string(),
    })
}

pub(crate) fn simulate_mechanism(
    p: &Prepared,
    scene: &Scene,
    req: &RunRequest,
    t0: f64,
    t_end: f64,
    sink: &mut dyn TrajectorySink,
) -> Result<RunResult, Error> {
    let window = match p.window_plan(req.window, t0, t_end)? {
        WindowPlan::Known(w) => w,
        WindowPlan::CrankTurn => {
            // The first pass (crate::run::window): the same run without energy, trajectory,
            // extra times or events; only the crank's last turn is kept.
            let mut probe = req.clone();
            probe.trajectory_points = Some(0);
            probe.output_every = None;
            probe.extra_times.clear();
            probe.energy = false;
            probe.keep_events = false;
            let mut none = Columns::new();
            let (_, track) = pass(
                p,
                scene,
                &probe,
                t0,
                t_end,
                (whole(t0, t_end), true),
                &mut none,
            )?;
            match track.and_then(|t| t.last_turn_start()) {
                Some(ts) => Window {
                    t_end,
                    period: t_end - ts,
                },
                None => whole(t0, t_end),
            }
        }
    };
    Ok(pass(p, scene, req, t0, t_end, (window, false), sink)?.0)
}

/// The scene a run with `method` builds: the paper's method stays the paper's
/// (docs/model.md §12, §7) — fixed-step RK4 on a scene whose formulation is `auto` runs
/// `lagrange_baumgarte`, and on a scene that leaves `kink_events` to the automatic choice runs
/// without kink events, as Peng et al. did (a run without event location only counts their
/// crossings; its numbers are the same either way, crates/validation/src/run/tests/kinks.rs);
/// every other choice is the scene's.
pub(crate) fn paper_formulation(scene: &Scene, method: lash_solver::Method) -> Scene {
    if method == lash_solver::Method::Rk4 {
        paper_scene(scene)
    } else {
        scene.clone()
    }
}

/// `scene` as the paper computed it: `auto` runs `lagrange_baumgarte`, and a scene that leaves
/// `kink_events` to the automatic choice runs without them; what the scene states is kept.
/// For the paper's RK4 ([`paper_formulation`]) and every run of the paper's study.
pub(crate) fn paper_scene(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    if s.formulation == lash_model::FormulationName::Auto {
        s.formulation = lash_model::FormulationName::LagrangeBaumgarte;
    }
    s.kink_events.get_or_insert(false);
    s
}

/// One pass of a mechanism run over [t0, t_end] with its metrics window; `track`: keep the
/// crank's last turn (crate::run::window).
fn pass(
    p: &Prepared,
    scene: &Scene,
    req: &RunRequest,
    t0: f64,
    t_end: f64,
    (window, track): (Window, bool),
    sink: &mut dyn TrajectorySink,
) -> Result<(RunResult, Option<CrankTrack>), Error> {
    let info = p
        .info
        .as_ref()
        .ok_or_else(|| Error::Internal("mechanism without info".into()))?;
    check_times(&req.extra_times, t0, t_end)?;
    let tgrid = plan_run(p, req, t0, t_end)?;
    options_within(req, t0, &[])?;
    let mech = Mechanism::from_scene(&paper_formulation(scene, req.opts.method))
        .map_err(|e| scene_error(&p.case, e))?;
    mech.reset_formulation_stats();
    let opts = &options_within(req, t0, &mech.initial_state())?;
    let sampler = Sampler::new(&mech, scene);
    let header = Header::new(sampler.fixed_present(), mech.output_columns())?;
    sink.start(&header)?;
    let y0 = mech.initial_state();
    let n = y0.len();
    let clr_names = mech.clearance_names();
    let names: Vec<(&'static str, Option<usize>)> = (0..mech.n_events())
        .map(|i| match mech.event_name(i) {
            Some((kind, j)) => (kind, clr_names.iter().position(|c| *c == j)),
            None => ("", None),
        })
        .collect();
    let power = |t: f64, y: &[f64]| power_array(&mech.power(t, y));
    let power_ref: PowerFn<'_> = &power;
    let max_panel = info
        .period
        .map_or(f64::INFINITY, |t| t * QUADRATURE_PANEL_PER_PERIOD);
    let quad = if req.energy {
        let q = Quadrature::new(
            opts.method.is_fixed_step(),
            max_panel,
            t0,
            checked_power(power_ref, t0, &y0)?,
        );
        Some(if step_ends(opts.method) {
            q.on_step_ends()
        } else {
            q
        })
    } else {
        None
    };
    let has_slider = mech.roles().slider.is_some();
    let n_clr = clr_names.len();
    let n_q = if has_slider { 2 } else { 0 } + 4 * n_clr;
    let w0 = window.t_end - window.period;
    let int_bodies: Vec<usize> = mech
        .integrated_bodies()
        .iter()
        .filter_map(|name| scene.bodies.iter().position(|b| b.name == *name))
        .collect();
    let n_abs = 6 * int_bodies.len();
    let mut obs = MechanismRun {
        mech: &mech,
        sampler,
        header,
        sink,
        row: Vec::new(),
        wgrid: metrics::grid(window.t_end, window.period),
        tgrid,
        extra_times: &req.extra_times,
        idx: [0; 3],
        t0,
        t_end,
        track: track.then(CrankTrack::default),
        window: Vec::with_capacity(GRID_POINTS),
        extra: Vec::with_capacity(req.extra_times.len()),
        extra_states: empty_solution(n_abs),
        int_bodies,
        rows: 0,
        w0,
        w1: window.t_end,
        peaks: Peaks::new(n_q),
        cv_max: 0.0,
        has_slider,
        n_clr,
        quad,
        power: req.energy.then_some(power_ref),
        names,
        keep_events: req.keep_events,
        events: Vec::new(),
        ybuf: vec![0.0; n],
        laws: LawRangeMonitor::new(&mech),
        last_output: None,
        nodes: Vec::new(),
    };
    obs.laws
        .observe(&mech, t0, &y0)
        .map_err(|v| law_out_of_range(t0, &y0, &v))?;
    let start = mech.outputs(t0, &y0);
    if let (Some(tr), Some(phi), Some(rate)) =
        (obs.track.as_mut(), start.crank_angle, start.crank_rate)
    {
        tr.push(t0, phi, rate);
    }
    // The power terms as the system's quadrature: the method integrates them at its own
    // stages (crate::run::quadrature), out of its error norm.
    let q = |t: f64, y: &[f64], out: &mut [f64]| out.copy_from_slice(&power(t, y));
    let sys = WithQuadrature {
        sys: &mech,
        m: if req.energy && own_quadrature(opts.method) {
            TERMS
        } else {
            0
        },
        q: &q,
    };
    let d = drive(&sys, t0, t_end, &y0, opts, &mut obs).map_err(|e| singular_rhs(&mech, e))?;
    // The window's grid samples are samples of the extrema too.
    let mut dense = obs.dense_extremes(scene);
    for s in &obs.window {
        if let (Some(a), Some((lo, hi))) = (s.slider_a, dense.slider_acc.as_mut()) {
            *lo = lo.min(a);
            *hi = hi.max(a);
        }
    }
    let mut extra_states = std::mem::replace(&mut obs.extra_states, empty_solution(n_abs));
    extra_states.stats = d.stats;
    extra_states.t_final = d.t_final;
    extra_states.y_final = d.y_final.clone();
    let end = mech.outputs(d.t_final, &d.y_final);
    // Read before the state tolerance's evaluations, which would count in them.
    let formulation_stats = mech.formulation_stats();
    let energy = match obs.quad.as_mut() {
        Some(q) => {
            q.finish();
            let o0 = &start;
            let o1 = &end;
            Some(EnergyTotals {
                driver_work: q.total[0],
                kinetic_change: o1.kinetic_energy - o0.kinetic_energy,
                potential_change: o1.potential_energy - o0.potential_energy,
                dissipated_damping: q.total[1],
                dissipated_friction: q.total[2],
                dissipated_film: q.total[3],
                load_work: q.total[4],
                motor_work: q.total[5],
                dissipated_damper: q.total[6],
                element_potential_change: o1.elements.iter().map(|e| e.potential).sum::<f64>()
                    - o0.elements.iter().map(|e| e.potential).sum::<f64>(),
                quadrature_error: q.err.iter().sum(),
                state_tolerance: state_tolerance(&mech, opts, (t0, &y0), (d.t_final, &d.y_final)),
            })
        }
        None => None,
    };
    let metrics = metrics::compute(
        &obs.window,
        window,
        info.joint,
        &obs.events,
        energy,
        Some(&dense),
    )?;
    let mut summary = d.summary(p, opts, t_end);
    summary.metrics = Some(metrics);
    summary.formulation = Some(mech.formulation_name().to_string());
    summary.kink_events = Some(mech.kink_events());
    summary.formulation_stats = formulation_stats;
    summary.law_range = (!obs.laws.is_empty()).then(|| obs.laws.records().to_vec());
    summary.metrics_window = Some([window.t_end - window.period, window.t_end]);
    summary.crank_revolutions = start
        .crank_angle
        .zip(end.crank_angle)
        .map(|(a, b)| (b - a) / std::f64::consts::TAU);
    let result = RunResult {
        summary,
        window: std::mem::take(&mut obs.window),
        trajectory: Columns::new(),
        trajectory_rows: obs.rows,
        extra: std::mem::take(&mut obs.extra),
        extra_states,
        events: std::mem::take(&mut obs.events),
        event_names: info.event_names.clone(),
        ideal: obs.sampler.ideal,
    };
    Ok((result, obs.track.take()))
}
