//! Clearance joints, side by side: the revolute joint (a journal in a bearing, docs/model.md
//! §2–§4) and the prismatic joint (a block in a guide, §11), their shared contact laws, and the
//! revolute joint's kinematics and force laws.

pub mod contact;
pub mod geometry;
pub mod laws;
pub mod prismatic;
pub mod revolute;
mod revolute_jacobian;
