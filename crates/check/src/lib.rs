//! `check`: an independent geometric re-check of an htngtp plan JSON.
//!
//! It uses only what the file declares (scene objects' shapes and poses, each agent link's shapes,
//! link poses per frame, `holding` / `held_pose`, the timed `joint_trajectory` with its declared
//! limits, `object_poses` after each step, the literals a step adds and deletes) and parry3d's
//! queries; never the planner's state or its collision code, so that a plan it passes is
//! collision-free by a second opinion. The rules are in `docs/check.md`; `htngtp check
//! PLAN.json` is this crate's command line. [`check_file`] reads and checks a file,
//! [`parse_plan`] and [`check_plan`] do the two halves, and the [`Report`] lists each
//! [`Fault`] with its step, trajectory, frame and the bodies involved.
//!
//! # Example
//!
//! A one-step plan that puts a book down 1 cm inside the desk: the check reports the
//! penetration, and with the book resting on the desk's top the plan is clean.
//!
//! ```
//! use check::{FaultKind, Options, check_plan, parse_plan};
//!
//! let plan_with_book_at = |z: f32| {
//!     format!(
//!         r#"{{"format": "htngtp-plan", "version": 1, "domain": "d", "problem": "p",
//!            "status": "solved",
//!            "scene": {{"agents": [], "objects": [
//!              {{"name": "desk", "movable": false, "pose": {{"t": [1, 0, 0.375], "q": [0, 0, 0, 1]}},
//!                "shape": {{"box": {{"half_extents": [0.5, 0.5, 0.375]}}}}}},
//!              {{"name": "book", "movable": true, "pose": {{"t": [1, 0, 0.7702], "q": [0, 0, 0, 1]}},
//!                "shape": {{"box": {{"half_extents": [0.1, 0.14, 0.02]}}}}}}]}},
//!            "tree": [{{"id": 0, "action": "put", "args": ["book"], "step": 0}}], "root": [0],
//!            "steps": [{{"index": 0, "id": 0, "action": "put", "args": ["book"],
//!              "added": [], "deleted": [], "gtp": null,
//!              "object_poses": {{"book": {{"t": [1, 0.2, {z}], "q": [0, 0, 0, 1]}}}}}}]}}"#
//!     )
//! };
//!
//! let sunk = parse_plan(&plan_with_book_at(0.76), "sunk.json")?;
//! let report = check_plan(&sunk, &Options::default());
//! assert_eq!(report.faults.len(), 1);
//! assert_eq!(report.faults[0].kind, FaultKind::Penetration);
//! println!("{}", report.faults[0]);
//!
//! let resting = parse_plan(&plan_with_book_at(0.7702), "resting.json")?;
//! assert!(check_plan(&resting, &Options::default()).faults.is_empty());
//! # Ok::<(), check::InputError>(())
//! ```

mod bodies;
pub mod error;
mod grip;
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
