//! The 3D world: scenes, robot and human models, kinematics, collision, pixel visibility,
//! effort levels and the shared literals derived from geometry.
pub mod agent;
pub mod kinematics;
pub mod ik;
pub mod collision;
