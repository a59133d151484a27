//! `check`: an independent geometric re-check of an htngtp plan JSON.
//!
//! It uses only what the file declares (scene objects' shapes and poses, each agent link's shapes,
//! link poses per frame, `holding` / `held_pose`, the timed `joint_trajectory` with its declared
//! limits, `object_poses` after each step, the literals a step adds and deletes) and parry3d's
//! queries; never the planner's state or its collision code, so that a plan it passes is
//! collision-free by a second opinion. The rules are in
//! `docs/check.md`.

mod bodies;
pub mod error;
pub mod kinematics;
mod literals;
pub mod model;
mod motion;
mod parse;
pub mod report;
mod rest;
mod sweep;
mod timing;
mod walk;
mod world;

pub use error::InputError;
pub use model::Plan;
pub use parse::parse_plan;
pub use report::{Fault, FaultKind, Report};
pub use walk::check_plan;

/// Tolerances of a check.
#[derive(Clone, Debug)]
pub struct Options {
    /// Interpolated configurations between consecutive frames (at least 4 is the rule).
    pub sub: usize,
    /// Deepest allowed interpenetration (m).
    pub depth: f32,
    /// Largest allowed gap between a resting object's bottom and its support (m).
    pub gap: f32,
    /// Deepest a hand may sink into what it grasps (m): fingers squeeze, a hand does not pass
    /// through a book.
    pub grasp_depth: f32,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            sub: 4,
            depth: 0.001,
            gap: 0.002,
            grasp_depth: 0.01,
        }
    }
}

/// Read, parse and check the plan file at `path`.
pub fn check_file(path: &std::path::Path, opts: &Options) -> Result<Report, InputError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| InputError::Io {
        file: file.clone(),
        source,
    })?;
    let plan = parse_plan(&text, &file)?;
    Ok(check_plan(&plan, opts))
}
