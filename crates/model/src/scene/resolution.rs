//! Inputs that f64 cannot resolve for the model (docs/model.md §1.6, "Resolution"): an input
//! error naming the field, as for the time axis and a driver's angle (lash-validation's run
//! plan).
//!
//! ```text
//! body angle     16 ε |θ| > ANGLE_SPACING (1e-9 rad)      → bodies[k].angle
//!                (|θ| > 2.8e5 rad: sin and cos of θ + a microradian lose their digits)
//! clearance      ε · |r| > CLEARANCE_RESOLUTION · c        → bodies[k].position, or the
//!                (|r| the distance from the origin of a     joint's ground location
//!                 clearance joint's end, c its clearance:   (joints[i].bearing.at,
//!                 positions there cannot resolve a          joints[i].guide.at)
//!                 millionth of the clearance)
//! ```

use crate::scene::error::{invalid, SceneError};
use crate::scene::format::{JointSpec, Scene};

/// The largest spacing of f64 angles (16 ε |θ|, the solvers' step floor) a body's initial
/// angle may have, rad.
pub(crate) const ANGLE_SPACING: f64 = 1e-9;

/// The smallest fraction of a clearance the positions of its ends must resolve (ε |r| ≤ this
/// × c).
pub(crate) const CLEARANCE_RESOLUTION: f64 = 1e-6;

/// The checks of the module doc; the first failure with its JSON path.
pub(crate) fn check(scene: &Scene) -> Result<(), SceneError> {
    for (k, b) in scene.bodies.iter().enumerate() {
        let spacing = 16.0 * f64::EPSILON * b.angle.abs();
        if spacing > ANGLE_SPACING {
            return Err(invalid(
                format!("bodies[{k}].angle"),
                format!(
                    "angle {:e} rad is too far from 0 for f64: angles there are {spacing:.2e} \
                     rad apart (16 ε |θ|), more than {ANGLE_SPACING:e} rad; give it modulo 2π",
                    b.angle
                ),
            ));
        }
    }
    for (i, j) in scene.joints.iter().enumerate() {
        let (c, ends): (f64, Vec<(String, f64)>) = match j {
            JointSpec::Clearance(s) => {
                let c = s.bearing.radius - s.journal.radius;
                let ends = [("bearing", &s.bearing), ("journal", &s.journal)]
                    .into_iter()
                    .map(|(name, e)| match (e.at, scene.body_index(&e.body)) {
                        (Some(at), _) => (format!("joints[{i}].{name}.at"), norm(at)),
                        (None, Some(k)) => body_end(scene, k, e.point.as_deref()),
                        (None, None) => (String::new(), 0.0),
                    })
                    .collect();
                (c, ends)
            }
            JointSpec::PrismaticClearance(s) => {
                let mut ends = vec![(format!("joints[{i}].guide.at"), norm(s.guide.at))];
                if let Some(k) = scene.body_index(&s.block.body) {
                    ends.push(body_end(scene, k, Some(&s.block.point)));
                }
                (s.clearance(), ends)
            }
            _ => continue,
        };
        if !(c > 0.0) {
            continue; // the joint's own checks name it
        }
        for (path, r) in ends {
            if f64::EPSILON * r > CLEARANCE_RESOLUTION * c {
                return Err(invalid(
                    path,
                    format!(
                        "joints[{i}] ('{}'): its end lies {r:e} m from the origin, where f64 \
                         positions are {:.2e} m apart, more than {CLEARANCE_RESOLUTION:e} of \
                         its clearance {c:e} m; move the scene toward the origin",
                        j.name(),
                        f64::EPSILON * r
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn norm(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

/// A body end: the path of the body's position and a bound on the end's distance from the
/// origin (|position| + |point|).
fn body_end(scene: &Scene, k: usize, point: Option<&str>) -> (String, f64) {
    let b = &scene.bodies[k];
    let s = point
        .and_then(|p| b.points.get(p))
        .map_or(0.0, |s| norm(*s));
    (format!("bodies[{k}].position"), norm(b.position) + s)
}
