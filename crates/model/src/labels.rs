//! The names a mechanism reports: output columns with their units, and the labels of events.
//!
//! ```text
//! Column       <part>.<suffix> in trajectory.csv, in unit `unit`
//! EventLabels  an event function's kind, and what its rising and falling crossings are called
//! ```
//! Each is declared once, by the element or joint that owns the column or the event
//! (docs/outputs.md, docs/model.md §7).

/// One output column of a part of a mechanism.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Column {
    /// The column's suffix: `<part name>.<suffix>` in trajectory.csv.
    pub suffix: &'static str,
    /// Its SI unit (`"1"` for a ratio).
    pub unit: &'static str,
}

/// The names of one kind of event function (docs/model.md §7).
///
/// ```text
/// kind     what crosses zero ("contact": δ of a revolute clearance joint, …)
/// rising   the name of an upward crossing ("contact_onset"), falling of a downward one
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EventLabels {
    /// The kind (as [`crate::Mechanism::event_name`] reports it).
    pub kind: &'static str,
    /// The name of a rising crossing.
    pub rising: &'static str,
    /// The name of a falling crossing.
    pub falling: &'static str,
}

impl EventLabels {
    /// The label of a crossing in the given direction.
    pub fn label(&self, rising: bool) -> &'static str {
        if rising {
            self.rising
        } else {
            self.falling
        }
    }
}
