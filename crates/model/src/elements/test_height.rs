//! A force element for the unit tests of the element seam only (registered under
//! `#[cfg(test)]`): it applies no load and has one event function, the height of a body point
//! above a level, so that the events of elements are exercised end to end.
//!
//! ```text
//! g = y^P − h,  ġ = ẏ^P;  column height (m) = g
//! ```

use serde::{Deserialize, Serialize};

use crate::elements::input::{point_state, Kin, Load, Pt};
use crate::elements::interface::{ElementEval, ElementSpec, ForceElement};
use crate::elements::table::{check_point_ref, point_ref, PointRef};
use crate::labels::{Column, EventLabels};
use crate::scene::check::Checker;
use crate::scene::error::SceneError;
use crate::scene::refs::SceneRefs;

/// A probe of a body point's height (tests only).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TestHeightSpec {
    /// Unique element name.
    pub name: String,
    /// The point.
    pub at: PointRef,
    /// The level h (m).
    pub level: f64,
}

impl ElementSpec for TestHeightSpec {
    type Element = TestHeight;

    fn validate(&self, p: &str, refs: &dyn SceneRefs) -> Result<(), SceneError> {
        check_point_ref(refs, &format!("{p}.at"), &self.at)?;
        Checker::finite(&format!("{p}.level"), self.level)
    }

    fn compile(&self, refs: &dyn SceneRefs) -> TestHeight {
        TestHeight {
            p: point_ref(refs, &self.at),
            level: self.level,
        }
    }
}

/// A compiled probe.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TestHeight {
    p: Pt,
    level: f64,
}

impl ForceElement for TestHeight {
    const COLUMNS: &'static [Column] = &[Column {
        suffix: "height",
        unit: "m",
    }];
    const EVENTS: &'static [EventLabels] = &[EventLabels {
        kind: "test_height",
        rising: "test_height_up",
        falling: "test_height_down",
    }];

    fn eval(&self, _t: f64, kin: &Kin<'_>, _apply: impl FnMut(Load)) -> ElementEval {
        let mut out = ElementEval::new();
        out.load = point_state(&self.p, kin).0[1] - self.level;
        out
    }

    fn event(&self, _i: usize, _t: f64, kin: &Kin<'_>) -> (f64, f64) {
        let (r, v, _) = point_state(&self.p, kin);
        (r[1] - self.level, v[1])
    }
}

#[cfg(test)]
mod tests {
    //! The events of an element: placed after the clearance joints' and before the kinks,
    //! named and labelled by the element, located where the closed form puts them.
    use crate::{event_label, Mechanism, Scene};
    use lash_solver::{solve, Atol, Method, OdeSystem, SolverOptions};
    use serde_json::json;

    #[test]
    fn an_elements_event_is_listed_named_labelled_and_located() {
        // A free ball falls from y₀ = 1 m under g = 9.81 m/s²: it crosses h = 0.5 m at
        // t = √(2 (y₀ − h)/g), falling. A pin in a ground bearing (a clearance joint) gives the
        // event list a contact and, with kink events, kinks.
        let v = json!({
            "bodies": [
                {"name": "ball", "mass": 1.0, "inertia": 0.1, "position": [0.0, 1.0],
                 "points": {"c": [0.0, 0.0]}},
                {"name": "pin", "mass": 2.0, "inertia": 0.1, "points": {"c": [0.0, 0.0]}}
            ],
            "joints": [{"type": "clearance", "name": "bearing",
                "bearing": {"body": "ground", "at": [0.0, 0.0], "radius": 0.010},
                "journal": {"body": "pin", "point": "c", "radius": 0.009},
                "normal": {"law": "impact", "k": 1e9, "c_max": 100.0, "d_max": 1e-5}}],
            "forces": [{"type": "test_height", "name": "probe",
                        "at": {"body": "ball"}, "level": 0.5}],
            "gravity": [0.0, -9.81],
            "kink_events": true,
            "t_end": 0.5
        });
        let m = Mechanism::from_scene(&Scene::from_json_str(&v.to_string()).unwrap()).unwrap();
        let names: Vec<(&str, &str)> = (0..m.n_events()).map(|i| m.event_name(i).unwrap()).collect();
        assert_eq!(names[0], ("contact", "bearing"));
        assert_eq!(names[1], ("test_height", "probe"));
        assert!(names[2..].iter().all(|(k, _)| k.starts_with("kink_")), "{names:?}");
        assert_eq!(m.event_labels(1).unwrap().falling, "test_height_down");
        assert_eq!(event_label("test_height", true), "test_height_up");
        assert_eq!(m.output_columns().last().unwrap(), "probe.height");
        assert_eq!(m.output_units().last().unwrap(), &"m");
        let opts = SolverOptions {
            rtol: 1e-10,
            atol: Atol::Scalar(1e-12),
            event_rtol: 1e-12,
            ..SolverOptions::with_method(Method::Dop853)
        };
        let sol = solve(&m, (0.0, 0.5), &m.initial_state(), &opts).unwrap();
        let hits: Vec<_> = sol.events.iter().filter(|h| h.index == 1).collect();
        assert_eq!(hits.len(), 1, "{:?}", sol.events);
        let exact = (2.0 * 0.5 / 9.81f64).sqrt();
        assert!(!hits[0].rising && (hits[0].t - exact).abs() < 1e-9 * exact, "{:?}", hits[0]);
    }
}
