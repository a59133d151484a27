//! `htngtp bench`: the paper's experiment (`library`) and how cost grows (`scale`).

mod domain;
mod layout;
mod plot;
mod scale;

use std::path::PathBuf;

use anyhow::Context;
use geometry::world::World;
use htn::planner::{PlannerOptions, Strategy};
use hybrid::experiment::{Experiment, ExperimentOptions, Randomization, run_experiment};
use hybrid::{OracleConfig, RunOptions};

use crate::cmd::demo::library_dir;
use crate::exit;

/// Arguments of `htngtp bench`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub target: Target,
}

/// What to benchmark.
#[derive(clap::Subcommand)]
pub enum Target {
    /// The paper's experiment (Table II): MANAGEORDER with payment by card, many runs.
    Library(LibraryArgs),
    /// A domain's randomized benchmark: every problem of a folder, scenes nudged per run.
    Domain(domain::DomainArgs),
    /// How cost grows: MANAGEORDER with N books lent over a desk holding M other objects.
    Scale(scale::ScaleArgs),
}

/// Arguments of `htngtp bench library`.
#[derive(clap::Args)]
#[command(
    long_about = "The paper's experiment (Section V, Table II): plans MANAGEORDER for a member \
                  who must pay by card (method m7) in the variant of the library domain that \
                  groups PICK with the GTP task after it, `--runs` times, each over a randomized \
                  initial scene (books, POS machine and member moved and turned; `--fixed` keeps \
                  the paper's fixed scene). Prints Table II per GTP task (mean time, success %, \
                  points, grasps, orientations, trajectory-planner calls, means per request), \
                  HTN backtracks per run, complete failures and the total time; writes CSV and \
                  JSON. Runs in parallel on all cores.\n\n`--layout random` plans each run in a \
                  random layout of the scene instead, generated from the \
                  run's seed. Sensible means: every movable object (the books, the POS machine) \
                  on a free spot of any support surface of the room (desk, platform, POS stand, \
                  table, every shelf level), on any face (a book on its long edge, on its short \
                  edge or lying flat) and turned any way, 2 cm clear of the others, touching \
                  nothing but its support; the robot can pick it up, as the GTP's pick finds: \
                  the books from its station (the domain picks them there), the POS machine \
                  from its station or after driving to it (method m9 drives); the member seated \
                  on the chair moved with them along the desk (up to 0.45 m, 15 degrees) or \
                  standing on free floor facing the desk, 5 cm clear of furniture and robot, \
                  with a patch of the desk's top within both their reach (effort 1) and the \
                  robot's from its station; the robot at its station. It reports the share \
                  solved, the median and p90 run time, and each failure with the GTP task, its \
                  arguments and the constraint that stopped it, grouped by task and constraint \
                  (also in library-STRATEGY-layouts.csv and -failures.csv); `--save-scenes DIR` \
                  writes each layout as a scene file for `htngtp plan ... --scene`. With `--layout \
                  random` or `room` the default strategy is geometric-first (symbolic \
                  otherwise).\n\n`--layout room` plans each run in a whole random room, made \
                  from the run's seed with the scene's robot, member, chair, books and POS \
                  machine; every other piece of furniture is replaced. Sensible means: \
                  furniture drawn from kinds (desk, counter, reading table, side table, \
                  bookshelf with boards, cart, chair) with their sizes, top heights 0.6 to 1.1 \
                  m, positions and yaw, inside the room (3.6 x 3.6 m) and 5 cm apart (the \
                  member's chair aside); the counter the member is served at (`desk`: a desk, \
                  a counter or a reading table); the robot's station on free floor (2 cm from \
                  everything), facing the counter (within 20 degrees) and reaching at least 25 \
                  points of its top; a support beside the robot (side table, bookshelf, cart, \
                  desk or reading table) and up to 3 more pieces anywhere; the member seated on \
                  the chair (at a desk or table at most 0.8 m high) or standing, on a side of \
                  the counter the robot does not stand at, facing it, clear of furniture and \
                  robot, sharing a patch of its top with the robot; every book, the POS machine \
                  and every clutter object resting on a support surface touching nothing else, \
                  books standing side by side on the bookshelves' boards, up to 6 things (books \
                  lying, cups, boxes) on tops (clutter is fixed); the robot picks the books \
                  from its station and the POS machine from there or after driving, as the \
                  GTP's pick finds. A seed whose 60 attempts break a rule is refused with the \
                  count of each reason (the run fails with it).\n\n`--json FILE` writes a \
                  summary per strategy: runs solved, run times, GTP request latencies (median, \
                  p90, p99, max; over all and per task), the five slowest requests, failures \
                  grouped by task and constraint."
)]
pub struct LibraryArgs {
    /// Number of runs.
    #[arg(long, default_value_t = 100)]
    pub runs: usize,
    /// Seed of the scene randomization and of every search.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Keep the initial scene fixed (the paper's setting).
    #[arg(long, conflicts_with = "layout")]
    pub fixed: bool,
    /// How the scene varies per run: `nudge` (objects and the member moved by a few
    /// centimetres), `random` (objects anywhere sensible, the member seated or standing) or
    /// `room` (a whole random room; see the long help).
    #[arg(long, value_enum, default_value_t = layout::LayoutArg::Nudge)]
    pub layout: layout::LayoutArg,
    /// With `--layout random` or `room`: write each run's layout as a scene file into this
    /// folder (`layout-INDEX.toml`), to plan it again with `htngtp plan ... --scene`.
    #[arg(long, value_name = "DIR")]
    pub save_scenes: Option<PathBuf>,
    /// Backtracking strategy, or several separated by commas, each run over the same seeds
    /// [default: symbolic, the paper's, with `--layout nudge`; geometric-first, as `bench
    /// domain`, with `--layout random` or `room`, where the first geometric solution is more
    /// often a dead end].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub strategy: Vec<crate::cmd::plan::StrategyArg>,
    /// With `--layout random` or `room`: write a summary per strategy as JSON (success, GTP
    /// request latencies, the slowest requests, failures by task and constraint).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// With geometric-first: other geometric solutions tried per failure.
    #[arg(long, default_value_t = 3)]
    pub geo_alternatives: usize,
    /// Run all three strategies on the same scenes and print them side by side.
    #[arg(long)]
    pub compare: bool,
    /// Domain (default: the bundled domains/library/domain-compound.hddl).
    #[arg(long)]
    pub domain: Option<PathBuf>,
    /// Problem (default: the bundled domains/library/pay-by-card.hddl).
    #[arg(long)]
    pub problem: Option<PathBuf>,
    /// Scene (default: the bundled domains/library/scene.toml).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Time limit of each run, seconds.
    #[arg(long, default_value_t = 60.0, value_parser = crate::input::seconds)]
    pub time_limit: f64,
    /// Folder for the CSV and JSON results.
    #[arg(long, default_value = "htngtp-bench")]
    pub out: PathBuf,
    /// Run only the run with this index (0-based; same scene and seeds as in the full
    /// experiment), e.g. to retrace a failure with `HTNGTP_TRACE=1`.
    #[arg(long, value_name = "INDEX")]
    pub only: Option<usize>,
    /// Write each solved run's plan JSON into this folder (`STRATEGY-INDEX.json`), for
    /// `htngtp check` or the viewer.
    #[arg(long, value_name = "DIR")]
    pub plans: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    match args.target {
        Target::Library(a) => library(a),
        Target::Domain(a) => domain::run(a),
        Target::Scale(a) => scale::scale(a),
    }
}

