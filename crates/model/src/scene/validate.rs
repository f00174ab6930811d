//! Scene validation: every value and every reference, the first failure with its JSON path.
//!
//! ```text
//! validate = bodies → joints (each by its kind; clearance joints in clearance/) → force
//!            elements (elements/) → gravity, Baumgarte, t_start → roles → time span
//! ```
//! Constraint rank and assembly are checked by [`crate::Mechanism::from_scene`].

use crate::scene::check::{check_name, Checker};
use crate::scene::error::{invalid, SceneError};
use crate::scene::format::{
    BodySpec, DriverSpec, JointSpec, RevoluteSpec, Scene, TranslationalSpec,
};
use crate::scene::refs::{check_attachment, check_body_point, check_moving, GROUND};

type C = Checker;

impl Scene {
    /// Checks every value and every reference; the first failure is returned with its JSON path.
    /// (Constraint rank and assembly are checked by [`crate::Mechanism::from_scene`].)
    pub fn validate(&self) -> Result<(), SceneError> {
        self.check_bodies()?;
        self.check_joints()?;
        crate::elements::validate_all(&self.forces, self)?;
        self.check_globals()?;
        self.check_roles()?;
        crate::scene::resolution::check(self)?;
        self.check_time_span()
    }

    /// At least one body; each named uniquely (not "ground"), with positive mass and inertia
    /// and finite points and initial values.
    fn check_bodies(&self) -> Result<(), SceneError> {
        if self.bodies.is_empty() {
            return Err(invalid("bodies", "a scene needs at least one body"));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            let p = format!("bodies[{i}]");
            check_name(&format!("{p}.name"), &b.name)?;
            if b.name == GROUND {
                return Err(invalid(
                    format!("{p}.name"),
                    "\"ground\" is reserved for the fixed frame",
                ));
            }
            if self.bodies[..i].iter().any(|o| o.name == b.name) {
                return Err(invalid(
                    format!("{p}.name"),
                    format!("duplicate body name '{}'", b.name),
                ));
            }
            check_body(&p, b)?;
        }
        Ok(())
    }

    /// Every joint: a unique name, its kind's checks, its initial rate.
    fn check_joints(&self) -> Result<(), SceneError> {
        for (i, j) in self.joints.iter().enumerate() {
            let p = format!("joints[{i}]");
            check_name(&format!("{p}.name"), j.name())?;
            if self.joints[..i].iter().any(|o| o.name() == j.name()) {
                return Err(invalid(
                    format!("{p}.name"),
                    format!("duplicate joint name '{}'", j.name()),
                ));
            }
            match j {
                JointSpec::Revolute(r) => self.check_revolute(&p, r)?,
                JointSpec::Translational(t) => self.check_translational(&p, t)?,
                JointSpec::Driver(d) => self.check_driver(&p, d)?,
                JointSpec::Clearance(c) => crate::clearance::revolute::validate(self, &p, c)?,
                JointSpec::PrismaticClearance(c) => {
                    crate::clearance::prismatic::validate(self, &p, c)?
                }
            }
            let rate = match j {
                JointSpec::Revolute(r) => r.initial_rate,
                JointSpec::Translational(t) => t.initial_rate,
                _ => None,
            };
            if let Some(v) = rate {
                C::finite(&format!("{p}.initial_rate"), v)?;
            }
        }
        Ok(())
    }

    /// A revolute joint: two attachments on different bodies.
    fn check_revolute(&self, p: &str, r: &RevoluteSpec) -> Result<(), SceneError> {
        check_attachment(self, &format!("{p}.a"), &r.a.body, &r.a.point, &r.a.at)?;
        check_attachment(self, &format!("{p}.b"), &r.b.body, &r.b.point, &r.b.at)?;
        if r.a.body == r.b.body {
            return Err(invalid(
                format!("{p}.b.body"),
                format!(
                    "a revolute joint needs two different bodies, both are '{}'",
                    r.a.body
                ),
            ));
        }
        Ok(())
    }

    /// A translational joint: a body point, a line, an angle.
    fn check_translational(&self, p: &str, t: &TranslationalSpec) -> Result<(), SceneError> {
        check_body_point(self, p, &t.body, &t.point)?;
        C::finite2(&format!("{p}.origin"), t.origin)?;
        C::finite2(&format!("{p}.direction"), t.direction)?;
        if t.direction[0] == 0.0 && t.direction[1] == 0.0 {
            return Err(invalid(
                format!("{p}.direction"),
                "must not be the zero vector",
            ));
        }
        if let Some(a) = t.angle {
            C::finite(&format!("{p}.angle"), a)?;
        }
        Ok(())
    }

