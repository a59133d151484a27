//! How cost grows: a generated family of library problems, MANAGEORDER with
//! N books lent from the librarians' tables over a desk holding M other objects, several
//! randomized scenes per (N, M), each planned once ([`run_scale`]).
//!
//! The scene is the library's (`domains/library/scene.toml`), edited in memory
//! ([`crate::layout::SceneText`]): its two books removed; a second librarians' table, the
//! first's mirror image, on the robot's left (the shelf and the POS machine moved 0.67 m
//! further left to make room); N small books standing on their long edge in slots of the two
//! tables (two rows of six each, 8 cm apart: room for the gripper's fingers between two books;
//! the rows 2 cm apart end to end; the 16 slots the arm picks from its station kept), drawn at
//! random and nudged by up to 1 cm and 5 degrees; M small boxes and cylinders (3 to 8 cm
//! across) at random free spots of the desk, 3 cm apart. The problem gives
//! the member credit for exactly N books, so payment is the library account (m6): the family
//! measures lending alone. Everything is drawn from one seed: the same seed, the same scenes.

use std::path::Path;
use std::sync::Arc;

use geometry::world::World;
use gtp::planner::Planner;
use htn::model::{Domain, Problem, SourceName};
use rayon::prelude::*;
use serde::Serialize;

use crate::experiment::{RunRecord, run_one};
use crate::layout::{Footprints, NewObject, NewShape, SceneText, surfaces};
use crate::run::RunOptions;

/// Book slots per librarians' table (two rows of six), before those out of the arm's way are
/// dropped ([`book_slots`]).
const SLOTS_PER_TABLE: usize = 12;
/// The most books a generated scene holds: the slots the robot picks from its station.
pub const MAX_BOOKS: usize = 16;
/// A slot nearer the robot's base than this (horizontally, metres), or behind it, is dropped:
/// the gripper comes down onto a standing book from above, which the arm cannot do right
/// beside or behind the base (found with `htngtp gtp SCENE pick book-I` on every slot: each
/// kept slot is picked, each dropped one but one is not).
const SLOT_CLEARANCE_FROM_BASE: f32 = 0.6;
/// How far the shelf (with the POS machine on it) moves to the left, metres.
const SHELF_SHIFT: f32 = 0.67;

/// One problem of the family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct ScaleSpec {
    /// Books lent (N).
    pub books: usize,
    /// Other objects on the desk (M).
    pub others: usize,
    /// Seed of the scene's draws.
    pub seed: u64,
}

/// A generated problem: the world and the HDDL problem's text.
pub struct ScaleProblem {
    pub world: World,
    pub problem_text: String,
}

/// Generates the problem of `spec` from the library folder `library_dir` (its `scene.toml`).
pub fn generate(library_dir: &Path, spec: &ScaleSpec) -> Result<ScaleProblem, String> {
    if spec.books == 0 || spec.books > MAX_BOOKS {
        return Err(format!(
            "{} books: the generated scene holds 1 to {MAX_BOOKS}",
            spec.books
        ));
    }
    let mut rng = fastrand::Rng::with_seed(spec.seed);
    let mut text = SceneText::load(&library_dir.join("scene.toml"))?;
    text.remove(&["grey-book", "white-book"])?;
    text.shift("shelf", [0.0, SHELF_SHIFT, 0.0])?;
    text.shift("pos-machine", [0.0, SHELF_SHIFT, 0.0])?;
    text.duplicate("table", "table-2", [-0.6, 0.78, 0.0])?;
    let source = format!(
        "scale(N={}, M={}, seed={})",
        spec.books, spec.others, spec.seed
    );
    let base = text.world(&source, library_dir)?;
    for (i, xyz) in book_slots(&base, spec.books, &mut rng)?
        .into_iter()
        .enumerate()
    {
        text.add(&NewObject {
            name: format!("book-{}", i + 1),
            shape: NewShape::Box([0.07, 0.1, 0.015]),
            xyz,
            rpy: [0.0, 90.0, (rng.f32() * 2.0 - 1.0) * 5.0],
            colour: geometry::scene::palette(i),
            movable: true,
        })?;
    }
    for o in desk_objects(&base, spec.others, &mut rng)? {
        text.add(&o)?;
    }
    let world = text.world(&source, library_dir)?;
    Ok(ScaleProblem {
        world,
        problem_text: problem_text(spec.books),
    })
}

