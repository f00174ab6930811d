//! Parameter sweeps: a grid of points over a base case, run in parallel, resumable, shardable,
//! and merged into one table.
//!
//! ```text
//! SWEEP.json = { "case": PATH | "testset:NAME",            (PATH relative to the sweep file)
//!                "speed_rpm": [..], "clearance": [..], "viscosity": [..], "stiffness": [..],
//!                "method": [..], "rtol": [..] (alias "tolerance"), "step": [..],
//!                "controller": [..] }                      (every list optional, none empty)
//! grid   = speed × clearance × viscosity × stiffness × solver choices, in that order, where
//!          solver choices = for each method: fixed-step → step list;
//!                                             diffsol   → rtol list;
//!                                             ours      → rtol × controller
//! id     = first 16 hex digits of sha256(canonical JSON of the point's parameters)
//!          (keys sorted, absent parameters left out, the base case by name and file sha256)
//! shard I/N = the points with index mod N = I
//! OUT/points.json      the whole grid (index, id, parameters), so merge can name what is missing
//! OUT/id/claim.json    created exclusively by the process that runs the point, removed when it
//!                      ends (module claim): concurrent processes never run one point twice
//! OUT/id/result.json   written atomically when the point finishes (ok or solver failure);
//!                      its presence means "done", so a rerun skips the point
//! stop requested       (SIGINT, SIGTERM: lash_solver::interrupt) no new point starts; the
//!                      point in flight is abandoned and its files removed; finished ones stay
//! merge(DIR...) = the result.json files found → one table (CSV + markdown); the points of the
//!                 manifests without a result are unfinished, unreadable results corrupt
//! ```
//!
//! Source: docs/outputs.md ("Sweeps").

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Mutex;
use std::time::Instant;

use lash_model::scene::{JointSpec, NormalSpec};
use lash_model::Scene;
use lash_solver::{ControllerKind, Method, OptionField};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::Error;
use crate::progress::{self, NoProgress, Progress};
use crate::run::case::{sha256_hex, Case};
use crate::store::claim;
use crate::store::io;

/// Name of the result file of a point.
pub const RESULT_FILE: &str = "result.json";

/// A slice of a grid for one machine of a job array.
///
/// ```text
/// shard I/N selects the points with index mod N = I,  0 ≤ I < N
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// I, counting from 0.
    pub index: usize,
    /// N ≥ 1.
    pub count: usize,
}

impl Shard {
    /// The whole grid (0/1).
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Whether the point with this index belongs to the shard.
    pub fn contains(&self, point_index: usize) -> bool {
        point_index % self.count == self.index
    }
}

impl FromStr for Shard {
    type Err = Error;
    fn from_str(s: &str) -> Result<Shard, Error> {
        let bad = || Error::Usage(format!("shard must be I/N with 0 <= I < N, got '{s}'"));
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The contents of SWEEP.json.
///
/// ```text
/// grid = speed_rpm × clearance × viscosity × stiffness × (method-dependent solver choices)
/// ```
///
/// Source: docs/outputs.md ("Sweeps": the sweep file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// The base case: a scene file (relative to the sweep file) or `testset:NAME`.
    pub case: String,
    /// Crank speeds, rpm; each > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_rpm: Option<Vec<f64>>,
    /// Radial clearances c, m; each > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clearance: Option<Vec<f64>>,
    /// Lubricant viscosities μ, Pa·s; each > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viscosity: Option<Vec<f64>>,
    /// Contact stiffnesses K, N/m^1.5; each > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<Vec<f64>>,
    /// Methods (names of docs/outputs.md, "Method and controller names").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<Vec<Method>>,
    /// Relative tolerances of adaptive methods; each in the solver's range
    /// (`lash_solver::Rule::RTOL`).
    #[serde(default, alias = "tolerance", skip_serializing_if = "Option::is_none")]
    pub rtol: Option<Vec<f64>>,
    /// Fixed steps of fixed-step methods, s; each > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<Vec<f64>>,
    /// Controllers of our adaptive methods (names of docs/outputs.md, "Method and controller
    /// names").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub controller: Option<Vec<ControllerKind>>,
}

/// The parameters of one grid point; `None` means "as in the base case".
///
/// ```text
/// id = hex(sha256(canonical_json(self)))[..16]
/// ```
///
/// Source: docs/outputs.md ("Sweeps": a directory named by a stable hash of its parameters).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointParams {
    /// The base case's name (file stem or `testset:NAME`).
    pub case: String,
    /// sha256 of the base case file (None for built-ins).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_sha256: Option<String>,
    /// Crank speed, rpm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_rpm: Option<f64>,
    /// Radial clearance, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clearance: Option<f64>,
    /// Viscosity, Pa·s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viscosity: Option<f64>,
    /// Contact stiffness, N/m^1.5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Method.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<Method>,
    /// Relative tolerance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rtol: Option<f64>,
    /// Fixed step, s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// Controller.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub controller: Option<ControllerKind>,
}

/// Parameter columns of the merged table, in order.
const PARAM_COLUMNS: [&str; 10] = [
    "case",
    "scene_sha256",
    "speed_rpm",
    "clearance",
    "viscosity",
    "stiffness",
    "method",
    "rtol",
    "step",
    "controller",
];

impl PointParams {
    /// The canonical JSON text: keys sorted at every level, no whitespace, absent parameters
    /// left out, numbers in serde_json's shortest round-trip form.
    pub fn canonical_json(&self) -> String {
        let v = serde_json::to_value(self).unwrap_or(Value::Null);
        canonical(&v)
    }

    /// The stable id: the first 16 hex digits of sha256 of [`PointParams::canonical_json`].
    pub fn id(&self) -> String {
        sha256_hex(self.canonical_json().as_bytes())[..16].to_string()
    }
}

/// Serialises a JSON value with object keys sorted at every level.
pub fn canonical(v: &Value) -> String {
    match v {
        Value::Object(m) => {
            let mut keys: Vec<&String> = m.keys().collect();
            keys.sort();
            let parts: Vec<String> = keys
                .into_iter()
                .map(|k| format!("{}:{}", Value::String(k.clone()), canonical(&m[k])))
                .collect();
            format!("{{{}}}", parts.join(","))
        }
        Value::Array(a) => {
            let parts: Vec<String> = a.iter().map(canonical).collect();
            format!("[{}]", parts.join(","))
        }
        other => other.to_string(),
    }
}

/// One grid point.
///
/// ```text
/// (index, id = PointParams::id(), params);  shard I/N runs it iff index mod N = I
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPoint {
    /// Position in the grid (0-based), the index sharding uses.
    pub index: usize,
    /// Its stable id (directory name).
    pub id: String,
    /// Its parameters.
    pub params: PointParams,
}

/// A loaded and checked sweep: the file, its base case, its grid.
///
/// ```text
/// SWEEP.json + base case → points() = the grid of the module doc
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Clone, Debug)]
pub struct SweepSpec {
    /// The parsed file.
    pub file: SweepFile,
    /// The base case.
    pub case: Case,
}