    /// A driver: a moving body, θ₀, and exactly one of ω and rpm.
    fn check_driver(&self, p: &str, d: &DriverSpec) -> Result<(), SceneError> {
        check_moving(self, &format!("{p}.body"), &d.body)?;
        C::finite(&format!("{p}.theta0"), d.theta0)?;
        match (d.omega, d.rpm) {
            (Some(w), None) => C::finite(&format!("{p}.omega"), w),
            (None, Some(n)) => C::finite(&format!("{p}.rpm"), n),
            (Some(_), Some(_)) => Err(invalid(
                format!("{p}.rpm"),
                "give either omega (rad/s) or rpm, not both",
            )),
            (None, None) => Err(invalid(p, "a driver needs omega (rad/s) or rpm")),
        }
    }

    /// Gravity, the Baumgarte parameters, the start time.
    fn check_globals(&self) -> Result<(), SceneError> {
        C::finite2("gravity", self.gravity)?;
        C::non_negative("baumgarte.alpha", self.baumgarte.alpha, "alpha")?;
        C::non_negative("baumgarte.beta", self.baumgarte.beta, "beta")?;
        let al = &self.augmented_lagrangian;
        C::positive("augmented_lagrangian.penalty", al.penalty, "penalty")?;
        C::non_negative("augmented_lagrangian.xi", al.xi, "xi")?;
        C::non_negative("augmented_lagrangian.omega", al.omega, "omega")?;
        C::positive("augmented_lagrangian.tol", al.tol, "tol")?;
        if !(al.tol < 1.0) {
            return Err(invalid(
                "augmented_lagrangian.tol",
                format!("tol = {} must be below 1 (a relative change of q̈)", al.tol),
            ));
        }
        if al.max_iterations == 0 {
            return Err(invalid(
                "augmented_lagrangian.max_iterations",
                "at least one iteration",
            ));
        }
        self.solver.check()?;
        C::finite("t_start", self.t_start)
    }

    /// The roles name parts of the right kinds.
    fn check_roles(&self) -> Result<(), SceneError> {
        if let Some(s) = &self.roles.slider {
            if self.body_index(s).is_none() {
                return Err(invalid("roles.slider", format!("no body named '{s}'")));
            }
        }
        if let Some(d) = &self.roles.crank_driver {
            match self.joint_index(d).map(|k| &self.joints[k]) {
                Some(JointSpec::Driver(_)) => {}
                Some(other) => {
                    return Err(invalid(
                        "roles.crank_driver",
                        format!("joint '{d}' is a {} joint, not a driver", other.type_name()),
                    ))
                }
                None => {
                    return Err(invalid(
                        "roles.crank_driver",
                        format!("no joint named '{d}'"),
                    ))
                }
            }
        }
        if let Some(c) = &self.roles.crank {
            self.check_crank_role(c)?;
        }
        if let Some(d) = &self.roles.clearance_joint {
            match self.joint_index(d).map(|k| &self.joints[k]) {
                Some(JointSpec::Clearance(_)) => {}
                Some(other) => {
                    return Err(invalid(
                        "roles.clearance_joint",
                        format!(
                            "joint '{d}' is a {} joint, not a clearance joint",
                            other.type_name()
                        ),
                    ))
                }
                None => {
                    return Err(invalid(
                        "roles.clearance_joint",
                        format!("no joint named '{d}'"),
                    ))
                }
            }
        }
        Ok(())
    }

