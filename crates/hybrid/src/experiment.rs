//! The paper's experiment (Section V, Table II): MANAGEORDER planned many times, with per-GTP-task
//! statistics, HTN backtracks per run and complete failures; over randomized initial scenes
//! (the paper kept its scene fixed and left randomization as future work).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use geometry::world::{World, base_pose};
use gtp::planner::Planner;
use htn::model::{Domain, Problem};
use htn::planner::{Outcome, PlannerOptions};
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::query::intersection_test;
use rayon::prelude::*;
use serde::Serialize;

use crate::oracle::RequestTime;
use crate::oracle::TaskStats;
use crate::random_layout::{Layout, LayoutSummary};
use crate::run::{RunOptions, plan};

/// How much the initial scene is perturbed per run.
#[derive(Clone, Copy, Debug)]
pub struct Randomization {
    /// Largest shift of a movable object on its support (metres, in x and y).
    pub object_shift: f32,
    /// Largest turn of a movable object about the vertical (radians).
    pub object_turn: f32,
    /// Largest shift of each human's base (metres) and turn (radians).
    pub human_shift: f32,
    pub human_turn: f32,
}

impl Default for Randomization {
    fn default() -> Self {
        Randomization {
            object_shift: 0.03,
            object_turn: 0.17,
            human_shift: 0.05,
            human_turn: 0.1,
        }
    }
}

/// A randomized copy of `world`: every movable object shifted and turned about the vertical
/// where it rests (a draw that makes it touch anything but its support is drawn again, at most
/// 20 times, else the object stays), every human's base shifted and turned.
pub fn randomize(world: &World, r: &Randomization, seed: u64) -> World {
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut w = world.clone();
    let mut sym = |a: f32| (rng.f32() * 2.0 - 1.0) * a;
    for id in world.object_ids() {
        let o = world.object(id);
        if !o.movable || world.attachment(id).is_some() {
            continue;
        }
        let start = world.object_pose(id);
        for _ in 0..20 {
            let shift = Vector::new(sym(r.object_shift), sym(r.object_shift), 0.0);
            let turn = Rotation::from_rotation_z(sym(r.object_turn));
            let pose = Pose::from_parts(start.translation + shift, turn * start.rotation);
            w.set_object_pose(id, pose);
            let shape_pose = w.object_shape_pose(id);
            let touching = w.obstacles().any(|(other, shape, p)| {
                other != id
                    && !geometry::facts::on(&w, id, other, 0.02)
                    && intersection_test(&shape_pose, o.shape.as_ref(), &p, shape.as_ref())
                        .map_or(true, |i| i.intersecting)
            });
            if !touching {
                break;
            }
            w.set_object_pose(id, start);
        }
    }
    for id in world.agent_ids() {
        if world.agent(id).kind() != geometry::scene::AgentKind::Human {
            continue;
        }
        let s = world.agent_state(id);
        let yaw = 2.0 * s.base.rotation.z.atan2(s.base.rotation.w);
        let base = base_pose(
            s.base.translation.x + sym(r.human_shift),
            s.base.translation.y + sym(r.human_shift),
            yaw + sym(r.human_turn),
        );
        let q = s.q.clone();
        w.set_agent_config(id, base, &q);
    }
    w
}

/// One run of the experiment.
#[derive(Clone, Debug, Serialize)]
pub struct RunRecord {
    pub index: usize,
    pub seed: u64,
    pub solved: bool,
    /// `solved`, `unsolvable` or `limit`, with the reason when not solved.
    pub status: String,
    pub htn_backtracks: u64,
    pub gtp_backtracks: u64,
    pub actions: usize,
    pub time_s: f64,
    /// Per GTP task.
    pub tasks: BTreeMap<String, TaskStats>,
    /// Why the run's plan JSON could not be written (with `plans`).
    pub plan_file_error: Option<String>,
    /// For a run that found no plan: the last geometric task that failed and the constraint
    /// that stopped it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cause: Option<FailureCause>,
    /// The random layout the run planned in (`--layout random`, `--layout room`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layout: Option<LayoutSummary>,
    /// Every GTP solution request of the run, timed.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub requests: Vec<RequestTime>,
}

/// What makes a run's scene from its seed: a random layout of a scene
/// ([`crate::random_layout::RandomLayouts`]) or a random room
/// ([`crate::room_layout::RandomRooms`]).
pub trait LayoutSource: Send + Sync + std::fmt::Debug {
    /// The scene of `seed`, or why there is none.
    fn generate(&self, seed: u64) -> Result<Layout, String>;
}