impl SweepSpec {
    /// Reads and checks a sweep file; the base case is resolved relative to its directory.
    pub fn load(path: &Path) -> Result<SweepSpec, Error> {
        if !path.is_file() {
            return Err(Error::Input(format!(
                "sweep file {} not found",
                path.display()
            )));
        }
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let file: SweepFile = serde_json::from_slice(&bytes)
            .map_err(|e| Error::Input(format!("sweep file {}: {e}", path.display())))?;
        let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
        SweepSpec::new(file, dir)
    }

    /// Checks a parsed sweep file, resolving the base case relative to `base_dir`.
    pub fn new(file: SweepFile, base_dir: Option<&Path>) -> Result<SweepSpec, Error> {
        check_file(&file)?;
        let case = Case::load(&file.case, base_dir)?;
        Ok(SweepSpec { file, case })
    }

    /// The grid, in its fixed order (see the module doc).
    pub fn points(&self) -> Result<Vec<SweepPoint>, Error> {
        let f = &self.file;
        let opt = |l: &Option<Vec<f64>>| -> Vec<Option<f64>> {
            match l {
                Some(v) => v.iter().copied().map(Some).collect(),
                None => vec![None],
            }
        };
        let solver = solver_choices(f);
        let mut points = Vec::new();
        for &speed_rpm in &opt(&f.speed_rpm) {
            for &clearance in &opt(&f.clearance) {
                for &viscosity in &opt(&f.viscosity) {
                    for &stiffness in &opt(&f.stiffness) {
                        for &(method, rtol, step, controller) in &solver {
                            let params = PointParams {
                                case: self.case.name.clone(),
                                scene_sha256: self.case.sha256().map(str::to_string),
                                speed_rpm,
                                clearance,
                                viscosity,
                                stiffness,
                                method,
                                rtol,
                                step,
                                controller,
                            };
                            points.push(SweepPoint {
                                index: points.len(),
                                id: params.id(),
                                params,
                            });
                        }
                    }
                }
            }
        }
        let ids: BTreeSet<&str> = points.iter().map(|p| p.id.as_str()).collect();
        if ids.len() != points.len() {
            return Err(Error::Internal("two sweep points share an id".into()));
        }
        Ok(points)
    }
}

type SolverChoice = (
    Option<Method>,
    Option<f64>,
    Option<f64>,
    Option<ControllerKind>,
);

fn solver_choices(f: &SweepFile) -> Vec<SolverChoice> {
    let rtols: Vec<Option<f64>> = match &f.rtol {
        Some(v) => v.iter().copied().map(Some).collect(),
        None => vec![None],
    };
    let steps: Vec<Option<f64>> = match &f.step {
        Some(v) => v.iter().copied().map(Some).collect(),
        None => vec![None],
    };
    let ctls: Vec<Option<ControllerKind>> = match &f.controller {
        Some(v) => v.iter().copied().map(Some).collect(),
        None => vec![None],
    };
    let mut out = Vec::new();
    match &f.method {
        None => {
            for &r in &rtols {
                for &c in &ctls {
                    for &s in &steps {
                        out.push((None, r, s, c));
                    }
                }
            }
        }
        Some(methods) => {
            for &m in methods {
                let family = m.info().family;
                if family.takes(OptionField::Step) {
                    for &s in &steps {
                        out.push((Some(m), None, s, None));
                    }
                } else if !family.takes(OptionField::Controller) {
                    for &r in &rtols {
                        out.push((Some(m), r, None, None));
                    }
                } else {
                    for &r in &rtols {
                        for &c in &ctls {
                            out.push((Some(m), r, None, c));
                        }
                    }
                }
            }
        }
    }
    out
}

fn check_file(f: &SweepFile) -> Result<(), Error> {
    let bad = |m: String| Err(Error::Input(format!("sweep: {m}")));
    let lists: [(&str, &Option<Vec<f64>>); 6] = [
        ("speed_rpm", &f.speed_rpm),
        ("clearance", &f.clearance),
        ("viscosity", &f.viscosity),
        ("stiffness", &f.stiffness),
        ("rtol", &f.rtol),
        ("step", &f.step),
    ];
    for (name, l) in lists {
        if let Some(v) = l {
            if v.is_empty() {
                return bad(format!("'{name}' is an empty list"));
            }
            for (i, x) in v.iter().enumerate() {
                if !(x.is_finite() && *x > 0.0) {
                    return bad(format!("{name}[{i}] must be finite and > 0, got {x}"));
                }
                if v[..i].contains(x) {
                    return bad(format!("'{name}' lists {x} twice"));
                }
            }
        }
    }
    if let Some(r) = &f.rtol {
        for x in r {
            if let Err(e) = lash_solver::Rule::RTOL.check(*x) {
                return bad(format!("every {e}"));
            }
        }
    }
    if let Some(m) = &f.method {
        if m.is_empty() {
            return bad("'method' is an empty list".into());
        }
        for (i, a) in m.iter().enumerate() {
            if m[..i].contains(a) {
                return bad(format!("'method' lists {a} twice"));
            }
        }
    }
    if let Some(c) = &f.controller {
        if c.is_empty() {
            return bad("'controller' is an empty list".into());
        }
        for (i, a) in c.iter().enumerate() {
            if c[..i].contains(a) {
                return bad(format!("'controller' lists {a} twice"));
            }
        }
    }
    match &f.method {
        Some(m) => {
            let takes = |m: &Method, field| m.info().family.takes(field);
            let fixed = m.iter().find(|m| takes(m, OptionField::Step));
            if let (Some(fm), None) = (fixed, &f.step) {
                return bad(format!("method {fm} is fixed-step and needs a 'step' list"));
            }
            if f.step.is_some() && fixed.is_none() {
                return bad(
                    "'step' is only for fixed-step methods, and 'method' lists none".into(),
                );
            }
            if f.rtol.is_some() && !m.iter().any(|m| takes(m, OptionField::Rtol)) {
                return bad("'rtol' is only for adaptive methods, and 'method' lists none".into());
            }
            if f.controller.is_some() && !m.iter().any(|m| takes(m, OptionField::Controller)) {
                return bad(
                    "'controller' needs an adaptive method with our step control in 'method'"
                        .into(),
                );
            }
        }
        None => {
            if f.step.is_some() && (f.rtol.is_some() || f.controller.is_some()) {
                return bad(
                    "without 'method', give either 'step' or 'rtol'/'controller', not both".into(),
                );
            }
        }
    }
    Ok(())
}

