//! The typed error of a wrong option: which field, what is wrong, the value and the allowed
//! range, with a message that names fields apart from its text so that each front end spells
//! them its own way ([`OptionError::render`]).
//!
//! ```text
//! OptionError { field: Rtol, reason: OutOfRange { value: 0.0, allowed: RTOL } }
//!   Display (engine names):  "rtol must be in [1e-14, 1), got 0"
//!   lash:                    "--rtol must be in [1e-14, 1), got 0"
//! ```

use std::fmt;

use crate::method::{Family, Method};

/// An option (a field of [`crate::SolverOptions`], of its step limits, or an argument of an
/// integration), by its engine name ([`OptionField::name`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum OptionField {
    /// `method`.
    Method,
    /// `rtol`.
    Rtol,
    /// `atol`.
    Atol,
    /// `step`, the fixed step of fixed-step methods.
    Step,
    /// `h0`, the first step (the step of every step with `adaptive = false`).
    H0,
    /// `adaptive`.
    Adaptive,
    /// `h_min`.
    HMin,
    /// `h_max`.
    HMax,
    /// `h_max_near_events`, the contact-aware step limit.
    HMaxNearEvents,
    /// `max_steps`.
    MaxSteps,
    /// `controller`.
    Controller,
    /// `limits.safety`.
    Safety,
    /// `limits.max_growth`.
    MaxGrowth,
    /// `limits.max_first_growth`.
    MaxFirstGrowth,
    /// `limits.min_shrink`.
    MinShrink,
    /// `limits.max_after_reject`.
    MaxAfterReject,
    /// `limits.max_growth_after_reject`.
    MaxGrowthAfterReject,
    /// `limits.max_after_repeated_reject`.
    MaxAfterRepeatedReject,
    /// `limits.deadband` (entry 0 the lower end, 1 the upper).
    Deadband,
    /// `output` (its times).
    Output,
    /// `event_rtol`.
    EventRtol,
    /// `event_samples`.
    EventSamples,
    /// `max_wall_time`.
    MaxWallTime,
    /// `divergence_bound`.
    DivergenceBound,
    /// `rk4_instability_steps`.
    Rk4InstabilitySteps,
    /// `y0`, the initial state of an integration.
    Y0,
    /// `t0`, the start of an integration.
    T0,
    /// `t_end`, the end of an integration.
    TEnd,
    /// `t_stop`, the stop time of one step of a stepper.
    TStop,
    /// `tableau`, a custom Butcher tableau.
    Tableau,
}

impl OptionField {
    /// The engine's name of the field (the name of the [`crate::SolverOptions`] field;
    /// `limits.NAME` for the step limits).
    pub const fn name(self) -> &'static str {
        use OptionField as F;
        match self {
            F::Method => "method",
            F::Rtol => "rtol",
            F::Atol => "atol",
            F::Step => "step",
            F::H0 => "h0",
            F::Adaptive => "adaptive",
            F::HMin => "h_min",
            F::HMax => "h_max",
            F::HMaxNearEvents => "h_max_near_events",
            F::MaxSteps => "max_steps",
            F::Controller => "controller",
            F::Safety => "limits.safety",
            F::MaxGrowth => "limits.max_growth",
            F::MaxFirstGrowth => "limits.max_first_growth",
            F::MinShrink => "limits.min_shrink",
            F::MaxAfterReject => "limits.max_after_reject",
            F::MaxGrowthAfterReject => "limits.max_growth_after_reject",
            F::MaxAfterRepeatedReject => "limits.max_after_repeated_reject",
            F::Deadband => "limits.deadband",
            F::Output => "output",
            F::EventRtol => "event_rtol",
            F::EventSamples => "event_samples",
            F::MaxWallTime => "max_wall_time",
            F::DivergenceBound => "divergence_bound",
            F::Rk4InstabilitySteps => "rk4_instability_steps",
            F::Y0 => "y0",
            F::T0 => "t0",
            F::TEnd => "t_end",
            F::TStop => "t_stop",
            F::Tableau => "tableau",
        }
    }
}

