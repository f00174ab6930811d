//! Force elements a researcher brings (docs/model.md §10): springs and dampers, applied forces
//! and torques (constant, or tabulated against time or one coordinate), motors with a
//! torque–speed curve. One file per kind holds its scene type, its checks, its compiled form
//! and its evaluation (`interface.rs` says what a kind implements); the table below registers
//! the kinds.
//!
//! ```text
//! spring_damper             F = k (L − L₀) + c L̇   (or F = curve(L) + c L̇), tension > 0
//! rotational_spring_damper  τ = k (θ − θ₀) + c θ̇   (or curve(θ) + c θ̇),  θ = φ_a − φ_b
//! force                     F = f(s) d̂  at a body point, d̂ global or in the body frame
//! torque                    τ = f(s)    on a body
//! motor                     τ = T(ω),  ω = φ̇_rotor − φ̇_stator  (table, or T_s (1 − ω/ω₀))
//! linear_bushing            F = −k d − c ḋ,  d = r_a^P − r_b^P  (isotropic)
//! f(s) = value | table(s) piecewise linear, s = t | x, y of a body point | a body angle |
//!        a joint's relative coordinate | a spring's length
//! ```
//! Adding a kind: a new file implementing `ElementSpec` and `ForceElement`
//! (elements/interface.rs), and one line in the `force_elements!` table of this file; the line
//! declares the module, the variant of [`ForceElementSpec`] (its `"type"` tag, its
//! `Deserialize`, its place in the "expected one of" list) and of the compiled `Element`, and
//! every dispatch. A scene without force elements runs none of this code.
//!
//! Sources: docs/model.md §10; Nikravesh, Computer-Aided Analysis of Mechanical Systems
//! (1988), §5 (point-to-point and rotational spring-damper-actuators).

pub(crate) mod input;
pub(crate) mod interface;
pub(crate) mod table;

use crate::elements::input::{Input, Kin, Load};
use crate::elements::interface::{Account, ElementEval, ElementSpec, ForceElement, ForceJacobian};
use crate::labels::{Column, EventLabels};
use crate::scene::check::check_name;
use crate::scene::de::tagged_kinds;
use crate::scene::error::{invalid, SceneError};
use crate::scene::refs::SceneRefs;

pub use input::Outside;
pub use table::{Acts, BodyRef, CurveSpec, ElementRef, InputSpec, JointRef, PointRef, TableSpec};

