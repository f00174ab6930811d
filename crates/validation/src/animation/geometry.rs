//! What the animation page receives: the scene's geometry (bodies as outlines in their own
//! frames, anchors of joints and springs), the poses of every body on the frames, each
//! clearance joint's eccentricity and forces, and the trajectory columns for the time-series
//! panel, all decimated to the frames the display needs.
//!
//! ```text
//! frames      rows 0, s, 2s, …, and the last row; s = ⌈(rows − 1)/(max_frames − 1)⌉
//! pose        (x, y, θ) of body k on frame f = trajectory.csv <body>.x, .y, .theta at row s·f
//! place       r + A(θ) s' for a body anchor (s' in the body frame), s for a ground anchor
//! clearance   e/c, F_N, F_T from <joint>.ex_over_c, .ey_over_c, .contact_force,
//!             .friction_force; the film's (F_r, F_t) from the mechanism re-evaluated at the
//!             row's state (trajectory.csv holds only |F_film|; the state (q, q̇) of the
//!             integrated bodies is read back from their columns bit for bit, so
//!             hypot(F_r, F_t) = <joint>.film_force and e/c = <joint>.ex_over_c, checked)
//! drawn       journal centre at C_B + M e, journal radius R_B − M c, M = the largest 1-2-5
//!             number ≤ R_B / (2c) (≥ 1): the journal touches the bearing circle exactly
//!             when |e| = c, and the drawn contact point C_B + (R_B + M δ) n
//! force       on the journal: −F_N n + F_T t at the contact point; film F_r n + F_t t at the
//!             journal centre (n = e/|e|, t = (−n_y, n_x); docs/model.md §2–§4)
//! series      every filled column but t, on the frames; with s > 1 also the least and
//!             largest value of the rows each frame stands for (the panel draws that band,
//!             so no contact spike between two frames is lost)
//! numbers     7 significant digits (the display's need; relative error ≤ 5e-7), times exact
//! ```
//!
//! Source: docs/outputs.md ("`animation.html`"); docs/model.md §2–§4 (clearance geometry and
//! forces); docs/scene-format.md (bodies, points, joints, attachments).

use std::collections::BTreeMap;

use lash_model::elements::ForceElementSpec;
use lash_model::scene::{Attachment, ClearanceEnd, JointSpec};
use lash_model::{Mechanism, Scene, GROUND};
use serde::Serialize;

use super::table::{unit, Table};
use crate::error::Error;

/// A number as the page receives it: rounded to 7 significant digits.
pub(crate) fn round7(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    format!("{x:.6e}").parse().unwrap_or(x)
}

fn ser7<S: serde::Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeSeq;
    let mut seq = s.serialize_seq(Some(v.len()))?;
    for x in v {
        seq.serialize_element(&round7(*x))?;
    }
    seq.end()
}

fn ser7_opt<S: serde::Serializer>(v: &Option<Vec<f64>>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(v) => ser7(v, s),
        None => s.serialize_none(),
    }
}

/// Where something is fixed: on a body (in its frame) or on the ground (global).
///
/// ```text
/// place = r_body + A(θ_body) s   (body = Some(k));   s   (body = None: the ground)
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub(crate) struct Anchor {
    /// Index into [`PageData::bodies`]; None for the ground.
    pub body: Option<usize>,
    /// The local offset on the body, or the global location on the ground, m.
    pub s: [f64; 2],
}

/// How a body is drawn.
///
/// ```text
/// polygon  the convex hull of its ≥ 3 named points     bar   a thick line between 2 points,
///          or from its one point through the centre of mass to the point's mirror image
/// block    a rectangle around its one point at the centre of mass (a slider)
/// disc     no points
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Shape {
    /// The convex hull of the points.
    Polygon,
    /// A bar between the two outline points.
    Bar,
    /// A rectangle (the outline's four corners).
    Block,
    /// A disc of radius `width` at the centre of mass.
    Disc,
}

/// A named point of a body.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct NamedPoint {
    /// The point's name in the scene.
    pub name: String,
    /// Its offset from the centre of mass in the body frame, m.
    pub s: [f64; 2],
}