impl fmt::Display for OptionField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The values a numeric option may take.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Allowed {
    /// Finite.
    Finite,
    /// Greater than the bound (+∞ allowed).
    Above(f64),
    /// Finite and greater than the bound.
    FiniteAbove(f64),
    /// Finite and at least the bound.
    FiniteAtLeast(f64),
    /// At least the bound (whole numbers).
    AtLeast(f64),
    /// At most the bound (whole numbers).
    AtMost(f64),
    /// Between two finite bounds, each included or not.
    Range {
        /// Lower bound.
        lo: f64,
        /// Whether `lo` is allowed.
        lo_closed: bool,
        /// Upper bound.
        hi: f64,
        /// Whether `hi` is allowed.
        hi_closed: bool,
    },
}

impl Allowed {
    /// Whether `v` is allowed (NaN never is).
    #[inline]
    pub fn contains(&self, v: f64) -> bool {
        match *self {
            Allowed::Finite => v.is_finite(),
            Allowed::Above(b) => v > b,
            Allowed::FiniteAbove(b) => v.is_finite() && v > b,
            Allowed::FiniteAtLeast(b) => v.is_finite() && v >= b,
            Allowed::AtLeast(b) => v >= b,
            Allowed::AtMost(b) => v <= b,
            Allowed::Range {
                lo,
                lo_closed,
                hi,
                hi_closed,
            } => {
                let above = if lo_closed { v >= lo } else { v > lo };
                let below = if hi_closed { v <= hi } else { v < hi };
                above && below
            }
        }
    }
}

impl fmt::Display for Allowed {
    /// The allowed set as messages say it: `finite and > 0`, `in [1e-14, 1)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Allowed::Finite => f.write_str("finite"),
            Allowed::Above(b) => write!(f, "> {}", Num(b)),
            Allowed::FiniteAbove(b) => write!(f, "finite and > {}", Num(b)),
            Allowed::FiniteAtLeast(b) => write!(f, "finite and >= {}", Num(b)),
            Allowed::AtLeast(b) => write!(f, ">= {}", Num(b)),
            Allowed::AtMost(b) => write!(f, "<= {}", Num(b)),
            Allowed::Range {
                lo,
                lo_closed,
                hi,
                hi_closed,
            } => write!(
                f,
                "in {}{}, {}{}",
                if lo_closed { '[' } else { '(' },
                Num(lo),
                Num(hi),
                if hi_closed { ']' } else { ')' }
            ),
        }
    }
}

/// A number as messages print it: plain between 0.01 and 10⁶ (`0.5`, `-1`, `64`), else in
/// exponent form (`1e-14`, `2.5e-7`).
#[derive(Clone, Copy, Debug)]
pub struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if self.0 == 0.0 || !a.is_finite() || (1e-2..1e6).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// What is wrong with an option.
#[derive(Clone, Debug, PartialEq)]
pub enum Reason {
    /// The value lies outside the allowed set.
    OutOfRange {
        /// The value given.
        value: f64,
        /// What is allowed.
        allowed: Allowed,
    },
    /// One entry of a list lies outside the allowed set.
    EntryOutOfRange {
        /// The entry's index.
        index: usize,
        /// The entry's value.
        value: f64,
        /// What is allowed.
        allowed: Allowed,
    },
    /// The value must exceed another option's (h_max > h_min, t_end > t0).
    NotAbove {
        /// The value given.
        value: f64,
        /// The option it must exceed.
        other: OptionField,
        /// That option's value.
        other_value: f64,
    },
    /// A stop time that does not lie after the stepper's current time.
    NotAfter {
        /// The stop time given.
        value: f64,
        /// The current time.
        t: f64,
    },
    /// A list has the wrong length.
    WrongLength {
        /// Its length.
        len: usize,
        /// The system's dimension.
        expected: usize,
    },
    /// A list must be non-decreasing and entry `index` is smaller than the one before.
    Decreasing {
        /// The first entry out of order.
        index: usize,
    },
    /// The method needs the option and it was not given.
    Required {
        /// The method.
        method: Method,
    },
    /// Another option's value needs this one and it was not given (`adaptive = false` needs
    /// `h0`).
    RequiredBy {
        /// The option that needs it.
        other: OptionField,
    },
    /// The option was given but does not apply to the method.
    NotForMethod {
        /// The method.
        method: Method,
    },
    /// A constructor of one family was handed a method of another.
    WrongFamily {
        /// The method given.
        method: Method,
        /// What the constructor builds ([`Family::describe`]).
        expected: &'static str,
    },
    /// Anything else, in words (a custom tableau's shape, diffsol's own complaint).
    Invalid(String),
}

