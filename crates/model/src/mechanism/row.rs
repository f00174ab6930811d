//! A constraint equation: Φ = konst + rate·t + Σ terms, each term on one body (the data only;
//! its evaluation is in constraints.rs). The ideal joints and drivers give such equations, and
//! so do the clearance joints for the initial assembly (their initial eccentricity, offset,
//! tilt).
//!
//! ```text
//! term    w · r^P  (r^P = r + A(φ) s, a body point)   |   c · φ
//! ```

use crate::planar::dot;
use crate::scene::refs::{point_of, Attachment, SceneRefs, GROUND};

/// A term of a constraint equation.
#[derive(Clone, Copy, Debug)]
pub(crate) enum TermKind {
    /// w · r^P, r^P = r + A(φ) s
    Point { s: [f64; 2], w: [f64; 2] },
    /// c · φ
    Angle { c: f64 },
}

/// A term on one body.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Term {
    pub body: usize,
    pub kind: TermKind,
}

/// One scalar constraint equation Φ = konst + rate·t + Σ terms.
#[derive(Clone, Debug)]
pub(crate) struct Row {
    pub terms: [Term; 2],
    pub n_terms: usize,
    pub konst: f64,
    pub rate: f64,
    /// Scene joint index.
    pub joint: usize,
    /// Which equation of the joint ("x", "y", "across the line", ...).
    pub label: &'static str,
    /// Whether the joint is a driver (its multiplier is the driving torque).
    pub driver: bool,
}

/// One evaluated constraint row.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowEval {
    pub phi: f64,
    pub phid: f64,
    pub gamma: f64,
    /// ∂Φ/∂(x, y, φ) of the body of each term.
    pub jrows: [[f64; 3]; 2],
}

impl Row {
    pub(crate) fn new(joint: usize, label: &'static str) -> Row {
        Row {
            terms: [Term {
                body: 0,
                kind: TermKind::Angle { c: 0.0 },
            }; 2],
            n_terms: 0,
            konst: 0.0,
            rate: 0.0,
            joint,
            label,
            driver: false,
        }
    }

    pub(crate) fn push(&mut self, t: Term) {
        self.terms[self.n_terms] = t;
        self.n_terms += 1;
    }

    /// Adds w · r^P of an attachment (folds a ground location into the constant).
    pub(crate) fn add_attachment(&mut self, refs: &dyn SceneRefs, a: &Attachment, w: [f64; 2]) {
        if a.body == GROUND {
            self.konst += dot(w, a.at.expect("validated"));
        } else {
            let k = refs.body_index(&a.body).expect("validated");
            self.push(Term {
                body: k,
                kind: TermKind::Point {
                    s: point_of(refs, a),
                    w,
                },
            });
        }
    }

    /// The row with the target rate Φ̇ = v at t₀ and Φ(t₀) unchanged: rate −v, constant + v t₀.
    pub(crate) fn with_rate(mut self, v: f64, t0: f64) -> Row {
        self.rate -= v;
        self.konst += v * t0;
        self
    }
}
