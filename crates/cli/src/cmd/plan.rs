//! `htngtp plan`: plan an HDDL problem with the HTN planner, validate the plan, print it.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use htn::planner::{Limits, Outcome, PlannerOptions, Strategy};

use crate::exit;

/// Arguments of `htngtp plan`.
#[derive(clap::Args)]
#[command(
    after_help = "Exit codes: 0 plan found; 1 proven unsolvable (the whole search space was \
                        explored with no cap: with a scene, --strategy chronological or \
                        geometric-first, over every solution the GTP enumerates); 2 stopped \
                        incomplete: a time, node or memory limit, or the cap on geometric \
                        alternatives of --strategy symbolic (one per task); \
                        which one is said on stderr and in the JSON; 3 bad input.\n\nThe plan is checked by the independent \
                        validator before it is printed; it is printed in the competition format \
                        (or as JSON with --json, with search statistics)."
)]
pub struct Args {
    /// The HDDL domain file.
    pub domain: PathBuf,
    /// The HDDL problem file.
    pub problem: PathBuf,
    /// Stop after this many seconds (above 0, at most a year). Checked inside the search's
    /// every node, inside each geometric task call, and after parsing and compiling.
    #[arg(long, value_name = "S", default_value_t = DEFAULT_TIME_LIMIT_S,
          value_parser = crate::input::seconds)]
    pub time_limit: f64,
    /// Stop after expanding this many search nodes.
    #[arg(long, value_name = "N")]
    pub node_limit: Option<u64>,
    /// Stop when the process's resident memory exceeds this many MiB (read every 2 ms in every
    /// phase: reading, compiling, searching, validating; the check keeps 1/32 of it as
    /// headroom).
    #[arg(long, value_name = "MB", default_value_t = DEFAULT_MEMORY_LIMIT_MB,
          value_parser = clap::value_parser!(u64).range(1..))]
    pub memory_limit: u64,
    /// Seed of the search (it is deterministic for a given seed).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print the result as JSON: status, plan, plan text, statistics, limit.
    #[arg(long)]
    pub json: bool,
    /// Backtracking over geometric solutions: symbolic, chronological, plain-chronological or
    /// geometric-first.
    #[arg(long, value_enum, default_value_t = StrategyArg::Chronological)]
    pub strategy: StrategyArg,
    /// With --strategy geometric-first: how many other geometric solutions to try per failure,
    /// shared among the earlier geometric tasks, the latest first.
    #[arg(long, alias = "geo-alternatives", default_value_t = 3)]
    pub geo_k: usize,
    /// A 3D scene (docs/scene-format.md): geometric tasks are answered by the GTP in it, and the
    /// shared predicates' initial facts are computed from it.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// With --scene: a threshold of every geometric task call, KEY=VALUE as `htngtp gtp --set`
    /// takes it (repeatable); e.g. `robot-effort=1` keeps the robot's base where the domain
    /// puts it (no base moves inside pick, place or hand-over).
    #[arg(long, value_name = "KEY=VALUE", requires = "scene", value_parser = crate::input::gtp_setting)]
    pub gtp_set: Vec<(String, String)>,
    /// With --scene: read the scene even when objects start inside one another (a warning
    /// then, not an error); a robot inside furniture is still refused.
    #[arg(long)]
    pub allow_initial_contact: bool,
    /// With --scene: write pictures of the world after each GS action into this folder.
    #[arg(long, value_name = "DIR", requires = "scene")]
    pub png: Option<PathBuf>,
    /// With --scene: write the plan JSON (docs/plan-json.md) to this file as well.
    #[arg(long, value_name = "FILE", requires = "scene")]
    pub json_out: Option<PathBuf>,
    /// Acceleration limit of the plan JSON's timed joint trajectories for every arm joint whose
    /// URDF declares none (rad/s^2, or m/s^2 for sliding joints; the shipped models declare
    /// none). The planar base keeps its own limits (docs/plan-json.md).
    #[arg(long, value_name = "A", default_value_t = hybrid::timing::DEFAULT_JOINT_ACCELERATION,
          value_parser = crate::input::acceleration)]
    pub max_acceleration: f64,
    /// Turn off duplicate detection (for experiments; the search may not terminate).
    #[arg(long, hide = true)]
    pub no_duplicate_detection: bool,
    /// Turn off the left-recursion check (for experiments).
    #[arg(long, hide = true)]
    pub no_loop_check: bool,
    /// Turn off the pruning by guarded goal achievers (for experiments).
    #[arg(long, hide = true)]
    pub no_goal_guards: bool,
    /// With --time-limit, on problems without geometric tasks: the share of the time during
    /// which a best-first search runs beside the depth-first one, on a second thread, once the
    /// depth-first search has used the rest without deciding; before it, from 1 s on, that
    /// thread runs short depth-first searches in random orders (restarts). The first to find a
    /// plan or prove there is none ends all (0 turns the second thread off, 1 starts the
    /// best-first search at once).
    #[arg(long, value_name = "SHARE", default_value_t = 0.8, value_parser = share)]
    pub best_first_share: f64,
    /// With --strategy geometric-first and --time-limit, on problems with geometric tasks: the
    /// share of the time left to the chronological pass that follows geometric-first's repairs
    /// (they hand over when they have used the rest, or earlier when spent; 0: the pass only
    /// after them)
    #[arg(long, value_name = "SHARE", default_value_t = 0.5, value_parser = share)]
    pub chronological_share: f64,
    /// End as soon as stdin closes: `bench-hddl` gives its children a pipe that closes when it
    /// ends, however it ends (a signal, even SIGKILL), so no child outlives it.
    #[arg(long, hide = true)]
    pub exit_with_stdin: bool,
}

