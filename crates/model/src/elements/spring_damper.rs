//! The point-to-point spring-damper (docs/model.md §10.1): scene type, checks, compiled element.

use serde::{Deserialize, Serialize};

use crate::elements::input::{point_state, Input, Kin, Load, Pt, Table};
use crate::elements::interface::{ElementEval, ElementSpec, ForceElement};
use crate::elements::table::{check_stiffness_or_curve, curve, CurveSpec};
use crate::labels::Column;
use crate::planar::dot;
use crate::scene::check::Checker;
use crate::scene::de::object;
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::{check_attachment, pt_of, Attachment, SceneRefs};

/// Point-to-point spring-damper (docs/model.md §10.1).
///
/// ```text
/// L = |r_b^P − r_a^P|,  L̇ = (r_b^P − r_a^P)·(ṙ_b^P − ṙ_a^P)/L
/// F = k (L − L₀) + c L̇   (F = curve(L) + c L̇ with a force–length curve);  F > 0 pulls
/// f_a = F (r_b − r_a)/L on a, −f_a on b;  V = ½ k (L − L₀)² (or ∫ curve dL);  D = c L̇²
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringDamperSpec {
    /// Unique element name.
    pub name: String,
    /// First end (a body point, or the ground with `at`).
    #[serde(deserialize_with = "object")]
    pub a: Attachment,
    /// Second end.
    #[serde(deserialize_with = "object")]
    pub b: Attachment,
    /// Stiffness k (N/m), ≥ 0. Default 0. Not with `curve`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Damping c (N·s/m), ≥ 0. Default 0.
    #[serde(default)]
    pub damping: f64,
    /// Free length L₀ (m), ≥ 0. Default: the length at the assembled initial state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_length: Option<f64>,
    /// Force–length curve F(L) (N against m) instead of k (L − L₀).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curve: Option<CurveSpec>,
}

impl ElementSpec for SpringDamperSpec {
    type Element = SpringDamper;

    fn validate(&self, p: &str, refs: &dyn SceneRefs) -> Result<(), SceneError> {
        let s = self;
        check_attachment(refs, &format!("{p}.a"), &s.a.body, &s.a.point, &s.a.at)?;
        check_attachment(refs, &format!("{p}.b"), &s.b.body, &s.b.point, &s.b.at)?;
        if s.a.body == s.b.body {
            return Err(invalid(
                format!("{p}.b.body"),
                format!(
                    "a spring needs two different bodies (or a body and the ground), both are \
                     '{}'",
                    s.a.body
                ),
            ));
        }
        check_stiffness_or_curve(p, s.stiffness, &s.curve, "force–length")?;
        Checker::non_negative(&format!("{p}.damping"), s.damping, "damping")?;
        if let Some(l0) = s.free_length {
            Checker::non_negative(&format!("{p}.free_length"), l0, "free length")?;
        }
        Ok(())
    }

    fn compile(&self, refs: &dyn SceneRefs) -> SpringDamper {
        SpringDamper {
            a: pt_of(refs, &self.a),
            b: pt_of(refs, &self.b),
            k: self.stiffness.unwrap_or(0.0),
            c: self.damping,
            // The assembled initial length when not given (`set_initial`).
            l0: self.free_length.unwrap_or(f64::NAN),
            curve: self.curve.as_ref().map(curve),
        }
    }

    fn has_length(&self) -> bool {
        true
    }

    fn length(&self, refs: &dyn SceneRefs) -> Option<Input> {
        Some(Input::Length(pt_of(refs, &self.a), pt_of(refs, &self.b)))
    }
}

/// A compiled spring-damper.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SpringDamper {
    a: Pt,
    b: Pt,
    k: f64,
    c: f64,
    l0: f64,
    curve: Option<Table>,
}

impl ForceElement for SpringDamper {
    const COLUMNS: &'static [Column] = &[
        Column {
            suffix: "force",
            unit: "N",
        },
        Column {
            suffix: "length",
            unit: "m",
        },
    ];

    #[inline]
    fn eval(&self, _t: f64, kin: &Kin<'_>, mut apply: impl FnMut(Load)) -> ElementEval {
        let mut out = ElementEval::new();
        let (ra, va, arm_a) = point_state(&self.a, kin);
        let (rb, vb, arm_b) = point_state(&self.b, kin);
        let d = [rb[0] - ra[0], rb[1] - ra[1]];
        let len = d[0].hypot(d[1]);
        // At zero length the line is undefined: no force (docs/model.md §10.1).
        let e = if len > 0.0 {
            [d[0] / len, d[1] / len]
        } else {
            [0.0; 2]
        };
        let ldot = dot(e, [vb[0] - va[0], vb[1] - va[1]]);
        let (k, c, l0) = (self.k, self.c, self.l0);
        let (elastic, pot) = match &self.curve {
            Some(tab) => (tab.eval(len), tab.integral(len)),
            None => (k * (len - l0), 0.5 * k * (len - l0) * (len - l0)),
        };
        let f = elastic + c * ldot;
        let fa = [f * e[0], f * e[1]];
        if let Some(ka) = self.a.body {
            apply((ka, arm_a, fa, 0.0));
        }
        if let Some(kb) = self.b.body {
            apply((kb, arm_b, [-fa[0], -fa[1]], 0.0));
        }
        out.load = f;
        out.coord = len;
        out.dissipation = c * ldot * ldot;
        out.potential = pot;
        out
    }

    fn set_initial(&mut self, t0: f64, kin: &Kin<'_>) {
        if self.l0.is_nan() {
            self.l0 = Input::Length(self.a, self.b).value(t0, kin);
        }
    }
}
