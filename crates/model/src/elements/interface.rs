//! What a force element kind implements (docs/model.md §10): its scene side
//! ([`ElementSpec`]: checks and compilation) and its compiled side ([`ForceElement`]: loads,
//! Jacobian, columns, events and energy terms). The registry (elements/mod.rs) turns one line
//! per kind into the tagged `"type"` of the scene format and the dispatch of both sides.
//!
//! ```text
//! ElementSpec    validate(p, refs) → first error with its JSON path (p = forces[i])
//!                compile(refs) → the element;   length(refs): its L as a table input, if any
//! ForceElement   eval(t, kin, apply) → loads (body, arm, force, torque) and ElementEval
//!                  (load, coordinate, power in, dissipation, potential)
//!                COLUMNS (suffix, unit): the first the load, the second (if any) the coordinate
//!                ACCOUNT: where its power in is booked (applied load | motor)
//!                set_initial(t0, kin): defaults of the assembled initial state (free length)
//!                jacobian(t, kin, dg) → true when it added ∂g/∂(q, q̇) in closed form;
//!                  false (the default): the mechanism differences it with the others
//!                EVENTS and event(i, t, kin) → (g, ġ): its event functions (none by default)
//! energy: d/dt (T + V) = Σ power in − Σ dissipation;  V includes every potential
//! ```

use crate::elements::input::{Input, Kin, Load};
use crate::labels::{Column, EventLabels};
use crate::scene::error::SceneError;
use crate::scene::refs::SceneRefs;

/// The scene side of a force element kind.
pub(crate) trait ElementSpec {
    /// The compiled element.
    type Element: ForceElement;

    /// Checks every field of the element at JSON path `p` (`forces[i]`; its name is checked by
    /// the registry): the first failure, with its path.
    fn validate(&self, p: &str, refs: &dyn SceneRefs) -> Result<(), SceneError>;

    /// The compiled element (after `validate`).
    fn compile(&self, refs: &dyn SceneRefs) -> Self::Element;

    /// Whether the element has a length, a table input (`of: length`) of other elements.
    fn has_length(&self) -> bool {
        false
    }

    /// That length (after `validate`); None for an element without one.
    fn length(&self, _refs: &dyn SceneRefs) -> Option<Input> {
        None
    }
}

/// Where the power an element puts into the mechanism is booked (docs/model.md §1.8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Account {
    /// Applied forces and torques, and elements that put in none (springs: their work is
    /// their potential).
    Load,
    /// Motors.
    Motor,
}

/// What one force element does at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ElementEval {
    /// Its load: the first output column (N or N·m).
    pub load: f64,
    /// Its coordinate: the second output column (NaN for an element with one column).
    pub coord: f64,
    /// Power it puts into the mechanism (W).
    pub power: f64,
    /// Power its damper dissipates (W, ≥ 0).
    pub dissipation: f64,
    /// Potential energy it stores (J).
    pub potential: f64,
}

impl ElementEval {
    /// Nothing yet: zero load and energy terms, no coordinate.
    pub(crate) fn new() -> ElementEval {
        ElementEval {
            coord: f64::NAN,
            ..ElementEval::default()
        }
    }
}

/// ∂g/∂(q, q̇) of the integrated bodies, being assembled (n_q × 2n_q, column-major: column j
/// holds ∂g/∂y_j with y = (q, q̇)).
pub(crate) struct ForceJacobian<'a> {
    /// The integrated index of every scene body (None: prescribed).
    pub int_of: &'a [Option<usize>],
    /// n_q = 3 × the integrated bodies.
    pub nq: usize,
    /// The matrix.
    pub dg: &'a mut [f64],
}

impl ForceJacobian<'_> {
    /// Adds `d` to ∂g_{(row body, row component)}/∂y_{(column body, column component)}; the
    /// components are x, y, φ (0–2) of g and, in the columns, x, y, φ (0–2) and ẋ, ẏ, φ̇
    /// (3–5). Entries of prescribed bodies are dropped.
    pub(crate) fn add(&mut self, row: (usize, usize), col: (usize, usize), d: f64) {
        let (Some(i), Some(j)) = (self.int_of[row.0], self.int_of[col.0]) else {
            return;
        };
        let c = if col.1 < 3 {
            3 * j + col.1
        } else {
            self.nq + 3 * j + col.1 - 3
        };
        self.dg[c * self.nq + 3 * i + row.1] += d;
    }
}

/// The compiled side of a force element kind (module doc).
pub(crate) trait ForceElement {
    /// Its output columns (suffix and unit): the load, then the coordinate if it has one.
    const COLUMNS: &'static [Column];
    /// Where its power in is booked.
    const ACCOUNT: Account = Account::Load;
    /// The kinds of its event functions, one per function (none by default).
    const EVENTS: &'static [EventLabels] = &[];

    /// Evaluates the element at t and the poses of `kin`; `apply` receives every load on a
    /// body (body, global arm from its centre of mass, force, torque).
    fn eval(&self, t: f64, kin: &Kin<'_>, apply: impl FnMut(Load)) -> ElementEval;

    /// Sets the defaults that the scene leaves to the assembled initial state.
    fn set_initial(&mut self, _t0: f64, _kin: &Kin<'_>) {}

    /// Adds its ∂g/∂(q, q̇) in closed form and returns true; false (the default) leaves it to
    /// the mechanism's central differences.
    fn jacobian(&self, _t: f64, _kin: &Kin<'_>, _jac: &mut ForceJacobian<'_>) -> bool {
        false
    }

    /// Event function `i` of [`ForceElement::EVENTS`] and its rate (g, ġ) at t and `kin`.
    fn event(&self, i: usize, _t: f64, _kin: &Kin<'_>) -> (f64, f64) {
        unreachable!("event {i} of an element without events")
    }
}