/// One body: its outline and its pose on every frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct BodyData {
    /// The body's name.
    pub name: String,
    /// How it is drawn.
    pub shape: Shape,
    /// The outline in the body frame, m (hull, bar ends, rectangle corners; empty for a disc).
    pub outline: Vec<[f64; 2]>,
    /// Bar width, or disc radius, m.
    pub width: f64,
    /// The scene's named points.
    pub points: Vec<NamedPoint>,
    /// Centre of mass x on each frame, m.
    #[serde(serialize_with = "ser7")]
    pub x: Vec<f64>,
    /// Centre of mass y on each frame, m.
    #[serde(serialize_with = "ser7")]
    pub y: Vec<f64>,
    /// Angle on each frame, rad.
    #[serde(serialize_with = "ser7")]
    pub theta: Vec<f64>,
}

/// An ideal revolute joint, drawn as a pin where its first side is.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct Pin {
    /// The joint's name.
    pub name: String,
    /// Side a.
    pub a: Anchor,
    /// Side b (the ground, for a pivot).
    pub b: Anchor,
}

/// A translational joint's line.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct Guide {
    /// The joint's name.
    pub name: String,
    /// A point of the line, m.
    pub origin: [f64; 2],
    /// Its unit direction.
    pub direction: [f64; 2],
}

/// A rotational driver, drawn as a turning arrow around its body's pivot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct Driver {
    /// The joint's name.
    pub name: String,
    /// The pivot (the driven body's point pinned to the ground or another body), or the
    /// body's centre of mass.
    pub at: Anchor,
    /// Sign of the driver's speed (+1 counter-clockwise).
    pub sense: f64,
}

/// A point-to-point spring-damper, drawn as a zigzag.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct Spring {
    /// The element's name.
    pub name: String,
    /// End a.
    pub a: Anchor,
    /// End b.
    pub b: Anchor,
}

/// A prismatic clearance joint: the block on its body and the guide's two faces.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct Block {
    /// The joint's name.
    pub name: String,
    /// The block's centre on its body.
    pub center: Anchor,
    /// The block's long axis in the body frame (unit).
    pub axis: [f64; 2],
    /// Length along the axis, m.
    pub length: f64,
    /// Width, m.
    pub width: f64,
    /// A point of the guide's centre line (ground), m.
    pub guide_at: [f64; 2],
    /// The guide's unit direction.
    pub guide_direction: [f64; 2],
    /// Distance between the guide's faces, m.
    pub guide_width: f64,
}

/// A revolute clearance joint on every frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct Clearance {
    /// The joint's name.
    pub name: String,
    /// The bearing's centre.
    pub bearing: Anchor,
    /// The journal's centre.
    pub journal: Anchor,
    /// Bearing radius R_B, m.
    pub rb: f64,
    /// Journal radius R_J, m.
    pub rj: f64,
    /// Radial clearance c = R_B − R_J, m.
    pub c: f64,
    /// The factor M the drawn eccentricity is magnified by (module doc).
    pub magnify: f64,
    /// e_x / c on each frame.
    #[serde(serialize_with = "ser7")]
    pub ex: Vec<f64>,
    /// e_y / c on each frame.
    #[serde(serialize_with = "ser7")]
    pub ey: Vec<f64>,
    /// Normal contact force F_N ≥ 0 on each frame, N.
    #[serde(serialize_with = "ser7", rename = "fn")]
    pub f_n: Vec<f64>,
    /// Friction force F_T along t on each frame, N.
    #[serde(serialize_with = "ser7")]
    pub ft: Vec<f64>,
    /// Film force along n on each frame, N (None: a dry joint).
    #[serde(serialize_with = "ser7_opt")]
    pub film_r: Option<Vec<f64>>,
    /// Film force along t on each frame, N (None: a dry joint).
    #[serde(serialize_with = "ser7_opt")]
    pub film_t: Option<Vec<f64>>,
}

/// One trajectory column on the frames.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct SeriesData {
    /// The column's name in trajectory.csv.
    pub name: String,
    /// Its SI unit ([`unit()`]).
    pub unit: String,
    /// Its value on each frame.
    #[serde(serialize_with = "ser7")]
    pub v: Vec<f64>,
    /// Least value of the rows each frame stands for (None when every row is a frame).
    #[serde(serialize_with = "ser7_opt")]
    pub lo: Option<Vec<f64>>,
    /// Largest value of those rows.
    #[serde(serialize_with = "ser7_opt")]
    pub hi: Option<Vec<f64>>,
}

