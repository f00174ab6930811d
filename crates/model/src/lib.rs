//! # lash-model
//!
//! Planar multibody scenes with dry and lubricated revolute clearance joints (MODEL.md), turned
//! into an index-1 ODE `y' = f(t, y)` with y = (q, q̇) for the integrators of `lash-solver`.
#![warn(missing_docs)]

pub mod geometry;
pub mod laws;