/// With `--exit-with-stdin`: a thread that ends the process when stdin reaches its end.
fn exit_when_stdin_closes() {
    std::thread::spawn(|| {
        use std::io::Read;
        let mut buf = [0u8; 64];
        let mut stdin = std::io::stdin();
        while matches!(stdin.read(&mut buf), Ok(n) if n > 0) {}
        eprintln!("stopped: the parent process ended");
        std::process::exit(exit::LIMIT.into());
    });
}

/// The default `--time-limit`: nothing runs unbounded.
pub const DEFAULT_TIME_LIMIT_S: f64 = 300.0;
/// The default `--memory-limit`, MiB (8 GiB).
pub const DEFAULT_MEMORY_LIMIT_MB: u64 = 8192;

fn share(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("expected a share between 0 and 1, found `{s}`")),
    }
}

/// The `--strategy` values.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum StrategyArg {
    /// Each geometric task gives at most one solution; only HTN choices are revisited.
    Symbolic,
    /// Every choice point, latest first, in rounds that allow more and more revisions of
    /// geometric solutions later ones built on (0, 1, 2, ...: limited discrepancy); as
    /// complete as plain-chronological.
    Chronological,
    /// Every choice point, latest first, in one search: every solution of the latest
    /// geometric task before an earlier one is revisited (the paper's interleaved
    /// backtracking; for comparison).
    PlainChronological,
    /// On a geometric failure, try other solutions of earlier geometric tasks first.
    GeometricFirst,
}

impl StrategyArg {
    /// The planner's strategy, with `k` other solutions per geometric-first repair, and
    /// whether its chronological search goes in rounds of limited discrepancy.
    pub fn options(self, k: usize) -> (Strategy, bool) {
        match self {
            StrategyArg::Symbolic => (Strategy::Symbolic, true),
            StrategyArg::Chronological => (Strategy::Chronological, true),
            StrategyArg::PlainChronological => (Strategy::Chronological, false),
            StrategyArg::GeometricFirst => (Strategy::GeometricFirst { k }, true),
        }
    }
}

