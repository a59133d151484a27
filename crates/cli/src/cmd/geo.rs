//! Combined HTN-GTP planning from the command line: `htngtp plan ... --scene SCENE` and
//! `htngtp demo` share this. Prints the decomposition tree and the plan with each GS action's
//! geometric summary, the run's statistics, and writes the plan JSON and pictures on request.

use std::path::{Path, PathBuf};

use anyhow::Context;
use geometry::render::{Camera, agent_camera, render};
use geometry::scene::{AgentKind, SceneError};
use geometry::world::World;
use gtp::solution::SolutionSummary;
use htn::model::{Domain, Problem};
use htn::planner::{Outcome, PlannerOptions};
use hybrid::{OracleConfig, Run, RunOptions};

use crate::exit;

/// Where the outputs of a combined run go.
#[derive(Default)]
pub struct Outputs {
    /// Print the plan JSON on standard output instead of the text report.
    pub json: bool,
    /// Write the plan JSON to this file.
    pub json_file: Option<PathBuf>,
    /// Write pictures of the world after each GS action into this folder.
    pub png_dir: Option<PathBuf>,
    /// How the plan JSON's joint trajectories are timed.
    pub timing: hybrid::export::TimingOptions,
}

/// A scene file to read, and whether objects that start inside one another may be read with a
/// warning (`--allow-initial-contact`).
pub struct SceneInput<'a> {
    pub path: &'a Path,
    pub allow_initial_contact: bool,
}

/// Loads a scene; with `allow_contact`, objects that start inside one another are a warning
/// on standard error (`--allow-initial-contact`), not an error. A robot inside furniture
/// stays an error.
/// What an agent's URDF loaded past (a visual mesh that names no file) is a warning too.
pub fn load_world(path: &Path, allow_contact: bool) -> Result<World, SceneError> {
    let world = if allow_contact {
        let (world, warning) = World::load_allowing_contact(path)?;
        if let Some(w) = warning {
            eprintln!("warning: {w} (read anyway: --allow-initial-contact)");
        }
        world
    } else {
        World::load(path)?
    };
    for id in world.agent_ids() {
        for w in world.agent(id).model.load_warnings() {
            eprintln!("warning: {w}");
        }
    }
    Ok(world)
}

/// Plans `problem` of `domain` in `scene` and reports; returns the exit code.
/// `domain` and `problem` are read; `began` is when the command started reading.
pub fn run_plan(
    domain: &Domain,
    problem: &Problem,
    began: std::time::Instant,
    scene: SceneInput<'_>,
    planner: PlannerOptions,
    oracle: OracleConfig,
    out: &Outputs,
) -> anyhow::Result<u8> {
    // Reading a scene takes about 64 times its size in memory (TOML's tree): the memory limit
    // holds there too.
    let len = std::fs::metadata(scene.path).map(|m| m.len()).unwrap_or(0);
    if !htn::budget::fits(len.saturating_mul(geometry::scene::SCENE_MEMORY_PER_BYTE)) {
        anyhow::bail!(htn::budget::message(
            htn::planner::Limit::Memory,
            &format!(
                "reading the scene {} ({} KiB)",
                scene.path.display(),
                len >> 10
            )
        ));
    }
    let world =
        load_world(scene.path, scene.allow_initial_contact).map_err(|e| anyhow::anyhow!("{e}"))?;
    if let Some(limit) = htn::budget::check() {
        anyhow::bail!(htn::budget::message(limit, "reading the scene"));
    }
    // The time limit covers reading the files: the planner gets what is left.
    let mut planner = planner;
    planner.limits.time = planner
        .limits
        .time
        .map(|t| t.saturating_sub(began.elapsed()));
    let options = RunOptions { planner, oracle };
    let run = hybrid::plan(
        domain,
        problem,
        world,
        std::sync::Arc::new(gtp::planner::Planner::new()),
        &options,
    )?;
    // The plan JSON holds the whole scene and every trajectory: built only when asked for.
    let json = if out.json || out.json_file.is_some() {
        hybrid::export::plan_json_with(&run, &domain.name, &problem.name, &out.timing)
    } else {
        serde_json::Value::Null
    };
    if out.json {
        println!("{}", serde_json::to_string(&json)?);
    } else {
        print_report(&run);
    }
    if let Some(f) = &out.json_file {
        // Compact, as `--json` and the benches write it: a plan JSON is data (frames of link
        // poses), and indented it is three to four times larger.
        std::fs::write(f, serde_json::to_string(&json)?)
            .with_context(|| format!("writing {}", f.display()))?;
        eprintln!("plan JSON written to {}", f.display());
    }
    if let Some(dir) = &out.png_dir {
        let n = write_pictures(&run, dir)?;
        eprintln!("{n} pictures written to {}", dir.display());
    }
    Ok(match &run.result.outcome {
        Outcome::Found { .. } => exit::OK,
        Outcome::Unsolvable => exit::UNSOLVABLE,
        Outcome::LimitReached { .. } => exit::LIMIT,
    })
}

