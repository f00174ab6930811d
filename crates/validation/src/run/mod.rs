//! Running one case: case references, the runner every command calls, runs until periodic,
//! and the files of one run.

pub mod case;
pub mod files;
pub mod simulate;
pub mod steady;
