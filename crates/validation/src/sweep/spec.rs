//! The sweep file and its grid: parameters, points and their ids, the checks of the file, the
//! shards of a job array, and a point's parameters laid over the base scene.
//!
//! Source: docs/outputs.md ("Sweeps").

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::Path;
use std::str::FromStr;

use lash_model::scene::{JointSpec, NormalSpec};
use lash_model::Scene;
use lash_solver::{ControllerKind, Method, OptionField};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::Error;
use crate::run::case::{sha256_hex, Case};
use crate::store::cache::canonical;
use crate::sweep::sample::SampleSpec;

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
    pub(crate) const ALL: Shard = Shard { index: 0, count: 1 };

    /// Whether the point with this index belongs to the shard.
    pub(crate) fn contains(&self, point_index: usize) -> bool {
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
/// grid = speed_rpm × clearance × viscosity × stiffness × set × sample
///        × (method-dependent solver choices)
/// ```
///
/// Source: docs/outputs.md ("Sweeps": the sweep file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SweepFile {
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
    /// Any scene field by its path (`joints[3].friction.mu`, `forces[motor].stall_torque`):
    /// the values of each (module `sweep::set`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub set: Option<BTreeMap<String, Vec<Value>>>,
    /// Scene fields drawn from distributions (module `sweep::sample`): each sample a point of
    /// its own (times the rest of the grid), its values under their paths as `set`'s are.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample: Option<SampleSpec>,
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
    /// The scene fields the point sets, by path, each a key of its own in `params` (and a
    /// column of merged.csv named by the path as written); empty for points without `set`,
    /// so their ids are those of a sweep without it.
    #[serde(flatten)]
    pub set: BTreeMap<String, Value>,
}

/// Parameter columns of the merged table, in order.
pub(crate) const PARAM_COLUMNS: [&str; 10] = [
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
    pub(crate) fn canonical_json(&self) -> String {
        let v = serde_json::to_value(self).unwrap_or(Value::Null);
        canonical(&v)
    }

    /// The stable id: the first 16 hex digits of sha256 of [`PointParams::canonical_json`].
    pub(crate) fn id(&self) -> String {
        sha256_hex(self.canonical_json().as_bytes())[..16].to_string()
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
pub(crate) struct SweepSpec {
    /// The parsed file.
    pub file: SweepFile,
    /// The base case.
    pub case: Case,
}

impl SweepSpec {
    /// Reads and checks a sweep file; the base case is resolved relative to its directory.
    pub(crate) fn load(path: &Path) -> Result<SweepSpec, Error> {
        if !path.is_file() {
            return Err(Error::Input(format!(
                "sweep file {} not found",
                path.display()
            )));
        }
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        SweepSpec::from_json(path, &bytes)
    }

    /// Parses and checks a sweep file's JSON text as if read from `path` (the base case is
    /// resolved relative to its directory): a sweep given as text (lash.sweep's dict).
    pub(crate) fn from_json(path: &Path, bytes: &[u8]) -> Result<SweepSpec, Error> {
        // The path of a field that does not parse is named (`sample.count: invalid type…`).
        let de = &mut serde_json::Deserializer::from_slice(bytes);
        let file: SweepFile = serde_path_to_error::deserialize(de).map_err(|e| {
            let at = e.path().to_string();
            let at = if at == "." {
                String::new()
            } else {
                format!("{at}: ")
            };
            Error::Input(format!("sweep file {}: {at}{}", path.display(), e.inner()))
        })?;
        let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
        SweepSpec::new(file, dir)
    }

    /// Checks a parsed sweep file, resolving the base case relative to `base_dir`.
    pub(crate) fn new(file: SweepFile, base_dir: Option<&Path>) -> Result<SweepSpec, Error> {
        check_file(&file)?;
        let case = Case::load(&file.case, base_dir)?;
        Ok(SweepSpec { file, case })
    }

    /// The grid, in its fixed order (see the module doc).
    pub(crate) fn points(&self) -> Result<Vec<SweepPoint>, Error> {
        let f = &self.file;
        let opt = |l: &Option<Vec<f64>>| -> Vec<Option<f64>> {
            match l {
                Some(v) => v.iter().copied().map(Some).collect(),
                None => vec![None],
            }
        };
        let solver = solver_choices(f);
        let mut sets = set_combinations(f.set.as_ref());
        if let Some(sample) = &f.sample {
            let draws = sample.draws()?;
            sets = sets
                .iter()
                .flat_map(|c| {
                    draws.iter().map(move |d| {
                        let mut c = c.clone();
                        c.extend(d.iter().map(|(k, v)| (k.clone(), v.clone())));
                        c
                    })
                })
                .collect();
        }
        let mut points = Vec::new();
        for &speed_rpm in &opt(&f.speed_rpm) {
            for &clearance in &opt(&f.clearance) {
                for &viscosity in &opt(&f.viscosity) {
                    for &stiffness in &opt(&f.stiffness) {
                        for (set, &(method, rtol, step, controller)) in
                            sets.iter().flat_map(|s| solver.iter().map(move |c| (s, c)))
                        {
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
                                set: set.clone(),
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

/// Every combination of the `set` lists, paths in sorted order, the last varying fastest (one
/// empty combination without `set`).
fn set_combinations(set: Option<&BTreeMap<String, Vec<Value>>>) -> Vec<BTreeMap<String, Value>> {
    let mut out = vec![BTreeMap::new()];
    for (path, values) in set.into_iter().flatten() {
        out = out
            .iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.insert(path.clone(), v.clone());
                    c
                })
            })
            .collect();
    }
    out
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
    if let Some(set) = &f.set {
        crate::sweep::set::check_set(set)?;
    }
    if let Some(sample) = &f.sample {
        sample.check(f.set.as_ref())?;
    }
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
pub(crate) fn apply_params(scene: &mut Scene, p: &PointParams) -> Result<(), Error> {
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
