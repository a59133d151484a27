//! `htngtp bench domain DIR`: a domain's randomized benchmark. Every problem
//! of the folder is planned in its scene with the scene's movable objects nudged and its people
//! moved per run, as `bench library` does, and the share of runs solved is reported with, for
//! the failures, the geometric task and the constraint that stopped them.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use geometry::world::World;
use gtp::planner::Planner;
use htn::model::{Domain, Problem};
use htn::planner::Outcome;
use hybrid::RunOptions;
use hybrid::experiment::{Randomization, randomize};
use rayon::prelude::*;

use crate::exit;

/// Arguments of `htngtp bench domain`.
#[derive(clap::Args)]
#[command(
    long_about = "A domain's randomized benchmark: DIR holds `domain.hddl` and problems whose \
                  leading comment names their scene (`Scene: office.toml.`, a file of DIR). \
                  Run i plans problem i mod P (P problems, in file-name order) in its scene \
                  with every movable object moved by up to 3 cm and turned by up to 10 degrees \
                  on its support and every person moved by up to 5 cm and 6 degrees (`bench \
                  library`'s randomization). Prints the share solved per problem and overall, \
                  and the failures grouped by the geometric task and the constraint that \
                  stopped them. Runs in parallel on all cores."
)]
pub struct DomainArgs {
    /// The domain's folder (`domains/office`).
    pub dir: PathBuf,
    /// Number of runs, shared round-robin among the problems.
    #[arg(long, default_value_t = 100)]
    pub runs: usize,
    /// Seed of the scene randomization and of every search.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Backtracking strategy.
    #[arg(long, value_enum, default_value_t = crate::cmd::plan::StrategyArg::GeometricFirst)]
    pub strategy: crate::cmd::plan::StrategyArg,
    /// With geometric-first: other geometric solutions tried per failure.
    #[arg(long, default_value_t = 3)]
    pub geo_alternatives: usize,
    /// Time limit of each run, seconds.
    #[arg(long, default_value_t = 60.0, value_parser = crate::input::seconds)]
    pub time_limit: f64,
    /// Run only the run with this index (0-based; same problem, scene and seeds as in the full
    /// benchmark), e.g. to retrace a failure with `HTNGTP_TRACE=1`.
    #[arg(long, value_name = "INDEX")]
    pub only: Option<usize>,
    /// Write each solved run's plan JSON into this folder (`PROBLEM-INDEX.json`), for `htngtp
    /// check`.
    #[arg(long, value_name = "DIR")]
    pub plans: Option<PathBuf>,
}

/// One problem of the folder with its scene.
struct Case {
    name: String,
    problem: Problem,
    world: World,
}

/// One run's outcome.
struct Record {
    index: usize,
    problem: String,
    solved: bool,
    /// `solved`, `unsolvable` or `limit: ...`.
    status: String,
    /// For a failure: the last geometric task that failed and the constraint that stopped it.
    cause: Option<(String, String)>,
    message: String,
    time_s: f64,
}

pub fn run(args: DomainArgs) -> anyhow::Result<u8> {
    super::check_runs(args.runs, args.only)?;
    let domain = crate::input::load_domain(&args.dir.join("domain.hddl"))?;
    let cases = cases(&args.dir, &domain)?;
    if let Some(dir) = &args.plans {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let (strategy, name) = super::strategy(args.strategy, args.geo_alternatives);
    let options = super::run_options(strategy, args.time_limit);
    let planner = Arc::new(Planner::new());
    let start = Instant::now();
    let indices: Vec<usize> = match args.only {
        Some(i) => vec![i],
        None => (0..args.runs).collect(),
    };
    let records: Vec<Record> = indices
        .into_par_iter()
        .map(|i| {
            let case = &cases[i % cases.len()];
            let seed = args.seed.wrapping_mul(1_000_003).wrapping_add(i as u64);
            one_run(&domain, case, i, seed, &planner, &options, &args.plans)
        })
        .collect();
    print_report(
        &args.dir,
        name,
        &cases,
        &records,
        start.elapsed().as_secs_f64(),
    );
    Ok(exit::OK)
}

/// The search strategy of `arg`, with its name.
/// The problems of `dir` (every `.hddl` file but those whose name starts with `domain`), in
/// file-name order, each with the scene its leading comment names.
fn cases(dir: &Path, domain: &Domain) -> anyhow::Result<Vec<Case>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "hddl"))
        .filter(|p| {
            !p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("domain"))
        })
        .collect();
    files.sort();
    if files.is_empty() {
        anyhow::bail!(
            "{}: no problem (.hddl other than domain*.hddl)",
            dir.display()
        );
    }
    files
        .iter()
        .map(|path| {
            let scene = scene_of(path)?;
            let problem = htn::load_problem(path, domain)?;
            let world = World::load(dir.join(&scene)).map_err(|e| anyhow::anyhow!("{e}"))?;
            Ok(Case {
                name: problem.name.clone(),
                problem,
                world,
            })
        })
        .collect()
}

