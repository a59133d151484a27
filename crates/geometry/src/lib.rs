//! The 3D world: scenes, robot and human models, kinematics, collision, pixel visibility,
//! effort levels and the shared literals derived from geometry.
pub mod mesh_file;
pub mod scene;
pub mod world;
pub mod effort;
pub mod render;
pub mod visibility;
pub mod facts;
pub mod mightability;
pub mod agent;
pub mod kinematics;
pub mod ik;
pub mod collision;