/// One piece of an option error's message: text, or a field that each front end spells its
/// own way.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Part {
    /// Text, as is.
    Text(String),
    /// A field (the engine spells it [`OptionField::name`], `lash` as its flag).
    Field(OptionField),
}

/// A wrong option: which field, and what is wrong with it (the value and what is allowed are
/// in the [`Reason`]). [`Display`](fmt::Display) names fields by their engine names;
/// [`OptionError::render`] spells them as a front end does.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", self.render(&|f| f.name().to_string()))]
pub struct OptionError {
    /// The field at fault.
    pub field: OptionField,
    /// What is wrong.
    pub reason: Reason,
}

impl OptionError {
    /// The error of `field` for `reason`.
    pub fn new(field: OptionField, reason: Reason) -> Self {
        OptionError { field, reason }
    }

    /// `field`'s `value` outside `allowed`.
    pub fn out_of_range(field: OptionField, value: f64, allowed: Allowed) -> Self {
        OptionError::new(field, Reason::OutOfRange { value, allowed })
    }

    /// `field` given for a method it does not apply to.
    pub fn not_for(field: OptionField, method: Method) -> Self {
        OptionError::new(field, Reason::NotForMethod { method })
    }

    /// The message as pieces of text and fields.
    pub fn parts(&self) -> Vec<Part> {
        let f = self.field;
        let mut p = Parts::default();
        match &self.reason {
            Reason::OutOfRange { value, allowed } => {
                p.field(f).text(out_of_range(*value, allowed));
            }
            Reason::EntryOutOfRange {
                index,
                value,
                allowed,
            } => {
                p.field(f)
                    .text(format!("[{index}]{}", out_of_range(*value, allowed)));
            }
            Reason::NotAbove {
                value,
                other,
                other_value,
            } => {
                p.field(f)
                    .text(format!(" ({}) must exceed ", Num(*value)))
                    .field(*other)
                    .text(format!(" ({})", Num(*other_value)));
            }
            Reason::NotAfter { value, t } => {
                p.field(f)
                    .text(format!(" ({}) is not after t = {}", Num(*value), Num(*t)));
            }
            Reason::WrongLength { len, expected } => {
                p.field(f)
                    .text(format!(" has {len} entries, the system {expected}"));
            }
            Reason::Decreasing { index } => {
                p.field(f).text(format!(
                    " must be non-decreasing, and entry {index} is smaller than entry {}",
                    index.saturating_sub(1)
                ));
            }
            Reason::Required { method } if f == OptionField::Step => {
                p.text(format!("method {method} is fixed-step and needs "))
                    .field(f)
                    .text(" (it needs a fixed step size)");
            }
            Reason::Required { method } => {
                p.text(format!("method {method} needs ")).field(f);
            }
            Reason::RequiredBy { other } if *other == OptionField::Adaptive => {
                p.field(*other)
                    .text(" = false needs ")
                    .field(f)
                    .text(", the size of every step");
            }
            Reason::RequiredBy { other } => {
                p.field(*other).text(" needs ").field(f);
            }
            Reason::NotForMethod { method } => not_for_method(&mut p, f, *method),
            Reason::WrongFamily { method, expected } => {
                p.text(format!("method {method} is not {expected}"));
            }
            Reason::Invalid(what) => {
                p.field(f).text(format!(": {what}"));
            }
        }
        p.0
    }