/// The planner's options for `--strategy`: the strategy, whether its chronological search
/// goes in rounds of limited discrepancy, and the name results are filed under.
fn strategy(arg: crate::cmd::plan::StrategyArg, k: usize) -> (Chosen, &'static str) {
    use crate::cmd::plan::StrategyArg as S;
    let (strategy, rounds) = arg.options(k);
    let name = match arg {
        S::Symbolic => "symbolic",
        S::Chronological => "chronological",
        S::PlainChronological => "plain-chronological",
        S::GeometricFirst => "geometric-first",
    };
    (Chosen { strategy, rounds }, name)
}

/// A strategy as `--strategy` chose it.
#[derive(Clone, Copy)]
struct Chosen {
    strategy: Strategy,
    rounds: bool,
}

/// Refuses `--runs 0` and an `--only` index past the last run.
fn check_runs(runs: usize, only: Option<usize>) -> anyhow::Result<()> {
    if runs == 0 {
        anyhow::bail!("--runs must be at least 1");
    }
    if let Some(i) = only.filter(|&i| i >= runs) {
        anyhow::bail!("--only {i}: there are only {runs} runs (0..{})", runs - 1);
    }
    Ok(())
}

/// The options of one benchmark run: `strategy`, the time limit in seconds, default oracle.
fn run_options(chosen: Chosen, time_limit: f64) -> RunOptions {
    RunOptions {
        planner: PlannerOptions {
            strategy: chosen.strategy,
            discrepancy_rounds: chosen.rounds,
            limits: htn::planner::Limits {
                time: Some(crate::input::duration(time_limit)),
                ..Default::default()
            },
            ..PlannerOptions::default()
        },
        oracle: OracleConfig::default(),
    }
}

