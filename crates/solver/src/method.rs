//! The integration methods and one table of their facts ([`Method::info`]).
//!
//! ```text
//! method    family      order  embedded  error order  stages  FSAL  implicit  Jacobian  controller   dense degree
//! rk4       fixed step    4       –          –           4      no     no        no        –              3
//! bs32      explicit      3       2          2           4      yes    no        no        pi             3
//! dopri54   explicit      5       4          4           7      yes    no        no        pi             4
//! tsit54    explicit      5       4          4           7      yes    no        no        pi             4
//! dop853    explicit      8       5          7          12      no     no        no        pi             7
//! bdf       diffsol     1–5       –          –           –      no     yes       yes       –              5
//! trbdf2    diffsol       2       3          –           3      no     yes       yes       –              2
//! esdirk34  diffsol       3       4          –           4      no     yes       yes       –              3
//! rodas5p   Rosenbrock    5       4          4           8      no     yes       yes       gustafsson     4
//! ```
//!
//! Every crate asks these facts of [`Method::info`] and nowhere else: the family decides which
//! options a method takes (the rules of [`crate::options`]), the steppers take their
//! default controller from it, the front ends their names and the degree of the dense output.
//! Where the facts come from, and the tests that hold them to it:
//!
//! - orders, stages, FSAL and dense degree of the explicit pairs: their Butcher tableaus
//!   ([`crate::erk::tableaus`]); `tests/erk_tableaus.rs` proves the orders by the order
//!   conditions of all rooted trees and compares every entry of this table with the tableau;
//! - Rodas5P: Steinebach 2023 ([`crate::rosenbrock`]; its order conditions are checked there);
//! - diffsol's methods: diffsol 0.18's tableaus (TR-BDF2: Bank et al. 1985, order 2 with an
//!   order-3 estimate, dense output from its β matrix of degree 2; ESDIRK3(4): Jørgensen et
//!   al. 2018, order 3 with an order-4 estimate, cubic Hermite dense output) and its BDF
//!   (variable order 1–5, NDF form; the dense output interpolates the difference table, degree
//!   = the current order);
//! - the dense degree of every method is measured on its own interpolant by
//!   `tests/method_info.rs` (a polynomial of that degree reproduces it, one degree less does
//!   not), which also checks that explicit methods evaluate no Jacobian and implicit ones do.

use crate::controller::ControllerKind;

/// Integration method. Names are the contract of docs/outputs.md ("Method and controller names").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Classical Runge–Kutta 4, fixed step (the paper's method). Needs `step`.
    Rk4,
    /// Bogacki–Shampine 3(2), FSAL.
    Bs32,
    /// Dormand–Prince 5(4), FSAL.
    Dopri54,
    /// Tsitouras 5(4), FSAL.
    Tsit54,
    /// Dormand–Prince 8(5,3) (Hairer's DOP853).
    Dop853,
    /// diffsol's variable-order BDF.
    Bdf,
    /// diffsol's TR-BDF2 (an ESDIRK).
    Trbdf2,
    /// diffsol's ESDIRK3(4).
    Esdirk34,
    /// Our own Rosenbrock method Rodas5P (Steinebach 2023), order 5(4), stiffly accurate.
    Rodas5p,
}

/// How a method steps, which decides the options it takes ([`crate::options`]) and the
/// stepper that runs it ([`crate::make_stepper`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// A fixed step, no error control (RK4): takes `step`, no tolerances.
    FixedStep,
    /// An explicit embedded Runge–Kutta pair, run by our one-step driver
    /// ([`crate::onestep`]): tolerances, our controllers, `adaptive = false`.
    Explicit,
    /// A Rosenbrock method, run by the same one-step driver: as [`Family::Explicit`], with a
    /// Jacobian every step.
    Rosenbrock,
    /// One of diffsol's methods: tolerances and step limits, diffsol's own step control.
    Diffsol,
}

