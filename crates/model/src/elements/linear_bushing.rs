//! The linear bushing: an isotropic spring and damper that pull two points together
//! (docs/model.md §10.5): scene type, checks, compiled element with its Jacobian in closed form.

use serde::{Deserialize, Serialize};

use crate::elements::input::{point_state, Kin, Load, Pt};
use crate::elements::interface::{ElementEval, ElementSpec, ForceElement, ForceJacobian};
use crate::labels::Column;
use crate::planar::{cross, dot, perp};
use crate::scene::check::Checker;
use crate::scene::de::object;
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::{check_attachment, pt_of, Attachment, SceneRefs};

/// Linear bushing between a point of body a and a point of body b (or a ground location),
/// isotropic in the plane (docs/model.md §10.5).
///
/// ```text
/// d = r_a^P − r_b^P,  ḋ = ṙ_a^P − ṙ_b^P
/// F = −k d − c ḋ on a at its point, −F on b;  V = ½ k |d|²;  D = c |ḋ|²
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearBushingSpec {
    /// Unique element name.
    pub name: String,
    /// First point (a body point, or the ground with `at`).
    #[serde(deserialize_with = "object")]
    pub a: Attachment,
    /// Second point.
    #[serde(deserialize_with = "object")]
    pub b: Attachment,
    /// Stiffness k (N/m), ≥ 0.
    pub stiffness: f64,
    /// Damping c (N·s/m), ≥ 0. Default 0.
    #[serde(default)]
    pub damping: f64,
}

impl ElementSpec for LinearBushingSpec {
    type Element = LinearBushing;

    fn validate(&self, p: &str, refs: &dyn SceneRefs) -> Result<(), SceneError> {
        let (a, b) = (&self.a, &self.b);
        check_attachment(refs, &format!("{p}.a"), &a.body, &a.point, &a.at)?;
        check_attachment(refs, &format!("{p}.b"), &b.body, &b.point, &b.at)?;
        if a.body == b.body {
            return Err(invalid(
                format!("{p}.b.body"),
                format!(
                    "a bushing needs two different bodies (or a body and the ground), both are \
                     '{}'",
                    a.body
                ),
            ));
        }
        Checker::non_negative(&format!("{p}.stiffness"), self.stiffness, "stiffness")?;
        Checker::non_negative(&format!("{p}.damping"), self.damping, "damping")
    }

    fn compile(&self, refs: &dyn SceneRefs) -> LinearBushing {
        LinearBushing {
            a: pt_of(refs, &self.a),
            b: pt_of(refs, &self.b),
            k: self.stiffness,
            c: self.damping,
        }
    }
}

/// A compiled linear bushing.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LinearBushing {
    a: Pt,
    b: Pt,
    k: f64,
    c: f64,
}

impl LinearBushing {
    /// d, ḋ, F and the arms A s of both points.
    #[inline]
    fn state(&self, kin: &Kin<'_>) -> ([f64; 2], [f64; 2], [f64; 2], [[f64; 2]; 2]) {
        let (ra, va, arm_a) = point_state(&self.a, kin);
        let (rb, vb, arm_b) = point_state(&self.b, kin);
        let d = [ra[0] - rb[0], ra[1] - rb[1]];
        let dd = [va[0] - vb[0], va[1] - vb[1]];
        let f = [
            -self.k * d[0] - self.c * dd[0],
            -self.k * d[1] - self.c * dd[1],
        ];
        (d, dd, f, [arm_a, arm_b])
    }
}

impl ForceElement for LinearBushing {
    const COLUMNS: &'static [Column] = &[
        Column {
            suffix: "force",
            unit: "N",
        },
        Column {
            suffix: "stretch",
            unit: "m",
        },
    ];

    #[inline]
    fn eval(&self, _t: f64, kin: &Kin<'_>, mut apply: impl FnMut(Load)) -> ElementEval {
        let (d, dd, f, [arm_a, arm_b]) = self.state(kin);
        if let Some(ka) = self.a.body {
            apply((ka, arm_a, f, 0.0));
        }
        if let Some(kb) = self.b.body {
            apply((kb, arm_b, [-f[0], -f[1]], 0.0));
        }
        let mut out = ElementEval::new();
        out.load = f[0].hypot(f[1]);
        out.coord = d[0].hypot(d[1]);
        out.dissipation = self.c * dot(dd, dd);
        out.potential = 0.5 * self.k * dot(d, d);
        out
    }

    /// ```text
    /// ∂F/∂(x, y)_β = −σ_β k I,  ∂F/∂(ẋ, ẏ)_β = −σ_β c I,  ∂F/∂φ̇_β = −σ_β c (A s)⊥_β
    /// ∂F/∂φ_β = σ_β (−k (A s)⊥_β + c φ̇_β (A s)_β)          (σ_a = 1, σ_b = −1)
    /// g_β = ρ_β (F, (A s)_β × F):  ∂g_β = ρ_β (∂F, (A s)_β × ∂F) + [φ_β] (0, −ρ_β (A s)_β·F)
    /// ```
    fn jacobian(&self, _t: f64, kin: &Kin<'_>, jac: &mut ForceJacobian<'_>) -> bool {
        let (_, _, f, arms) = self.state(kin);
        let (k, c) = (self.k, self.c);
        let ends = [(self.a.body, 1.0, arms[0]), (self.b.body, -1.0, arms[1])];
        for &(col_body, sigma, a) in &ends {
            let Some(kc) = col_body else { continue };
            let (p, w) = (perp(a), kin.vel[kc][2]);
            let d_f: [[f64; 2]; 6] = [
                [-sigma * k, 0.0],
                [0.0, -sigma * k],
                [sigma * (-k * p[0] + c * w * a[0]), sigma * (-k * p[1] + c * w * a[1])],
                [-sigma * c, 0.0],
                [0.0, -sigma * c],
                [-sigma * c * p[0], -sigma * c * p[1]],
            ];
            for (comp, df) in d_f.iter().enumerate() {
                for &(row_body, rho, ar) in &ends {
                    let Some(kr) = row_body else { continue };
                    let dfr = [rho * df[0], rho * df[1]];
                    jac.add((kr, 0), (kc, comp), dfr[0]);
                    jac.add((kr, 1), (kc, comp), dfr[1]);
                    jac.add((kr, 2), (kc, comp), cross(ar, dfr));
                }
            }
        }
        // The arms turn with their bodies: ∂((A s) × ρF)/∂φ = (A s)⊥ × ρF = −ρ (A s)·F.
        for &(body, rho, a) in &ends {
            if let Some(kb) = body {
                jac.add((kb, 2), (kb, 2), -rho * dot(a, f));
            }
        }
        true
    }
}
