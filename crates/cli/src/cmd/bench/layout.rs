//! `bench library --layout random|room`: the report of the runs planned in random layouts or
//! random rooms: the share solved, run times, GTP request latencies, and the failures by GTP
//! task and constraint; `--json FILE`'s summary.

use std::collections::BTreeMap;
use std::path::Path;

use hybrid::experiment::{Experiment, RunRecord};
use hybrid::scale::quantile;
use serde::Serialize;

use crate::cmd::bench_hddl::csv_field;

/// How `bench library` varies the scene per run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LayoutArg {
    /// Every movable object shifted by up to 3 cm and turned by up to 10 degrees where it
    /// rests, every person moved by up to 5 cm and 6 degrees (the default).
    Nudge,
    /// A random layout per run: the books and the POS machine on random free spots of any
    /// support surface, on any face, where the robot can pick them up (the books from its
    /// station, the POS machine after driving to it); the member seated on the chair moved
    /// along the desk, or standing on free floor facing it, sharing a reach patch of the desk
    /// with the robot.
    Random,
    /// A random room per run: furniture of every kind drawn (sizes, top heights 0.6-1.1 m,
    /// places, yaw), the member seated or standing at a free side of the counter, the robot's
    /// station found, books and the POS machine on any support, books side by side on
    /// bookshelf boards, clutter (see the long help for what is sensible).
    Room,
}

/// The failures of one (task, constraint) pair.
#[derive(Clone, Debug, Serialize)]
pub struct FailureGroup {
    pub task: String,
    pub constraint: String,
    pub runs: usize,
    /// The runs' indices.
    pub indices: Vec<usize>,
}

/// The summary of a random-layout experiment.
#[derive(Clone, Debug, Serialize)]
pub struct LayoutReport {
    pub runs: usize,
    pub solved: usize,
    pub solved_pct: f64,
    /// Wall time of a run (failures included, at the time they stopped), seconds.
    pub median_time_s: f64,
    pub p90_time_s: f64,
    /// Runs whose layout could not be generated.
    pub layout_errors: usize,
    /// Mean whole-layout attempts per generated layout.
    pub mean_layout_attempts: f64,
    pub failures: Vec<FailureGroup>,
}

/// Whether the run had no layout (the generator gave up).
fn layout_failed(r: &RunRecord) -> bool {
    r.status.starts_with("error: the layout")
}

/// The task and constraint of a failed run: its cause, else `-` and the start of its status
/// (a layout error, an HTN failure with no geometric task failed).
fn key(r: &RunRecord) -> (String, String) {
    match &r.cause {
        Some(c) => (c.task.clone(), c.constraint.clone()),
        None if layout_failed(r) => ("-".into(), "layout".into()),
        None => ("-".into(), "no geometric task failed".into()),
    }
}

/// The report of `e`'s runs.
pub fn report(e: &Experiment) -> LayoutReport {
    let runs = e.runs.len();
    let solved = e.runs.iter().filter(|r| r.solved).count();
    let mut times: Vec<f64> = e.runs.iter().map(|r| r.time_s).collect();
    times.sort_by(f64::total_cmp);
    let mut groups: BTreeMap<(String, String), Vec<usize>> = BTreeMap::new();
    for r in e.runs.iter().filter(|r| !r.solved) {
        groups.entry(key(r)).or_default().push(r.index);
    }
    let mut failures: Vec<FailureGroup> = groups
        .into_iter()
        .map(|((task, constraint), indices)| FailureGroup {
            task,
            constraint,
            runs: indices.len(),
            indices,
        })
        .collect();
    failures.sort_by_key(|g| std::cmp::Reverse(g.runs));
    let laid: Vec<usize> = e
        .runs
        .iter()
        .filter_map(|r| r.layout.as_ref().map(|l| l.attempts))
        .collect();
    LayoutReport {
        runs,
        solved,
        solved_pct: 100.0 * solved as f64 / runs.max(1) as f64,
        median_time_s: quantile(&times, 0.5),
        p90_time_s: quantile(&times, 0.9),
        layout_errors: e.runs.iter().filter(|r| layout_failed(r)).count(),
        mean_layout_attempts: laid.iter().sum::<usize>() as f64 / laid.len().max(1) as f64,
        failures,
    }
}