/// Why a run found no plan: the last GTP task that found no (further) solution, its
/// arguments, and the stage of the GTP's constraint hierarchy that stopped it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FailureCause {
    /// The geometric task as the domain names it (`pick-and-make-accessible`).
    pub task: String,
    pub args: Vec<String>,
    /// The stage ([`gtp::planner::Stage`]'s name: `pick`, `visibility`, ...), `?` when the
    /// GTP named none.
    pub constraint: String,
    /// The GTP's reason in words.
    pub message: String,
}

impl FailureCause {
    /// `task(arg, ...)`.
    pub fn call(&self) -> String {
        format!("{}({})", self.task, self.args.join(", "))
    }
}

impl RunRecord {
    /// A run that did not plan (its input could not be made): `status` says why.
    pub fn failed(index: usize, seed: u64, status: String) -> RunRecord {
        RunRecord {
            plan_file_error: None,
            cause: None,
            layout: None,
            requests: Vec::new(),
            index,
            seed,
            solved: false,
            status,
            htn_backtracks: 0,
            gtp_backtracks: 0,
            actions: 0,
            time_s: 0.0,
            tasks: BTreeMap::new(),
        }
    }
}

/// The whole experiment: its runs and their totals (the paper's Table II and run figures).
#[derive(Clone, Debug, Serialize)]
pub struct Experiment {
    pub strategy: String,
    pub runs: Vec<RunRecord>,
    pub wall_time_s: f64,
}

/// One row of Table II: a task's [`TaskStats`] as means per request (the paper's columns).
#[derive(Clone, Debug, Serialize)]
pub struct TableRow {
    pub task: String,
    /// Mean search time per solution request, seconds.
    pub mean_time_s: f64,
    pub success_pct: f64,
    /// Means per request.
    pub points: f64,
    pub grasps: f64,
    pub orientations: f64,
    pub planner_calls: f64,
    pub attempts: u64,
}

impl TableRow {
    /// The row of `task` from its totals.
    fn of(task: String, s: &TaskStats) -> TableRow {
        let n = s.attempts.max(1) as f64;
        let mean = |v: usize| v as f64 / n;
        TableRow {
            task,
            mean_time_s: s.total_time_s() / n,
            success_pct: 100.0 * s.successes as f64 / n,
            points: mean(s.search.points),
            grasps: mean(s.search.grasps),
            orientations: mean(s.search.orientations),
            planner_calls: mean(s.search.planner_calls),
            attempts: s.attempts,
        }
    }
}

impl Experiment {
    /// Table II: per GTP task, over every solution request of every run.
    pub fn table(&self) -> Vec<TableRow> {
        let mut sum: BTreeMap<String, TaskStats> = BTreeMap::new();
        for r in &self.runs {
            for (k, s) in &r.tasks {
                sum.entry(k.clone()).or_default().add(s);
            }
        }
        sum.into_iter()
            .map(|(task, s)| TableRow::of(task, &s))
            .collect()
    }

    /// Share of runs that found a plan, percent.
    pub fn success_pct(&self) -> f64 {
        100.0 * self.runs.iter().filter(|r| r.solved).count() as f64 / self.runs.len().max(1) as f64
    }

    /// Mean HTN backtracks per run.
    pub fn mean_htn_backtracks(&self) -> f64 {
        self.runs
            .iter()
            .map(|r| r.htn_backtracks as f64)
            .sum::<f64>()
            / self.runs.len().max(1) as f64
    }

    /// Share of runs with more than 3 HTN backtracks, percent.
    pub fn share_over_3_backtracks(&self) -> f64 {
        100.0 * self.runs.iter().filter(|r| r.htn_backtracks > 3).count() as f64
            / self.runs.len().max(1) as f64
    }
}

/// Settings of the experiment.
#[derive(Clone, Debug)]
pub struct ExperimentOptions {
    pub runs: usize,
    /// Only the run with this index (the others are skipped; seeds are unchanged).
    pub only: Option<usize>,
    pub seed: u64,
    /// Keep the scene as it is (the paper's setting) instead of randomizing it per run.
    pub fixed: bool,
    pub randomization: Randomization,
    pub run: RunOptions,
    /// Write each solved run's plan JSON here (`{strategy}-{index:03}.json`), for checking.
    pub plans: Option<std::path::PathBuf>,
    /// Plan each run in a random layout of the scene instead of a nudged copy (`--layout
    /// random`; the scene `world` is then unused).
    pub layouts: Option<Arc<dyn LayoutSource>>,
    /// Write each run's random layout here (`layout-{index:03}.toml`), to plan it again.
    pub save_scenes: Option<std::path::PathBuf>,
}

