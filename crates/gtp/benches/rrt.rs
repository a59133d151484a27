//! RRT-Connect queries in the library scene: the PR2's right arm between the configurations
//! of a real make-accessible solution (approach to the grey book, carrying it to the desk, the
//! arm's return), each planned from scratch with a fresh seed per iteration; plus one
//! collision check for scale; and a query that cannot connect (a wall across a 7-joint space,
//! validity free of geometry), whose cost is the trees' nearest-neighbour searches up to the
//! node limit.
//!
//! Run: `cargo bench -p gtp --bench rrt`. Target: median < 1 ms per query.

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use geometry::world::World;
use gtp::planner::{CallOptions, Planner};
use gtp::robot::{self, ArmMotion};
use gtp::solution::Phase;

fn library() -> World {
    World::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../domains/library/scene.toml"
    ))
    .expect("library scene")
}

fn bench_rrt(c: &mut Criterion) {
    let world = library();
    let planner = Planner::new();
    let solution = planner
        .run(
            &world,
            "make-accessible",
            &["grey-book", "member"],
            &CallOptions::default(),
        )
        .expect("task")
        .next()
        .expect("a make-accessible solution in the library scene");
    let setup = planner.robot(&world).unwrap();
    let book = world.object_id("grey-book").unwrap();
    let arm = setup
        .arms
        .iter()
        .find(|a| a.name == solution.summary.grasp.as_ref().unwrap().arm)
        .unwrap();
    let base = world.agent_state(setup.agent).base;
    let q0 = world.agent_state(setup.agent).q.clone();
    let params = planner.config().rrt.clone();
    let st = world.agent_state(setup.agent);
    let (centre, radius) = setup.workspace(st.base, &st.q, 0.3);
    let near = |o: geometry::collision::StaticObstacles| robot::near(&o, centre, radius);
    let mut g = c.benchmark_group("rrt_connect");
    for t in &solution.summary.trajectories {
        let (obstacles, held) = match t.phase {
            Phase::Approach => (near(robot::obstacles(&world, setup.agent, &[])), None),
            Phase::Transfer => {
                let h = t.held.as_ref().unwrap();
                let held =
                    robot::held_object(&world, &setup, arm, book, h.object_in_tool.into()).unwrap();
                (
                    near(robot::obstacles(&world, setup.agent, &[book])),
                    Some(held),
                )
            }
            Phase::Return => (
                near(robot::obstacles(&solution.world, setup.agent, &[])),
                None,
            ),
            _ => continue,
        };
        let mut template = q0.clone();
        robot::set_opening(&setup.model, arm, &mut template, t.gripper_opening);
        let motion = ArmMotion::new(&setup, arm, Arc::new(obstacles), held, base, template);
        let start = t.waypoints.first().unwrap().clone();
        let goal = t.waypoints.last().unwrap().clone();
        if std::env::var_os("RRT_STATS").is_some() {
            for s in 0..5 {
                let mut rng = fastrand::Rng::with_seed(s);
                match motion.plan(&start, &goal, &params, &mut rng) {
                    Ok((p, st)) => eprintln!(
                        "{:?}: {} waypoints, length {:.2} (straight {:.2}), {st:?}",
                        t.phase,
                        p.waypoints.len(),
                        p.length(&arm.space),
                        arm.space.distance(&start, &goal)
                    ),
                    Err(e) => eprintln!("{:?}: {e}", t.phase),
                }
            }
        }
        let mut seed = 0u64;
        g.bench_function(format!("{:?}", t.phase), |b| {
            b.iter(|| {
                seed += 1;
                let mut rng = fastrand::Rng::with_seed(seed);
                black_box(motion.plan(&start, &goal, &params, &mut rng).ok())
            })
        });
        if t.phase == Phase::Approach {
            g.bench_function("one collision check", |b| {
                b.iter(|| black_box(motion.free(&start)))
            });
            // As the planner checks: only the arm's links move.
            let checker = motion.arm_checker();
            let full = motion.full(&start);
            g.bench_function("one collision check, arm only", |b| {
                b.iter(|| black_box(checker.is_config_free(&full)))
            });
        }
    }
    g.finish();
}

/// A query whose goal lies behind a wall through the whole space: the trees grow to
/// `max_nodes` and the query fails; the time is the search's own (sampling, nearest
/// neighbours, extension), not the geometry's.
fn bench_unconnectable(c: &mut Criterion) {
    use gtp::rrt::{self, JointSpace, RrtParams};
    let space = JointSpace::new(
        &[(-2.5, 2.5, false); 6]
            .iter()
            .copied()
            .chain([(0.0, 0.0, true)])
            .collect::<Vec<_>>(),
    );
    let (start, goal) = (vec![-2.0; 7], vec![2.0; 7]);
    let valid = |q: &[f32]| q[0].abs() > 0.3;
    let mut g = c.benchmark_group("rrt unconnectable");
    g.sample_size(10);
    for max_nodes in [1000, 5000] {
        let params = RrtParams {
            max_nodes,
            max_checks: usize::MAX,
            time_limit: std::time::Duration::from_secs(60),
            ..RrtParams::default()
        };
        g.bench_function(format!("{max_nodes} nodes"), |b| {
            b.iter(|| {
                let mut rng = fastrand::Rng::with_seed(1);
                black_box(rrt::plan(&space, &start, &goal, valid, &params, &mut rng).is_err())
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_rrt, bench_unconnectable);
criterion_main!(benches);
