//! Full-robot collision checks per second, inverse kinematics and forward kinematics, in a
//! library-like scene (the paper's Fig. 4: a table with two books in front of the PR2, a
//! reception desk, a POS machine on its stand, a shelf, walls and the floor).
//!
//! Run: `cargo bench -p geometry --bench collision`. Throughput figures are per configuration
//! (collision, forward kinematics) or per solve (inverse kinematics).

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use geometry::agent::AgentModel;
use geometry::collision::{
    CollisionChecker, Obstacle, SelfCollisionModel, SelfCollisionOptions, StaticObstacles,
};
use geometry::ik::{IkOptions, solve_ik};
use parry3d::math::{Pose, Vector};
use parry3d::shape::SharedShape;

fn boxed(name: &str, min: [f32; 3], max: [f32; 3]) -> Obstacle {
    let (min, max) = (Vector::from(min), Vector::from(max));
    let h = (max - min) * 0.5;
    Obstacle {
        name: name.to_string(),
        pose: Pose::from_translation((min + max) * 0.5),
        shape: SharedShape::cuboid(h.x, h.y, h.z),
    }
}

/// The library-like obstacle set: 24 boxes.
fn library() -> Vec<Obstacle> {
    let mut o = vec![
        boxed("floor", [-4.0, -4.0, -0.1], [4.0, 4.0, -0.001]),
        boxed("wall-back", [-3.0, 2.5, 0.0], [3.0, 2.6, 2.5]),
        boxed("wall-side", [3.0, -3.0, 0.0], [3.1, 2.5, 2.5]),
        // The table in front of the robot, with the books on it.
        boxed("table-top", [0.55, -0.6, 0.70], [1.35, 0.6, 0.74]),
        boxed("grey-book", [0.70, -0.30, 0.74], [0.92, -0.14, 0.78]),
        boxed("white-book", [0.80, 0.15, 0.74], [1.00, 0.31, 0.77]),
        // The reception desk across from the robot, the platform and the POS machine.
        boxed("desk", [1.8, -1.0, 0.0], [2.4, 1.0, 1.05]),
        boxed("platform", [1.55, -0.3, 0.0], [1.8, 0.3, 0.9]),
        boxed("pos-stand", [1.9, -1.5, 0.0], [2.1, -1.3, 1.1]),
        boxed("pos-machine", [1.93, -1.47, 1.1], [2.07, -1.33, 1.18]),
        // The shelf to the robot's left.
        boxed("shelf-left", [-0.6, 1.2, 0.0], [-0.58, 1.6, 1.8]),
        boxed("shelf-right", [0.58, 1.2, 0.0], [0.6, 1.6, 1.8]),
        boxed("shelf-back", [-0.6, 1.58, 0.0], [0.6, 1.6, 1.8]),
        boxed("shelf-book-1", [-0.5, 1.25, 0.42], [-0.46, 1.5, 0.7]),
        boxed("shelf-book-2", [-0.3, 1.25, 0.82], [-0.25, 1.5, 1.1]),
        boxed("shelf-book-3", [0.1, 1.25, 1.22], [0.14, 1.5, 1.5]),
    ];
    for (i, z) in [0.0f32, 0.4, 0.8, 1.2, 1.6].iter().enumerate() {
        o.push(boxed(
            &format!("shelf-board-{i}"),
            [-0.58, 1.2, *z],
            [0.58, 1.58, z + 0.02],
        ));
    }
    for (i, (x, y)) in [(0.57, -0.58), (1.33, -0.58), (0.57, 0.58)]
        .iter()
        .enumerate()
    {
        o.push(boxed(
            &format!("table-leg-{i}"),
            [x - 0.02, y - 0.02, 0.0],
            [x + 0.02, y + 0.02, 0.70],
        ));
    }
    o
}

fn pr2() -> Arc<AgentModel> {
    let path = format!("{}/../../models/pr2.urdf", env!("CARGO_MANIFEST_DIR"));
    Arc::new(AgentModel::from_urdf_file(path).expect("models/pr2.urdf loads"))
}

