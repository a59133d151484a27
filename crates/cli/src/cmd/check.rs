//! `htngtp check`: the independent geometric re-check of a plan JSON (crate `check`).

use std::path::PathBuf;

use crate::exit;

/// Arguments of `htngtp check`.
#[derive(clap::Args)]
#[command(
    after_help = "Replays the plan JSON from what it declares alone (shapes, link poses \
    per frame, held poses, object poses after each step) with its own geometry (parry3d), never \
    the planner's collision code. Checks, with SUB interpolated configurations between frames \
    (translation linear, rotation slerp): every link, held object and scene object against each \
    other (grasping links may sink up to GRASP_DEPTH into the object they hold or the step's \
    target; adjacent links of one agent may touch, see docs/check.md); that every object at rest after a step lies within \
    2 mm of a surface under it and penetrates nothing; and re-measures each added or deleted \
    `visible` / `reachable` literal (visible: half of the pixels; reach 0.95 m robot, 0.70 m \
    person), reporting only clear disagreements; and, where a trajectory has a \
    `joint_trajectory`, its timing: times strictly increasing from 0, at rest at both ends, \
    velocities and accelerations within the limits it declares, its ends at its first and \
    last waypoints (`timing` faults); and, where it also declares its gripper, that a finger \
    of the holding hand is within 3 mm of what it carries at its end (`loose-grip`).\n\nExit codes: 0 clean, 1 faults found, \
    3 bad input (unreadable file, bad JSON with line and column, missing key with its path)."
)]
pub struct Args {
    /// The plan JSON (`htngtp plan --json-out`, `htngtp demo`).
    pub plan: PathBuf,
    /// Interpolated configurations between consecutive frames (4 to 64).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(4..=64))]
    pub sub: u32,
    /// Deepest allowed interpenetration, metres.
    #[arg(long, default_value_t = 0.001)]
    pub depth: f32,
    /// Deepest a hand may sink into the object it grasps, metres.
    #[arg(long, default_value_t = 0.01)]
    pub grasp_depth: f32,
    /// Print a machine-readable JSON report instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    for (name, v) in [("--depth", args.depth), ("--grasp-depth", args.grasp_depth)] {
        if !(v.is_finite() && v >= 0.0) {
            anyhow::bail!("{name} must be a non-negative number of metres");
        }
    }
    let opts = check::Options {
        sub: args.sub as usize,
        depth: args.depth,
        grasp_depth: args.grasp_depth,
        ..check::Options::default()
    };
    crate::input::check_file(&args.plan)?;
    // A fault of the collision library on some input is said as an error, not a panic (the
    // input checks are meant to rule these out; the fuzz harness calls the check unguarded).
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let checked = std::panic::catch_unwind(|| check::check_file(&args.plan, &opts));
    std::panic::set_hook(hook);
    let report = match checked {
        Ok(Ok(r)) => r,
        Ok(Err(e @ (check::InputError::Bad { .. } | check::InputError::Missing { .. }))) => {
            anyhow::bail!("{}: {e}", args.plan.display())
        }
        Ok(Err(e)) => return Err(e.into()),
        Err(_) => anyhow::bail!(
            "{}: the geometric check failed on this plan (a fault in the checker; please \
             report it with the file)",
            args.plan.display()
        ),
    };
    if args.json {
        let mut v = serde_json::to_value(&report)?;
        v["summary"] = report.summary().into();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        for f in &report.faults {
            println!("{f}");
        }
        println!("{}", report.summary());
    }
    Ok(if report.faults.is_empty() {
        exit::OK
    } else {
        exit::UNSOLVABLE
    })
}
