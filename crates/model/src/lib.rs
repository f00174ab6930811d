//! # lash-model
//!
//! Planar multibody scenes with dry and lubricated revolute clearance joints (MODEL.md).
#![warn(missing_docs)]
