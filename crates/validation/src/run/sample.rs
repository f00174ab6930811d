//! Samples of a mechanism: one evaluation of its outputs seen through the scene's roles
//! (slider, crank driver, clearance joint), with the closed-form ideal slider-crank beside, and
//! the fixed trajectory columns it fills.
//!
//! Source: docs/outputs.md (`trajectory.csv`, `metrics`).

use lash_model::scene::JointSpec;
use lash_model::{IdealSliderCrank, Mechanism, Outputs, Scene};

use crate::report::metrics::Sample;

/// The role-based view of one mechanism evaluation: maps `Mechanism::outputs` to a metrics
/// [`Sample`] through the scene's roles (slider, crank driver, clearance joint), with the ideal
/// closed-form slider acceleration beside. Used by every command that samples a run.
pub(crate) struct Sampler<'a> {
    pub(crate) mech: &'a Mechanism,
    pub(crate) ideal: Option<IdealSliderCrank>,
    pub(crate) clearance_index: Option<usize>,
    pub(crate) driver_pos: Option<usize>,
}

impl<'a> Sampler<'a> {
    /// The sampler of `mech`, built from `scene` (the scene the mechanism was made from).
    pub(crate) fn new(mech: &'a Mechanism, scene: &Scene) -> Sampler<'a> {
        let roles = mech.roles();
        let driver_pos = roles.crank_driver.map(|j| {
            scene.joints[..j]
                .iter()
                .filter(|x| matches!(x, JointSpec::Driver(_)))
                .count()
        });
        Sampler {
            mech,
            ideal: mech.ideal_slider_crank(),
            clearance_index: roles.clearance_index,
            driver_pos,
        }
    }

    /// One sample at (t, y).
    pub(crate) fn sample(&self, t: f64, y: &[f64]) -> Sample {
        self.of_outputs(t, &self.mech.outputs(t, y))
    }

    /// The sample of one evaluation `o` at time t.
    pub(crate) fn of_outputs(&self, t: f64, o: &Outputs) -> Sample {
        let c = self.clearance_index.and_then(|k| o.clearance.get(k));
        let ideal_a = match (&self.ideal, o.crank_angle, o.slider_a) {
            (Some(i), Some(phi), Some(_)) => Some(i.a_at(i.theta_of_crank_angle(phi))),
            _ => None,
        };
        Sample {
            t,
            crank_angle: o.crank_angle,
            slider_x: o.slider_x,
            slider_v: o.slider_v,
            slider_a: o.slider_a,
            ex_over_c: c.map(|c| c.ex_over_c),
            ey_over_c: c.map(|c| c.ey_over_c),
            eps: c.map(|c| c.eps),
            delta: c.map(|c| c.delta),
            contact_force: c.map(|c| c.contact_force),
            friction_force: c.map(|c| c.friction_force),
            film_force: c.map(|c| c.film_force),
            constraint_violation: o.constraint_violation,
            driver_torque: self
                .driver_pos
                .and_then(|i| o.driver_torques.get(i).copied()),
            ideal_slider_a: ideal_a,
        }
    }

    /// Which fixed trajectory columns ([`crate::report::trajectory::COLUMNS`]) this mechanism fills.
    pub(crate) fn fixed_present(&self) -> [bool; 13] {
        let roles = self.mech.roles();
        let (crank, slider, joint) = (
            roles.crank_body.is_some(),
            roles.slider.is_some(),
            self.clearance_index.is_some(),
        );
        [
            true,
            crank,
            slider,
            slider,
            slider,
            joint,
            joint,
            joint,
            joint,
            joint,
            joint,
            true,
            self.driver_pos.is_some(),
        ]
    }
}

/// The fixed trajectory columns of a sample (NaN where absent), in the order of
/// [`crate::report::trajectory::COLUMNS`].
pub(crate) fn fixed_values(s: &Sample) -> [f64; 13] {
    let v = |x: Option<f64>| x.unwrap_or(f64::NAN);
    [
        s.t,
        v(s.crank_angle),
        v(s.slider_x),
        v(s.slider_v),
        v(s.slider_a),
        v(s.ex_over_c),
        v(s.ey_over_c),
        v(s.delta),
        v(s.contact_force),
        v(s.friction_force),
        v(s.film_force),
        s.constraint_violation,
        v(s.driver_torque),
    ]
}
