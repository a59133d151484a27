//! `htngtp gtp`: run one geometric task in a scene and print its solutions.

use std::path::PathBuf;

use anyhow::Context;
use geometry::render::{Camera, render};
use gtp::planner::{CallOptions, Planner};
use gtp::solution::SolutionSummary;
use gtp::verify::recheck_trajectories;
use serde::Serialize;

use crate::exit;

/// Arguments of `htngtp gtp`.
#[derive(clap::Args)]
#[command(
    about = "Run one geometric task (pick, place-on, show, give, make-accessible, put-away, \
             navigate-to, pick-and-make-accessible) in a scene",
    long_about = "Run one task of the geometric task planner in a scene and print the solution: \
                  the grasp, the placement (or hand-over pose), the visibility reached, the \
                  length of each trajectory (approach, grasp, lift, transfer, place, retreat, \
                  return), and the call's statistics (the paper's Table II columns: time, \
                  points tested, grasps tried, orientations tried, trajectory-planner calls).\n\n\
                  Tasks and arguments: pick OBJECT; place-on OBJECT SUPPORT; show|give|\
                  make-accessible|put-away|pick-and-make-accessible OBJECT HUMAN; navigate-to \
                  TARGET. Thresholds can be changed with --set KEY=VALUE (min-visibility, \
                  max-visibility, reach-within, unreachable-within, max-effort, robot-effort, \
                  lift, approach, time-limit, max-points).\n\n\
                  When a pick, place or hand-over finds nothing from where the robot stands, the \
                  same call tries base poses nearby: turning in place, then stepping up to 1 m \
                  (robot-effort 2 and 4; the default 4; robot-effort=1 keeps the base fixed). \
                  Such a solution starts with the drive; `base poses nearby` counts the poses \
                  tried.\n\n\
                  Exit codes: 0 solved, 1 no solution (the report says which constraint stopped \
                  the search), 2 time limit, 3 bad input.",
    after_help = "Example: htngtp gtp domains/library/scene.toml make-accessible grey-book member --solutions 3"
)]
pub struct Args {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Read the scene even when objects start inside one another (a warning then, not an
    /// error); a robot inside furniture is still refused.
    #[arg(long)]
    pub allow_initial_contact: bool,
    /// The task's name.
    pub task: String,
    /// The task's arguments (object, support, human or target names).
    pub args: Vec<String>,
    /// Seed of every random choice (inverse-kinematics restarts, RRT samples).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// How many solutions to pull from the stream (each different from the ones before).
    #[arg(long, default_value_t = 1)]
    pub solutions: usize,
    /// Threshold overrides, KEY=VALUE (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Print everything as JSON, trajectories included.
    #[arg(long)]
    pub json: bool,
    /// Render the world after the (last) solution, from above, into this PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Re-check every trajectory at 4x finer resolution before reporting it.
    #[arg(long)]
    pub verify: bool,
    /// Filter candidate points with the scene's mightability maps (computed first, ~0.6 s)
    /// instead of testing each point directly.
    #[arg(long)]
    pub mightability: bool,
}

#[derive(Serialize)]
struct Report<'a> {
    task: &'a str,
    args: &'a [String],
    seed: u64,
    solutions: Vec<SolutionSummary>,
    failure: Option<gtp::planner::Failure>,
    stats: gtp::stats::Stats,
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    let world = match crate::cmd::geo::load_world(&args.scene, args.allow_initial_contact) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: {}", htn::text::clip(&e.to_string()));
            return Ok(exit::BAD_INPUT);
        }
    };
    let mut options = CallOptions::seeded(args.seed);
    for kv in &args.set {
        let Some((k, v)) = kv.split_once('=') else {
            eprintln!("error: --set {kv}: expected KEY=VALUE");
            return Ok(exit::BAD_INPUT);
        };
        options = options.with(k.trim(), v.trim());
    }
    let planner = Planner::with_config(gtp::planner::PlannerConfig {
        mightability: args.mightability,
        ..Default::default()
    });
    let names: Vec<&str> = args.args.iter().map(String::as_str).collect();
    let mut stream = match planner.run(&world, &args.task, &names, &options) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {}", htn::text::clip(&e.to_string()));
            return Ok(exit::BAD_INPUT);
        }
    };
    let mut solutions = Vec::new();
    let mut last_world = None;
    for _ in 0..args.solutions.max(1) {
        let Some(s) = stream.next() else { break };
        if args.verify {
            let res = planner.config().rrt.resolution / 4.0;
            if let Err(e) = recheck_trajectories(&planner, &world, &s.summary, res) {
                anyhow::bail!("solution {} fails its re-check: {e}", s.summary.index);
            }
        }
        if !args.json {
            print_solution(&s.summary);
        }
        solutions.push(s.summary);
        last_world = Some(s.world);
    }
    let failure = if solutions.len() < args.solutions.max(1) {
        stream.failure().cloned()
    } else {
        None
    };
    let stats = stream.stats();
    let solved = !solutions.is_empty();
    if args.json {
        let report = Report {
            task: &args.task,
            args: &args.args,
            seed: args.seed,
            solutions,
            failure: failure.clone(),
            stats,
        };
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        if let Some(f) = &failure {
            if !solved {
                println!("no solution: {f}");
            } else {
                println!("no further solution: {f}");
            }
        }
        println!(
            "stats: time {:.1} ms, success {}, points {}, grasps {}, orientations {}, \
             trajectory-planner calls {}, IK calls {}, visibility checks {}, effort level {}, \
             base poses nearby {}",
            stats.time_s * 1e3,
            solved,
            stats.points,
            stats.grasps,
            stats.orientations,
            stats.planner_calls,
            stats.ik_calls,
            stats.visibility_checks,
            stats.effort_level,
            stats.base_poses
        );
    }
    if let (Some(path), Some(w)) = (&args.png, &last_world) {
        let b = w.bounds();
        let img = render(w, &Camera::top(&b, 1.0), 800, 800);
        img.save_png(path)
            .map_err(anyhow::Error::msg)
            .with_context(|| format!("writing {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(if solved {
        exit::OK
    } else if failure.as_ref().is_some_and(|f| f.limit) {
        exit::LIMIT
    } else {
        exit::UNSOLVABLE
    })
}