/// Lays a point's physical parameters over a scene (its typed serde structure).
///
/// ```text
/// speed_rpm  → the crank_driver role's driver: rpm = v (omega dropped)
/// clearance  → every clearance joint (the clearance_joint role's only, if declared):
///              journal radius R_J = R_B − c
/// viscosity  → the film viscosity μ of those joints that have a film
/// stiffness  → the contact stiffness K of their normal law (materials dropped)
/// ```
///
/// A parameter the scene cannot take (no crank driver, no clearance joint, no film) is an
/// input error; the scene is validated again when the point's mechanism is built.
/// Source: docs/outputs.md ("Scene roles"), docs/scene-format.md.
pub fn apply_params(scene: &mut Scene, p: &PointParams) -> Result<(), Error> {
    let bad = |m: &str| Err(Error::Input(format!("sweep: {m}")));
    if let Some(rpm) = p.speed_rpm {
        let Some(name) = scene.roles.crank_driver.clone() else {
            return bad("speed_rpm needs the scene's crank_driver role");
        };
        let driver = scene.joints.iter_mut().find_map(|j| match j {
            JointSpec::Driver(d) if d.name == name => Some(d),
            _ => None,
        });
        let Some(d) = driver else {
            return bad(&format!("the crank_driver role '{name}' is not a driver"));
        };
        d.rpm = Some(rpm);
        d.omega = None;
    }
    if p.clearance.is_none() && p.viscosity.is_none() && p.stiffness.is_none() {
        return Ok(());
    }
    let role = scene.roles.clearance_joint.clone();
    let mut joints: Vec<&mut lash_model::scene::ClearanceSpec> = scene
        .joints
        .iter_mut()
        .filter_map(|j| match j {
            JointSpec::Clearance(c) if role.as_ref().is_none_or(|r| *r == c.name) => Some(c),
            _ => None,
        })
        .collect();
    if joints.is_empty() {
        return bad("clearance, viscosity and stiffness need a clearance joint in the scene");
    }
    if let Some(c) = p.clearance {
        for j in joints.iter_mut() {
            j.journal.radius = j.bearing.radius - c;
        }
    }
    if let Some(mu) = p.viscosity {
        let mut any = false;
        for j in joints.iter_mut() {
            if let Some(f) = j.film.as_mut() {
                f.viscosity = mu;
                any = true;
            }
        }
        if !any {
            return bad("viscosity needs a lubricated clearance joint (one with a film)");
        }
    }
    if let Some(k) = p.stiffness {
        for j in joints.iter_mut() {
            match &mut j.normal {
                NormalSpec::Impact(s) => {
                    s.k = Some(k);
                    s.materials = None;
                }
                NormalSpec::LankaraniNikravesh(s)
                | NormalSpec::Flores(s)
                | NormalSpec::HuntCrossley(s) => {
                    s.k = Some(k);
                    s.materials = None;
                }
            }
        }
    }
    Ok(())
}

/// What a point runner returns: named scalar values for the merged table.
///
/// ```text
/// values = flatten(object): {"a": {"b": 1}} → {"a.b": 1}; arrays kept as JSON text
/// ```
///
/// Source: docs/outputs.md ("Sweeps": point files, merge).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// Column name → value (number, string, bool or null).
    pub values: BTreeMap<String, Value>,
}

impl PointResult {
    /// Flattens a JSON object (a summary.json, say) into dotted column names.
    pub fn flatten(v: &Value) -> PointResult {
        let mut values = BTreeMap::new();
        flatten_into("", v, &mut values);
        PointResult { values }
    }
}

fn flatten_into(prefix: &str, v: &Value, out: &mut BTreeMap<String, Value>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten_into(&key, x, out);
            }
        }
        Value::Array(_) => {
            out.insert(prefix.to_string(), Value::String(v.to_string()));
        }
        other => {
            out.insert(prefix.to_string(), other.clone());
        }
    }
}

/// How a finished point ended.
///
/// ```text
/// ok | solver_failed  (both finished: a rerun skips them)
/// ```
///
/// Source: this module.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointStatus {
    /// The runner returned results.
    Ok,
    /// The solver failed: a result too (a method that cannot do the point), not rerun.
    SolverFailed,
}

/// The content of OUT/id/result.json.
///
/// ```text
/// OUT/id/result.json = { id, index, params, status, error, values }
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointRecord {
    /// The point's id (its directory name).
    pub id: String,
    /// Its index in the grid.
    pub index: usize,
    /// Its parameters.
    pub params: PointParams,
    /// How it ended.
    pub status: PointStatus,
    /// The solver's error (status `solver_failed`), else None.
    pub error: Option<String>,
    /// The runner's values (empty on solver failure).
    pub values: BTreeMap<String, Value>,
}

/// How [`run_sweep`] runs.
///
/// ```text
/// jobs threads (None = cores), shard I/N
/// ```
///
/// Source: docs/outputs.md ("Sweeps": `--jobs`, `--shard`).
#[derive(Clone, Debug)]
pub struct SweepOptions {
    /// Worker threads; None = one per core.
    pub jobs: Option<usize>,
    /// Which points.
    pub shard: Shard,
}

impl Default for SweepOptions {
    fn default() -> Self {
        SweepOptions {
            jobs: None,
            shard: Shard::ALL,
        }
    }
}

/// What [`run_sweep`] did.
///
/// ```text
/// selected = skipped + ok + solver_failed + |failed| + |busy| + abandoned
/// ```
///
/// Source: this module.
#[derive(Debug, Default)]
pub struct SweepReport {
    /// Points in the shard.
    pub selected: usize,
    /// Points skipped because they had finished before (or finished meanwhile in another
    /// process).
    pub skipped: usize,
    /// Points that ran and finished ok.
    pub ok: usize,
    /// Points that ran and ended in a solver failure (recorded, finished).
    pub solver_failed: usize,
    /// Points whose runner failed otherwise (not recorded: a rerun tries them again).
    pub failed: Vec<(usize, Error)>,
    /// Points another live process holds a claim on (index, "host:pid"): left to it.
    pub busy: Vec<(usize, String)>,
    /// Points not run or abandoned because a stop was requested (left for a rerun).
    pub abandoned: usize,
    /// Points whose result.json was there but corrupt (index, reason): run again.
    pub corrupt: Vec<(usize, String)>,
}

impl SweepReport {
    /// Ok if no point failed unrecorded and no stop was requested; else the first failure's
    /// error kind with a message that counts them, or [`Error::Interrupted`] with the counts.
    pub fn into_result(mut self) -> Result<SweepReport, Error> {
        if self.abandoned > 0 {
            let done = self.skipped + self.ok + self.solver_failed;
            return Err(Error::Interrupted(format!(
                "sweep: {} point(s) finished in this run and {done} of {} in all are kept; {} \
                 left (rerun the same command to resume)",
                self.ok + self.solver_failed,
                self.selected,
                self.selected - done
            )));
        }
        if self.failed.is_empty() {
            return Ok(self);
        }
        self.failed.sort_by_key(|(i, _)| *i);
        let n = self.failed.len();
        let (i, e) = self.failed.swap_remove(0);
        let head = format!("{n} sweep point(s) failed; first, point {i}: ");
        let msg = format!("{head}{e}");
        Err(match e {
            Error::Usage(_) => Error::Usage(msg),
            Error::Option(o) => Error::Option(o.prefixed(head)),
            Error::Input(_) | Error::Scene { .. } | Error::Io { .. } => Error::Input(msg),
            Error::NotYetAvailable(_) => Error::NotYetAvailable(msg),
            Error::Solver(_) | Error::Internal(_) => Error::Internal(msg),
            Error::Interrupted(_) => Error::Interrupted(msg),
        })
    }
}