/// The registry of force element kinds (module doc): one line per kind,
/// `"tag" => Variant(module::Spec => Element)`, optionally after `@cfg(…)`.
macro_rules! force_elements {
    ($(
        $(@cfg($cfg:meta))?
        $tag:literal => $variant:ident($module:ident::$spec:ident => $element:ident)
    ),+ $(,)?) => {
        $( $(#[cfg($cfg)])? mod $module; )+
        $( $(#[cfg($cfg)])? pub use $module::$spec; )+

        tagged_kinds! {
            /// A force element (`"type"` selects the kind; docs/scene-format.md, "Force
            /// elements").
            pub enum ForceElementSpec named, tag "type", unknown "force element type" {
                $(
                    $(@cfg($cfg))?
                    #[doc = concat!("A `", $tag, "` element.")]
                    $tag => $variant($spec)
                ),+
            }
        }

        impl ForceElementSpec {
            /// Checks the element's own fields at `p` (`forces[i]`).
            fn validate(&self, p: &str, refs: &dyn SceneRefs) -> Result<(), SceneError> {
                match self {
                    $( $(#[cfg($cfg)])? Self::$variant(s) => s.validate(p, refs), )+
                }
            }

            /// The compiled element (validated).
            pub(crate) fn compile(&self, refs: &dyn SceneRefs) -> Element {
                match self {
                    $( $(#[cfg($cfg)])? Self::$variant(s) => Element::$variant(s.compile(refs)), )+
                }
            }

            /// Whether the element has a length (a table input `of: length`).
            pub(crate) fn has_length(&self) -> bool {
                match self {
                    $( $(#[cfg($cfg)])? Self::$variant(s) => s.has_length(), )+
                }
            }

            /// Its length as a table input (validated; None without one).
            pub(crate) fn length(&self, refs: &dyn SceneRefs) -> Option<Input> {
                match self {
                    $( $(#[cfg($cfg)])? Self::$variant(s) => s.length(refs), )+
                }
            }
        }

        /// A compiled force element of the scene's `forces` (docs/model.md §10).
        #[derive(Clone, Debug, PartialEq)]
        pub(crate) enum Element {
            $(
                $(#[cfg($cfg)])?
                #[doc = concat!("A `", $tag, "` element.")]
                $variant($module::$element),
            )+
        }

        impl Element {
            /// Evaluates the element; `apply(body, arm, force, torque)` receives every load.
            #[inline]
            pub(crate) fn eval(&self, t: f64, kin: &Kin<'_>, apply: impl FnMut(Load)) -> ElementEval {
                match self {
                    $( $(#[cfg($cfg)])? Element::$variant(e) => e.eval(t, kin, apply), )+
                }
            }

            /// Its output columns.
            pub(crate) fn columns(&self) -> &'static [Column] {
                match self {
                    $( $(#[cfg($cfg)])? Element::$variant(_) => <$module::$element as ForceElement>::COLUMNS, )+
                }
            }

            /// Where its power in is booked.
            pub(crate) fn account(&self) -> Account {
                match self {
                    $( $(#[cfg($cfg)])? Element::$variant(_) => <$module::$element as ForceElement>::ACCOUNT, )+
                }
            }

            /// The event kinds of every element kind, in registry order.
            pub(crate) fn all_events() -> Vec<EventLabels> {
                let mut all = Vec::new();
                $( $(#[cfg($cfg)])? all.extend_from_slice(<$module::$element as ForceElement>::EVENTS); )+
                all
            }

            /// Its event functions' kinds.
            pub(crate) fn events(&self) -> &'static [EventLabels] {
                match self {
                    $( $(#[cfg($cfg)])? Element::$variant(_) => <$module::$element as ForceElement>::EVENTS, )+
                }
            }

            /// Its event function `i` and rate.
            pub(crate) fn event(&self, i: usize, t: f64, kin: &Kin<'_>) -> (f64, f64) {
                match self {
                    $( $(#[cfg($cfg)])? Element::$variant(e) => e.event(i, t, kin), )+
                }
            }

            /// Sets the defaults of the assembled initial state.
            pub(crate) fn set_initial(&mut self, t0: f64, kin: &Kin<'_>) {
                match self {
                    $( $(#[cfg($cfg)])? Element::$variant(e) => e.set_initial(t0, kin), )+
                }
            }

            /// Adds its closed-form ∂g/∂(q, q̇); false: it has none (differenced).
            pub(crate) fn jacobian(&self, t: f64, kin: &Kin<'_>, jac: &mut ForceJacobian<'_>) -> bool {
                match self {
                    $( $(#[cfg($cfg)])? Element::$variant(e) => e.jacobian(t, kin, jac), )+
                }
            }
        }
    };
}

force_elements! {
    "spring_damper" => SpringDamper(spring_damper::SpringDamperSpec => SpringDamper),
    "rotational_spring_damper" =>
        RotationalSpringDamper(rotational_spring_damper::RotationalSpringDamperSpec => RotationalSpringDamper),
    "force" => Force(force::ForceSpec => Force),
    "torque" => Torque(torque::TorqueSpec => Torque),
    "motor" => Motor(motor::MotorSpec => Motor),
    "linear_bushing" => LinearBushing(linear_bushing::LinearBushingSpec => LinearBushing),
    @cfg(test) "test_height" => TestHeight(test_height::TestHeightSpec => TestHeight),
}

pub use force::Frame;

/// Checks every force element (docs/scene-format.md, "Force elements"): its name (unique), then
/// its own fields; the first failure with its JSON path.
pub(crate) fn validate_all(
    forces: &[ForceElementSpec],
    refs: &dyn SceneRefs,
) -> Result<(), SceneError> {
    for (i, f) in forces.iter().enumerate() {
        let p = format!("forces[{i}]");
        check_name(&format!("{p}.name"), f.name())?;
        if forces[..i].iter().any(|o| o.name() == f.name()) {
            return Err(invalid(
                format!("{p}.name"),
                format!("duplicate force element name '{}'", f.name()),
            ));
        }
        f.validate(&p, refs)?;
    }
    Ok(())
}
