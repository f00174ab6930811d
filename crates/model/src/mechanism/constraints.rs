//! Constraint equations: each scalar equation Φ = konst + rate·t + Σ terms, and its evaluation.

use crate::planar::dot;
use crate::scene::{Attachment, Scene, GROUND};

#[derive(Clone, Copy, Debug)]
pub(crate) enum TermKind {
    /// w · r^P, r^P = r + A(φ) s
    Point { s: [f64; 2], w: [f64; 2] },
    /// c · φ
    Angle { c: f64 },
}

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
        }
    }

    pub(crate) fn push(&mut self, t: Term) {
        self.terms[self.n_terms] = t;
        self.n_terms += 1;
    }

    /// Adds w · r^P of an attachment (folds a ground location into the constant).
    pub(crate) fn add_attachment(&mut self, scene: &Scene, a: &Attachment, w: [f64; 2]) {
        if a.body == GROUND {
            self.konst += dot(w, a.at.expect("validated"));
        } else {
            let k = scene.body_index(&a.body).expect("validated");
            self.push(Term {
                body: k,
                kind: TermKind::Point {
                    s: point_of(scene, a),
                    w,
                },
            });
        }
    }
}

pub(crate) fn point_of(scene: &Scene, a: &Attachment) -> [f64; 2] {
    if a.body == GROUND {
        return a.at.expect("validated");
    }
    let k = scene.body_index(&a.body).expect("validated");
    scene.bodies[k].points[a.point.as_ref().expect("validated")]
}
