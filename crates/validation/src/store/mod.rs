//! What is kept on disk: atomic writes, the cache of finished runs, claim files.

pub mod cache;
pub mod claim;
pub mod io;