    /// `roles.crank` names a body or a revolute joint that is not ground on both sides, and
    /// agrees with `roles.crank_driver` (whose body is the crank) when both are given.
    fn check_crank_role(&self, c: &str) -> Result<(), SceneError> {
        const P: &str = "roles.crank";
        let bodies = if c == crate::scene::GROUND {
            return Err(invalid(
                P,
                "the ground does not turn: name a body or a revolute joint",
            ));
        } else if self.body_index(c).is_some() {
            [c.to_string(), crate::scene::GROUND.to_string()]
        } else {
            match self.joint_index(c).map(|k| &self.joints[k]) {
                Some(JointSpec::Revolute(r)) => [r.a.body.clone(), r.b.body.clone()],
                Some(other) => {
                    return Err(invalid(
                        P,
                        format!(
                            "joint '{c}' is a {} joint, not a revolute joint (a crank is a body \
                             or a revolute joint)",
                            other.type_name()
                        ),
                    ))
                }
                None => return Err(invalid(P, format!("no body or revolute joint named '{c}'"))),
            }
        };
        if let Some(d) = &self.roles.crank_driver {
            if let Some(JointSpec::Driver(dr)) = self.joint_index(d).map(|k| &self.joints[k]) {
                let agrees = (bodies[0] == dr.body && bodies[1] == crate::scene::GROUND)
                    || (bodies[1] == dr.body && bodies[0] == crate::scene::GROUND);
                if !agrees {
                    return Err(invalid(
                        P,
                        format!(
                            "'{c}' is not the body '{}' that the crank driver '{d}' turns \
                             against the ground (crank_driver implies the crank; give one)",
                            dr.body
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Exactly one of t_end and revolutions, giving a finite end time after t_start.
    fn check_time_span(&self) -> Result<(), SceneError> {
        match (self.t_end, self.revolutions) {
            (Some(te), None) => {
                C::finite("t_end", te)?;
                if !(te > self.t_start) {
                    return Err(invalid(
                        "t_end",
                        format!("must be greater than t_start = {}, got {te}", self.t_start),
                    ));
                }
                if !(te - self.t_start).is_finite() {
                    return Err(invalid(
                        "t_end",
                        format!(
                            "the time span t_end − t_start = {te:?} − {:?} overflows",
                            self.t_start
                        ),
                    ));
                }
            }
            (None, Some(n)) => {
                C::positive("revolutions", n, "revolutions")?;
                let Some(d) = &self.roles.crank_driver else {
                    let why = match &self.roles.crank {
                        Some(c) => format!(
                            "needs roles.crank_driver (a driver at a prescribed speed): the \
                             time the crank '{c}' takes to turn is not known before the run; \
                             give t_end"
                        ),
                        None => "needs roles.crank_driver (the driver whose revolutions are \
                                 counted)"
                            .to_string(),
                    };
                    return Err(invalid("revolutions", why));
                };
                let k = self.joint_index(d).expect("checked above");
                if let JointSpec::Driver(dr) = &self.joints[k] {
                    let w = dr.omega_rad_s();
                    if w == 0.0 {
                        return Err(invalid(
                            "revolutions",
                            format!("the crank driver '{d}' does not turn (omega = 0)"),
                        ));
                    }
                    // The end time must be a finite time after t_start in f64 (1e300 revolutions
                    // overflow; t_start = 1e300 absorbs any span).
                    let span = n * 2.0 * std::f64::consts::PI / w.abs();
                    let te = self.t_start + span;
                    if !(span.is_finite() && te.is_finite() && te > self.t_start) {
                        return Err(invalid(
                            "revolutions",
                            format!(
                                "the end time t_start + revolutions·2π/|ω| = {:?} + {span:?} s \
                             is not a finite time after t_start",
                                self.t_start
                            ),
                        ));
                    }
                }
            }
            (Some(_), Some(_)) => {
                return Err(invalid(
                    "revolutions",
                    "give either t_end or revolutions, not both",
                ))
            }
            (None, None) => {
                return Err(invalid(
                    ".",
                    "the scene needs t_end (s) or revolutions (of roles.crank_driver)",
                ))
            }
        }
        Ok(())
    }
}

/// A body's values: mass and inertia positive, points and initial values finite.
fn check_body(p: &str, b: &BodySpec) -> Result<(), SceneError> {
    C::positive(&format!("{p}.mass"), b.mass, "mass")?;
    C::positive(&format!("{p}.inertia"), b.inertia, "inertia")?;
    for (name, s) in &b.points {
        C::finite2(&format!("{p}.points.{name}"), *s)?;
    }
    C::finite2(&format!("{p}.position"), b.position)?;
    C::finite(&format!("{p}.angle"), b.angle)?;
    C::finite2(&format!("{p}.velocity"), b.velocity)?;
    C::finite(&format!("{p}.angular_velocity"), b.angular_velocity)?;
    if let Some(iv) = &b.initial_velocity {
        for (f, v) in [("vx", iv.vx), ("vy", iv.vy), ("omega", iv.omega)] {
            if let Some(v) = v {
                C::finite(&format!("{p}.initial_velocity.{f}"), v)?;
            }
        }
    }
    Ok(())
}