/// Everything the page receives (module doc).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct PageData {
    /// Heading of the page.
    pub title: String,
    /// The scene's description.
    pub subtitle: String,
    /// Rows of the trajectory.
    pub rows: usize,
    /// Rows per frame (module doc).
    pub stride: usize,
    /// The trajectory row of each frame.
    #[serde(skip)]
    pub frame_rows: Vec<usize>,
    /// Time of each frame, s (exact).
    pub t: Vec<f64>,
    /// The region every frame's drawing fits in: [x_min, x_max, y_min, y_max], m.
    pub view: [f64; 4],
    /// The bodies.
    pub bodies: Vec<BodyData>,
    /// Ideal revolute joints.
    pub pins: Vec<Pin>,
    /// Translational joints.
    pub guides: Vec<Guide>,
    /// Rotational drivers.
    pub drivers: Vec<Driver>,
    /// Point-to-point springs.
    pub springs: Vec<Spring>,
    /// Prismatic clearance joints.
    pub blocks: Vec<Block>,
    /// Revolute clearance joints.
    pub clearance: Vec<Clearance>,
    /// The trajectory columns.
    pub series: Vec<SeriesData>,
    /// The point whose path is drawn: `BODY.POINT`, or `BODY` for its centre of mass.
    pub trace: String,
    /// The column the time-series panel shows first.
    pub column: String,
}

/// The choices of an animation.
///
/// ```text
/// trace      BODY.POINT | BODY (centre of mass); default: the centre of mass of the body
///            carrying the clearance_joint role's journal (else of the first clearance joint,
///            else of the last body)
/// column     a filled trajectory column; default: contact_force, else slider_a, else the
///            angle of the first integrated body
/// max_frames ≥ 2; default DEFAULT_MAX_FRAMES
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct AnimationOptions {
    /// The point whose path is drawn.
    pub trace: Option<String>,
    /// The column the time-series panel shows first.
    pub column: Option<String>,
    /// Most frames; None = [`DEFAULT_MAX_FRAMES`].
    pub max_frames: Option<usize>,
}

/// Frames of an animation unless chosen: about 40 s of playback at 60 frames per second,
/// more than a time axis of the page has pixels.
pub(crate) const DEFAULT_MAX_FRAMES: usize = 2500;

/// The trajectory rows shown as frames (module doc): every `stride`-th and the last.
pub(crate) fn frame_rows(rows: usize, max_frames: usize) -> (Vec<usize>, usize) {
    if rows <= 1 {
        return (vec![0; rows.min(1)], 1);
    }
    let max_frames = max_frames.max(2);
    let stride = (rows - 1).div_ceil(max_frames - 1).max(1);
    let mut f: Vec<usize> = (0..rows).step_by(stride).collect();
    if *f.last().unwrap_or(&0) != rows - 1 {
        f.push(rows - 1);
    }
    (f, stride)
}

/// The largest 1-2-5 number ≤ R_B / (2c), at least 1 (module doc): the magnified clearance
/// M c is at most half the bearing's radius.
pub(crate) fn magnification(rb: f64, c: f64) -> f64 {
    let target = 0.5 * rb / c;
    if !(target > 1.0) || !target.is_finite() {
        return 1.0;
    }
    // Within 1e-9 of a 1-2-5 number counts as that number (R_B / 2c rounds either way).
    let p = 10f64.powf((target.log10() + 1e-9).floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * p)
        .find(|v| *v <= target * (1.0 + 1e-9))
        .unwrap_or(p)
}

fn rot(th: f64, s: [f64; 2]) -> [f64; 2] {
    let (sn, cs) = th.sin_cos();
    [cs * s[0] - sn * s[1], sn * s[0] + cs * s[1]]
}

impl PageData {
    /// Where `a` is on frame `f`, m (module doc: place).
    pub(crate) fn place(&self, f: usize, a: &Anchor) -> [f64; 2] {
        match a.body {
            None => a.s,
            Some(k) => {
                let b = &self.bodies[k];
                let r = rot(b.theta[f], a.s);
                [b.x[f] + r[0], b.y[f] + r[1]]
            }
        }
    }

    /// The series named `name`.
    pub(crate) fn series(&self, name: &str) -> Option<&SeriesData> {
        self.series.iter().find(|s| s.name == name)
    }