/// The centres of `n` books standing on their long edge (0.14 m tall), in slots of the two
/// librarians' tables drawn at random, each nudged by up to 1 cm; slots beside or behind the
/// robot's base are left out ([`SLOT_CLEARANCE_FROM_BASE`]).
fn book_slots(world: &World, n: usize, rng: &mut fastrand::Rng) -> Result<Vec<[f32; 3]>, String> {
    let robot = world
        .agent_ids()
        .find(|&a| world.agent(a).kind() == geometry::scene::AgentKind::Robot)
        .ok_or("the scene has no robot")?;
    let base = world.agent_state(robot).base.translation;
    let mut slots = Vec::with_capacity(2 * SLOTS_PER_TABLE);
    for table in ["table", "table-2"] {
        let id = world
            .object_id(table)
            .ok_or_else(|| format!("the scene has no `{table}`"))?;
        let s = surfaces(world)
            .into_iter()
            .find(|s| s.support == id)
            .ok_or_else(|| format!("`{table}` has no support surface"))?;
        // Rows run along x; the first row is the one nearer the robot (y = 0).
        let toward = -s.centre.y.signum();
        for row in 0..2 {
            let y = s.centre.y + toward * (0.19 - 0.22 * row as f32);
            for col in 0..SLOTS_PER_TABLE / 2 {
                let x = s.centre.x - 0.2 + 0.08 * col as f32;
                let (dx, dy) = (x - base.x, y - base.y);
                if dx >= 0.0 && dx.hypot(dy) >= SLOT_CLEARANCE_FROM_BASE {
                    slots.push([x, y, s.centre.z + 0.0702]);
                }
            }
        }
    }
    if slots.len() < n {
        return Err(format!(
            "{n} books: the tables have {} slots the robot picks from",
            slots.len()
        ));
    }
    rng.shuffle(&mut slots);
    let mut nudge = || (rng.f32() * 2.0 - 1.0) * 0.01;
    Ok(slots
        .into_iter()
        .take(n)
        .map(|[x, y, z]| [x + nudge(), y + nudge(), z])
        .collect())
}

/// `m` small boxes and cylinders at random free spots of the desk, 3 cm apart.
fn desk_objects(
    world: &World,
    m: usize,
    rng: &mut fastrand::Rng,
) -> Result<Vec<NewObject>, String> {
    let desk = world.object_id("desk").ok_or("the scene has no `desk`")?;
    let surface = surfaces(world)
        .into_iter()
        .find(|s| s.support == desk)
        .ok_or("`desk` has no support surface")?;
    let mut taken = Footprints::of(world);
    let mut out = Vec::with_capacity(m);
    for j in 0..m {
        let (shape, half) = if rng.bool() {
            let h = [
                0.02 + rng.f32() * 0.02,
                0.02 + rng.f32() * 0.02,
                0.01 + rng.f32() * 0.04,
            ];
            (NewShape::Box(h), h)
        } else {
            let r = 0.015 + rng.f32() * 0.02;
            let hh = 0.03 + rng.f32() * 0.03;
            (
                NewShape::Cylinder {
                    radius: r,
                    half_height: hh,
                },
                [r, r, hh],
            )
        };
        // Turned about the vertical: the footprint is the box's circumscribed square.
        let yaw: f32 = rng.f32() * 90.0;
        let reach = (half[0] * half[0] + half[1] * half[1]).sqrt();
        let spot = taken
            .draw(&surface, [reach, reach], 0.01, 0.03, 2000, rng)
            .ok_or_else(|| format!("no free spot left on the desk for object {}", j + 1))?;
        let z = surface.centre.z + half[2] + 2e-4;
        taken.take(spot, [reach, reach], [surface.centre.z, z + half[2]]);
        out.push(NewObject {
            name: format!("item-{}", j + 1),
            shape,
            xyz: [spot.x, spot.y, z],
            rpy: [0.0, 0.0, yaw],
            colour: geometry::scene::palette(j + 7),
            movable: true,
        });
    }
    Ok(out)
}

/// The HDDL problem: `n` books held for the member, with titles, and credit for all of them.
pub fn problem_text(n: usize) -> String {
    let books: Vec<String> = (1..=n).map(|i| format!("book-{i}")).collect();
    let titles: Vec<String> = (1..=n).map(|i| format!("title-{i}")).collect();
    let init: Vec<String> = (1..=n)
        .map(|i| format!("    (held book-{i} member) (title book-{i} title-{i})"))
        .collect();
    format!(
        "; Generated by htngtp bench scale: {n} books lent, paid from the library credit (m6).\n\
         (define (problem scale-{n}) (:domain library)\n  (:objects\n    member - member\n    \
         {} - book\n    {} - phrase)\n  (:htn :parameters () :ordered-subtasks (and (manage-order \
         member)))\n  (:init\n{}\n    (= (num-lent member) 0)\n    (= (book-cost) 4)\n    \
         (= (credit member) {})))\n",
        books.join(" "),
        titles.join(" "),
        init.join("\n"),
        4 * n
    )
}