impl Family {
    /// Whether the family's methods are run by our one-step driver ([`crate::onestep`]).
    pub const fn is_one_step(self) -> bool {
        matches!(self, Family::Explicit | Family::Rosenbrock)
    }

    /// What the family is, as messages say it ("an explicit Runge–Kutta pair").
    pub const fn describe(self) -> &'static str {
        match self {
            Family::FixedStep => "a fixed-step method",
            Family::Explicit => "an explicit Runge–Kutta pair",
            Family::Rosenbrock => "a Rosenbrock method",
            Family::Diffsol => "one of diffsol's methods",
        }
    }
}

/// The facts of one method (the table of the [module documentation](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MethodInfo {
    /// The method's name in the CLI, scene options and summary.json (docs/outputs.md).
    pub name: &'static str,
    /// How it steps.
    pub family: Family,
    /// Order p of the propagated solution (BDF: its highest order, 5).
    pub order: usize,
    /// Order of the embedded solution of the error estimate (None: no embedded formula,
    /// RK4 and BDF).
    pub embedded_order: Option<usize>,
    /// Order q̂ of our controllers' error estimate, whose exponent is 1/(q̂ + 1) (None for
    /// methods without our controllers). Equals the embedded order except for DOP853, whose
    /// combined estimate E₅²/√(E₅² + 0.01 E₃²) behaves like h⁸ (HNW I §II.10).
    pub error_order: Option<usize>,
    /// Stages per step (None for the multistep BDF); for DOP853 without its three extra
    /// dense-output stages.
    pub stages: Option<usize>,
    /// First same as last: the last stage of a step is the first of the next.
    pub fsal: bool,
    /// Implicit (the stiff methods): each step solves with the iteration matrix I − hγJ.
    pub implicit: bool,
    /// Uses ∂f/∂y every step (the system's Jacobian, else finite differences).
    pub jacobian: bool,
    /// The controller used when the options name none (None: the method takes no
    /// controller of ours, RK4 and diffsol's methods).
    pub default_controller: Option<ControllerKind>,
    /// Degree in t of the dense output on one step (an upper bound: BDF's is its current
    /// order).
    pub dense_degree: usize,
}

/// The table, in the order of [`Method::ALL`] (the declaration order of [`Method`]).
const INFO: [MethodInfo; 9] = [
    MethodInfo {
        name: "rk4",
        family: Family::FixedStep,
        order: 4,
        embedded_order: None,
        error_order: None,
        stages: Some(4),
        fsal: false,
        implicit: false,
        jacobian: false,
        default_controller: None,
        dense_degree: 3,
    },
    MethodInfo {
        name: "bs32",
        family: Family::Explicit,
        order: 3,
        embedded_order: Some(2),
        error_order: Some(2),
        stages: Some(4),
        fsal: true,
        implicit: false,
        jacobian: false,
        default_controller: Some(ControllerKind::Pi),
        dense_degree: 3,
    },
    MethodInfo {
        name: "dopri54",
        family: Family::Explicit,
        order: 5,
        embedded_order: Some(4),
        error_order: Some(4),
        stages: Some(7),
        fsal: true,
        implicit: false,
        jacobian: false,
        default_controller: Some(ControllerKind::Pi),
        dense_degree: 4,
    },
    MethodInfo {
        name: "tsit54",
        family: Family::Explicit,
        order: 5,
        embedded_order: Some(4),
        error_order: Some(4),
        stages: Some(7),
        fsal: true,
        implicit: false,
        jacobian: false,
        default_controller: Some(ControllerKind::Pi),
        dense_degree: 4,
    },
    MethodInfo {
        name: "dop853",
        family: Family::Explicit,
        order: 8,
        embedded_order: Some(5),
        error_order: Some(7),
        stages: Some(12),
        fsal: false,
        implicit: false,
        jacobian: false,
        default_controller: Some(ControllerKind::Pi),
        dense_degree: 7,
    },
    MethodInfo {
        name: "bdf",
        family: Family::Diffsol,
        order: 5,
        embedded_order: None,
        error_order: None,
        stages: None,
        fsal: false,
        implicit: true,
        jacobian: true,
        default_controller: None,
        dense_degree: 5,
    },
    MethodInfo {
        name: "trbdf2",
        family: Family::Diffsol,
        order: 2,
        embedded_order: Some(3),
        error_order: None,
        stages: Some(3),
        fsal: false,
        implicit: true,
        jacobian: true,
        default_controller: None,
        dense_degree: 2,
    },
    MethodInfo {
        name: "esdirk34",
        family: Family::Diffsol,
        order: 3,
        embedded_order: Some(4),
        error_order: None,
        stages: Some(4),
        fsal: false,
        implicit: true,
        jacobian: true,
        default_controller: None,
        dense_degree: 3,
    },
    MethodInfo {
        name: "rodas5p",
        family: Family::Rosenbrock,
        order: 5,
        embedded_order: Some(4),
        error_order: Some(4),
        stages: Some(8),
        fsal: false,
        implicit: true,
        jacobian: true,
        default_controller: Some(ControllerKind::Gustafsson),
        dense_degree: 4,
    },
];

