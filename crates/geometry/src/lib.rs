//! The 3D world: scenes, robot and human models, kinematics, collision, pixel visibility,
//! effort levels and the shared literals derived from geometry.
//!
//! A [`world::World`] is read from a scene file ([`scene`], `docs/scene-format.md`) with its
//! agents' URDF and SRDF models ([`agent`]); it is cheap to clone, so planners copy and change
//! it (object poses, what an agent holds, joint values). From a world, [`facts`] computes the
//! shared literals the HTN planner reads (`visible` and `reachable` with the least effort level
//! at which they hold, `on`, `inside`, `covered-by`), [`visibility`] the fraction of an object's
//! pixels an agent sees, [`mightability`] per-level maps of what an agent could see and reach,
//! [`collision`] and [`ik`] what the geometric task planner needs to move an arm, and [`render`]
//! pictures.
//!
//! # Example
//!
//! The library scene: how much of the grey book the member sees with the head turned to it,
//! and at which effort level the book is visible and reachable for them:
//!
//! ```
//! use geometry::facts::{FactParams, reachable_effort, shared_literals, visible_effort};
//! use geometry::visibility::{Aim, visibility_for_agent};
//! use geometry::world::World;
//!
//! let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../../domains/library/scene.toml");
//! let world = World::load(scene)?;
//! let book = world.object_id("grey-book").expect("the scene has a grey book");
//! let member = world.agent_id("member").expect("and a member");
//!
//! let seen = visibility_for_agent(&world, member, book, Aim::AtTarget, 64).fraction();
//! assert!((0.0..=1.0).contains(&seen));
//!
//! let params = FactParams::default(); // visible: at least half of the pixels, 64 x 64 rays
//! assert_eq!(visible_effort(&world, member, book, &params), Some(3)); // standing up
//! assert_eq!(reachable_effort(&world, member, book, &params), Some(4)); // walking over
//! let on_table = shared_literals(&world, &params)
//!     .into_iter()
//!     .any(|f| f.predicate == "on" && f.args == ["grey-book", "table"]);
//! assert!(on_table);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod agent;
pub mod collision;
pub mod effort;
pub mod facts;
pub mod ik;
pub mod kinematics;
pub mod mesh_file;
pub mod mightability;
pub mod perception;
pub mod ray_capsule_cylinder;
pub mod render;
pub mod scene;
pub mod visibility;
pub mod world;