/// The scene a problem file names in its leading `;` comment: the word after `Scene:`.
fn scene_of(path: &Path) -> anyhow::Result<String> {
    crate::input::check_file(path)?;
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    for (n, line) in text.lines().enumerate() {
        let Some(comment) = line.trim_start().strip_prefix(';') else {
            break;
        };
        if let Some(at) = comment.find("Scene:") {
            let rest = comment[at + "Scene:".len()..].trim_start();
            let name = rest.split_whitespace().next().unwrap_or("");
            let name = name.trim_end_matches(['.', ',', ';']);
            if name.is_empty() {
                anyhow::bail!("{}:{}: `Scene:` names no file", path.display(), n + 1);
            }
            return Ok(name.to_string());
        }
    }
    anyhow::bail!(
        "{}:1:1: the leading comment names no scene (write `; ... Scene: FILE.toml.`)",
        path.display()
    )
}

/// Plans one run in a randomized copy of the case's scene.
fn one_run(
    domain: &Domain,
    case: &Case,
    index: usize,
    seed: u64,
    planner: &Arc<Planner>,
    options: &RunOptions,
    plans: &Option<PathBuf>,
) -> Record {
    let world = nudged(&case.world, seed);
    let mut options = options.clone();
    options.oracle.seed = seed;
    options.planner.seed = seed;
    let t0 = Instant::now();
    let record = |solved, status: String, message: String| Record {
        index,
        problem: case.name.clone(),
        solved,
        cause: (!solved).then(|| cause(&message)).flatten(),
        status,
        message,
        time_s: t0.elapsed().as_secs_f64(),
    };
    match hybrid::plan(domain, &case.problem, world, planner.clone(), &options) {
        Ok(run) => match &run.result.outcome {
            Outcome::Found { .. } => {
                let message = match plans {
                    Some(dir) => write_plan(&run, domain, case, dir, index).err(),
                    None => None,
                };
                match message {
                    Some(e) => record(false, "plan JSON not written".into(), e),
                    None => record(true, "solved".into(), String::new()),
                }
            }
            Outcome::Unsolvable => record(false, "unsolvable".into(), run.failure_message()),
            Outcome::LimitReached { limit } => {
                record(false, format!("limit: {limit}"), run.failure_message())
            }
        },
        Err(e) => record(false, "error".into(), e.to_string()),
    }
}

/// `bench library`'s randomized copy of `world`, drawn again (at most 20 times, else the scene
/// as it is) while a movable object sinks more than 1 mm into another object or lies on a
/// movable object with its centre beyond that one's footprint. `randomize` moves each object on
/// its own and lets it overlap what it rests on, which for a thing standing in a container
/// includes the container's walls: a start in collision that no plan can leave, or a folder
/// left toppling off the wallet it lay on.
fn nudged(world: &World, seed: u64) -> World {
    (0..20u64)
        .map(|k| randomize(world, &Randomization::default(), seed ^ (k << 48)))
        .find(|w| !overlaps(w) && !toppling(world, w))
        .unwrap_or_else(|| world.clone())
}

/// Whether a movable object that rests on another movable object in `start` has, in `world`,
/// its centre outside that object's footprint (its bounding box in its own frame, seen from
/// above). The pairs come from `start`: in `world` the `on` test itself needs the centre over
/// the footprint.
fn toppling(start: &World, world: &World) -> bool {
    let movable: Vec<_> = start
        .object_ids()
        .filter(|&o| start.object(o).movable)
        .collect();
    movable.iter().any(|&a| {
        movable.iter().any(|&b| {
            a != b && geometry::facts::on(start, a, b, 0.02) && {
                let c = world.object_aabb(a).center();
                let local = world.object_shape_pose(b).inverse_transform_point(c);
                let lb = world.object(b).shape.compute_local_aabb();
                !(lb.mins.x..=lb.maxs.x).contains(&local.x)
                    || !(lb.mins.y..=lb.maxs.y).contains(&local.y)
            }
        })
    })
}