/// Latencies of GTP solution requests, milliseconds.
#[derive(Clone, Debug, Serialize)]
pub struct Latency {
    pub requests: usize,
    pub median_ms: f64,
    pub p90_ms: f64,
    pub p99_ms: f64,
    pub max_ms: f64,
}

impl Latency {
    /// The figures of `times` (seconds, any order).
    pub fn of(mut times: Vec<f64>) -> Latency {
        times.sort_by(f64::total_cmp);
        let ms = |q: f64| quantile(&times, q) * 1e3;
        Latency {
            requests: times.len(),
            median_ms: ms(0.5),
            p90_ms: ms(0.9),
            p99_ms: ms(0.99),
            max_ms: times.last().copied().unwrap_or(0.0) * 1e3,
        }
    }
}

/// One GTP request among the slowest of an experiment.
#[derive(Clone, Debug, Serialize)]
pub struct SlowRequest {
    pub run: usize,
    pub seed: u64,
    pub task: String,
    pub args: Vec<String>,
    pub solved: bool,
    /// The constraint that stopped it, for a request that found nothing.
    pub stage: Option<String>,
    pub time_ms: f64,
    pub points: usize,
    pub grasps: usize,
    pub orientations: usize,
    pub planner_calls: usize,
    pub ik_calls: usize,
    pub base_poses: usize,
}

/// The latencies of every GTP request of `e`'s runs: over all, and per task.
pub fn latencies(e: &Experiment) -> (Latency, BTreeMap<String, Latency>) {
    let all = e.runs.iter().flat_map(|r| &r.requests);
    let mut by_task: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for q in all.clone() {
        by_task
            .entry(q.task.clone())
            .or_default()
            .push(q.search.time_s);
    }
    let total = Latency::of(all.map(|q| q.search.time_s).collect());
    let by_task = by_task
        .into_iter()
        .map(|(t, v)| (t, Latency::of(v)))
        .collect();
    (total, by_task)
}

/// The `n` slowest GTP requests of `e`'s runs, slowest first.
pub fn slowest(e: &Experiment, n: usize) -> Vec<SlowRequest> {
    let mut all: Vec<SlowRequest> = e
        .runs
        .iter()
        .flat_map(|r| {
            r.requests.iter().map(move |q| SlowRequest {
                run: r.index,
                seed: r.seed,
                task: q.task.clone(),
                args: q.args.clone(),
                solved: q.solved,
                stage: q.stage.clone(),
                time_ms: q.search.time_s * 1e3,
                points: q.search.points,
                grasps: q.search.grasps,
                orientations: q.search.orientations,
                planner_calls: q.search.planner_calls,
                ik_calls: q.search.ik_calls,
                base_poses: q.search.base_poses,
            })
        })
        .collect();
    all.sort_by(|a, b| b.time_ms.total_cmp(&a.time_ms));
    all.truncate(n);
    all
}

/// The machine-readable summary of one strategy's runs (`--json FILE`): success, run times,
/// GTP request latencies over all and per task, the five slowest requests, failures grouped
/// by task and constraint.
pub fn summary(e: &Experiment, r: &LayoutReport) -> serde_json::Value {
    let (total, by_task) = latencies(e);
    serde_json::json!({
        "strategy": e.strategy,
        "runs": r.runs,
        "solved": r.solved,
        "solved_pct": r.solved_pct,
        "run_time_s": { "median": r.median_time_s, "p90": r.p90_time_s },
        "wall_time_s": e.wall_time_s,
        "layout_errors": r.layout_errors,
        "mean_layout_attempts": r.mean_layout_attempts,
        "gtp_latency": total,
        "gtp_latency_by_task": by_task,
        "slowest_requests": slowest(e, 5),
        "failures": r.failures,
    })
}

