//! One geometric task through the `gtp` crate's API: load a scene, ask the task, pull its first
//! solutions and print what each one is (effort level, grasp, placement, visibility reached,
//! trajectories) and, when the stream ends, the constraint that stopped it.
//!
//! ```sh
//! cargo run --release -p gtp --example one_task -- domains/library/scene.toml \
//!     make-accessible grey-book member
//! cargo run --release -p gtp --example one_task -- domains/library/scene-cart.toml pick grey-book
//! ```
//!
//! Arguments: `SCENE TASK ARG...` (the task names and arguments of `htngtp gtp`). At most three
//! solutions are pulled; `htngtp gtp` is the full command-line tool for the same call.

use std::process::ExitCode;
use std::time::Instant;

use geometry::world::World;
use gtp::planner::{CallOptions, Planner};

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
    let [scene, task, rest @ ..] = args.as_slice() else {
        return Err("usage: one_task SCENE TASK ARG...".into());
    };
    let world = World::load(scene).map_err(|e| e.to_string())?;
    // The planner caches what depends only on the scene (grasp sets, the robot's arms).
    let planner = Planner::new();
    let rest: Vec<&str> = rest.iter().map(String::as_str).collect();
    let began = Instant::now();
    let mut stream = planner
        .run(&world, task, &rest, &CallOptions::default())
        .map_err(|e| e.to_string())?;
    for i in 0..3 {
        // Each `next()` resumes the search where the previous solution was found.
        let Some(solution) = stream.next() else {
            match stream.failure() {
                Some(f) => println!("no (further) solution: {f}"),
                None => println!("no (further) solution"),
            }
            break;
        };
        let s = &solution.summary;
        println!("solution {i}: effort level {}", s.effort_level);
        if let Some(g) = &s.grasp {
            let id = g.id.map_or("held".to_string(), |id| id.to_string());
            println!("  grasp {id} on {}, jaw {:.3} m", g.arm, g.width);
        }
        if let Some(p) = &s.placement {
            let [x, y, z] = p.point;
            let on = p.support.as_deref().unwrap_or("the hand-over point");
            println!("  placed on {on} at ({x:.2}, {y:.2}, {z:.2})");
        }
        if let Some(v) = s.visibility {
            println!("  visibility {:.0} %", v * 100.0);
        }
        for (phase, length) in s.trajectory_lengths() {
            println!("  {phase:?}: {length:.2}");
        }
    }
    let stats = stream.stats();
    println!(
        "{} points, {} grasps, {} orientations, {} trajectory-planner calls, {:.1} ms",
        stats.points,
        stats.grasps,
        stats.orientations,
        stats.planner_calls,
        began.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}