/// Whether a movable object of `world` sinks more than 1 mm into another object.
fn overlaps(world: &World) -> bool {
    let depth = geometry::world::CONTACT_TOLERANCE_M;
    world.obstacles().any(|(a, shape_a, pose_a)| {
        world.object(a).movable
            && world.obstacles().any(|(b, shape_b, pose_b)| {
                a != b
                    && parry3d::query::contact(&pose_a, &**shape_a, &pose_b, &**shape_b, 0.0)
                        .ok()
                        .flatten()
                        .is_some_and(|c| -c.dist > depth)
            })
    })
}

/// The task and the constraint of a failure message ("... the last geometric task to fail was
/// pick(deed): no grasp ... (pick)").
fn cause(message: &str) -> Option<(String, String)> {
    let marker = "the last geometric task to fail was ";
    let rest = &message[message.find(marker)? + marker.len()..];
    let task = rest.split('(').next()?.to_string();
    let constraint = message
        .trim_end()
        .strip_suffix(')')
        .and_then(|m| m.rsplit('(').next())
        .unwrap_or("?")
        .to_string();
    Some((task, constraint))
}

fn write_plan(
    run: &hybrid::Run,
    domain: &Domain,
    case: &Case,
    dir: &Path,
    index: usize,
) -> Result<(), String> {
    let path = dir.join(format!("{}-{index:03}.json", case.name));
    let json = hybrid::export::plan_json(run, &domain.name, &case.problem.name);
    let text = serde_json::to_string(&json).map_err(|e| e.to_string())?;
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
}

fn print_report(dir: &Path, strategy: &str, cases: &[Case], records: &[Record], wall_s: f64) {
    let solved = records.iter().filter(|r| r.solved).count();
    println!(
        "Domain {} ({strategy}): {solved} of {} runs solved ({:.1} %), {wall_s:.1} s wall",
        dir.display(),
        records.len(),
        100.0 * solved as f64 / records.len() as f64
    );
    println!(
        "{:<24} {:>6} {:>6} {:>12}",
        "problem", "runs", "solved", "median s"
    );
    for case in cases {
        let mut times: Vec<f64> = records
            .iter()
            .filter(|r| r.problem == case.name)
            .map(|r| r.time_s)
            .collect();
        times.sort_by(f64::total_cmp);
        let ok = records
            .iter()
            .filter(|r| r.problem == case.name && r.solved)
            .count();
        let median = times.get(times.len() / 2).copied().unwrap_or(0.0);
        println!(
            "{:<24} {:>6} {:>6} {:>12.2}",
            case.name,
            times.len(),
            ok,
            median
        );
    }
    let mut by_cause: BTreeMap<(String, String), usize> = BTreeMap::new();
    for r in records.iter().filter(|r| !r.solved) {
        let key = r.cause.clone().unwrap_or_else(|| ("-".into(), "-".into()));
        *by_cause.entry(key).or_default() += 1;
    }
    if by_cause.is_empty() {
        return;
    }
    println!("Failures by task and constraint:");
    for ((task, constraint), n) in &by_cause {
        println!("  {n:>4}  {task} / {constraint}");
    }
    for r in records.iter().filter(|r| !r.solved) {
        println!(
            "  run {} ({}): {}: {}",
            r.index, r.problem, r.status, r.message
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failure_names_its_task_and_constraint() {
        let m = "no decomposition works; the last geometric task to fail was \
                 pick-and-give(deed, archivist): no grasp of `deed` can be picked up (160 \
                 tried; the last: the gripper hits `box-file`) (pick)";
        assert_eq!(
            cause(m),
            Some(("pick-and-give".to_string(), "pick".to_string()))
        );
        assert_eq!(
            cause("no decomposition works (no geometric task failed)"),
            None
        );
    }

    #[test]
    fn the_scene_comes_from_the_leading_comment() {
        let dir = std::env::temp_dir().join(format!("htngtp-scene-of-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let with = dir.join("a.hddl");
        std::fs::write(
            &with,
            "; Two lines.\n; Scene: office.toml.\n(define (problem a))",
        )
        .unwrap();
        assert_eq!(scene_of(&with).unwrap(), "office.toml");
        let without = dir.join("b.hddl");
        std::fs::write(
            &without,
            "; No scene here.\n(define (problem b))\n; Scene: x.toml",
        )
        .unwrap();
        let e = scene_of(&without).unwrap_err().to_string();
        assert!(
            e.contains("b.hddl:1:1") && e.contains("names no scene"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
