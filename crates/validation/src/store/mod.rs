//! What is kept on disk: atomic writes, the cache of finished runs, claim files.

pub(crate) mod cache;
pub(crate) mod claim;
pub(crate) mod io;