/// The text report: tree, plan with GTP summaries, statistics, or why no plan exists.
pub fn print_report(run: &Run) {
    let stats = &run.result.stats;
    match &run.result.outcome {
        Outcome::Found { plan } => {
            println!("Decomposition:");
            let by_id: std::collections::HashMap<u32, &htn::plan::Decomposition> =
                plan.decompositions.iter().map(|d| (d.id, d)).collect();
            let actions: std::collections::HashMap<u32, &htn::plan::PlanAction> =
                plan.actions.iter().map(|a| (a.id, a)).collect();
            fn walk(
                id: u32,
                depth: usize,
                by_id: &std::collections::HashMap<u32, &htn::plan::Decomposition>,
                actions: &std::collections::HashMap<u32, &htn::plan::PlanAction>,
            ) {
                let pad = "  ".repeat(depth + 1);
                if let Some(d) = by_id.get(&id) {
                    println!("{pad}{} {} -> {}", d.task, d.args.join(" "), d.method);
                    for &c in &d.subtasks {
                        walk(c, depth + 1, by_id, actions);
                    }
                } else if let Some(a) = actions.get(&id) {
                    println!("{pad}{} {}", a.name.to_uppercase(), a.args.join(" "));
                }
            }
            for &r in &plan.root {
                walk(r, 0, &by_id, &actions);
            }
            println!("\nPlan ({} actions):", plan.actions.len());
            for (i, a) in plan.actions.iter().enumerate() {
                println!("  {i:>2}. {} {}", a.name, a.args.join(" "));
                if let Some(g) = &a.geometric {
                    let mut parts = vec![format!("{}({})", g.task, g.args.join(", "))];
                    let summary = run.oracle.solution_summary(g.solution);
                    parts.extend(summary.map(solution_parts).unwrap_or_default());
                    println!("      GTP: {}", parts.join("; "));
                    let fmt = |v: &[htn::oracle::GroundAtom]| {
                        v.iter()
                            .map(|a| a.to_string())
                            .collect::<Vec<_>>()
                            .join(" ")
                    };
                    if !g.add.is_empty() {
                        println!("      + {}", fmt(&g.add));
                    }
                    if !g.delete.is_empty() {
                        println!("      - {}", fmt(&g.delete));
                    }
                }
            }
        }
        Outcome::Unsolvable => println!("No plan: {}", run.failure_message()),
        Outcome::LimitReached { limit } => {
            println!("Stopped by the {limit}; {}", run.failure_message())
        }
    }
    println!(
        "\nStatistics: {} nodes, {} HTN backtracks, {} GTP backtracks, {:.3} s",
        stats.nodes, stats.htn_backtracks, stats.geo_backtracks, stats.time_s
    );
    let mut tasks: Vec<_> = run.oracle.task_stats().iter().collect();
    tasks.sort_by(|a, b| a.0.cmp(b.0));
    println!(
        "  {:<26} {:>8} {:>6} {:>9} {:>5} {:>7} {:>5} {:>6}",
        "GTP task", "attempts", "succ", "time ms", "pts", "grasps", "orts", "calls"
    );
    for (name, s) in tasks {
        println!(
            "  {:<26} {:>8} {:>6} {:>9.1} {:>5} {:>7} {:>5} {:>6}",
            name,
            s.attempts,
            s.successes,
            s.total_time_s() * 1e3,
            s.search.points,
            s.search.grasps,
            s.search.orientations,
            s.search.planner_calls
        );
    }
}

/// A GTP solution in words: grasp, placement, visibility and trajectory length.
fn solution_parts(s: &SolutionSummary) -> Vec<String> {
    let mut parts = Vec::new();
    if let Some(g) = &s.grasp {
        let id = g.id.map_or_else(|| "null".to_string(), |i| i.to_string());
        parts.push(format!("grasp {id} on {}", g.arm));
    }
    if let Some(p) = &s.placement {
        let [x, y, z] = p.point;
        parts.push(format!(
            "placed on {} at ({x:.2}, {y:.2}, {z:.2})",
            p.support.as_deref().unwrap_or("(held)")
        ));
    }
    if let Some(v) = s.visibility {
        parts.push(format!("visibility {:.0}%", v * 100.0));
    }
    let len: f32 = s.trajectories.iter().map(|t| t.length).sum();
    parts.push(format!("trajectory length {len:.2}"));
    parts
}

/// Pictures of the initial world and of the world after each GS action, from the first human's
/// eyes and from above. Returns how many were written.
pub fn write_pictures(run: &Run, dir: &Path) -> anyhow::Result<usize> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut worlds: Vec<(String, &World)> = vec![("00-initial".into(), &run.initial)];
    if let Outcome::Found { plan } = &run.result.outcome {
        for (i, a) in plan.actions.iter().enumerate() {
            if let Some(w) = a
                .geometric
                .as_ref()
                .and_then(|g| run.oracle.solution_world(g.solution))
            {
                worlds.push((format!("{:02}-{}", i + 1, a.name), w));
            }
        }
    }
    let mut n = 0;
    for (label, world) in worlds {
        let human = world
            .agent_ids()
            .find(|&a| world.agent(a).kind() == AgentKind::Human);
        let mut views = vec![("top", Camera::top(&world.bounds(), 4.0 / 3.0), 480, 360)];
        if let Some(h) = human {
            views.push(("human", agent_camera(world, h), 480, 360));
        }
        for (view, camera, w, h) in views {
            let path = dir.join(format!("{label}-{view}.png"));
            render(world, &camera, w, h)
                .save_png(&path)
                .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))?;
            n += 1;
        }
    }
    Ok(n)
}
