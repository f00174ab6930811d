//! The motor: a torque between a rotor and a stator from its torque–speed curve
//! (docs/model.md §10.4): scene type, checks, compiled element.

use serde::{Deserialize, Serialize};

use crate::elements::input::{omega_of, Kin, Load, Outside, Table};
use crate::elements::interface::{Account, ElementEval, ElementSpec, ForceElement};
use crate::elements::table::{check_curve, curve, ground_name, CurveSpec};
use crate::labels::Column;
use crate::scene::check::Checker;
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::{body_or_ground, check_body_or_ground, check_moving, SceneRefs};

/// A motor: a torque between a rotor and a stator from its torque–speed curve (docs/model.md
/// §10.4).
///
/// ```text
/// ω = φ̇_rotor − φ̇_stator;  τ = T(ω): the table, or T_s (1 − ω/ω₀) (a DC motor's line)
/// τ on the rotor, −τ on the stator;  P = τ ω
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotorSpec {
    /// Unique element name.
    pub name: String,
    /// The rotor (a moving body).
    pub rotor: String,
    /// The stator: a body or "ground". Default "ground".
    #[serde(default = "ground_name")]
    pub stator: String,
    /// Torque–speed curve: points [ω (rad/s), τ (N·m)]. Not with the line's two numbers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_speed: Option<CurveSpec>,
    /// Stall torque T_s (N·m) of the line T_s (1 − ω/ω₀).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stall_torque: Option<f64>,
    /// No-load speed ω₀ (rad/s, ≠ 0) of the line. Exactly one of `no_load_speed` and
    /// `no_load_rpm` with `stall_torque`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub no_load_speed: Option<f64>,
    /// No-load speed in revolutions per minute.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub no_load_rpm: Option<f64>,
}

impl ElementSpec for MotorSpec {
    type Element = Motor;

    fn validate(&self, p: &str, refs: &dyn SceneRefs) -> Result<(), SceneError> {
        type C = Checker;
        let s = self;
        check_moving(refs, &format!("{p}.rotor"), &s.rotor)?;
        check_body_or_ground(refs, &format!("{p}.stator"), &s.stator)?;
        if s.rotor == s.stator {
            return Err(invalid(
                format!("{p}.stator"),
                format!("rotor and stator must differ, both are '{}'", s.rotor),
            ));
        }
        let line = s.stall_torque.is_some() || s.no_load_speed.is_some() || s.no_load_rpm.is_some();
        match (&s.torque_speed, line) {
            (Some(c), false) => check_curve(&format!("{p}.torque_speed.points"), &c.points)?,
            (Some(_), true) => {
                return Err(invalid(
                    format!("{p}.torque_speed"),
                    "give either a torque_speed table or stall_torque and a no-load speed, not \
                     both",
                ))
            }
            (None, true) => {
                let Some(ts) = s.stall_torque else {
                    return Err(invalid(
                        format!("{p}.stall_torque"),
                        "the motor line T_s (1 − ω/ω₀) needs stall_torque (N·m)",
                    ));
                };
                C::finite(&format!("{p}.stall_torque"), ts)?;
                let (w0, wp) = match (s.no_load_speed, s.no_load_rpm) {
                    (Some(w), None) => (w, "no_load_speed"),
                    (None, Some(n)) => (n, "no_load_rpm"),
                    (Some(_), Some(_)) => {
                        return Err(invalid(
                            format!("{p}.no_load_rpm"),
                            "give either no_load_speed (rad/s) or no_load_rpm, not both",
                        ))
                    }
                    (None, None) => {
                        return Err(invalid(
                            format!("{p}.no_load_speed"),
                            "the motor line T_s (1 − ω/ω₀) needs no_load_speed (rad/s) or \
                             no_load_rpm",
                        ))
                    }
                };
                C::finite(&format!("{p}.{wp}"), w0)?;
                if w0 == 0.0 {
                    return Err(invalid(format!("{p}.{wp}"), "must not be 0"));
                }
            }
            (None, false) => {
                return Err(invalid(
                    p,
                    "a motor needs a torque_speed table, or stall_torque and no_load_speed (or \
                     no_load_rpm)",
                ))
            }
        }
        Ok(())
    }

    fn compile(&self, refs: &dyn SceneRefs) -> Motor {
        let curve = match &self.torque_speed {
            Some(c) => curve(c),
            None => {
                let ts = self.stall_torque.expect("validated");
                let w0 = self
                    .no_load_speed
                    .or(self.no_load_rpm.map(|n| n * std::f64::consts::PI / 30.0))
                    .expect("validated");
                // The line through (0, T_s) and (ω₀, 0), extended both ways.
                let mut pts = [[0.0, ts], [w0, 0.0]];
                pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
                Table::new(&pts, Outside::Linear)
            }
        };
        Motor {
            rotor: refs.body_index(&self.rotor).expect("validated"),
            stator: body_or_ground(refs, &self.stator),
            curve,
        }
    }
}

/// A compiled motor.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Motor {
    rotor: usize,
    stator: Option<usize>,
    curve: Table,
}

impl ForceElement for Motor {
    const COLUMNS: &'static [Column] = &[
        Column {
            suffix: "torque",
            unit: "N·m",
        },
        Column {
            suffix: "speed",
            unit: "rad/s",
        },
    ];
    const ACCOUNT: Account = Account::Motor;

    #[inline]
    fn eval(&self, _t: f64, kin: &Kin<'_>, mut apply: impl FnMut(Load)) -> ElementEval {
        let mut out = ElementEval::new();
        let w = kin.vel[self.rotor][2] - omega_of(self.stator, kin);
        let tau = self.curve.eval(w);
        apply((self.rotor, [0.0; 2], [0.0; 2], tau));
        if let Some(ks) = self.stator {
            apply((ks, [0.0; 2], [0.0; 2], -tau));
        }
        out.load = tau;
        out.coord = w;
        out.power = tau * w;
        out
    }
}
