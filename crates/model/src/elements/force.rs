//! The applied force at a body point (docs/model.md §10.3): scene type, checks, compiled
//! element.

use serde::{Deserialize, Serialize};

use crate::elements::input::{opposing_factor, point_state, Kin, Law, Load, Pt};
use crate::elements::interface::{ElementEval, ElementSpec, ForceElement};
use crate::elements::table::{
    check_point_ref, check_value_or_table, default_ramp, law, point_ref, Acts, PointRef,
    TableSpec,
};
use crate::labels::Column;
use crate::planar::{dot, rot};
use crate::scene::check::Checker;
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::SceneRefs;

/// In which frame a force's direction is given.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Frame {
    /// Global (default).
    #[default]
    Global,
    /// The body's frame (the direction turns with the body).
    Body,
}

/// An applied force at a body point (docs/model.md §10.3).
///
/// ```text
/// F = f(s) d̂,  d̂ = direction/|direction| (global) or A(φ) direction/|direction| (body frame)
/// f(s) = value, or the table; 0 while acts = opposing and F·ṙ^P ≥ 0;  P = F·ṙ^P
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    /// Unique element name.
    pub name: String,
    /// The loaded body (moving).
    pub body: String,
    /// Point of application. Default: the centre of mass.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<String>,
    /// Frame of `direction`. Default `global`.
    #[serde(default)]
    pub frame: Frame,
    /// Direction (any length > 0).
    pub direction: [f64; 2],
    /// Constant magnitude f (N). Exactly one of `value` and `table`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// Tabulated magnitude f(s) (N). Exactly one of `value` and `table`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<TableSpec>,
    /// When it acts. Default `always`.
    #[serde(default)]
    pub acts: Acts,
    /// v_ramp of an opposing load (m/s), ≥ 0. Default 1e-4.
    #[serde(default = "default_ramp")]
    pub ramp_speed: f64,
}

impl ForceSpec {
    /// The point of application as a [`PointRef`].
    fn point_ref(&self) -> PointRef {
        PointRef {
            body: self.body.clone(),
            point: self.point.clone(),
        }
    }
}

impl ElementSpec for ForceSpec {
    type Element = Force;

    fn validate(&self, p: &str, refs: &dyn SceneRefs) -> Result<(), SceneError> {
        let s = self;
        check_point_ref(refs, p, &s.point_ref())?;
        Checker::finite2(&format!("{p}.direction"), s.direction)?;
        if s.direction == [0.0, 0.0] {
            return Err(invalid(
                format!("{p}.direction"),
                "must not be the zero vector",
            ));
        }
        check_value_or_table(refs, p, s.value, &s.table)?;
        Checker::non_negative(&format!("{p}.ramp_speed"), s.ramp_speed, "ramp speed")
    }

    fn compile(&self, refs: &dyn SceneRefs) -> Force {
        let l = self.direction[0].hypot(self.direction[1]);
        Force {
            p: point_ref(refs, &self.point_ref()),
            dir: [self.direction[0] / l, self.direction[1] / l],
            body_frame: self.frame == Frame::Body,
            law: law(refs, self.value, &self.table),
            opposing: (self.acts == Acts::Opposing).then_some(self.ramp_speed),
        }
    }
}

/// A compiled applied force.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Force {
    p: Pt,
    dir: [f64; 2],
    body_frame: bool,
    law: Law,
    /// v_ramp of an opposing load; None: always acts.
    opposing: Option<f64>,
}

impl ForceElement for Force {
    const COLUMNS: &'static [Column] = &[Column {
        suffix: "force",
        unit: "N",
    }];

    #[inline]
    fn eval(&self, t: f64, kin: &Kin<'_>, mut apply: impl FnMut(Load)) -> ElementEval {
        let mut out = ElementEval::new();
        let (_, v, arm) = point_state(&self.p, kin);
        let k = self.p.body.expect("forces act on bodies");
        let d = if self.body_frame {
            rot(kin.cs[k], self.dir)
        } else {
            self.dir
        };
        let mut f = self.law.value(t, kin);
        if let Some(ramp) = self.opposing {
            f *= opposing_factor(f, dot(d, v), ramp);
        }
        apply((k, arm, [f * d[0], f * d[1]], 0.0));
        out.load = f;
        out.power = f * dot(d, v);
        out
    }
}
