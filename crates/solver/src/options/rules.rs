//! The numeric rules of the options ([`Rule`]: a field and the values it allows), written
//! once: the configurations check them in their constructors, [`StepLimits::validate`] the
//! limits' rules, and a front end checks a value with the same rule before it has options.
//! The table of values is in the [`crate::options`] module documentation.

use crate::controller::StepLimits;
use crate::options::error::{Allowed, OptionError, OptionField, Reason};

/// A numeric rule: a field and the values it allows. The constants are the rules of the
/// module documentation; a front end checks a value with the same rule
/// (`Rule::RTOL.check(v)`) and spells the error its own way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rule {
    /// The field.
    pub field: OptionField,
    /// What it allows.
    pub allowed: Allowed,
}

/// (0, 1]: the range of the step-limit factors below 1.
const UNIT: Allowed = Allowed::Range {
    lo: 0.0,
    lo_closed: false,
    hi: 1.0,
    hi_closed: true,
};

impl Rule {
    /// `rtol` ∈ [1e-14, 1).
    pub const RTOL: Rule = Rule {
        field: OptionField::Rtol,
        allowed: Allowed::Range {
            lo: 1e-14,
            lo_closed: true,
            hi: 1.0,
            hi_closed: false,
        },
    };
    /// `atol` (each entry) finite and > 0.
    pub const ATOL: Rule = Rule::new(OptionField::Atol, Allowed::FiniteAbove(0.0));
    /// `step` finite and > 0.
    pub const STEP: Rule = Rule::new(OptionField::Step, Allowed::FiniteAbove(0.0));
    /// `h0` finite and > 0.
    pub const H0: Rule = Rule::new(OptionField::H0, Allowed::FiniteAbove(0.0));
    /// `h_min` finite and ≥ 0 (`h_max` > `h_min` is a relation: [`crate::options::StepBounds::new`]).
    pub const H_MIN: Rule = Rule::new(OptionField::HMin, Allowed::FiniteAtLeast(0.0));
    /// `h_max_near_events` > 0 (∞: the contact-aware step limit off).
    pub const H_MAX_NEAR_EVENTS: Rule = Rule::new(OptionField::HMaxNearEvents, Allowed::Above(0.0));
    /// `max_steps` ≥ 1.
    pub const MAX_STEPS: Rule = Rule::new(OptionField::MaxSteps, Allowed::AtLeast(1.0));
    /// `max_wall_time` finite and > 0.
    pub const MAX_WALL_TIME: Rule = Rule::new(OptionField::MaxWallTime, Allowed::FiniteAbove(0.0));
    /// `event_rtol` ∈ [1e-15, 1e-3].
    pub const EVENT_RTOL: Rule = Rule {
        field: OptionField::EventRtol,
        allowed: Allowed::Range {
            lo: 1e-15,
            lo_closed: true,
            hi: 1e-3,
            hi_closed: true,
        },
    };
    /// `event_samples` ≤ 64.
    pub const EVENT_SAMPLES: Rule = Rule::new(OptionField::EventSamples, Allowed::AtMost(64.0));
    /// `divergence_bound` > 0 (+∞ allowed: no bound).
    pub const DIVERGENCE_BOUND: Rule = Rule::new(OptionField::DivergenceBound, Allowed::Above(0.0));
    /// Output times (each) finite.
    pub const OUTPUT_TIME: Rule = Rule::new(OptionField::Output, Allowed::Finite);
    /// `limits.safety` ∈ (0, 1].
    pub const SAFETY: Rule = Rule::new(OptionField::Safety, UNIT);
    /// `limits.max_growth` finite and > 1.
    pub const MAX_GROWTH: Rule = Rule::new(OptionField::MaxGrowth, Allowed::FiniteAbove(1.0));
    /// `limits.max_first_growth` finite and > 1.
    pub const MAX_FIRST_GROWTH: Rule =
        Rule::new(OptionField::MaxFirstGrowth, Allowed::FiniteAbove(1.0));
    /// `limits.min_shrink` ∈ (0, 1).
    pub const MIN_SHRINK: Rule = Rule {
        field: OptionField::MinShrink,
        allowed: Allowed::Range {
            lo: 0.0,
            lo_closed: false,
            hi: 1.0,
            hi_closed: false,
        },
    };
    /// `limits.max_after_reject` ∈ (0, 1].
    pub const MAX_AFTER_REJECT: Rule = Rule::new(OptionField::MaxAfterReject, UNIT);
    /// `limits.max_growth_after_reject` finite and ≥ 1.
    pub const MAX_GROWTH_AFTER_REJECT: Rule = Rule::new(
        OptionField::MaxGrowthAfterReject,
        Allowed::FiniteAtLeast(1.0),
    );
    /// `limits.max_after_repeated_reject` ∈ (0, 1].
    pub const MAX_AFTER_REPEATED_REJECT: Rule =
        Rule::new(OptionField::MaxAfterRepeatedReject, UNIT);
    /// `limits.deadband` lower end (entry 0) ∈ (0, 1].
    pub const DEADBAND_LOWER: Rule = Rule::new(OptionField::Deadband, UNIT);
    /// `limits.deadband` upper end (entry 1) finite and ≥ 1.
    pub const DEADBAND_UPPER: Rule = Rule::new(OptionField::Deadband, Allowed::FiniteAtLeast(1.0));

    /// The rule of `field` allowing `allowed`.
    pub const fn new(field: OptionField, allowed: Allowed) -> Self {
        Rule { field, allowed }
    }

    /// `value` if allowed, else the typed error.
    pub fn check(&self, value: f64) -> Result<f64, OptionError> {
        if self.allowed.contains(value) {
            Ok(value)
        } else {
            Err(OptionError::out_of_range(self.field, value, self.allowed))
        }
    }

    /// Entry `index` of a list, `value`, if allowed, else the typed error.
    pub fn check_entry(&self, index: usize, value: f64) -> Result<f64, OptionError> {
        if self.allowed.contains(value) {
            Ok(value)
        } else {
            Err(OptionError::new(
                self.field,
                Reason::EntryOutOfRange {
                    index,
                    value,
                    allowed: self.allowed,
                },
            ))
        }
    }
}

impl StepLimits {
    /// Checks the ranges documented on each field (the rules [`Rule::SAFETY`], …; written
    /// here, beside the rules, so that the controllers need nothing of the options).
    pub fn validate(&self) -> Result<(), OptionError> {
        Rule::SAFETY.check(self.safety)?;
        Rule::MAX_GROWTH.check(self.max_growth)?;
        Rule::MAX_FIRST_GROWTH.check(self.max_first_growth)?;
        Rule::MIN_SHRINK.check(self.min_shrink)?;
        Rule::MAX_AFTER_REJECT.check(self.max_after_reject)?;
        Rule::MAX_GROWTH_AFTER_REJECT.check(self.max_growth_after_reject)?;
        Rule::MAX_AFTER_REPEATED_REJECT.check(self.max_after_repeated_reject)?;
        Rule::DEADBAND_LOWER.check_entry(0, self.deadband.0)?;
        Rule::DEADBAND_UPPER.check_entry(1, self.deadband.1)?;
        Ok(())
    }
}