/// Collision checks of the PR2 in the library scene and a cluttered one, and forward
/// kinematics.
fn bench_collision(c: &mut Criterion) {
    let model = pr2();
    let agent = Arc::new(SelfCollisionModel::new(
        model.clone(),
        &SelfCollisionOptions::default(),
    ));
    let obstacles = Arc::new(StaticObstacles::new(library()));
    let checker = CollisionChecker::new(agent, obstacles, Pose::IDENTITY);
    let random = random_configurations(&model);
    let mut rng = fastrand::Rng::with_seed(42);
    for _ in 0..random.len() {
        model.random_configuration(&mut rng);
    }
    // Collision-free configurations: the worst case, every test runs to the end.
    let mut free = Vec::new();
    while free.len() < 1000 {
        let q = model.random_configuration(&mut rng).into_vec();
        if checker.is_config_free(&q) {
            free.push(q);
        }
    }
    let n_free_random = random.iter().filter(|q| checker.is_config_free(q)).count();
    eprintln!(
        "library scene: {} obstacles; {} of 1000 random configurations are free; {} self pairs checked",
        checker.obstacles().len(),
        n_free_random,
        checker.self_collision_model().checked_pair_count()
    );

    let mut g = c.benchmark_group("collision");
    g.throughput(Throughput::Elements(1000));
    g.bench_function("is_config_free/random_1000", |b| {
        b.iter(|| {
            random
                .iter()
                .filter(|q| checker.is_config_free(black_box(q)))
                .count()
        })
    });
    g.bench_function("is_config_free/free_1000", |b| {
        b.iter(|| {
            free.iter()
                .filter(|q| checker.is_config_free(black_box(q)))
                .count()
        })
    });
    // Arm motion planning: only the right arm moves; the rest is cached.
    let chain = model.chain("right_arm").expect("right_arm");
    // Torso raised so that the arms clear the table top.
    let mut template = model.default_configuration();
    template.set("torso_lift_joint", 0.2).expect("in limits");
    let template = template.into_vec();
    assert!(checker.is_config_free(&template), "template must be free");
    let mut arm_checker = checker.clone();
    arm_checker.set_fixed_joints(&template, &chain.dofs);
    let mut arm_free = Vec::new();
    while arm_free.len() < 1000 {
        let r = model.random_configuration(&mut rng).into_vec();
        let mut q = template.clone();
        for &d in &chain.dofs {
            q[d] = r[d];
        }
        if checker.is_config_free(&q) {
            arm_free.push(q);
        }
    }
    g.bench_function("is_config_free/right_arm_free_1000_full", |b| {
        b.iter(|| {
            arm_free
                .iter()
                .filter(|q| checker.is_config_free(black_box(q)))
                .count()
        })
    });
    g.bench_function("is_config_free/right_arm_free_1000_fixed_joints", |b| {
        b.iter(|| {
            arm_free
                .iter()
                .filter(|q| arm_checker.is_config_free(black_box(q)))
                .count()
        })
    });
    // A cluttered scene: the library plus 300 small boxes around the robot (BVH broad phase).
    let mut clutter = library();
    let mut crng = fastrand::Rng::with_seed(3);
    for i in 0..300 {
        let (x, y, z) = (
            crng.f32() * 6.0 - 3.0,
            crng.f32() * 6.0 - 3.0,
            crng.f32() * 2.0,
        );
        if x.abs() < 1.2 && y.abs() < 1.2 {
            continue; // keep the robot's reach clear enough to have free configurations
        }
        clutter.push(boxed(
            &format!("clutter-{i}"),
            [x, y, z],
            [x + 0.05, y + 0.2, z + 0.25],
        ));
    }
    let n_clutter = clutter.len();
    let clutter_checker = CollisionChecker::new(
        checker.self_collision_model().clone(),
        Arc::new(StaticObstacles::new(clutter)),
        Pose::IDENTITY,
    );
    eprintln!("cluttered scene: {n_clutter} obstacles");
    g.bench_function("is_config_free/cluttered_random_1000", |b| {
        b.iter(|| {
            random
                .iter()
                .filter(|q| clutter_checker.is_config_free(black_box(q)))
                .count()
        })
    });
    g.bench_function("forward_kinematics_1000", |b| {
        let mut poses = Vec::new();
        b.iter(|| {
            for q in &random {
                model.link_poses_into(Pose::IDENTITY, black_box(q), &mut poses);
            }
            poses.len()
        })
    });
    g.finish();
}