fn print_solution(s: &SolutionSummary) {
    println!(
        "solution {} of {}({}): effort level {}",
        s.index,
        s.task,
        s.args.join(", "),
        s.effort_level
    );
    if let Some(g) = &s.grasp {
        let id = g.id.map_or("held".to_string(), |i| format!("#{i}"));
        println!(
            "  grasp {id} with the {}, jaws {:.1} cm, tool at {:?} in the object's frame",
            g.arm,
            g.width * 100.0,
            g.tool_in_object.xyz.map(|c| (c * 1000.0).round() / 1000.0)
        );
    }
    if let Some(p) = &s.placement {
        println!(
            "  object at {:?} ({}), face {}, yaw {}",
            p.pose.xyz.map(|c| (c * 1000.0).round() / 1000.0),
            p.support
                .as_deref()
                .map_or("held in the air".to_string(), |n| format!("on {n}")),
            p.orientation,
            p.yaw_index
        );
    }
    if let Some(b) = s.robot_base {
        println!(
            "  robot base at x {:.2} y {:.2} yaw {:.2}",
            b[0], b[1], b[2]
        );
    }
    if let Some(v) = s.visibility {
        println!("  visibility {:.2}", v);
    }
    if let Some(r) = s.reach_effort {
        println!("  reachable by the human at effort level {r}");
    }
    let lengths: Vec<String> = s
        .trajectories
        .iter()
        .map(|t| format!("{:?} {:.2} ({} pts)", t.phase, t.length, t.waypoints.len()))
        .collect();
    println!("  trajectories: {}", lengths.join(", "));
}
