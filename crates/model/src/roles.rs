//! The parts of a scene that the press metrics need (docs/outputs.md, "Scene roles"), resolved
//! to indices.

use crate::clearance::revolute::Revolute;
use crate::scene::format::{JointSpec, Scene};

/// The parts that the press metrics need, resolved to indices (docs/outputs.md, "Scene roles").
///
/// ```text
/// slider → body index,  crank_driver → joint index,  clearance_joint → joint index and its
/// position among the clearance joints (the index into `Outputs::clearance`)
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
    /// Scene index of the body turned by the crank driver.
    pub crank_body: Option<usize>,
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
        let crank_body = crank_driver.and_then(|j| match &scene.joints[j] {
            JointSpec::Driver(d) => scene.body_index(&d.body),
            _ => None,
        });
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
        }
    }
}