/// What `plan --json` prints: the search result with the plan text and how it ended.
#[derive(serde::Serialize)]
struct JsonReport<'a> {
    #[serde(flatten)]
    result: &'a htn::planner::SearchResult,
    plan_text: Option<&'a str>,
    peak_memory_kb: u64,
    validated: bool,
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    if args.exit_with_stdin {
        exit_when_stdin_closes();
    }
    let scene = args.scene.as_deref();
    crate::input::check_files([&*args.domain, &*args.problem].into_iter().chain(scene))?;
    let began = std::time::Instant::now();
    crate::input::set_budget(began, args.time_limit, args.memory_limit);
    let domain = crate::input::load_domain(&args.domain)?;
    let problem = htn::load_problem(&args.problem, &domain)?;
    let (strategy, discrepancy_rounds) = args.strategy.options(args.geo_k);
    let options = PlannerOptions {
        limits: Limits {
            // The time limit covers parsing: the planner gets what is left.
            time: Some(crate::input::duration(args.time_limit).saturating_sub(began.elapsed())),
            nodes: args.node_limit,
            memory_mb: Some(args.memory_limit),
        },
        seed: args.seed,
        strategy,
        discrepancy_rounds,
        duplicate_detection: !args.no_duplicate_detection,
        loop_check: !args.no_loop_check,
        goal_guards: !args.no_goal_guards,
        best_first_share: args.best_first_share,
        chronological_share: args.chronological_share,
        ..PlannerOptions::default()
    };
    if let Some(scene) = &args.scene {
        let oracle = hybrid::OracleConfig {
            seed: args.seed,
            constraints: args.gtp_set.clone(),
            ..hybrid::OracleConfig::default()
        };
        let out = crate::cmd::geo::Outputs {
            json: args.json,
            json_file: args.json_out.clone(),
            png_dir: args.png.clone(),
            timing: hybrid::export::TimingOptions {
                joint_acceleration: args.max_acceleration,
            },
        };
        let scene = crate::cmd::geo::SceneInput {
            path: scene,
            allow_initial_contact: args.allow_initial_contact,
        };
        return crate::cmd::geo::run_plan(&domain, &problem, began, scene, options, oracle, &out);
    }
    let mut result = htn::planner::plan(&domain, &problem, &options, None)?;
    let mut plan_text = None;
    if let Outcome::Found { plan } = &result.outcome {
        let checked = htn::validate::validate(&domain, &problem, plan, &[]);
        if let (Err(e), Some(limit)) = (&checked, htn::budget::tripped()) {
            // The limits cover the validation too: a plan not validated is not printed.
            eprintln!("{}", e.0);
            result.outcome = Outcome::LimitReached { limit };
        } else {
            checked.context(
                "BUG: the planner returned a plan that the validator rejects; please report it",
            )?;
            plan_text = Some(plan.to_competition_format());
        }
    }
    let peak_kb = htn::planner::peak_rss_kb().max(result.stats.peak_memory_kb);
    let code = match &result.outcome {
        Outcome::Found { .. } => exit::OK,
        Outcome::Unsolvable => exit::UNSOLVABLE,
        Outcome::LimitReached { .. } => exit::LIMIT,
    };
    if args.json {
        // Written as it is serialized: a plan of 262,143 actions is 105 MB of JSON.
        let report = JsonReport {
            result: &result,
            plan_text: plan_text.as_deref(),
            peak_memory_kb: peak_kb,
            validated: plan_text.is_some(),
        };
        let mut out = std::io::BufWriter::new(std::io::stdout().lock());
        serde_json::to_writer(&mut out, &report)?;
        writeln!(out)?;
        out.flush()?;
    } else {
        if let Some(t) = &plan_text {
            print!("{t}");
        }
        let s = &result.stats;
        let what = match &result.outcome {
            Outcome::Found { plan } => format!(
                "plan found and validated: {} actions, {} decompositions",
                plan.actions.len(),
                plan.decompositions.len()
            ),
            Outcome::Unsolvable => "no plan exists (the whole search space was explored)".into(),
            Outcome::LimitReached { limit } => format!("stopped: {limit} reached"),
        };
        eprintln!(
            "{what}\n{} nodes, {} HTN backtracks, {} geometric backtracks, {:.3} s, peak memory {:.1} MiB",
            s.nodes,
            s.htn_backtracks,
            s.geo_backtracks,
            s.time_s,
            peak_kb as f64 / 1024.0
        );
    }
    Ok(code)
}
