//! Running one case: case references, the runner every command calls, runs until periodic,
//! and the files of one run.

pub(crate) mod case;
pub(crate) mod files;
pub(crate) mod simulate;
pub(crate) mod steady;

#[cfg(test)]
mod tests;
