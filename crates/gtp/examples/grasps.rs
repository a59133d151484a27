//! The grasps the GTP generates for a box with a robot's gripper: how many antipodal pairs the
//! box offers, how many grasps survive the gripper's collision pre-check, and each grasp's
//! score, tool position and approach direction in the box's frame. Useful when bringing a new
//! robot: a gripper model that yields no grasps for the objects of a scene fails every pick.
//!
//! ```sh
//! cargo run --release -p gtp --example grasps -- 0.1 0.14 0.02              # the PR2's right arm
//! cargo run --release -p gtp --example grasps -- 0.1 0.14 0.02 \
//!     models/fetch.urdf models/fetch.srdf arm                                # the Fetch-like robot
//! ```
//!
//! Arguments: the box's half extents `HX HY HZ` in metres, then optionally `URDF SRDF ARM` (an
//! SRDF group whose chain ends at an end effector; default `models/pr2.urdf`, `models/pr2.srdf`,
//! `right_arm`).

use std::io::{ErrorKind, Write};
use std::process::ExitCode;

use geometry::agent::AgentModel;
use gtp::grasp::{GraspParams, generate_grasps};
use gtp::gripper::GripperModel;
use parry3d::math::Vector;
use parry3d::shape::Cuboid;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(3)
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 3 && args.len() != 6 {
        return Err("usage: grasps HX HY HZ [URDF SRDF ARM]".into());
    }
    let half: Vec<f32> = args[..3]
        .iter()
        .map(|s| {
            s.parse::<f32>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("`{s}`: a half extent must be a positive number (m)"))
        })
        .collect::<Result<_, _>>()?;
    let models = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/");
    let (urdf, srdf, arm) = match &args[3..] {
        [u, s, a] => (u.clone(), s.clone(), a.as_str()),
        _ => (
            format!("{models}pr2.urdf"),
            format!("{models}pr2.srdf"),
            "right_arm",
        ),
    };
    let model = AgentModel::from_urdf_file(&urdf)
        .and_then(|m| m.with_srdf_file(&srdf))
        .map_err(|e| e.to_string())?;
    let gripper = GripperModel::of_named_arm(&model, arm)?;
    let object = Cuboid::new(Vector::new(half[0], half[1], half[2]));
    let set =
        generate_grasps(&object, &GraspParams::default(), &gripper).map_err(|e| e.to_string())?;
    let mut out = std::io::stdout().lock();
    let mut lines = vec![format!(
        "{} grasps from {} antipodal pairs ({} dropped: the gripper collides with the box)",
        set.grasps.len(),
        set.antipodal_pairs,
        set.colliding
    )];
    for g in &set.grasps {
        let t = g.tool_in_object.translation;
        let x = g.tool_in_object.rotation * Vector::X;
        lines.push(format!(
            "score {:.3}  tool at ({:.3}, {:.3}, {:.3})  approach ({:.2}, {:.2}, {:.2})  jaw {:.3} m",
            g.score, t.x, t.y, t.z, x.x, x.y, x.z, g.width
        ));
    }
    for line in lines {
        match writeln!(out, "{line}") {
            Ok(()) => {}
            // A reader that stops early (`| head`) ends the listing quietly.
            Err(e) if e.kind() == ErrorKind::BrokenPipe => return Ok(()),
            Err(e) => return Err(format!("writing to stdout: {e}")),
        }
    }
    Ok(())
}
