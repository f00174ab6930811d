//! The applied torque on a body (docs/model.md §10.3): scene type, checks, compiled element.

use serde::{Deserialize, Serialize};

use crate::elements::input::{opposing_factor, Input, Kin, Law, Load};
use crate::elements::interface::{ElementEval, ElementSpec, ForceElement, ForceJacobian};
use crate::elements::table::{check_value_or_table, default_ramp, law, Acts, TableSpec};
use crate::labels::Column;
use crate::scene::check::Checker;
use crate::scene::error::SceneError;
use crate::scene::refs::{check_moving, SceneRefs};

/// An applied torque on a body (docs/model.md §10.3).
///
/// ```text
/// τ = f(s) (counter-clockwise);  0 while acts = opposing and τ φ̇ ≥ 0;  P = τ φ̇
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TorqueSpec {
    /// Unique element name.
    pub name: String,
    /// The loaded body (moving).
    pub body: String,
    /// Constant torque (N·m). Exactly one of `value` and `table`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// Tabulated torque f(s) (N·m). Exactly one of `value` and `table`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<TableSpec>,
    /// When it acts. Default `always`.
    #[serde(default)]
    pub acts: Acts,
    /// v_ramp of an opposing torque (rad/s), ≥ 0. Default 1e-4.
    #[serde(default = "default_ramp")]
    pub ramp_speed: f64,
}

impl ElementSpec for TorqueSpec {
    type Element = Torque;

    fn validate(&self, p: &str, refs: &dyn SceneRefs) -> Result<(), SceneError> {
        check_moving(refs, &format!("{p}.body"), &self.body)?;
        check_value_or_table(refs, p, self.value, &self.table)?;
        Checker::non_negative(&format!("{p}.ramp_speed"), self.ramp_speed, "ramp speed")
    }

    fn compile(&self, refs: &dyn SceneRefs) -> Torque {
        Torque {
            body: refs.body_index(&self.body).expect("validated"),
            law: law(refs, self.value, &self.table),
            opposing: (self.acts == Acts::Opposing).then_some(self.ramp_speed),
        }
    }
}

/// A compiled applied torque.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Torque {
    body: usize,
    law: Law,
    /// v_ramp of an opposing torque; None: always acts.
    opposing: Option<f64>,
}

impl ForceElement for Torque {
    const COLUMNS: &'static [Column] = &[Column {
        suffix: "torque",
        unit: "N·m",
    }];

    #[inline]
    fn eval(&self, t: f64, kin: &Kin<'_>, mut apply: impl FnMut(Load)) -> ElementEval {
        let mut out = ElementEval::new();
        let w = kin.vel[self.body][2];
        let mut tau = self.law.value(t, kin);
        if let Some(ramp) = self.opposing {
            tau *= opposing_factor(tau, w, ramp);
        }
        apply((self.body, [0.0; 2], [0.0; 2], tau));
        out.load = tau;
        out.power = tau * w;
        out
    }

    /// A constant torque, or one read from a table of time, that always acts depends on no
    /// coordinate: ∂g/∂y = 0 (nothing to add). Otherwise differenced.
    fn jacobian(&self, _t: f64, _kin: &Kin<'_>, _jac: &mut ForceJacobian<'_>) -> bool {
        self.opposing.is_none()
            && matches!(self.law, Law::Const(_) | Law::Table(_, Input::Time))
    }
}