/// What a point's directory holds.
///
/// ```text
/// Finished(record) | Missing (no result.json) | Corrupt(reason: unreadable, not a
/// PointRecord, or a record of another point)
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Clone, Debug, PartialEq)]
pub enum PointState {
    /// result.json names this point.
    Finished(Box<PointRecord>),
    /// No result.json.
    Missing,
    /// result.json is there but unusable: why.
    Corrupt(String),
}

/// The state of the point with id `id` in `dir` (its directory).
pub fn point_state(dir: &Path, id: &str) -> PointState {
    let p = dir.join(RESULT_FILE);
    let bytes = match std::fs::read(&p) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return PointState::Missing,
        Err(e) => return PointState::Corrupt(format!("{}: {e}", p.display())),
    };
    match serde_json::from_slice::<PointRecord>(&bytes) {
        Ok(r) if r.id == id => PointState::Finished(Box::new(r)),
        Ok(r) => PointState::Corrupt(format!(
            "{}: the record of point {}, not {id}",
            p.display(),
            r.id
        )),
        Err(e) => PointState::Corrupt(format!("{}: {e}", p.display())),
    }
}

/// Whether the point's result file exists, parses and names this point.
pub fn is_finished(root: &Path, point: &SweepPoint) -> bool {
    matches!(
        point_state(&root.join(&point.id), &point.id),
        PointState::Finished(_)
    )
}

/// Name of the grid's manifest in a sweep's output directory: every point (index, id,
/// parameters), so that `merge` can name the points that have not finished.
pub const MANIFEST_FILE: &str = "points.json";

/// The content of OUT/points.json.
///
/// ```text
/// { points: [{ index, id, params }] }   the whole grid, whatever the shard
/// ```
///
/// Source: docs/outputs.md ("Sweeps").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// The grid's points.
    pub points: Vec<ManifestPoint>,
}

/// One point of a [`Manifest`].
///
/// Source: this module.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManifestPoint {
    /// Index in the grid.
    pub index: usize,
    /// Id (directory name).
    pub id: String,
    /// Parameters.
    pub params: PointParams,
}

/// Runs the points of `opts.shard` that have not finished, in parallel, each in its own
/// directory `root/id` (created before `runner` is called and passed to it). A finished
/// point's `result.json` is written atomically; a solver failure is recorded as finished; any
/// other runner error leaves the point unfinished for a rerun. No progress reports (see
/// [`run_sweep_with_progress`]).
pub fn run_sweep<F>(
    points: &[SweepPoint],
    root: &Path,
    opts: &SweepOptions,
    runner: F,
) -> Result<SweepReport, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    run_sweep_with_progress(points, root, opts, runner, &NoProgress)
}

/// [`run_sweep`], reporting to `progress`: `started` with the number of points to run, then
/// `finished` (the point and its wall time) as each point ends, whatever its outcome.
///
/// ```text
/// root/points.json  the grid (atomically, every run)
/// per point:  stop requested → left (abandoned);  finished → skipped;
///             claim::try_claim(root/id) busy → left to its holder;
///             claimed → finished meanwhile? skipped : clear temporaries of dead holders,
///             run, write result.json, release the claim
/// a stop requested while a point runs: the point's partial files are removed, its claim
///             released; the report counts it as abandoned
/// ```
pub fn run_sweep_with_progress<F>(
    points: &[SweepPoint],
    root: &Path,
    opts: &SweepOptions,
    runner: F,
    progress: &dyn Progress,
) -> Result<SweepReport, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error> + Sync,
{
    io::create_dir(root)?;
    let manifest = Manifest {
        points: points
            .iter()
            .map(|p| ManifestPoint {
                index: p.index,
                id: p.id.clone(),
                params: p.params.clone(),
            })
            .collect(),
    };
    io::write_json_atomic(&root.join(MANIFEST_FILE), &manifest)?;
    claim::remove_dead_temporaries(root);
    let selected: Vec<&SweepPoint> = points
        .iter()
        .filter(|p| opts.shard.contains(p.index))
        .collect();
    let mut corrupt = Vec::new();
    let mut todo = Vec::new();
    for p in &selected {
        match point_state(&root.join(&p.id), &p.id) {
            PointState::Finished(_) => {}
            PointState::Missing => todo.push(*p),
            PointState::Corrupt(why) => {
                progress
                    .note(&format!("sweep: point {} ({}) runs again: {why}", p.index, p.id).into());
                corrupt.push((p.index, why));
                todo.push(*p);
            }
        }
    }
    let report = Mutex::new(SweepReport {
        selected: selected.len(),
        skipped: selected.len() - todo.len(),
        corrupt,
        ..Default::default()
    });
    if report.lock().map(|r| r.skipped).unwrap_or(0) > 0 {
        progress.note(
            &format!(
                "sweep: {} of {} points already done",
                selected.len() - todo.len(),
                selected.len()
            )
            .into(),
        );
    }
    progress.started("points", todo.len());
    let jobs = progress::jobs_within_parallelism(opts.jobs, progress);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::Internal(format!("thread pool: {e}")))?;
    let held_set: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());
    let held = &held_set;
    let (stop_beat, beat) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|s| {
        // Dropped on every way out of this closure (a panic too), which ends the heartbeat.
        let stop_beat = stop_beat;
        // The heartbeat: refreshes the claims this process holds (claim::HEARTBEAT).
        s.spawn(move || {
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
                beat.recv_timeout(claim::HEARTBEAT)
            {
                for p in held.lock().unwrap_or_else(|e| e.into_inner()).iter() {
                    claim::touch(p);
                }
            }
        });
        pool.install(|| {
            todo.par_iter().for_each(|p| {
                let clock = Instant::now();
                let outcome = run_point(p, root, &runner, held);
                let mut r = report.lock().unwrap_or_else(|e| e.into_inner());
                let what = match outcome {
                    Ok(Ran::Status(PointStatus::Ok)) => {
                        r.ok += 1;
                        "ok".to_string()
                    }
                    Ok(Ran::Status(PointStatus::SolverFailed)) => {
                        r.solver_failed += 1;
                        "solver failure (recorded)".to_string()
                    }
                    Ok(Ran::AlreadyDone) => {
                        r.skipped += 1;
                        "finished meanwhile by another process".to_string()
                    }
                    Ok(Ran::Busy(holder)) => {
                        r.busy.push((p.index, holder.clone()));
                        format!("claimed by {holder}, left to it")
                    }
                    Ok(Ran::Abandoned) => {
                        r.abandoned += 1;
                        "abandoned (stop requested)".to_string()
                    }
                    Err(e) => {
                        let s = format!("failed: {e}");
                        r.failed.push((p.index, e));
                        s
                    }
                };
                drop(r);
                progress.finished(
                    &format!("point {} ({}): {what}", p.index, p.id),
                    clock.elapsed().as_secs_f64(),
                );
            })
        });
        let _ = stop_beat.send(());
    });
    let r = report.into_inner().unwrap_or_else(|e| e.into_inner());
    if !r.busy.is_empty() {
        let mut holders: Vec<&str> = r.busy.iter().map(|(_, h)| h.as_str()).collect();
        holders.sort();
        holders.dedup();
        progress.note(
            &format!(
                "sweep: {} point(s) claimed by other processes ({}), left to them",
                r.busy.len(),
                holders.join(", ")
            )
            .into(),
        );
    }
    Ok(r)
}