    /// The data as the page's JSON: numbers rounded as the module doc says; `</` written
    /// `<\/` so that the text can sit inside a script element.
    pub(crate) fn to_json(&self) -> Result<String, Error> {
        let s = serde_json::to_string(self)
            .map_err(|e| Error::Internal(format!("animation data: {e}")))?;
        Ok(s.replace("</", "<\\/"))
    }
}

/// An anchor of an attachment (`what` names it in errors).
fn anchor_of(
    scene: &Scene,
    body: &str,
    point: Option<&str>,
    at: Option<[f64; 2]>,
    what: &str,
) -> Result<Anchor, Error> {
    if body == GROUND {
        return Ok(Anchor {
            body: None,
            s: at.unwrap_or([0.0, 0.0]),
        });
    }
    let k = scene
        .body_index(body)
        .ok_or_else(|| Error::Input(format!("scene.json: {what} names no body '{body}'")))?;
    let s = match point {
        Some(p) => *scene.bodies[k].points.get(p).ok_or_else(|| {
            Error::Input(format!(
                "scene.json: {what} names no point '{p}' of body {body}"
            ))
        })?,
        None => [0.0, 0.0],
    };
    Ok(Anchor { body: Some(k), s })
}

fn attachment(scene: &Scene, a: &Attachment, what: &str) -> Result<Anchor, Error> {
    anchor_of(scene, &a.body, a.point.as_deref(), a.at, what)
}

fn clearance_end(scene: &Scene, e: &ClearanceEnd, what: &str) -> Result<Anchor, Error> {
    anchor_of(scene, &e.body, e.point.as_deref(), e.at, what)
}

