//! The rotational spring-damper between two bodies' angles (docs/model.md §10.2): scene type,
//! checks, compiled element.

use serde::{Deserialize, Serialize};

use crate::elements::input::{angle_of, omega_of, Input, Kin, Load, Table};
use crate::elements::interface::{ElementEval, ElementSpec, ForceElement};
use crate::elements::table::{check_stiffness_or_curve, curve, ground_name, CurveSpec};
use crate::labels::Column;
use crate::scene::check::Checker;
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::{body_or_ground, check_body_or_ground, check_moving, SceneRefs};

/// Rotational spring-damper between two bodies' angles (docs/model.md §10.2).
///
/// ```text
/// θ = φ_a − φ_b (φ_ground = 0),  τ = k (θ − θ₀) + c θ̇  (or curve(θ) + c θ̇)
/// torque −τ on a, +τ on b;  V = ½ k (θ − θ₀)² (or ∫ curve dθ);  D = c θ̇²
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotationalSpringDamperSpec {
    /// Unique element name.
    pub name: String,
    /// Body a (a moving body).
    pub a: String,
    /// Body b, or "ground". Default "ground".
    #[serde(default = "ground_name")]
    pub b: String,
    /// Stiffness k (N·m/rad), ≥ 0. Default 0. Not with `curve`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Damping c (N·m·s/rad), ≥ 0. Default 0.
    #[serde(default)]
    pub damping: f64,
    /// Free angle θ₀ (rad). Default: θ at the assembled initial state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_angle: Option<f64>,
    /// Torque–angle curve τ(θ) (N·m against rad) instead of k (θ − θ₀).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curve: Option<CurveSpec>,
}

impl ElementSpec for RotationalSpringDamperSpec {
    type Element = RotationalSpringDamper;

    fn validate(&self, p: &str, refs: &dyn SceneRefs) -> Result<(), SceneError> {
        let s = self;
        check_moving(refs, &format!("{p}.a"), &s.a)?;
        check_body_or_ground(refs, &format!("{p}.b"), &s.b)?;
        if s.a == s.b {
            return Err(invalid(
                format!("{p}.b"),
                format!(
                    "a rotational spring needs two different bodies, both are '{}'",
                    s.a
                ),
            ));
        }
        check_stiffness_or_curve(p, s.stiffness, &s.curve, "torque–angle")?;
        Checker::non_negative(&format!("{p}.damping"), s.damping, "damping")?;
        if let Some(a) = s.free_angle {
            Checker::finite(&format!("{p}.free_angle"), a)?;
        }
        Ok(())
    }

    fn compile(&self, refs: &dyn SceneRefs) -> RotationalSpringDamper {
        RotationalSpringDamper {
            a: refs.body_index(&self.a).expect("validated"),
            b: body_or_ground(refs, &self.b),
            k: self.stiffness.unwrap_or(0.0),
            c: self.damping,
            // θ at the assembled initial state when not given (`set_initial`).
            theta0: self.free_angle.unwrap_or(f64::NAN),
            curve: self.curve.as_ref().map(curve),
        }
    }
}

/// A compiled rotational spring-damper.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RotationalSpringDamper {
    a: usize,
    b: Option<usize>,
    k: f64,
    c: f64,
    theta0: f64,
    curve: Option<Table>,
}

impl ForceElement for RotationalSpringDamper {
    const COLUMNS: &'static [Column] = &[
        Column {
            suffix: "torque",
            unit: "N·m",
        },
        Column {
            suffix: "angle",
            unit: "rad",
        },
    ];

    #[inline]
    fn eval(&self, _t: f64, kin: &Kin<'_>, mut apply: impl FnMut(Load)) -> ElementEval {
        let mut out = ElementEval::new();
        let (k, c, theta0) = (self.k, self.c, self.theta0);
        let th = kin.pose[self.a][2] - angle_of(self.b, kin);
        let thd = kin.vel[self.a][2] - omega_of(self.b, kin);
        let (elastic, pot) = match &self.curve {
            Some(tab) => (tab.eval(th), tab.integral(th)),
            None => (k * (th - theta0), 0.5 * k * (th - theta0) * (th - theta0)),
        };
        let tau = elastic + c * thd;
        apply((self.a, [0.0; 2], [0.0; 2], -tau));
        if let Some(kb) = self.b {
            apply((kb, [0.0; 2], [0.0; 2], tau));
        }
        out.load = tau;
        out.coord = th;
        out.dissipation = c * thd * thd;
        out.potential = pot;
        out
    }

    fn set_initial(&mut self, t0: f64, kin: &Kin<'_>) {
        if self.theta0.is_nan() {
            self.theta0 = Input::Relative(Some(self.a), self.b).value(t0, kin);
        }
    }
}