/// One run of the scale benchmark: its cell (N, M) and its record.
#[derive(Clone, Debug, Serialize)]
pub struct ScaleRun {
    pub books: usize,
    pub others: usize,
    pub record: RunRecord,
}

/// Settings of the scale benchmark.
#[derive(Clone, Debug)]
pub struct ScaleOptions {
    /// The (N, M) cells.
    pub cells: Vec<(usize, usize)>,
    /// Scenes per cell.
    pub runs: usize,
    pub seed: u64,
    pub run: RunOptions,
    /// Runs at once (threads).
    pub jobs: usize,
}

/// The seed of run `k` of cell (`n`, `m`): one draw per cell and run from `seed`.
pub fn run_seed(seed: u64, n: usize, m: usize, k: usize) -> u64 {
    let mut rng = fastrand::Rng::with_seed(seed ^ ((n as u64) << 40 | (m as u64) << 20 | k as u64));
    rng.u64(..)
}

/// Runs every cell `runs` times, `jobs` runs at once, calling `progress` after each run. A
/// scene that cannot be generated is a failed run with the generator's reason.
pub fn run_scale(
    domain: &Domain,
    library_dir: &Path,
    options: &ScaleOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<ScaleRun>, String> {
    let planner = Arc::new(Planner::new());
    let work: Vec<(usize, usize, usize)> = options
        .cells
        .iter()
        .flat_map(|&(n, m)| (0..options.runs).map(move |k| (n, m, k)))
        .collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs.max(1))
        .build()
        .map_err(|e| e.to_string())?;
    let runs = pool.install(|| {
        work.into_par_iter()
            .map(|(n, m, k)| {
                let seed = run_seed(options.seed, n, m, k);
                let record = one_run(domain, library_dir, &planner, options, (n, m, k), seed);
                progress();
                ScaleRun {
                    books: n,
                    others: m,
                    record,
                }
            })
            .collect()
    });
    Ok(runs)
}

fn one_run(
    domain: &Domain,
    library_dir: &Path,
    planner: &Arc<Planner>,
    options: &ScaleOptions,
    (n, m, k): (usize, usize, usize),
    seed: u64,
) -> RunRecord {
    let spec = ScaleSpec {
        books: n,
        others: m,
        seed,
    };
    let generated = generate(library_dir, &spec).and_then(|g| {
        let source: SourceName = Arc::new(format!("scale-{n}-{m}-{k}.hddl").into());
        htn::parse_problem(&g.problem_text, source, domain)
            .map(|p: Problem| (g.world, p))
            .map_err(|e| e.to_string())
    });
    match generated {
        Ok((world, problem)) => run_one(
            domain,
            &problem,
            world,
            planner,
            &options.run,
            k,
            seed,
            None,
        ),
        Err(e) => RunRecord::failed(k, seed, format!("error: the scene: {e}")),
    }
}

/// The summary of one (N, M) cell.
#[derive(Clone, Debug, Serialize)]
pub struct CellSummary {
    pub books: usize,
    pub others: usize,
    pub runs: usize,
    pub success_pct: f64,
    /// Wall time of a run (failed runs included, at the time they stopped), seconds.
    pub median_time_s: f64,
    pub p90_time_s: f64,
    /// Means per run.
    pub gtp_calls: f64,
    pub htn_backtracks: f64,
    pub gtp_backtracks: f64,
    /// Mean seconds per run in each GTP task (search and shared literals), by task.
    pub task_time_s: Vec<(String, f64)>,
    /// Mean GTP requests per run that failed, by task.
    pub task_failures: Vec<(String, f64)>,
}

/// The cells' summaries, in the order of `cells`.
pub fn summarize(cells: &[(usize, usize)], runs: &[ScaleRun]) -> Vec<CellSummary> {
    cells
        .iter()
        .map(|&(n, m)| {
            let rs: Vec<&RunRecord> = runs
                .iter()
                .filter(|r| r.books == n && r.others == m)
                .map(|r| &r.record)
                .collect();
            summarize_cell(n, m, &rs)
        })
        .collect()
}

