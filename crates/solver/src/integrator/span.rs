//! The checks of an integration's span and initial state (crate::integrator).

use crate::options::{Allowed, OptionError, OptionField, Reason, Rule};

/// The arguments of an integration: y0 has n finite entries, t0 and t_end are finite,
/// t_end > t0.
pub(super) fn check_span(t0: f64, t_end: f64, y0: &[f64], n: usize) -> Result<(), OptionError> {
    if y0.len() != n {
        return Err(OptionError::new(
            OptionField::Y0,
            Reason::WrongLength {
                len: y0.len(),
                expected: n,
            },
        ));
    }
    let finite = |field| Rule::new(field, Allowed::Finite);
    finite(OptionField::T0).check(t0)?;
    finite(OptionField::TEnd).check(t_end)?;
    if !(t_end > t0) {
        return Err(OptionError::new(
            OptionField::TEnd,
            Reason::NotAbove {
                value: t_end,
                other: OptionField::T0,
                other_value: t0,
            },
        ));
    }
    for (i, v) in y0.iter().enumerate() {
        finite(OptionField::Y0).check_entry(i, *v)?;
    }
    Ok(())
}
