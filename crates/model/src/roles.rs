//! The parts of a scene that the press metrics need (docs/outputs.md, "Scene roles"), resolved
//! to indices.

use std::fmt;
use std::str::FromStr;

use crate::clearance::revolute::Revolute;
use crate::scene::format::{JointSpec, Scene};

/// The parts that the press metrics need, resolved to indices (docs/outputs.md, "Scene roles").
///
/// ```text
/// slider → body index,  crank_driver → joint index,  clearance_joint → joint index and its
/// position among the clearance joints (the index into `Outputs::clearance`)
/// crank → (a, b): crank angle φ_a − φ_b (φ_ground = 0)
///   crank = BODY                → (BODY, ground)
///   crank = revolute JOINT      → (its body a, its body b)
///   crank_driver = driver JOINT → (its body, ground)   (implies the crank)
/// ```
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Roles {
    /// Scene index of the slider body.
    pub slider: Option<usize>,
    /// Scene index of the crank driver joint.
    pub crank_driver: Option<usize>,
    /// Scene index of the clearance joint.
    pub clearance_joint: Option<usize>,
    /// Index of the role's clearance joint in [`crate::Outputs::clearance`].
    pub clearance_index: Option<usize>,
    /// Scene index of the body turned by the crank (`crank` role, or the crank driver's
    /// body): the first of [`Roles::crank`] that is not the ground.
    pub crank_body: Option<usize>,
    /// The two sides of the crank angle φ_a − φ_b, scene body indices (None: the ground).
    pub crank: Option<[Option<usize>; 2]>,
}

impl Roles {
    pub(crate) fn resolve(scene: &Scene, clr: &[Revolute]) -> Roles {
        let slider = scene
            .roles
            .slider
            .as_ref()
            .and_then(|s| scene.body_index(s));
        let crank_driver = scene
            .roles
            .crank_driver
            .as_ref()
            .and_then(|s| scene.joint_index(s));
        let driven = crank_driver.and_then(|j| match &scene.joints[j] {
            JointSpec::Driver(d) => scene.body_index(&d.body).map(|k| [Some(k), None]),
            _ => None,
        });
        let named = scene.roles.crank.as_ref().and_then(|s| {
            if let Some(k) = scene.body_index(s) {
                return Some([Some(k), None]);
            }
            match scene.joint_index(s).map(|j| &scene.joints[j]) {
                Some(JointSpec::Revolute(r)) => {
                    Some([scene.body_index(&r.a.body), scene.body_index(&r.b.body)])
                }
                _ => None,
            }
        });
        let crank = named
            .or(driven)
            .filter(|c| c[0].is_some() || c[1].is_some());
        let crank_body = crank.and_then(|c| c[0].or(c[1]));
        let clearance_joint = scene
            .roles
            .clearance_joint
            .as_ref()
            .and_then(|s| scene.joint_index(s));
        let clearance_index = clearance_joint.and_then(|j| clr.iter().position(|c| c.joint == j));
        Roles {
            slider,
            crank_driver,
            clearance_joint,
            clearance_index,
            crank_body,
            crank,
        }
    }
}

/// The window of a run that its metrics summarise (`--window` of the engine's run and sweep;
/// docs/outputs.md, "The metrics window"); the engine decides each form's times.
///
/// ```text
/// last-revolution | all | T0:T1   (T0 < T1, finite, s)
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MetricsWindow {
    /// The last revolution of the crank (needs `roles.crank` or `roles.crank_driver`).
    LastRevolution,
    /// The whole run.
    All,
    /// The span [from, to] of the run, s.
    Span {
        /// Start, s.
        from: f64,
        /// End, s.
        to: f64,
    },
}

impl fmt::Display for MetricsWindow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MetricsWindow::LastRevolution => write!(f, "last-revolution"),
            MetricsWindow::All => write!(f, "all"),
            MetricsWindow::Span { from, to } => write!(f, "{from}:{to}"),
        }
    }
}

impl FromStr for MetricsWindow {
    type Err = String;

    /// `last-revolution`, `all` or `T0:T1` (two finite times, T0 < T1); the error says why
    /// and what is expected.
    fn from_str(s: &str) -> Result<MetricsWindow, String> {
        let bad = |why: &str| -> String {
            format!("'{s}': {why} (expected last-revolution, all, or T0:T1 in seconds, T0 < T1)")
        };
        match s.trim() {
            "last-revolution" => Ok(MetricsWindow::LastRevolution),
            "all" => Ok(MetricsWindow::All),
            other => {
                let Some((a, b)) = other.split_once(':') else {
                    return Err(bad("not a window"));
                };
                let num = |x: &str| x.trim().parse::<f64>().ok().filter(|v| v.is_finite());
                match (num(a), num(b)) {
                    (Some(from), Some(to)) if from < to => Ok(MetricsWindow::Span { from, to }),
                    (Some(_), Some(_)) => Err(bad("T0 must be before T1")),
                    _ => Err(bad("T0 and T1 must be finite numbers")),
                }
            }
        }
    }
}