    /// The message with each field spelled by `spell`.
    pub fn render(&self, spell: &dyn Fn(OptionField) -> String) -> String {
        self.parts()
            .into_iter()
            .map(|p| match p {
                Part::Text(s) => s,
                Part::Field(f) => spell(f),
            })
            .collect()
    }
}

/// What follows the field's name for a value outside `allowed`: " must be finite and > 0,
/// got -1", or " is not finite, got NaN" when only finite values are asked for.
fn out_of_range(value: f64, allowed: &Allowed) -> String {
    match allowed {
        Allowed::Finite => format!(" is not finite, got {}", Num(value)),
        _ => format!(" must be {allowed}, got {}", Num(value)),
    }
}

/// The message of a field given for a method it does not apply to, by the method's family.
fn not_for_method(p: &mut Parts, f: OptionField, method: Method) {
    use OptionField as F;
    let family = method.info().family;
    match (family, f) {
        (Family::FixedStep, _) => {
            p.field(f).text(format!(
                " is only for adaptive methods, and {method} is fixed-step"
            ));
        }
        (_, F::Step | F::Rk4InstabilitySteps) => {
            p.field(f).text(format!(
                " is only for fixed-step methods, and {method} is adaptive"
            ));
        }
        (Family::Diffsol, F::Controller) => {
            p.field(f).text(format!(
                " does not apply to {method}, which takes no controller of ours: it uses \
                 diffsol's own step control"
            ));
        }
        (Family::Diffsol, F::Adaptive) => {
            p.field(f).text(format!(
                " = false does not apply to {method}, which uses diffsol's own step control"
            ));
        }
        _ => {
            p.field(f).text(format!(" does not apply to {method}"));
        }
    }
}

/// A message under construction.
#[derive(Default)]
struct Parts(Vec<Part>);

impl Parts {
    fn text(&mut self, s: impl Into<String>) -> &mut Self {
        self.0.push(Part::Text(s.into()));
        self
    }
    fn field(&mut self, f: OptionField) -> &mut Self {
        self.0.push(Part::Field(f));
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_as_written() {
        let s: Vec<String> = [0.0, -1.0, 0.5, 64.0, 1e-14, 1e-3, 2.5e-7, 1e100, f64::NAN]
            .iter()
            .map(|v| Num(*v).to_string())
            .collect();
        assert_eq!(
            s,
            ["0", "-1", "0.5", "64", "1e-14", "1e-3", "2.5e-7", "1e100", "NaN"]
        );
    }

    #[test]
    fn ranges_contain_what_they_say() {
        let r = Allowed::Range {
            lo: 1e-14,
            lo_closed: true,
            hi: 1.0,
            hi_closed: false,
        };
        assert_eq!(r.to_string(), "in [1e-14, 1)");
        assert!(r.contains(1e-14) && r.contains(0.5));
        assert!(!r.contains(1.0) && !r.contains(f64::NAN) && !r.contains(9e-15));
        assert!(Allowed::Above(0.0).contains(f64::INFINITY));
        assert!(!Allowed::FiniteAbove(0.0).contains(f64::INFINITY));
        assert!(!Allowed::FiniteAbove(0.0).contains(0.0));
        assert!(Allowed::FiniteAtLeast(0.0).contains(0.0));
        assert!(!Allowed::AtMost(64.0).contains(65.0));
    }

    #[test]
    fn fields_are_spelled_by_the_front_end() {
        let e = OptionError::new(
            OptionField::HMax,
            Reason::NotAbove {
                value: 0.0,
                other: OptionField::HMin,
                other_value: 0.0,
            },
        );
        assert_eq!(e.to_string(), "h_max (0) must exceed h_min (0)");
        let flags = e.render(&|f| format!("--{}", f.name().replace('_', "-")));
        assert_eq!(flags, "--h-max (0) must exceed --h-min (0)");
    }
}