/// Prints the report and every failed run with its task, constraint and layout.
pub fn print(e: &Experiment, r: &LayoutReport, what: &str) {
    println!(
        "\n### {what} ({}): {} of {} solved ({:.1} %); run time median {:.2} s, p90 {:.2} s\n",
        e.strategy, r.solved, r.runs, r.solved_pct, r.median_time_s, r.p90_time_s
    );
    println!(
        "Layouts: {:.2} attempts each on average, {} runs without a layout.",
        r.mean_layout_attempts, r.layout_errors
    );
    let (total, _) = latencies(e);
    println!(
        "GTP requests: {}, latency median {:.1} ms, p90 {:.1} ms, p99 {:.1} ms, max {:.1} ms.",
        total.requests, total.median_ms, total.p90_ms, total.p99_ms, total.max_ms
    );
    for q in slowest(e, 5) {
        println!(
            "  slow: run {} {}({}) {:.1} ms, {}{} ({} points, {} orientations, {} trajectory-planner calls, {} base poses)",
            q.run,
            q.task,
            q.args.join(", "),
            q.time_ms,
            if q.solved { "solved" } else { "none" },
            q.stage.map(|s| format!(" at {s}")).unwrap_or_default(),
            q.points,
            q.orientations,
            q.planner_calls,
            q.base_poses
        );
    }
    if r.failures.is_empty() {
        return;
    }
    println!("\n| GTP task | constraint | failed runs | runs |\n|---|---|---:|---|");
    for g in &r.failures {
        let idx: Vec<String> = g.indices.iter().map(usize::to_string).collect();
        println!(
            "| {} | {} | {} | {} |",
            g.task,
            g.constraint,
            g.runs,
            idx.join(" ")
        );
    }
    println!();
    for run in e.runs.iter().filter(|r| !r.solved) {
        let what = match &run.cause {
            Some(c) => format!("{}: {} ({})", c.call(), c.constraint, c.message),
            None => run.status.clone(),
        };
        let layout = run
            .layout
            .as_ref()
            .map(|l| format!(" [{}]", l.line()))
            .unwrap_or_default();
        println!("  run {} (seed {}): {what}{layout}", run.index, run.seed);
    }
}

/// Writes `library-STRATEGY-layouts.csv` (one row per run) and
/// `library-STRATEGY-failures.csv` (one row per task and constraint) into `dir`.
pub fn write_csv(e: &Experiment, r: &LayoutReport, dir: &Path) -> anyhow::Result<()> {
    let base = format!("library-{}", e.strategy);
    let mut runs = String::from(
        "index,seed,solved,time_s,htn_backtracks,gtp_backtracks,task,args,constraint,status,layout\n",
    );
    for run in &e.runs {
        let (task, args, constraint) = match &run.cause {
            Some(c) => (c.task.clone(), c.args.join(" "), c.constraint.clone()),
            None if run.solved => Default::default(),
            None => {
                let (t, c) = key(run);
                (t, String::new(), c)
            }
        };
        let layout = run.layout.as_ref().map(|l| l.line()).unwrap_or_default();
        runs.push_str(&format!(
            "{},{},{},{:.3},{},{},{},{},{},{},{}\n",
            run.index,
            run.seed,
            run.solved,
            run.time_s,
            run.htn_backtracks,
            run.gtp_backtracks,
            csv_field(&task),
            csv_field(&args),
            csv_field(&constraint),
            csv_field(&run.status),
            csv_field(&layout)
        ));
    }
    std::fs::write(dir.join(format!("{base}-layouts.csv")), runs)?;
    let mut groups = String::from("task,constraint,failed_runs,runs\n");
    for g in &r.failures {
        let idx: Vec<String> = g.indices.iter().map(usize::to_string).collect();
        groups.push_str(&format!(
            "{},{},{},{}\n",
            csv_field(&g.task),
            csv_field(&g.constraint),
            g.runs,
            idx.join(" ")
        ));
    }
    std::fs::write(dir.join(format!("{base}-failures.csv")), groups)?;
    Ok(())
}
