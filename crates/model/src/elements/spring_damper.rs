//! The point-to-point spring-damper (docs/model.md §10.1): scene type, checks, compiled element.

use serde::{Deserialize, Serialize};

use crate::elements::input::{point_state, Input, Kin, Load, Pt, Table};
use crate::elements::interface::{ElementEval, ElementSpec, ForceElement, ForceJacobian};
use crate::elements::table::{check_stiffness_or_curve, curve, CurveSpec};
use crate::labels::Column;
use crate::planar::{cross, dot, perp};
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

    /// Closed form for a linear spring (a force–length curve, or zero length, is differenced):
    ///
    /// ```text
    /// d = r_b − r_a, L = |d|, e = d/L, u = v_b − v_a, L̇ = e·u, F = k (L − L₀) + c L̇
    /// a change (δd, δu):  δL = e·δd,  δe = (δd − e δL)/L,  δL̇ = δe·u + e·δu
    ///                     δF = k δL + c δL̇,  δ(F e) = δF e + F δe
    /// by body β's coordinates (σ_a = −1, σ_b = 1; s_β = A s its arm, s⊥ = (−s_y, s_x)):
    ///   x, y: δd = σ_β (1, 0), (0, 1);  φ: δd = σ_β s⊥_β, δu = −σ_β φ̇_β s_β
    ///   ẋ, ẏ: δu = σ_β (1, 0), (0, 1);  φ̇: δu = σ_β s⊥_β
    /// g_β = ρ_β (F e, s_β × F e) (ρ_a = 1, ρ_b = −1); the arm turns with φ_β:
    ///   ∂(s_β × ρ_β F e)/∂φ_β = s⊥_β × ρ_β F e = −ρ_β s_β · F e
    /// ```
    fn jacobian(&self, _t: f64, kin: &Kin<'_>, jac: &mut ForceJacobian<'_>) -> bool {
        if self.curve.is_some() {
            return false;
        }
        let (ra, va, arm_a) = point_state(&self.a, kin);
        let (rb, vb, arm_b) = point_state(&self.b, kin);
        let d = [rb[0] - ra[0], rb[1] - ra[1]];
        let len = d[0].hypot(d[1]);
        if !(len > 0.0) {
            return false;
        }
        let e = [d[0] / len, d[1] / len];
        let u = [vb[0] - va[0], vb[1] - va[1]];
        let (k, c) = (self.k, self.c);
        let f = k * (len - self.l0) + c * dot(e, u);
        let fe = [f * e[0], f * e[1]];
        let ends = [(self.a.body, -1.0, 1.0, arm_a), (self.b.body, 1.0, -1.0, arm_b)];
        for &(col_body, sigma, _, s) in &ends {
            let Some(kc) = col_body else { continue };
            let (p, w) = (perp(s), kin.vel[kc][2]);
            let z = [0.0; 2];
            // (δd, δu) of the six coordinates x, y, φ, ẋ, ẏ, φ̇ of the column body.
            let moves: [([f64; 2], [f64; 2]); 6] = [
                ([sigma, 0.0], z),
                ([0.0, sigma], z),
                ([sigma * p[0], sigma * p[1]], [-sigma * w * s[0], -sigma * w * s[1]]),
                (z, [sigma, 0.0]),
                (z, [0.0, sigma]),
                (z, [sigma * p[0], sigma * p[1]]),
            ];
            for (comp, (dd, du)) in moves.iter().enumerate() {
                let dl = dot(e, *dd);
                let de = [(dd[0] - e[0] * dl) / len, (dd[1] - e[1] * dl) / len];
                let df = k * dl + c * (dot(de, u) + dot(e, *du));
                let dfe = [df * e[0] + f * de[0], df * e[1] + f * de[1]];
                for &(row_body, _, rho, ar) in &ends {
                    let Some(kr) = row_body else { continue };
                    let g = [rho * dfe[0], rho * dfe[1]];
                    jac.add((kr, 0), (kc, comp), g[0]);
                    jac.add((kr, 1), (kc, comp), g[1]);
                    jac.add((kr, 2), (kc, comp), cross(ar, g));
                }
            }
        }
        for &(body, _, rho, s) in &ends {
            if let Some(kb) = body {
                jac.add((kb, 2), (kb, 2), -rho * dot(s, fe));
            }
        }
        true
    }

    fn set_initial(&mut self, t0: f64, kin: &Kin<'_>) {
        if self.l0.is_nan() {
            self.l0 = Input::Length(self.a, self.b).value(t0, kin);
        }
    }
}