/// The convex hull of `p` (Andrew's monotone chain), counter-clockwise, without collinear
/// points.
fn hull(p: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut v: Vec<[f64; 2]> = p.to_vec();
    v.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    v.dedup();
    if v.len() < 3 {
        return v;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut h: Vec<[f64; 2]> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(v.iter())
        } else {
            Box::new(v.iter().rev())
        };
        for &q in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

/// Reads the trajectory's columns `names` on the frame rows; a missing column is an input
/// error naming it.
fn frame_column(table: &Table, rows: &[usize], name: &str) -> Result<Vec<f64>, Error> {
    let c = table.column(name).ok_or_else(|| {
        Error::Input(format!(
            "trajectory.csv has no filled column {name}: it was not written by this scene \
             (or by an older lash without per-body columns)"
        ))
    })?;
    Ok(rows.iter().map(|&i| c[i]).collect())
}

/// The film's (F_r, F_t) of the lubricated clearance joints on the frames, by joint index in
/// `scene.joints`, from the mechanism re-evaluated at each frame's state; checks that the
/// re-evaluation gives the trajectory's e/c and |F_film| (module doc).
#[allow(clippy::type_complexity)]
fn film_components(
    scene: &Scene,
    table: &Table,
    rows: &[usize],
) -> Result<BTreeMap<usize, (Vec<f64>, Vec<f64>)>, Error> {
    let lubricated: Vec<(usize, &str)> = scene
        .joints
        .iter()
        .enumerate()
        .filter_map(|(k, j)| match j {
            JointSpec::Clearance(c) if c.film.is_some() => Some((k, c.name.as_str())),
            _ => None,
        })
        .collect();
    let mut out = BTreeMap::new();
    if lubricated.is_empty() {
        return Ok(out);
    }
    let m = Mechanism::from_scene(scene).map_err(|error| Error::Scene {
        case: "scene.json".into(),
        error,
    })?;
    let int = m.integrated_bodies();
    let mut cols: Vec<&[f64]> = Vec::new();
    for rate in [false, true] {
        for b in &int {
            for q in if rate {
                ["vx", "vy", "omega"]
            } else {
                ["x", "y", "theta"]
            } {
                let name = format!("{b}.{q}");
                cols.push(table.column(&name).ok_or_else(|| {
                    Error::Input(format!("trajectory.csv has no filled column {name}"))
                })?);
            }
        }
    }
    let t = table.t();
    let mut checks = Vec::new();
    for &(k, name) in &lubricated {
        let get = |q: &str| {
            let n = format!("{name}.{q}");
            table
                .column(&n)
                .ok_or_else(|| Error::Input(format!("trajectory.csv has no filled column {n}")))
        };
        checks.push((k, name, get("ex_over_c")?, get("film_force")?));
        out.insert(
            k,
            (
                Vec::with_capacity(rows.len()),
                Vec::with_capacity(rows.len()),
            ),
        );
    }
    let mut y = vec![0.0; cols.len()];
    for &i in rows {
        for (v, c) in y.iter_mut().zip(&cols) {
            *v = c[i];
        }
        // The trajectory holds the absolute (q, q̇); the mechanism's state is its
        // formulation's (joint coordinates under minimal).
        let o = m.outputs(t[i], &m.state_of_absolute(&y));
        for &(k, name, ex, film) in &checks {
            let c = o.clearance.iter().find(|c| c.name == name).ok_or_else(|| {
                Error::Internal(format!("animation: no outputs of clearance joint {name}"))
            })?;
            let mag = c.film_fr.hypot(c.film_ft);
            let ok_e = (c.ex_over_c - ex[i]).abs() <= 1e-9 * ex[i].abs().max(1.0);
            let ok_f = (mag - film[i]).abs() <= 1e-9 * film[i].abs().max(1e-9);
            if !(ok_e && ok_f) {
                return Err(Error::Input(format!(
                    "trajectory.csv does not match scene.json: at t = {} the scene gives \
                     {name}.ex_over_c = {} and |F_film| = {mag} N, the trajectory {} and {} N",
                    t[i], c.ex_over_c, ex[i], film[i]
                )));
            }
            let e = out.get_mut(&k).expect("inserted above");
            e.0.push(c.film_fr);
            e.1.push(c.film_ft);
        }
    }
    Ok(out)
}

/// Builds what the page receives from the scene and its run's trajectory (module doc).
/// Errors: a column the scene needs is missing or the trajectory does not match the scene
/// ([`Error::Input`]); an unknown trace point or column ([`Error::Usage`], listing the
/// choices).
pub(crate) fn page_data(
    scene: &Scene,
    table: &Table,
    title: &str,
    o: &AnimationOptions,
) -> Result<PageData, Error> {
    let max_frames = o.max_frames.unwrap_or(DEFAULT_MAX_FRAMES);
    if max_frames < 2 {
        return Err(Error::Usage(format!(
            "max_frames must be at least 2, got {max_frames}"
        )));
    }
    let (rows, stride) = frame_rows(table.rows(), max_frames);
    let t: Vec<f64> = rows.iter().map(|&i| table.t()[i]).collect();

    // Bodies and their poses.
    let mut bodies = Vec::new();
    for b in &scene.bodies {
        let q = |c: &str| frame_column(table, &rows, &format!("{}.{c}", b.name));
        bodies.push(BodyData {
            name: b.name.clone(),
            shape: Shape::Disc,
            outline: Vec::new(),
            width: 0.0,
            points: b
                .points
                .iter()
                .map(|(n, s)| NamedPoint {
                    name: n.clone(),
                    s: *s,
                })
                .collect(),
            x: q("x")?,
            y: q("y")?,
            theta: q("theta")?,
        });
    }

    // Joints and force elements.
    let mut pins = Vec::new();
    let mut guides = Vec::new();
    let mut drivers = Vec::new();
    let mut clearance = Vec::new();
    let mut blocks = Vec::new();
    let films = film_components(scene, table, &rows)?;
    for (k, j) in scene.joints.iter().enumerate() {
        let what = format!("joints[{k}] ({})", j.name());
        match j {
            JointSpec::Revolute(r) => pins.push(Pin {
                name: r.name.clone(),
                a: attachment(scene, &r.a, &what)?,
                b: attachment(scene, &r.b, &what)?,
            }),
            JointSpec::Translational(g) => {
                let d = g.direction;
                let n = d[0].hypot(d[1]);
                guides.push(Guide {
                    name: g.name.clone(),
                    origin: g.origin,
                    direction: [d[0] / n, d[1] / n],
                })
            }
            JointSpec::Driver(d) => {
                // The pivot: a revolute joint of the driven body.
                let pivot = scene.joints.iter().find_map(|j| match j {
                    JointSpec::Revolute(r) if r.a.body == d.body => Some(&r.a),
                    JointSpec::Revolute(r) if r.b.body == d.body => Some(&r.b),
                    _ => None,
                });
                let at = match pivot {
                    Some(a) => attachment(scene, a, &what)?,
                    None => anchor_of(scene, &d.body, None, None, &what)?,
                };
                drivers.push(Driver {
                    name: d.name.clone(),
                    at,
                    sense: d.omega_rad_s().signum(),
                });
            }
            JointSpec::Clearance(c) => {
                let (rb, rj) = (c.bearing.radius, c.journal.radius);
                let q = |s: &str| frame_column(table, &rows, &format!("{}.{s}", c.name));
                let film = films.get(&k);
                clearance.push(Clearance {
                    name: c.name.clone(),
                    bearing: clearance_end(scene, &c.bearing, &what)?,
                    journal: clearance_end(scene, &c.journal, &what)?,
                    rb,
                    rj,
                    c: rb - rj,
                    magnify: magnification(rb, rb - rj),
                    ex: q("ex_over_c")?,
                    ey: q("ey_over_c")?,
                    f_n: q("contact_force")?,
                    ft: q("friction_force")?,
                    film_r: film.map(|f| f.0.clone()),
                    film_t: film.map(|f| f.1.clone()),
                });
            }
            JointSpec::PrismaticClearance(p) => {
                let a = p.block.axis;
                let na = a[0].hypot(a[1]);
                let d = p.guide.direction;
                let nd = d[0].hypot(d[1]);
                blocks.push(Block {
                    name: p.name.clone(),
                    center: anchor_of(
                        scene,
                        &p.block.body,
                        Some(p.block.point.as_str()),
                        None,
                        &what,
                    )?,
                    axis: [a[0] / na, a[1] / na],
                    length: p.block.length,
                    width: p.block.width,
                    guide_at: p.guide.at,
                    guide_direction: [d[0] / nd, d[1] / nd],
                    guide_width: p.guide.width,
                });
            }
        }
    }
    let mut springs = Vec::new();
    for (k, f) in scene.forces.iter().enumerate() {
        if let ForceElementSpec::SpringDamper(s) = f {
            let what = format!("forces[{k}] ({})", s.name);
            springs.push(Spring {
                name: s.name.clone(),
                a: attachment(scene, &s.a, &what)?,
                b: attachment(scene, &s.b, &what)?,
            });
        }
    }

    let mut data = PageData {
        title: title.to_string(),
        subtitle: scene.description.clone(),
        rows: table.rows(),
        stride,
        frame_rows: rows.clone(),
        t,
        view: [0.0; 4],
        bodies,
        pins,
        guides,
        drivers,
        springs,
        blocks,
        clearance,
        series: Vec::new(),
        trace: String::new(),
        column: String::new(),
    };
    shapes_and_view(&mut data);

    // Series.
    for name in table.present() {
        if name == "t" {
            continue;
        }
        let c = table.column(name).unwrap_or_default();
        let v: Vec<f64> = rows.iter().map(|&i| c[i]).collect();
        let (lo, hi) = if stride > 1 {
            let mut lo = Vec::with_capacity(rows.len());
            let mut hi = Vec::with_capacity(rows.len());
            for (f, &i) in rows.iter().enumerate() {
                let from = if f == 0 { 0 } else { rows[f - 1] };
                let block = &c[from..=i];
                lo.push(block.iter().copied().fold(f64::INFINITY, f64::min));
                hi.push(block.iter().copied().fold(f64::NEG_INFINITY, f64::max));
            }
            (Some(lo), Some(hi))
        } else {
            (None, None)
        };
        data.series.push(SeriesData {
            name: name.to_string(),
            unit: unit(name).to_string(),
            v,
            lo,
            hi,
        });
    }
    data.trace = trace_choice(scene, &data, o.trace.as_deref())?;
    data.column = column_choice(scene, &data, o.column.as_deref())?;
    Ok(data)
}

/// The body shapes (sized from the extent of the motion) and the view: the box holding every
/// drawn outline, bearing circle, spring and block on every frame, padded by 8 %.
fn shapes_and_view(d: &mut PageData) {
    type Bounds = [f64; 4];
    fn add(b: &mut Bounds, p: [f64; 2], r: f64) {
        b[0] = b[0].min(p[0] - r);
        b[1] = b[1].max(p[0] + r);
        b[2] = b[2].min(p[1] - r);
        b[3] = b[3].max(p[1] + r);
    }
    let empty = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    // The extent of the points alone sets the sizes of bars, blocks and discs.
    let mut b = empty;
    let frames = d.t.len();
    for f in 0..frames {
        for (k, body) in d.bodies.iter().enumerate() {
            add(
                &mut b,
                d.place(
                    f,
                    &Anchor {
                        body: Some(k),
                        s: [0.0, 0.0],
                    },
                ),
                0.0,
            );
            for p in &body.points {
                add(
                    &mut b,
                    d.place(
                        f,
                        &Anchor {
                            body: Some(k),
                            s: p.s,
                        },
                    ),
                    0.0,
                );
            }
        }
        for c in &d.clearance {
            add(&mut b, d.place(f, &c.bearing), c.rb);
        }
    }
    for p in &d.pins {
        for a in [&p.a, &p.b] {
            if a.body.is_none() {
                add(&mut b, a.s, 0.0);
            }
        }
    }
    if !b[0].is_finite() {
        b = [-0.1, 0.1, -0.1, 0.1];
    }
    let diag = (b[1] - b[0]).hypot(b[3] - b[2]).max(1e-6);
    let base = 0.018 * diag;
    // Largest bearing radius on each body (a slider's block is drawn around its bearing).
    let mut bearing_r = vec![0.0f64; d.bodies.len()];
    for c in &d.clearance {
        if let Some(k) = c.bearing.body {
            bearing_r[k] = bearing_r[k].max(c.rb);
        }
    }
    for (k, body) in d.bodies.iter_mut().enumerate() {
        let pts: Vec<[f64; 2]> = body.points.iter().map(|p| p.s).collect();
        let h = hull(&pts);
        let len = |a: [f64; 2], c: [f64; 2]| (a[0] - c[0]).hypot(a[1] - c[1]);
        if h.len() >= 3 {
            body.shape = Shape::Polygon;
            body.outline = h;
            body.width = base * 0.5;
        } else if h.len() == 2 {
            body.shape = Shape::Bar;
            body.width = base.min(0.35 * len(h[0], h[1]));
            body.outline = h;
        } else if h.len() == 1 && h[0][0].hypot(h[0][1]) > 1e-9 * diag {
            // One point away from the centre of mass (a link pinned at one end): a bar from
            // it through the centre of mass to its mirror image.
            let (p, q) = (h[0], [-h[0][0], -h[0][1]]);
            body.shape = Shape::Bar;
            body.width = base.min(0.35 * len(p, q));
            body.outline = vec![p, q];
        } else if h.len() == 1 {
            body.shape = Shape::Block;
            let (w, hh) = if bearing_r[k] > 0.0 {
                (1.3 * bearing_r[k], bearing_r[k])
            } else {
                (2.0 * base, 1.5 * base)
            };
            let c = h[0];
            body.outline = vec![
                [c[0] - w, c[1] - hh],
                [c[0] + w, c[1] - hh],
                [c[0] + w, c[1] + hh],
                [c[0] - w, c[1] + hh],
            ];
            body.width = base * 0.5;
        } else {
            body.shape = Shape::Disc;
            body.width = 1.5 * base;
        }
    }
    // The view: everything drawn, on every frame.
    let mut v = b;
    for f in 0..frames {
        for (k, body) in d.bodies.iter().enumerate() {
            let r = if body.shape == Shape::Polygon {
                0.0
            } else {
                0.5 * body.width
            };
            for s in &body.outline {
                add(
                    &mut v,
                    d.place(
                        f,
                        &Anchor {
                            body: Some(k),
                            s: *s,
                        },
                    ),
                    r,
                );
            }
            if body.shape == Shape::Disc {
                add(&mut v, [body.x[f], body.y[f]], body.width);
            }
        }
        for s in &d.springs {
            add(&mut v, d.place(f, &s.a), 0.0);
            add(&mut v, d.place(f, &s.b), 0.0);
        }
        for bl in &d.blocks {
            add(
                &mut v,
                d.place(f, &bl.center),
                0.5 * bl.length.hypot(bl.width),
            );
        }
    }
    let pad = 0.08 * (v[1] - v[0]).max(v[3] - v[2]).max(1e-6);
    d.view = [v[0] - pad, v[1] + pad, v[2] - pad, v[3] + pad];
}

/// The trace point: the option (checked), else the module default.
fn trace_choice(scene: &Scene, d: &PageData, given: Option<&str>) -> Result<String, Error> {
    let mut choices: Vec<String> = Vec::new();
    for b in &d.bodies {
        choices.push(b.name.clone());
        for p in &b.points {
            choices.push(format!("{}.{}", b.name, p.name));
        }
    }
    if let Some(g) = given {
        if choices.iter().any(|c| c == g) {
            return Ok(g.to_string());
        }
        return Err(Error::Usage(format!(
            "trace: '{g}' is no body or body point of the scene; choose one of {}",
            choices.join(", ")
        )));
    }
    let role = scene.roles.clearance_joint.as_deref();
    let journal = scene
        .joints
        .iter()
        .filter_map(|j| match j {
            JointSpec::Clearance(c) => Some(c),
            _ => None,
        })
        .find(|c| role.is_none_or(|r| r == c.name))
        .map(|c| c.journal.body.clone())
        .filter(|b| b != GROUND);
    Ok(journal.unwrap_or_else(|| d.bodies.last().map(|b| b.name.clone()).unwrap_or_default()))
}

/// The first column of the panel: the option (checked), else the module default.
fn column_choice(scene: &Scene, d: &PageData, given: Option<&str>) -> Result<String, Error> {
    if let Some(g) = given {
        if d.series(g).is_some() {
            return Ok(g.to_string());
        }
        let names: Vec<&str> = d.series.iter().map(|s| s.name.as_str()).collect();
        return Err(Error::Usage(format!(
            "column: '{g}' is no filled column of trajectory.csv; choose one of {}",
            names.join(", ")
        )));
    }
    let first_angle = scene
        .bodies
        .first()
        .map(|b| format!("{}.theta", b.name))
        .unwrap_or_default();
    Ok(["contact_force", "slider_a"]
        .iter()
        .map(|s| s.to_string())
        .chain(d.bodies.iter().map(|b| format!("{}.theta", b.name)))
        .find(|n| {
            d.series(n).is_some_and(|s| {
                // A constant column shows nothing: prefer one that moves.
                s.v.iter().any(|v| *v != s.v[0]) || n == &first_angle
            })
        })
        .unwrap_or(first_angle))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_keep_both_ends_and_an_even_stride() {
        assert_eq!(frame_rows(5, 10), (vec![0, 1, 2, 3, 4], 1));
        assert_eq!(frame_rows(4001, 2500), ((0..4001).step_by(2).collect(), 2));
        let (f, s) = frame_rows(4002, 2500);
        assert_eq!((s, f.len(), *f.last().unwrap()), (2, 2002, 4001));
        let (f, s) = frame_rows(100_001, 2500);
        assert!(
            f.len() <= 2500 && s == 41 && f[f.len() - 1] == 100_000,
            "{s}"
        );
        assert_eq!(frame_rows(1, 10), (vec![0], 1));
    }

    #[test]
    fn magnification_is_1_2_5_below_half_the_bearing_over_the_clearance() {
        // The press: R_B = 50 mm, c = 0.1 mm → R_B / 2c = 250 → 200.
        assert_eq!(magnification(0.05, 1e-4), 200.0);
        // The four-bar: 10 mm, 0.5 mm → 10.
        assert_eq!(magnification(0.01, 5e-4), 10.0);
        // The pendulum: 10 mm, 1 mm → 5.
        assert_eq!(magnification(0.01, 1e-3), 5.0);
        // 0.05 / 1e-5 = 5000 → 5000 (a 1-2-5 number itself).
        assert_eq!(magnification(0.1, 1e-5), 5000.0);
        // A clearance near the radius: no magnification.
        assert_eq!(magnification(0.01, 0.006), 1.0);
        assert_eq!(magnification(0.01, 0.002), 2.0);
    }

    #[test]
    fn hull_is_counter_clockwise_and_drops_inner_points() {
        let h = hull(&[[0.0, 0.0], [1.0, 0.0], [0.5, 0.2], [1.0, 1.0], [0.0, 1.0]]);
        assert_eq!(h, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        assert_eq!(hull(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]).len(), 2);
    }

    #[test]
    fn rounding_keeps_seven_digits() {
        assert_eq!(round7(0.123456789), 0.1234568);
        assert_eq!(round7(-2.7182818e-17), -2.718282e-17);
        assert_eq!(round7(0.0), 0.0);
        for x in [0.3650000123, 1.0 / 3.0, 12345.678901, -9.81e-3] {
            assert!((round7(x) - x).abs() <= 5e-7 * x.abs(), "{x}");
        }
    }
}