fn summarize_cell(n: usize, m: usize, rs: &[&RunRecord]) -> CellSummary {
    let k = rs.len().max(1) as f64;
    let mut times: Vec<f64> = rs.iter().map(|r| r.time_s).collect();
    times.sort_by(f64::total_cmp);
    let mut tasks: std::collections::BTreeMap<String, (f64, f64)> = Default::default();
    for r in rs {
        for (t, s) in &r.tasks {
            let e = tasks.entry(t.clone()).or_default();
            e.0 += s.total_time_s() / k;
            e.1 += (s.attempts - s.successes) as f64 / k;
        }
    }
    let mean = |f: &dyn Fn(&RunRecord) -> f64| rs.iter().map(|r| f(r)).sum::<f64>() / k;
    CellSummary {
        books: n,
        others: m,
        runs: rs.len(),
        success_pct: 100.0 * rs.iter().filter(|r| r.solved).count() as f64 / k,
        median_time_s: quantile(&times, 0.5),
        p90_time_s: quantile(&times, 0.9),
        gtp_calls: mean(&|r| r.tasks.values().map(|s| s.attempts as f64).sum()),
        htn_backtracks: mean(&|r| r.htn_backtracks as f64),
        gtp_backtracks: mean(&|r| r.gtp_backtracks as f64),
        task_time_s: tasks.iter().map(|(t, v)| (t.clone(), v.0)).collect(),
        task_failures: tasks.iter().map(|(t, v)| (t.clone(), v.1)).collect(),
    }
}

/// The `q` quantile of sorted `v` (linear between neighbours; 0 when empty).
pub fn quantile(v: &[f64], q: f64) -> f64 {
    match v.len() {
        0 => 0.0,
        1 => v[0],
        n => {
            let x = q.clamp(0.0, 1.0) * (n - 1) as f64;
            let (i, f) = (x.floor() as usize, x.fract());
            v[i] + (v[(i + 1).min(n - 1)] - v[i]) * f
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geometry::world::Precision;

    fn library() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../domains/library")
    }

    fn spec(books: usize, others: usize, seed: u64) -> ScaleSpec {
        ScaleSpec {
            books,
            others,
            seed,
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_scene_and_another_seed_another() {
        let a = generate(&library(), &spec(8, 20, 7)).unwrap();
        let b = generate(&library(), &spec(8, 20, 7)).unwrap();
        let c = generate(&library(), &spec(8, 20, 8)).unwrap();
        let f = |w: &World| w.fingerprint(Precision::Exact);
        assert_eq!(f(&a.world), f(&b.world));
        assert_ne!(f(&a.world), f(&c.world));
        assert_eq!(a.problem_text, b.problem_text);
    }

    #[test]
    fn the_scene_holds_n_books_on_the_tables_and_m_objects_on_the_desk() {
        let g = generate(&library(), &spec(16, 20, 3)).unwrap();
        let w = &g.world;
        let tables = [
            w.object_id("table").unwrap(),
            w.object_id("table-2").unwrap(),
        ];
        let desk = w.object_id("desk").unwrap();
        for i in 1..=16 {
            let b = w.object_id(&format!("book-{i}")).unwrap();
            assert!(
                tables.iter().any(|&t| geometry::facts::on(w, b, t, 0.01)),
                "book-{i} is on neither table"
            );
        }
        assert!(w.object_id("book-17").is_none());
        for j in 1..=20 {
            let o = w.object_id(&format!("item-{j}")).unwrap();
            assert!(
                geometry::facts::on(w, o, desk, 0.01),
                "item-{j} is not on the desk"
            );
        }
        assert!(w.object_id("grey-book").is_none());
    }

    #[test]
    fn the_problem_parses_and_pays_from_the_credit() {
        let domain = htn::load_domain(library().join("domain-compound.hddl")).unwrap();
        let text = problem_text(4);
        let source: SourceName = Arc::new("scale.hddl".into());
        let p = htn::parse_problem(&text, source, &domain).unwrap();
        assert_eq!(
            p.objects
                .iter()
                .filter(|o| o.name.starts_with("book-"))
                .count(),
            4
        );
        assert!(text.contains("(= (credit member) 16)"));
    }

    #[test]
    fn too_many_books_is_an_error_not_a_panic() {
        let e = generate(&library(), &spec(MAX_BOOKS + 1, 0, 1))
            .err()
            .unwrap();
        assert!(e.contains("1 to 16"), "{e}");
        assert!(generate(&library(), &spec(0, 0, 1)).is_err());
    }

    #[test]
    fn a_desk_with_no_room_left_is_an_error() {
        let e = generate(&library(), &spec(1, 400, 1)).err().unwrap();
        assert!(e.contains("no free spot left on the desk"), "{e}");
    }

    #[test]
    fn quantiles_interpolate() {
        let v = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(quantile(&v, 0.5), 2.5);
        assert!((quantile(&v, 0.9) - 3.7).abs() < 1e-12);
        assert_eq!(quantile(&[], 0.5), 0.0);
    }
}
