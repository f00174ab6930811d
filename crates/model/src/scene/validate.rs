//! Scene validation: every value and every reference, the first failure with its JSON path.

use crate::clearance::contact::{FrictionSpec, Materials, NormalSpec};
use crate::clearance::laws::FilmModel;
use crate::clearance::revolute::ClearanceSpec;
use crate::scene::check::{check_name, Checker};
use crate::scene::error::{invalid, SceneError};
use crate::scene::format::{JointSpec, Scene};
use crate::scene::refs::GROUND;

impl Scene {
    /// Checks every value and every reference; the first failure is returned with its JSON path.
    /// (Constraint rank and assembly are checked by [`crate::Mechanism::from_scene`].)
    pub fn validate(&self) -> Result<(), SceneError> {
        type C = Checker;
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
        }
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
                JointSpec::Revolute(r) => {
                    self.check_attachment(&format!("{p}.a"), &r.a.body, &r.a.point, &r.a.at)?;
                    self.check_attachment(&format!("{p}.b"), &r.b.body, &r.b.point, &r.b.at)?;
                    if r.a.body == r.b.body {
                        return Err(invalid(
                            format!("{p}.b.body"),
                            format!(
                                "a revolute joint needs two different bodies, both are '{}'",
                                r.a.body
                            ),
                        ));
                    }
                }
                JointSpec::Translational(t) => {
                    self.check_body_point(&p, &t.body, &t.point)?;
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
                }
                JointSpec::Driver(d) => {
                    self.check_moving_body(&format!("{p}.body"), &d.body)?;
                    C::finite(&format!("{p}.theta0"), d.theta0)?;
                    match (d.omega, d.rpm) {
                        (Some(w), None) => C::finite(&format!("{p}.omega"), w)?,
                        (None, Some(n)) => C::finite(&format!("{p}.rpm"), n)?,
                        (Some(_), Some(_)) => {
                            return Err(invalid(
                                format!("{p}.rpm"),
                                "give either omega (rad/s) or rpm, not both",
                            ))
                        }
                        (None, None) => {
                            return Err(invalid(p.clone(), "a driver needs omega (rad/s) or rpm"))
                        }
                    }
                }
                JointSpec::Clearance(c) => self.check_clearance(&p, c)?,
                JointSpec::PrismaticClearance(c) => {
                    crate::clearance::prismatic::validate_prismatic(self, &p, c)?
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
        crate::elements::validate_forces(self)?;
        C::finite2("gravity", self.gravity)?;
        C::non_negative("baumgarte.alpha", self.baumgarte.alpha, "alpha")?;
        C::non_negative("baumgarte.beta", self.baumgarte.beta, "beta")?;
        C::finite("t_start", self.t_start)?;
        // Roles.
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
        // Time span.
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
                    return Err(invalid(
                        "revolutions",
                        "needs roles.crank_driver (the driver whose revolutions are counted)",
                    ));
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

    fn check_moving_body(&self, path: &str, body: &str) -> Result<usize, SceneError> {
        if body == GROUND {
            return Err(invalid(path, "must name a moving body, not the ground"));
        }
        self.body_index(body)
            .ok_or_else(|| invalid(path, format!("no body named '{body}'")))
    }

    fn check_body_point(&self, path: &str, body: &str, point: &str) -> Result<(), SceneError> {
        let k = self.check_moving_body(&format!("{path}.body"), body)?;
        if !self.bodies[k].points.contains_key(point) {
            return Err(invalid(
                format!("{path}.point"),
                format!("body '{body}' has no point named '{point}'"),
            ));
        }
        Ok(())
    }

    pub(crate) fn check_attachment(
        &self,
        path: &str,
        body: &str,
        point: &Option<String>,
        at: &Option<[f64; 2]>,
    ) -> Result<(), SceneError> {
        if body == GROUND {
            if point.is_some() {
                return Err(invalid(
                    format!("{path}.point"),
                    "the ground has no named points: give its location with \"at\"",
                ));
            }
            match at {
                Some(a) => Checker::finite2(&format!("{path}.at"), *a),
                None => Err(invalid(
                    format!("{path}.at"),
                    "a ground attachment needs its global location \"at\": [x, y]",
                )),
            }
        } else {
            // The body first: a misspelt "ground" is an unknown body, not a misplaced "at".
            self.check_moving_body(&format!("{path}.body"), body)?;
            if at.is_some() {
                return Err(invalid(
                    format!("{path}.at"),
                    "\"at\" is for ground attachments; name a point of the body instead",
                ));
            }
            match point {
                Some(pt) => self.check_body_point(path, body, pt),
                None => Err(invalid(format!("{path}.point"), "missing the point name")),
            }
        }
    }

    fn check_clearance(&self, p: &str, c: &ClearanceSpec) -> Result<(), SceneError> {
        type C = Checker;
        let b = &c.bearing;
        let j = &c.journal;
        self.check_attachment(&format!("{p}.bearing"), &b.body, &b.point, &b.at)?;
        self.check_attachment(&format!("{p}.journal"), &j.body, &j.point, &j.at)?;
        if b.body == j.body {
            return Err(invalid(
                format!("{p}.journal.body"),
                format!(
                    "bearing and journal must be on different bodies, both are '{}'",
                    b.body
                ),
            ));
        }
        C::positive(&format!("{p}.bearing.radius"), b.radius, "bearing radius")?;
        C::finite(&format!("{p}.journal.radius"), j.radius)?;
        let clearance = b.radius - j.radius;
        if !(clearance > 0.0) {
            return Err(invalid(
                format!("{p}.journal.radius"),
                format!(
                    "clearance R_B − R_J = {clearance} m must be > 0 (bearing radius {}, journal radius {})",
                    b.radius, j.radius
                ),
            ));
        }
        if !(clearance < b.radius) {
            return Err(invalid(
                format!("{p}.journal.radius"),
                format!(
                    "clearance R_B − R_J = {clearance} m must be smaller than the bearing radius {} m (the journal radius must be > 0)",
                    b.radius
                ),
            ));
        }
        let check_k =
            |path: &str, k: &Option<f64>, m: &Option<Materials>| -> Result<(), SceneError> {
                match (k, m) {
                    (Some(k), None) => C::positive(&format!("{path}.k"), *k, "stiffness k"),
                    (None, Some(m)) => {
                        for (side, mat) in [("bearing", m.bearing), ("journal", m.journal)] {
                            let mp = format!("{path}.materials.{side}");
                            C::positive(
                                &format!("{mp}.youngs_modulus"),
                                mat.youngs_modulus,
                                "Young's modulus",
                            )?;
                            C::finite(&format!("{mp}.poisson_ratio"), mat.poisson_ratio)?;
                            if !(mat.poisson_ratio > -1.0 && mat.poisson_ratio < 0.5) {
                                return Err(invalid(
                                    format!("{mp}.poisson_ratio"),
                                    format!(
                                        "Poisson's ratio must lie in (-1, 0.5), got {}",
                                        mat.poisson_ratio
                                    ),
                                ));
                            }
                        }
                        // Within the magnitude range K stays finite and positive (c ≥ ulp(R_B)
                        // bounds K by about E·√(R_B/(2ε)) < 1e233); the check guards the
                        // formula should the range ever be widened.
                        let k = crate::laws::hertz_stiffness(
                            b.radius,
                            j.radius,
                            m.bearing.youngs_modulus,
                            m.bearing.poisson_ratio,
                            m.journal.youngs_modulus,
                            m.journal.poisson_ratio,
                        );
                        if !(k.is_finite() && k > 0.0) {
                            return Err(invalid(
                                format!("{path}.materials"),
                                format!(
                                    "the Hertz stiffness K = {k} N/m^1.5 of these materials is \
                                     not a finite positive number"
                                ),
                            ));
                        }
                        Ok(())
                    }
                    (Some(_), Some(_)) => Err(invalid(
                        format!("{path}.materials"),
                        "give either k or materials, not both",
                    )),
                    (None, None) => Err(invalid(
                        path,
                        "the normal law needs its stiffness: k (N/m^1.5) or materials",
                    )),
                }
            };
        check_contact_laws(p, &c.normal, &c.friction, &check_k)?;
        if let Some(film) = &c.film {
            let fp = format!("{p}.film");
            C::non_negative(&format!("{fp}.viscosity"), film.viscosity, "viscosity")?;
            C::positive(&format!("{fp}.length"), film.length, "bearing length")?;
            if let Some(cap) = film.eps_cap {
                C::finite(&format!("{fp}.eps_cap"), cap)?;
                if !(cap > 0.0 && cap < 1.0) {
                    return Err(invalid(
                        format!("{fp}.eps_cap"),
                        format!("eps_cap must lie in (0, 1) or be null (no cap), got {cap}"),
                    ));
                }
            }
            if let Some(w) = film.omega0 {
                C::positive(&format!("{fp}.omega0"), w, "omega0")?;
                if !matches!(
                    film.model,
                    FilmModel::LongGumbelMirrored | FilmModel::ShortOcvirkMirrored
                ) {
                    return Err(invalid(
                        format!("{fp}.omega0"),
                        "omega0 (the width of the smooth sign of the mirrored models) applies \
                         only to long_gumbel_mirrored and short_ocvirk_mirrored"
                            .to_string(),
                    ));
                }
            }
        }
        C::finite2(&format!("{p}.initial_eccentricity"), c.initial_eccentricity)?;
        C::finite2(
            &format!("{p}.initial_eccentricity_rate"),
            c.initial_eccentricity_rate,
        )?;
        let e0 = c.initial_eccentricity[0].hypot(c.initial_eccentricity[1]);
        if e0 > clearance && !c.allow_initial_penetration {
            return Err(invalid(
                format!("{p}.initial_eccentricity"),
                format!(
                    "|e| = {e0:e} m exceeds the clearance R_B − R_J = {clearance:e} m (the \
                     journal would start {:e} m into the bearing); set \
                     allow_initial_penetration: true to start in contact",
                    e0 - clearance
                ),
            ));
        }
        if !(e0 - clearance < j.radius) {
            return Err(invalid(
                format!("{p}.initial_eccentricity"),
                format!(
                    "|e| = {e0:e} m puts the journal {:e} m into the bearing, beyond the \
                     journal radius {} m: the contact law does not hold there",
                    e0 - clearance,
                    j.radius
                ),
            ));
        }
        Ok(())
    }
}

/// `check_k(path of the normal law, k, materials)`: a joint's check of its contact stiffness.
pub(crate) type StiffnessCheck<'a> =
    dyn Fn(&str, &Option<f64>, &Option<Materials>) -> Result<(), SceneError> + 'a;

/// The checks a clearance joint's normal and friction laws share, revolute or prismatic:
/// `check_k(path of the normal law, k, materials)` checks the stiffness (a revolute joint may
/// derive it from materials, a flat guide face may not); the rest is the same for both.
pub(crate) fn check_contact_laws(
    p: &str,
    normal: &NormalSpec,
    friction: &FrictionSpec,
    check_k: &StiffnessCheck<'_>,
) -> Result<(), SceneError> {
    type C = Checker;
    let np = format!("{p}.normal");
    match normal {
        NormalSpec::Impact(s) => {
            check_k(&np, &s.k, &s.materials)?;
            C::non_negative(&format!("{np}.c_max"), s.c_max, "c_max")?;
            C::positive(&format!("{np}.d_max"), s.d_max, "d_max")?;
        }
        NormalSpec::LankaraniNikravesh(s) | NormalSpec::Flores(s) | NormalSpec::HuntCrossley(s) => {
            check_k(&np, &s.k, &s.materials)?;
            let rp = format!("{np}.restitution");
            C::finite(&rp, s.restitution)?;
            if !(s.restitution > 0.0 && s.restitution <= 1.0) {
                return Err(invalid(
                    rp,
                    format!(
                        "the coefficient of restitution must lie in (0, 1], got {}",
                        s.restitution
                    ),
                ));
            }
        }
    }
    if let FrictionSpec::Coulomb(f) = friction {
        let fp = format!("{p}.friction");
        C::non_negative(&format!("{fp}.mu"), f.mu, "mu")?;
        C::non_negative(&format!("{fp}.v0"), f.v0, "v0")?;
        C::finite(&format!("{fp}.v1"), f.v1)?;
        if !(f.v1 >= f.v0) {
            return Err(invalid(
                format!("{fp}.v1"),
                format!("v1 must be >= v0 = {}, got {}", f.v0, f.v1),
            ));
        }
    }
    Ok(())
}
