//! The system's quadrature ([`OdeSystem::quadrature`]) on diffsol's methods: diffsol's
//! output function integrated by the method itself (`integrate_out`, out of the error norm).
//!
//! ```text
//! BDF:            g_{n+1} by the same NDF formula as y, from q(t_{n+1}, y_{n+1}) and g's own
//!                 difference table
//! TR-BDF2, ESDIRK: g_{n+1} = g_n + h Σ b_i q(t_n + c_i h, Y_i), Y_i the stage states
//! start/restart:  g = 0, dg = q(t, y) (the first explicit stage and BDF's first difference)
//! per step:       increment = g after − g before (the Euler sliver has none)
//! ```
//! diffsol gives no error estimate for g when it is out of the error control: the increments
//! come without one ([`StepQuadrature::Value`]).

use crate::linear_algebra::La;
use crate::stepper::StepQuadrature;
use crate::system::OdeSystem;
use diffsol::Vector;

/// The increments of diffsol's integrated output over the last step.
pub(super) struct Track {
    /// g at the start of the step being taken.
    before: Vec<f64>,
    /// The last step's increment (None: no step of the method's own since the last start).
    step: Option<Vec<f64>>,
}

impl Track {
    pub(super) fn new(m: usize) -> Self {
        Track {
            before: vec![0.0; m],
            step: None,
        }
    }

    /// g = 0 and dg = q(t, y) of a fresh state (empty vectors without quadrature); forgets
    /// the last increment.
    pub(super) fn start<S: OdeSystem + ?Sized, B: La>(
        &mut self,
        sys: &S,
        t: f64,
        y: &[f64],
        ctx: B::C,
    ) -> (B::V, B::V) {
        self.step = None;
        let m = self.before.len();
        let mut dg = vec![0.0; m];
        if m > 0 {
            sys.quadrature(t, y, &mut dg);
        }
        (B::V::zeros(m, ctx), B::V::from_slice(&dg, ctx))
    }

    /// Whether the system has quadrature variables: without them `before` and `after` have
    /// nothing to record (and `write` reports none), so the step skips them.
    pub(super) fn is_on(&self) -> bool {
        !self.before.is_empty()
    }

    /// Before a step of diffsol's: its g.
    pub(super) fn before(&mut self, g: &[f64]) {
        self.step = None;
        self.before.copy_from_slice(g);
    }

    /// After an accepted step of diffsol's: its g.
    pub(super) fn after(&mut self, g: &[f64]) {
        self.step = Some(g.iter().zip(&self.before).map(|(a, b)| a - b).collect());
    }

    /// A step that is not diffsol's (the Euler sliver): no increment.
    pub(super) fn clear(&mut self) {
        self.step = None;
    }

    /// The last step's increment into `value`.
    pub(super) fn write(&self, value: &mut [f64]) -> StepQuadrature {
        match &self.step {
            Some(d) if !d.is_empty() => {
                value.copy_from_slice(d);
                StepQuadrature::Value
            }
            _ => StepQuadrature::Unavailable,
        }
    }
}