/// How one point of a sweep went in this process.
enum Ran {
    /// It ran to the end: its status is recorded.
    Status(PointStatus),
    /// Another process finished it between the listing and the claim.
    AlreadyDone,
    /// Another live process holds its claim ("host:pid").
    Busy(String),
    /// A stop was requested before or while it ran; nothing of it is kept.
    Abandoned,
}

fn run_point<F>(
    p: &SweepPoint,
    root: &Path,
    runner: &F,
    held: &Mutex<BTreeSet<PathBuf>>,
) -> Result<Ran, Error>
where
    F: Fn(&SweepPoint, &Path) -> Result<PointResult, Error>,
{
    if lash_solver::interrupt::stop_requested() {
        return Ok(Ran::Abandoned);
    }
    let dir = root.join(&p.id);
    io::create_dir(&dir)?;
    let guard = match claim::try_claim(&dir)? {
        claim::Claimed::Mine(g) => g,
        claim::Claimed::Busy(h) => return Ok(Ran::Busy(h.holder())),
    };
    if matches!(point_state(&dir, &p.id), PointState::Finished(_)) {
        return Ok(Ran::AlreadyDone);
    }
    // Whatever an earlier holder left half-written is ours to clear now.
    claim::remove_all_temporaries(&dir);
    held.lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(guard.path().to_path_buf());
    let ran = runner(p, &dir);
    held.lock()
        .unwrap_or_else(|e| e.into_inner())
        .remove(guard.path());
    let (status, error, values) = match ran {
        Ok(r) => (PointStatus::Ok, None, r.values),
        Err(e @ Error::Solver(_)) => (
            PointStatus::SolverFailed,
            Some(e.to_string()),
            BTreeMap::new(),
        ),
        Err(Error::Interrupted(_)) => {
            abandon(&dir, guard);
            return Ok(Ran::Abandoned);
        }
        Err(e) => return Err(e),
    };
    let record = PointRecord {
        id: p.id.clone(),
        index: p.index,
        params: p.params.clone(),
        status,
        error,
        values,
    };
    io::write_json_atomic(&dir.join(RESULT_FILE), &record)?;
    drop(guard);
    Ok(Ran::Status(status))
}