/// The first 1000 random configurations of the seeded generator both benchmarks draw from.
fn random_configurations(model: &AgentModel) -> Vec<Vec<f32>> {
    let mut rng = fastrand::Rng::with_seed(42);
    (0..1000)
        .map(|_| model.random_configuration(&mut rng).into_vec())
        .collect()
}

/// Inverse kinematics of the right arm: reachable poses, then failures behind the robot.
fn bench_ik(c: &mut Criterion) {
    let model = pr2();
    let chain = model.chain("right_arm").expect("right_arm");
    let random = random_configurations(&model);
    // Inverse kinematics on reachable poses (FK of random arm configurations).
    let rest = model.default_configuration().into_vec();
    let targets: Vec<Pose> = random
        .iter()
        .take(100)
        .map(|r| {
            let mut q = rest.clone();
            for &d in &chain.dofs {
                q[d] = r[d];
            }
            model.link_pose_by_id(Pose::IDENTITY, &q, chain.tip_link)
        })
        .collect();
    let options = IkOptions::default();
    let mut solved = 0;
    let mut rng = fastrand::Rng::with_seed(1);
    for t in &targets {
        solved += solve_ik(
            &model,
            &chain,
            Pose::IDENTITY,
            &rest,
            *t,
            &options,
            &mut rng,
        )
        .is_ok() as usize;
    }
    eprintln!("ik: {solved} of {} reachable poses solved", targets.len());
    let mut g = c.benchmark_group("ik");
    g.throughput(Throughput::Elements(targets.len() as u64));
    g.sample_size(20);
    g.bench_function("right_arm_pose_100", |b| {
        let mut rng = fastrand::Rng::with_seed(1);
        b.iter(|| {
            targets
                .iter()
                .filter(|t| {
                    solve_ik(
                        &model,
                        &chain,
                        Pose::IDENTITY,
                        &rest,
                        **t,
                        &options,
                        &mut rng,
                    )
                    .is_ok()
                })
                .count()
        })
    });
    // Failures: within the arm's reach distance but behind the robot with the tool pointing
    // forward (what a planner's rejected candidates cost).
    let behind: Vec<Pose> = (0..50)
        .map(|i| {
            let (a, b) = ((i % 5) as f32 / 4.0, (i / 5) as f32 / 9.0);
            Pose::from_translation(Vector::new(-0.7 + 0.2 * a, -0.3 + 0.6 * b, 0.6 + 0.4 * a))
        })
        .collect();
    let mut rng = fastrand::Rng::with_seed(2);
    let solved_behind = behind
        .iter()
        .filter(|t| {
            solve_ik(
                &model,
                &chain,
                Pose::IDENTITY,
                &rest,
                **t,
                &options,
                &mut rng,
            )
            .is_ok()
        })
        .count();
    eprintln!(
        "ik: {solved_behind} of {} poses behind the robot solved",
        behind.len()
    );
    g.throughput(Throughput::Elements(behind.len() as u64));
    g.bench_function("right_arm_behind_50", |b| {
        let mut rng = fastrand::Rng::with_seed(2);
        b.iter(|| {
            behind
                .iter()
                .filter(|t| {
                    solve_ik(
                        &model,
                        &chain,
                        Pose::IDENTITY,
                        &rest,
                        **t,
                        &options,
                        &mut rng,
                    )
                    .is_ok()
                })
                .count()
        })
    });
    g.finish();
}

criterion_group!(benches, bench_collision, bench_ik);
criterion_main!(benches);