fn library(args: LibraryArgs) -> anyhow::Result<u8> {
    check_runs(args.runs, args.only)?;
    let dir = library_dir()?;
    let domain_path = args
        .domain
        .clone()
        .unwrap_or_else(|| dir.join("domain-compound.hddl"));
    let problem_path = args
        .problem
        .clone()
        .unwrap_or_else(|| dir.join("pay-by-card.hddl"));
    let scene_path = args.scene.clone().unwrap_or_else(|| dir.join("scene.toml"));
    let domain = crate::input::load_domain(&domain_path)?;
    let problem = htn::load_problem(&problem_path, &domain)?;
    let world = World::load(&scene_path).map_err(|e| anyhow::anyhow!("{e}"))?;
    let random = args.layout != layout::LayoutArg::Nudge;
    if args.save_scenes.is_some() && !random {
        anyhow::bail!("--save-scenes needs --layout random or room");
    }
    if args.json.is_some() && !random {
        anyhow::bail!("--json needs --layout random or room");
    }
    let layouts: Option<std::sync::Arc<dyn hybrid::experiment::LayoutSource>> = match args.layout {
        layout::LayoutArg::Nudge => None,
        layout::LayoutArg::Random => {
            let rules = hybrid::random_layout::LayoutRules::default();
            let l = hybrid::random_layout::RandomLayouts::new(&scene_path, rules)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            Some(std::sync::Arc::new(l))
        }
        layout::LayoutArg::Room => {
            let rules = hybrid::room_layout::RoomRules::default();
            let l = hybrid::room_layout::RandomRooms::new(&scene_path, rules)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            Some(std::sync::Arc::new(l))
        }
    };
    if let Some(dir) = &args.save_scenes {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let strategies: Vec<_> = if args.compare {
        use crate::cmd::plan::StrategyArg as S;
        [S::Symbolic, S::Chronological, S::GeometricFirst]
            .into_iter()
            .map(|s| strategy(s, args.geo_alternatives))
            .collect()
    } else {
        use crate::cmd::plan::StrategyArg as S;
        let default = if random {
            S::GeometricFirst
        } else {
            S::Symbolic
        };
        let mut chosen = args.strategy.clone();
        if chosen.is_empty() {
            chosen.push(default);
        }

        chosen
            .into_iter()
            .map(|s| strategy(s, args.geo_alternatives))
            .collect()
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    if let Some(dir) = &args.plans {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let mut results = Vec::new();
    for (s, name) in strategies {
        let bar = indicatif::ProgressBar::new(if args.only.is_some() {
            1
        } else {
            args.runs as u64
        });
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg:>16} [{bar:40}] {pos}/{len} runs {elapsed}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar.set_message(name);
        let options = ExperimentOptions {
            runs: args.runs,
            only: args.only,
            seed: args.seed,
            fixed: args.fixed,
            randomization: Randomization::default(),
            plans: args.plans.clone(),
            layouts: layouts.clone(),
            save_scenes: args.save_scenes.clone(),
            run: run_options(s, args.time_limit),
        };
        let e = run_experiment(&domain, &problem, &world, &options, name, &|| bar.inc(1));
        bar.finish_and_clear();
        results.push(e);
    }
    for e in &results {
        if let Some(r) = e.runs.iter().find(|r| r.plan_file_error.is_some()) {
            anyhow::bail!(
                "run {}: the plan JSON was not written: {}",
                r.index,
                r.plan_file_error.as_deref().unwrap_or_default()
            );
        }
        let scene = match (args.layout, args.fixed) {
            (layout::LayoutArg::Random, _) => "random-layout",
            (layout::LayoutArg::Room, _) => "random-room",
            (_, true) => "fixed",
            (_, false) => "randomized",
        };
        print_experiment(e, scene);
        write_files(e, &args.out, random)?;
    }
    if results.len() > 1 {
        print_comparison(&results);
    }
    if let Some(path) = &args.json {
        let strategies: Vec<serde_json::Value> = results
            .iter()
            .map(|e| layout::summary(e, &layout::report(e)))
            .collect();
        let json = serde_json::json!({
            "layout": format!("{:?}", args.layout).to_lowercase(),
            "runs": args.runs,
            "seed": args.seed,
            "time_limit_s": args.time_limit,
            "strategies": strategies,
        });
        std::fs::write(path, serde_json::to_string_pretty(&json)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    eprintln!("results written to {}", args.out.display());
    Ok(exit::OK)
}

/// The paper's Table II (Section V), for the side-by-side print.
const PAPER: [(&str, f64, f64, f64, f64, f64, f64); 4] = [
    ("MAKEACC", 18.8, 99.5, 11.0, 93.3, 644.7, 16.2),
    ("SHOW", 13.3, 93.0, 1.0, 20.3, 406.6, 7.8),
    ("GIVE", 10.1, 100.0, 1.0, 4.2, 94.0, 7.9),
    ("PUTAWAY", 51.0, 48.0, 13.0, 110.3, 569.2, 17.9),
];

fn paper_row(task: &str) -> Option<&'static (&'static str, f64, f64, f64, f64, f64, f64)> {
    let key = match task {
        "make-accessible" | "pick-and-make-accessible" => "MAKEACC",
        "show" | "pick-and-show" => "SHOW",
        "give" | "pick-and-give" => "GIVE",
        "put-away" | "pick-and-put-away" => "PUTAWAY",
        _ => return None,
    };
    PAPER.iter().find(|r| r.0 == key)
}

fn print_experiment(e: &Experiment, scene: &str) {
    println!(
        "\n### htngtp bench library: {} runs, strategy {}, {scene} scene\n",
        e.runs.len(),
        e.strategy,
    );
    println!(
        "| GTP task | time (ms) | succ % | pts | grasps | orts | calls | requests | paper: time (s) | succ % | pts | grasps | orts | calls |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in e.table() {
        let paper = paper_row(&r.task)
            .map(|p| format!("{} | {} | {} | {} | {} | {}", p.1, p.2, p.3, p.4, p.5, p.6))
            .unwrap_or_else(|| "- | - | - | - | - | -".into());
        println!(
            "| {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {} | {} |",
            r.task,
            r.mean_time_s * 1e3,
            r.success_pct,
            r.points,
            r.grasps,
            r.orientations,
            r.planner_calls,
            r.attempts,
            paper
        );
    }
    let failures = e.runs.iter().filter(|r| !r.solved).count();
    println!(
        "\nMANAGEORDER solved in {:.1} % of runs ({} complete failures; the paper: 99 %, 1 failure)",
        e.success_pct(),
        failures
    );
    println!(
        "HTN backtracks per run: mean {:.2}, runs with more than 3: {:.1} % (the paper: 0.86 and slightly under 10 %)",
        e.mean_htn_backtracks(),
        e.share_over_3_backtracks()
    );
    println!(
        "GTP backtracks per run: mean {:.2}",
        e.runs.iter().map(|r| r.gtp_backtracks as f64).sum::<f64>() / e.runs.len().max(1) as f64
    );
    println!("Total wall time: {:.1} s", e.wall_time_s);
    if scene == "random-layout" || scene == "random-room" {
        let what = if scene == "random-room" {
            "Random rooms"
        } else {
            "Random layouts"
        };
        layout::print(e, &layout::report(e), what);
        return;
    }
    for r in e.runs.iter().filter(|r| !r.solved).take(5) {
        println!("  run {} (seed {}): {}", r.index, r.seed, r.status);
    }
}

fn print_comparison(results: &[Experiment]) {
    println!("\n### Strategies side by side\n");
    println!(
        "| strategy | success % | HTN backtracks / run | GTP backtracks / run | wall time (s) |"
    );
    println!("|---|---:|---:|---:|---:|");
    for e in results {
        let n = e.runs.len().max(1) as f64;
        println!(
            "| {} | {:.1} | {:.2} | {:.2} | {:.1} |",
            e.strategy,
            e.success_pct(),
            e.mean_htn_backtracks(),
            e.runs.iter().map(|r| r.gtp_backtracks as f64).sum::<f64>() / n,
            e.wall_time_s
        );
    }
}

fn write_files(e: &Experiment, dir: &std::path::Path, random: bool) -> anyhow::Result<()> {
    let base = dir.join(format!("library-{}", e.strategy));
    let json = if random {
        let report = layout::report(e);
        layout::write_csv(e, &report, dir)?;
        serde_json::json!({ "experiment": e, "table": e.table(), "layouts": report })
    } else {
        serde_json::json!({ "experiment": e, "table": e.table() })
    };
    std::fs::write(
        base.with_extension("json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    let mut csv = String::from(
        "task,mean_time_ms,success_pct,points,grasps,orientations,planner_calls,requests\n",
    );
    for r in e.table() {
        csv.push_str(&format!(
            "{},{:.3},{:.2},{:.2},{:.2},{:.2},{:.2},{}\n",
            r.task,
            r.mean_time_s * 1e3,
            r.success_pct,
            r.points,
            r.grasps,
            r.orientations,
            r.planner_calls,
            r.attempts
        ));
    }
    std::fs::write(base.with_extension("csv"), csv)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::Target;
    use super::layout::LayoutArg;

    #[derive(Parser)]
    struct Bench {
        #[command(subcommand)]
        target: Target,
    }

    fn library(args: &[&str]) -> Result<super::LibraryArgs, clap::Error> {
        let argv = ["bench", "library"].iter().chain(args);
        match Bench::try_parse_from(argv)?.target {
            Target::Library(a) => Ok(a),
            _ => panic!("not bench library"),
        }
    }

    #[test]
    fn the_layout_flag_parses() {
        let a = library(&["--layout", "random", "--runs", "100", "--seed", "1"]).unwrap();
        assert_eq!(a.layout, LayoutArg::Random);
        assert_eq!((a.runs, a.seed), (100, 1));
        let a = library(&["--layout", "random", "--save-scenes", "scenes"]).unwrap();
        assert_eq!(
            a.save_scenes.as_deref(),
            Some(std::path::Path::new("scenes"))
        );
        assert_eq!(library(&[]).unwrap().layout, LayoutArg::Nudge);
        assert!(library(&[]).unwrap().strategy.is_empty());
        let a = library(&[
            "--layout",
            "room",
            "--strategy",
            "chronological,geometric-first",
            "--json",
            "s.json",
        ])
        .unwrap();
        assert_eq!(a.layout, LayoutArg::Room);
        assert_eq!(a.strategy.len(), 2);
        assert_eq!(a.json.as_deref(), Some(std::path::Path::new("s.json")));
        assert!(library(&["--layout", "shuffled"]).is_err());
        assert!(library(&["--layout", "random", "--fixed"]).is_err());
    }
}