/// Removes what an abandoned point wrote (every file but its claim, which `guard` releases),
/// then its directory if nothing else is in it.
fn abandon(dir: &Path, guard: claim::ClaimGuard) {
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            if e.path() != guard.path() && e.path().is_file() {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    drop(guard);
    let _ = std::fs::remove_dir(dir);
}

/// A point of the grid that has no usable result.
///
/// ```text
/// (index, id, params, why: "unfinished" [held by host:pid] | the corruption)
/// ```
///
/// Source: docs/outputs.md ("Sweeps": `lash merge`).
#[derive(Clone, Debug, PartialEq)]
pub struct MissingPoint {
    /// Index in the grid (None for a corrupt file outside any manifest).
    pub index: Option<usize>,
    /// Id (directory name).
    pub id: String,
    /// Its parameters, if known from a manifest.
    pub params: Option<PointParams>,
    /// Why it has no result: "unfinished", "unfinished, claimed by host:pid", or what is
    /// wrong with its result.json.
    pub why: String,
}

/// The merged table of finished points.
///
/// ```text
/// columns = id, index, the parameters some point sets, status, error, every value name (sorted)
/// rows    = one per distinct point id, sorted by (index, id); finished points, then (when
///           asked for: MergedTable::with_missing) the unfinished and corrupt ones with status
///           `unfinished` / `corrupt` and the reason in `error`
/// ```
///
/// Source: docs/outputs.md ("Sweeps": `lash merge DIR...`).
#[derive(Clone, Debug, PartialEq)]
pub struct MergedTable {
    /// Column names.
    pub columns: Vec<String>,
    /// Cells, row by row (empty string for a missing value).
    pub rows: Vec<Vec<String>>,
    /// Points of the grids (manifests) with no result, or with a corrupt one.
    pub unfinished: Vec<MissingPoint>,
    /// Points whose result.json is corrupt.
    pub corrupt: Vec<MissingPoint>,
}

/// Reads the finished points under each directory (a sweep output directory, whose
/// subdirectories are points, or one point directory) and joins them. The points of the
/// directories' manifests ([`MANIFEST_FILE`]) that have no result anywhere are listed as
/// unfinished; result files that do not parse, or name another point, as corrupt.
pub fn merge(dirs: &[PathBuf]) -> Result<MergedTable, Error> {
    let mut records: BTreeMap<String, PointRecord> = BTreeMap::new();
    let mut expected: BTreeMap<String, ManifestPoint> = BTreeMap::new();
    let mut claims: BTreeMap<String, String> = BTreeMap::new();
    let mut corrupt_files: BTreeMap<String, String> = BTreeMap::new();
    for dir in dirs {
        if !dir.is_dir() {
            return Err(Error::Input(format!(
                "merge: {} is not a directory",
                dir.display()
            )));
        }
        let mf = dir.join(MANIFEST_FILE);
        if mf.is_file() {
            let bytes = std::fs::read(&mf).map_err(|e| Error::io(&mf, e))?;
            let m: Manifest = serde_json::from_slice(&bytes)
                .map_err(|e| Error::Input(format!("merge: {}: {e}", mf.display())))?;
            for p in m.points {
                expected.entry(p.id.clone()).or_insert(p);
            }
        }
        let point_dirs: Vec<PathBuf> = if dir.join(RESULT_FILE).is_file() {
            vec![dir.clone()]
        } else {
            let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
                .map_err(|e| Error::io(dir, e))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_dir())
                .collect();
            v.sort();
            v
        };
        for pd in point_dirs {
            let id = pd
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            match point_state(&pd, &id) {
                PointState::Finished(rec) => {
                    records.entry(rec.id.clone()).or_insert(*rec);
                }
                PointState::Missing => {
                    if let Some((c, age)) = claim::read_claim(&pd.join(claim::CLAIM_FILE)) {
                        let state = if claim::is_stale(&c, age) {
                            "stale claim of"
                        } else {
                            "claimed by"
                        };
                        claims.insert(id, format!("{state} {}", c.holder()));
                    }
                }
                PointState::Corrupt(why) => {
                    corrupt_files.insert(id, why);
                }
            }
        }
    }
    let mut corrupt = Vec::new();
    for (id, why) in corrupt_files {
        if records.contains_key(&id) {
            continue; // another directory holds a good copy
        }
        let m = expected.get(&id);
        corrupt.push(MissingPoint {
            index: m.map(|m| m.index),
            id,
            params: m.map(|m| m.params.clone()),
            why,
        });
    }
    let unfinished: Vec<MissingPoint> = expected
        .values()
        .filter(|m| !records.contains_key(&m.id) && !corrupt.iter().any(|c| c.id == m.id))
        .map(|m| MissingPoint {
            index: Some(m.index),
            id: m.id.clone(),
            params: Some(m.params.clone()),
            why: match claims.get(&m.id) {
                Some(c) => format!("unfinished, {c}"),
                None => "unfinished".into(),
            },
        })
        .collect();
    let mut unfinished = unfinished;
    unfinished.sort_by(|a, b| (a.index, &a.id).cmp(&(b.index, &b.id)));
    corrupt.sort_by(|a, b| (a.index, &a.id).cmp(&(b.index, &b.id)));
    let mut recs: Vec<PointRecord> = records.into_values().collect();
    recs.sort_by(|a, b| (a.index, &a.id).cmp(&(b.index, &b.id)));
    let param_maps: Vec<serde_json::Map<String, Value>> = recs
        .iter()
        .map(|r| match serde_json::to_value(&r.params) {
            Ok(Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        })
        .collect();
    let params: Vec<&str> = PARAM_COLUMNS
        .into_iter()
        .filter(|c| param_maps.iter().any(|m| m.contains_key(*c)))
        .collect();
    let value_names: BTreeSet<&String> = recs.iter().flat_map(|r| r.values.keys()).collect();
    let mut columns: Vec<String> = vec!["id".into(), "index".into()];
    columns.extend(params.iter().map(|s| s.to_string()));
    columns.push("status".into());
    columns.push("error".into());
    columns.extend(value_names.iter().map(|s| s.to_string()));
    let rows = recs
        .iter()
        .zip(&param_maps)
        .map(|(r, pm)| {
            let mut row = vec![r.id.clone(), r.index.to_string()];
            row.extend(params.iter().map(|c| cell(pm.get(*c))));
            row.push(
                match r.status {
                    PointStatus::Ok => "ok",
                    PointStatus::SolverFailed => "solver_failed",
                }
                .into(),
            );
            row.push(r.error.clone().unwrap_or_default());
            row.extend(value_names.iter().map(|c| cell(r.values.get(*c))));
            row
        })
        .collect();
    Ok(MergedTable {
        columns,
        rows,
        unfinished,
        corrupt,
    })
}

impl MergedTable {
    /// The table with a row for every unfinished and corrupt point (status `unfinished` or
    /// `corrupt`, the reason in `error`, the parameters where a manifest knows them, no
    /// values), after the finished rows.
    pub fn with_missing(mut self) -> MergedTable {
        let col = |n: &str| self.columns.iter().position(|c| c == n);
        let (st, er) = (col("status"), col("error"));
        let params: Vec<(usize, &str)> = PARAM_COLUMNS
            .iter()
            .filter_map(|c| col(c).map(|i| (i, *c)))
            .collect();
        let mut extra = Vec::new();
        for (m, status) in self
            .unfinished
            .iter()
            .map(|m| (m, "unfinished"))
            .chain(self.corrupt.iter().map(|m| (m, "corrupt")))
        {
            let mut row = vec![String::new(); self.columns.len()];
            row[0] = m.id.clone();
            row[1] = m.index.map_or(String::new(), |i| i.to_string());
            if let Some(p) = m.params.as_ref().and_then(|p| serde_json::to_value(p).ok()) {
                for &(i, c) in &params {
                    row[i] = cell(p.get(c));
                }
            }
            if let (Some(s), Some(e)) = (st, er) {
                row[s] = status.into();
                row[e] = m.why.clone();
            }
            extra.push(row);
        }
        self.rows.extend(extra);
        self
    }

    /// One line naming the points without a usable result: counts, then up to `max` of
    /// each kind by index and id.
    pub fn missing_summary(&self, max: usize) -> String {
        let list = |v: &[MissingPoint]| {
            let mut parts: Vec<String> = v
                .iter()
                .take(max)
                .map(|m| match m.index {
                    Some(i) => format!("#{i} {} ({})", m.id, m.why),
                    None => format!("{} ({})", m.id, m.why),
                })
                .collect();
            if v.len() > max {
                parts.push(format!("and {} more", v.len() - max));
            }
            parts.join("; ")
        };
        let mut s = Vec::new();
        if !self.unfinished.is_empty() {
            s.push(format!(
                "{} point(s) unfinished: {}",
                self.unfinished.len(),
                list(&self.unfinished)
            ));
        }
        if !self.corrupt.is_empty() {
            s.push(format!(
                "{} point(s) with a corrupt result.json: {}",
                self.corrupt.len(),
                list(&self.corrupt)
            ));
        }
        s.join("; ")
    }
}

fn cell(v: Option<&Value>) -> String {
    match v {
        None | Some(Value::Null) => String::new(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => other.to_string(),
    }
}

impl MergedTable {
    /// The table as CSV (RFC 4180 quoting).
    pub fn to_csv(&self) -> String {
        let q = |s: &str| {
            if s.contains([',', '"', '\n', '\r']) {
                format!("\"{}\"", s.replace('"', "\"\""))
            } else {
                s.to_string()
            }
        };
        let mut out = String::new();
        for row in std::iter::once(&self.columns).chain(&self.rows) {
            let cells: Vec<String> = row.iter().map(|c| q(c)).collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
        out
    }

    /// The table as a GitHub-flavoured markdown table (`|` escaped).
    pub fn to_markdown(&self) -> String {
        let esc = |s: &str| s.replace('|', "\\|").replace('\n', " ");
        let line = |r: &[String]| {
            let cells: Vec<String> = r.iter().map(|c| esc(c)).collect();
            format!("| {} |\n", cells.join(" | "))
        };
        let mut out = line(&self.columns);
        out.push_str(&format!("|{}\n", "---|".repeat(self.columns.len())));
        for r in &self.rows {
            out.push_str(&line(r));
        }
        out
    }

    /// Writes `merged.csv` and `merged.md` atomically into `dir` (created if needed); returns
    /// their paths.
    pub fn write(&self, dir: &Path) -> Result<(PathBuf, PathBuf), Error> {
        io::create_dir(dir)?;
        let csv = dir.join("merged.csv");
        let md = dir.join("merged.md");
        io::write_atomic(&csv, self.to_csv().as_bytes())?;
        io::write_atomic(&md, self.to_markdown().as_bytes())?;
        Ok((csv, md))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    fn spec(dir: &Path, json: &str) -> Result<SweepSpec, Error> {
        std::fs::write(dir.join("base.json"), b"{\"scene\": true}").unwrap();
        let p = dir.join("sweep.json");
        std::fs::write(&p, json).unwrap();
        SweepSpec::load(&p)
    }

    const GRID: &str = r#"{"case": "base.json", "speed_rpm": [120, 150],
        "method": ["rk4", "dopri54", "bdf"], "step": [1e-4, 5e-5],
        "tolerance": [1e-6, 1e-8], "controller": ["pi", "h211"]}"#;

    #[test]
    fn shard_syntax() {
        assert_eq!(
            "1/4".parse::<Shard>().unwrap(),
            Shard { index: 1, count: 4 }
        );
        assert_eq!("0/1".parse::<Shard>().unwrap(), Shard::ALL);
        for bad in ["4/4", "0/0", "-1/2", "a/b", "1", "1/2/3", ""] {
            let e = bad.parse::<Shard>().unwrap_err();
            assert_eq!(e.kind(), crate::ErrorKind::BadInput, "{bad}");
        }
        let s = Shard { index: 2, count: 3 };
        assert_eq!(
            (0..9).filter(|&i| s.contains(i)).collect::<Vec<_>>(),
            vec![2, 5, 8]
        );
        assert_eq!(s.to_string(), "2/3");
    }

    #[test]
    fn grid_is_the_method_aware_product() {
        let d = tempfile::tempdir().unwrap();
        let pts = spec(d.path(), GRID).unwrap().points().unwrap();
        // Per speed: rk4 × 2 steps + dopri54 × 2 rtol × 2 controllers + bdf × 2 rtol = 8.
        assert_eq!(pts.len(), 16);
        assert!(pts.iter().enumerate().all(|(i, p)| p.index == i));
        let first = &pts[0].params;
        assert_eq!(first.speed_rpm, Some(120.0));
        assert_eq!(
            (first.method, first.step, first.rtol),
            (Some(Method::Rk4), Some(1e-4), None)
        );
        let p3 = &pts[3].params;
        assert_eq!(
            (p3.method, p3.rtol, p3.controller, p3.step),
            (
                Some(Method::Dopri54),
                Some(1e-6),
                Some(ControllerKind::H211),
                None
            )
        );
        let p7 = &pts[7].params;
        assert_eq!(
            (p7.method, p7.rtol, p7.controller),
            (Some(Method::Bdf), Some(1e-8), None)
        );
        assert_eq!(pts[8].params.speed_rpm, Some(150.0));
        assert_eq!(first.case, "base");
        assert_eq!(
            first.scene_sha256.as_deref(),
            Some(sha256_hex(b"{\"scene\": true}").as_str())
        );
    }

    #[test]
    fn id_is_sha256_of_sorted_canonical_json() {
        let p = PointParams {
            case: "c".into(),
            scene_sha256: None,
            speed_rpm: Some(150.0),
            clearance: Some(1e-4),
            viscosity: None,
            stiffness: None,
            method: Some(Method::Dopri54),
            rtol: None,
            step: None,
            controller: Some(ControllerKind::H211),
        };
        let canon = r#"{"case":"c","clearance":0.0001,"controller":"h211","method":"dopri54","speed_rpm":150.0}"#;
        assert_eq!(p.canonical_json(), canon);
        assert_eq!(p.id(), &sha256_hex(canon.as_bytes())[..16]);
        // The same numbers written differently give the same id; another value another id.
        let q: PointParams = serde_json::from_str(
            r#"{"speed_rpm": 1.5e2, "method": "dopri54", "clearance": 1e-4, "controller": "h211", "case": "c"}"#,
        )
        .unwrap();
        assert_eq!(q.id(), p.id());
        let r = PointParams {
            speed_rpm: Some(150.0000001),
            ..p.clone()
        };
        assert_ne!(r.id(), p.id());
    }

    #[test]
    fn bad_sweep_files_name_the_problem() {
        let d = tempfile::tempdir().unwrap();
        let msg = |j: &str| spec(d.path(), j).unwrap_err().to_string();
        assert!(msg(r#"{"case": "base.json", "speed": [1]}"#).contains("unknown field `speed`"));
        assert!(msg(r#"{"case": "base.json", "clearance": []}"#)
            .contains("'clearance' is an empty list"));
        assert!(msg(r#"{"case": "base.json", "clearance": [0]}"#)
            .contains("clearance[0] must be finite and > 0"));
        assert!(msg(r#"{"case": "base.json", "method": ["rk4"]}"#)
            .contains("rk4 is fixed-step and needs a 'step' list"));
        assert!(
            msg(r#"{"case": "base.json", "method": ["bdf"], "controller": ["pi"]}"#)
                .contains("'controller' needs")
        );
        assert!(
            msg(r#"{"case": "base.json", "step": [1e-4], "rtol": [1e-6]}"#).contains("not both")
        );
        assert!(msg(r#"{"case": "base.json", "rtol": [2]}"#).contains("every rtol must be in"));
        assert!(msg(r#"{"case": "base.json", "method": ["euler"]}"#)
            .contains("unknown variant `euler`"));
        assert!(msg(r#"{"case": "nope.json"}"#).contains("not found"));
        assert!(msg(r#"{"case": "base.json", "speed_rpm": [1, 1]}"#).contains("twice"));
        let e = SweepSpec::load(&d.path().join("absent.json")).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::BadInput);
    }

    /// A fake runner: slider_acc_max = speed², and counts its calls.
    fn fake(p: &SweepPoint, dir: &Path, calls: &AtomicUsize) -> Result<PointResult, Error> {
        calls.fetch_add(1, Ordering::SeqCst);
        io::write_atomic(&dir.join("summary.json"), b"{}")?;
        let s = p.params.speed_rpm.unwrap_or(0.0);
        Ok(PointResult::flatten(&serde_json::json!({
            "metrics": {"slider_acc_max": s * s}, "stats": {"rhs_evals": p.index}
        })))
    }

    #[test]
    fn shards_partition_the_grid_and_merge_joins_them() {
        let d = tempfile::tempdir().unwrap();
        let pts = spec(d.path(), GRID).unwrap().points().unwrap();
        let calls = AtomicUsize::new(0);
        let mut roots = vec![];
        for i in 0..3 {
            let root = d.path().join(format!("shard{i}"));
            let opts = SweepOptions {
                jobs: Some(2),
                shard: Shard { index: i, count: 3 },
            };
            let r = run_sweep(&pts, &root, &opts, |p, dir| fake(p, dir, &calls)).unwrap();
            let expect = (0..16).filter(|k| k % 3 == i).count();
            assert_eq!((r.selected, r.ok, r.skipped), (expect, expect, 0));
            roots.push(root);
        }
        assert_eq!(calls.load(Ordering::SeqCst), 16);
        let t = merge(&roots).unwrap();
        assert_eq!(t.rows.len(), 16);
        assert!(t.unfinished.is_empty() && t.corrupt.is_empty());
        let col = |n: &str| t.columns.iter().position(|c| c == n).unwrap();
        for (k, row) in t.rows.iter().enumerate() {
            assert_eq!(row[col("index")], k.to_string());
            assert_eq!(row[col("id")], pts[k].id);
            assert_eq!(row[col("stats.rhs_evals")], k.to_string());
            let s: f64 = row[col("speed_rpm")].parse().unwrap();
            let a: f64 = row[col("metrics.slider_acc_max")].parse().unwrap();
            assert_eq!(a, s * s);
        }
        // Parameters no point sets are not columns.
        assert!(!t.columns.iter().any(|c| c == "viscosity"));
        let csv = t.to_csv();
        assert_eq!(csv.lines().count(), 17);
        assert!(csv.starts_with("id,index,case,scene_sha256,speed_rpm,method,rtol,step,controller,status,error,metrics.slider_acc_max,stats.rhs_evals\n"));
        let md = t.to_markdown();
        assert_eq!(md.lines().count(), 18);
        assert_eq!(
            md.lines().nth(1).unwrap().matches("---|").count(),
            t.columns.len()
        );
        // Merging the same shard twice does not duplicate rows.
        assert_eq!(
            merge(&[roots[0].clone(), roots[0].clone()])
                .unwrap()
                .rows
                .len(),
            6
        );
        let (c, m) = t.write(&d.path().join("merged")).unwrap();
        assert_eq!(std::fs::read_to_string(c).unwrap(), csv);
        assert_eq!(std::fs::read_to_string(m).unwrap(), md);
    }

    #[test]
    fn rerun_resumes_after_an_interruption() {
        let d = tempfile::tempdir().unwrap();
        let pts = spec(d.path(), GRID).unwrap().points().unwrap();
        let root = d.path().join("out");
        let k = 5;
        let calls = AtomicUsize::new(0);
        // Sequential, so exactly the first k points finish before the "interruption".
        let opts = SweepOptions {
            jobs: Some(1),
            ..Default::default()
        };
        let r = run_sweep(&pts, &root, &opts, |p, dir| {
            if calls.fetch_add(1, Ordering::SeqCst) >= k {
                Err(Error::Internal("killed".into()))
            } else {
                fake(p, dir, &AtomicUsize::new(0))
            }
        })
        .unwrap();
        assert_eq!((r.ok, r.failed.len()), (k, 16 - k));
        let t = merge(std::slice::from_ref(&root)).unwrap();
        assert_eq!((t.rows.len(), t.unfinished.len()), (k, 16 - k));
        let e = r.into_result().unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Bug);
        assert!(
            e.to_string()
                .contains("11 sweep point(s) failed; first, point 5: internal error: killed"),
            "{e}"
        );
        // The rerun runs only the unfinished points.
        let calls2 = AtomicUsize::new(0);
        let opts = SweepOptions {
            jobs: Some(2),
            ..Default::default()
        };
        let r = run_sweep(&pts, &root, &opts, |p, dir| fake(p, dir, &calls2)).unwrap();
        assert_eq!((r.skipped, r.ok), (k, 16 - k));
        assert_eq!(calls2.load(Ordering::SeqCst), 16 - k);
        assert_eq!(merge(&[root]).unwrap().rows.len(), 16);
    }

    #[test]
    fn solver_failures_are_results_not_retried() {
        let d = tempfile::tempdir().unwrap();
        let pts = spec(d.path(), GRID).unwrap().points().unwrap();
        let root = d.path().join("out");
        let runner = |p: &SweepPoint, dir: &Path| {
            if p.params.method == Some(Method::Rk4) {
                Err(Error::Solver(lash_solver::SolveError::NonFiniteState {
                    t: 0.5,
                    y: vec![1.0],
                }))
            } else {
                fake(p, dir, &AtomicUsize::new(0))
            }
        };
        let r = run_sweep(&pts, &root, &SweepOptions::default(), runner).unwrap();
        assert_eq!((r.ok, r.solver_failed), (12, 4));
        let r = run_sweep(&pts, &root, &SweepOptions::default(), runner).unwrap();
        assert_eq!((r.skipped, r.ok, r.solver_failed), (16, 0, 0));
        let t = merge(&[root]).unwrap();
        let st = t.columns.iter().position(|c| c == "status").unwrap();
        let er = t.columns.iter().position(|c| c == "error").unwrap();
        let failed: Vec<&Vec<String>> =
            t.rows.iter().filter(|r| r[st] == "solver_failed").collect();
        assert_eq!(failed.len(), 4);
        assert!(failed[0][er].starts_with("solver failed: non-finite"));
    }

    #[test]
    fn csv_quotes_and_markdown_escapes() {
        let t = MergedTable {
            columns: vec!["a".into(), "b".into()],
            rows: vec![vec!["x,y".into(), "say \"hi\" | there".into()]],
            unfinished: vec![],
            corrupt: vec![],
        };
        assert_eq!(t.to_csv(), "a,b\n\"x,y\",\"say \"\"hi\"\" | there\"\n");
        assert_eq!(
            t.to_markdown(),
            "| a | b |\n|---|---|\n| x,y | say \"hi\" \\| there |\n"
        );
    }

    fn params() -> PointParams {
        PointParams {
            case: "x".into(),
            scene_sha256: None,
            speed_rpm: None,
            clearance: None,
            viscosity: None,
            stiffness: None,
            method: None,
            rtol: None,
            step: None,
            controller: None,
        }
    }

    #[test]
    fn point_parameters_land_in_the_scene() {
        use lash_model::cases::{press_scene, PressJoint};
        let mut s = press_scene(PressJoint::Lubricated, 150.0, 1e-4);
        let p = PointParams {
            speed_rpm: Some(180.0),
            clearance: Some(3e-4),
            viscosity: Some(0.2),
            stiffness: Some(1e10),
            ..params()
        };
        apply_params(&mut s, &p).unwrap();
        let mut seen = 0;
        for j in &s.joints {
            match j {
                JointSpec::Driver(d) => {
                    assert_eq!((d.rpm, d.omega), (Some(180.0), None));
                    seen += 1;
                }
                JointSpec::Clearance(c) => {
                    assert!((c.bearing.radius - c.journal.radius - 3e-4).abs() < 1e-15);
                    assert_eq!(c.film.as_ref().unwrap().viscosity, 0.2);
                    let NormalSpec::Impact(i) = &c.normal else {
                        panic!()
                    };
                    assert_eq!(i.k, Some(1e10));
                    seen += 1;
                }
                _ => {}
            }
        }
        assert_eq!(seen, 2);
        s.validate().unwrap();
        // A dry scene has no film to take a viscosity; an ideal one no clearance joint.
        let mut dry = press_scene(PressJoint::Dry, 150.0, 1e-4);
        let e = apply_params(
            &mut dry,
            &PointParams {
                viscosity: Some(0.2),
                ..params()
            },
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("viscosity needs a lubricated"),
            "{e}"
        );
        let mut ideal = press_scene(PressJoint::Ideal, 150.0, 0.0);
        assert!(apply_params(
            &mut ideal,
            &PointParams {
                clearance: Some(1e-4),
                ..params()
            }
        )
        .is_err());
        // Solver parameters leave the scene alone.
        let before = ideal.clone();
        apply_params(
            &mut ideal,
            &PointParams {
                method: Some(Method::Bdf),
                rtol: Some(1e-6),
                ..params()
            },
        )
        .unwrap();
        assert_eq!(ideal, before);
    }

    #[test]
    fn flatten_uses_dotted_names() {
        let r = PointResult::flatten(
            &serde_json::json!({"a": {"b": 1, "c": null}, "d": [1, 2], "e": "s"}),
        );
        let keys: Vec<&String> = r.values.keys().collect();
        assert_eq!(keys, ["a.b", "a.c", "d", "e"]);
        assert_eq!(r.values["d"], Value::String("[1,2]".into()));
    }
}
