//! The 3D world: scenes, robot and human models, kinematics, collision, pixel visibility,
//! effort levels and the shared literals derived from geometry.
pub mod agent;
pub mod collision;
pub mod effort;
pub mod facts;
pub mod ik;
pub mod kinematics;
pub mod mesh_file;
pub mod mightability;
pub mod perception;
pub mod render;
pub mod scene;
pub mod visibility;
pub mod world;