/// Runs the experiment on all cores (one run per task of rayon's pool), calling `progress`
/// after each run.
pub fn run_experiment(
    domain: &Domain,
    problem: &Problem,
    world: &World,
    options: &ExperimentOptions,
    strategy_name: &str,
    progress: &(dyn Fn() + Sync),
) -> Experiment {
    let planner = Arc::new(Planner::new());
    let start = Instant::now();
    let indices: Vec<usize> = match options.only {
        Some(i) => vec![i],
        None => (0..options.runs).collect(),
    };
    let runs: Vec<RunRecord> = indices
        .into_par_iter()
        .map(|i| {
            let seed = options.seed.wrapping_mul(1_000_003).wrapping_add(i as u64);
            let (scene, layout) = match &options.layouts {
                Some(layouts) => match laid_out(layouts.as_ref(), options, i, seed) {
                    Ok((w, summary)) => (w, Some(summary)),
                    Err(e) => {
                        progress();
                        return RunRecord::failed(i, seed, format!("error: the layout: {e}"));
                    }
                },
                None if options.fixed => (world.clone(), None),
                None => (randomize(world, &options.randomization, seed), None),
            };
            let plans = options.plans.as_deref().map(|d| (d, strategy_name));
            let mut record = run_one(
                domain,
                problem,
                scene,
                &planner,
                &options.run,
                i,
                seed,
                plans,
            );
            record.layout = layout;
            progress();
            record
        })
        .collect();
    Experiment {
        strategy: strategy_name.to_string(),
        runs,
        wall_time_s: start.elapsed().as_secs_f64(),
    }
}

/// The random layout of run `index` (seed `seed`), written to `options.save_scenes` when set.
fn laid_out(
    layouts: &dyn LayoutSource,
    options: &ExperimentOptions,
    index: usize,
    seed: u64,
) -> Result<(World, LayoutSummary), String> {
    let layout = layouts.generate(seed)?;
    if let Some(dir) = &options.save_scenes {
        let path = dir.join(format!("layout-{index:03}.toml"));
        let text = format!(
            "# bench library --layout random or room: run {index}, seed {seed}.\n# {}\n{}",
            layout.summary.line(),
            layout.toml
        );
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok((layout.world, layout.summary))
}

/// One run: plans `problem` in `scene` with every seed set to `seed`, and records it as run
/// `index`; with `plans` (a folder and the strategy's name), writes a solved run's plan JSON
/// there. Shared by the Table II experiment and the scale benchmark ([`crate::scale`]).
#[allow(clippy::too_many_arguments)]
pub fn run_one(
    domain: &Domain,
    problem: &Problem,
    scene: World,
    planner: &Arc<Planner>,
    options: &RunOptions,
    index: usize,
    seed: u64,
    plans: Option<(&std::path::Path, &str)>,
) -> RunRecord {
    let mut run_options = options.clone();
    run_options.oracle.seed = seed;
    run_options.planner = PlannerOptions {
        seed,
        ..run_options.planner
    };
    let t0 = Instant::now();
    match plan(domain, problem, scene, planner.clone(), &run_options) {
        Ok(run) => {
            let (solved, status, actions) = match &run.result.outcome {
                Outcome::Found { plan } => (true, "solved".to_string(), plan.actions.len()),
                Outcome::Unsolvable => (false, format!("unsolvable: {}", run.failure_message()), 0),
                Outcome::LimitReached { limit } => (
                    false,
                    format!("limit: {limit} ({})", run.failure_message()),
                    0,
                ),
            };
            let plan_file_error = match (plans, solved) {
                (Some((dir, strategy)), true) => {
                    write_plan(&run, domain, problem, dir, strategy, index).err()
                }
                _ => None,
            };
            let cause = (!solved)
                .then(|| run.oracle.last_failure())
                .flatten()
                .map(|f| FailureCause {
                    task: f.task.clone(),
                    args: f.args.clone(),
                    constraint: f.stage.map_or_else(|| "?".into(), |s| s.name().to_string()),
                    message: f.why.clone(),
                });
            RunRecord {
                plan_file_error,
                cause,
                layout: None,
                requests: run.oracle.requests().to_vec(),
                index,
                seed,
                solved,
                status,
                htn_backtracks: run.result.stats.htn_backtracks,
                gtp_backtracks: run.result.stats.geo_backtracks,
                actions,
                time_s: t0.elapsed().as_secs_f64(),
                tasks: run.oracle.task_stats().clone().into_iter().collect(),
            }
        }
        Err(e) => RunRecord {
            time_s: t0.elapsed().as_secs_f64(),
            ..RunRecord::failed(index, seed, format!("error: {e}"))
        },
    }
}

/// Writes a run's plan JSON as `dir/{strategy}-{index:03}.json`.
fn write_plan(
    run: &crate::run::Run,
    domain: &Domain,
    problem: &Problem,
    dir: &std::path::Path,
    strategy: &str,
    index: usize,
) -> Result<(), String> {
    let path = dir.join(format!("{strategy}-{index:03}.json"));
    let json = crate::export::plan_json(run, &domain.name, &problem.name);
    let text = serde_json::to_string(&json).map_err(|e| e.to_string())?;
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
}