impl Method {
    /// All methods, in the order the tools list them.
    pub const ALL: [Method; 9] = [
        Method::Rk4,
        Method::Bs32,
        Method::Dopri54,
        Method::Tsit54,
        Method::Dop853,
        Method::Bdf,
        Method::Trbdf2,
        Method::Esdirk34,
        Method::Rodas5p,
    ];

    /// The method's facts (the table of the [module documentation](self)).
    pub const fn info(self) -> &'static MethodInfo {
        &INFO[self as usize]
    }

    /// The method's name in the CLI, scene options and summary.json.
    pub const fn name(self) -> &'static str {
        self.info().name
    }

    /// Parses a method name (the inverse of [`Method::name`]).
    pub fn from_name(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }

    /// The controller used when the options name none; None for methods that take no
    /// controller of ours (RK4, diffsol's methods).
    pub const fn default_controller(self) -> Option<ControllerKind> {
        self.info().default_controller
    }

    /// Degree in t of the method's dense output on one step ([`MethodInfo::dense_degree`]).
    pub const fn dense_degree(self) -> usize {
        self.info().dense_degree
    }

    /// True for fixed-step methods (they take `step`, not tolerances).
    pub const fn is_fixed_step(self) -> bool {
        matches!(self.info().family, Family::FixedStep)
    }

    /// True for diffsol's methods (they take no controller of ours).
    pub const fn is_diffsol(self) -> bool {
        matches!(self.info().family, Family::Diffsol)
    }

    /// True for implicit (stiff) methods.
    pub const fn is_stiff(self) -> bool {
        self.info().implicit
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_in_declaration_order_and_names_round_trip() {
        for (i, m) in Method::ALL.into_iter().enumerate() {
            assert_eq!(m as usize, i);
            assert_eq!(Method::from_name(m.name()), Some(m));
            // The serde name (scene options, summary.json) is the table's name.
            let json = serde_json::to_string(&m).unwrap();
            assert_eq!(json, format!("\"{}\"", m.name()));
        }
    }

    #[test]
    fn families_agree_with_the_other_facts() {
        for m in Method::ALL {
            let i = m.info();
            // Our controllers exactly for our one-step methods, with an error order.
            assert_eq!(
                i.default_controller.is_some(),
                i.family.is_one_step(),
                "{m}"
            );
            assert_eq!(i.error_order.is_some(), i.family.is_one_step(), "{m}");
            // The implicit methods are the stiff families, and only they use J every step.
            let stiff = matches!(i.family, Family::Rosenbrock | Family::Diffsol);
            assert_eq!(i.implicit, stiff, "{m}");
            assert_eq!(i.jacobian, stiff, "{m}");
        }
    }
}
