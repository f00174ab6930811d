//! Benchmarks for lash live in `benches/`; this library is empty on purpose.
