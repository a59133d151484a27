//! Full-robot collision checks per second, side by side: the hand-written `models/pr2.urdf`
//! (boxes, cylinders, capsules) and the real PR2 of `../shared/robots` (ROS's description,
//! links colliding as convex pieces of their meshes: by the rule of `geometry::agent::convex`,
//! and as hulls only), in the library-like obstacle set of the `collision` bench.
//!
//! Run: `cargo bench -p geometry --bench real_robot` (the real PR2 is left out, with a
//! message, when `../shared/robots` is absent). Throughput is per configuration.

use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use geometry::agent::{AgentModel, ConvexMode, MeshOptions, PackagePath};
use geometry::collision::{
    CollisionChecker, Obstacle, SelfCollisionModel, SelfCollisionOptions, StaticObstacles,
};
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

/// A table with two books in front of the robot, a desk, a shelf, walls and the floor.
fn library() -> Vec<Obstacle> {
    vec![
        boxed("floor", [-4.0, -4.0, -0.1], [4.0, 4.0, -0.001]),
        boxed("wall-back", [-3.0, 2.5, 0.0], [3.0, 2.6, 2.5]),
        boxed("table-top", [0.55, -0.6, 0.70], [1.35, 0.6, 0.74]),
        boxed("grey-book", [0.70, -0.30, 0.74], [0.92, -0.14, 0.78]),
        boxed("white-book", [0.80, 0.15, 0.74], [1.00, 0.31, 0.77]),
        boxed("desk", [1.8, -1.0, 0.0], [2.4, 1.0, 1.05]),
        boxed("shelf-left", [-0.6, 1.2, 0.0], [-0.58, 1.6, 1.8]),
        boxed("shelf-right", [0.58, 1.2, 0.0], [0.6, 1.6, 1.8]),
        boxed("shelf-back", [-0.6, 1.58, 0.0], [0.6, 1.6, 1.8]),
        boxed("shelf-board", [-0.58, 1.2, 0.8], [0.58, 1.58, 0.82]),
    ]
}

fn robots() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots")
}

/// The real PR2, its meshes made by the rule, or all as hulls.
fn real_pr2(hulls_only: bool) -> Option<AgentModel> {
    let path = robots().join("pr2_description/urdf/robot.xml");
    let text = std::fs::read_to_string(&path).ok()?;
    let mut options = MeshOptions {
        packages: PackagePath {
            urdf_dir: path.parent()?.to_path_buf(),
            scene_dirs: vec![robots()],
        },
        ..MeshOptions::default()
    };
    let load = |o: &MeshOptions| {
        AgentModel::from_urdf_str_with(&text, &path.display().to_string(), o)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let model = load(&options);
    if !hulls_only {
        return Some(model);
    }
    options.modes = model
        .links()
        .iter()
        .map(|l| (l.name.clone(), ConvexMode::Hull))
        .collect();
    Some(load(&options))
}

fn hand_written() -> AgentModel {
    let path = format!("{}/../../models/pr2.urdf", env!("CARGO_MANIFEST_DIR"));
    AgentModel::from_urdf_file(path).expect("models/pr2.urdf loads")
}

/// Collision-free configurations in path order, as a planner's edge check visits them: ten
/// straight segments of 100 steps, each from a free configuration 0.3 rad per joint (at most)
/// towards a random direction, every step free.
fn free_paths(
    checker: &CollisionChecker,
    free: &[Vec<f32>],
    rng: &mut fastrand::Rng,
) -> Vec<Vec<f32>> {
    let mut path = Vec::new();
    for start in free {
        if path.len() == 1000 {
            break;
        }
        let delta: Vec<f32> = start.iter().map(|_| (rng.f32() - 0.5) * 0.6).collect();
        let segment: Vec<Vec<f32>> = (0..100)
            .map(|k| {
                let t = k as f32 / 99.0;
                start.iter().zip(&delta).map(|(a, d)| a + t * d).collect()
            })
            .collect();
        if segment.iter().all(|q| checker.is_config_free(q)) {
            path.extend(segment);
        }
    }
    path
}

/// A checker for `model` and its random configurations: 1000 drawn, and 1000 collision-free.
fn setup(model: AgentModel) -> (CollisionChecker, Vec<Vec<f32>>, Vec<Vec<f32>>) {
    let model = Arc::new(model);
    let agent = Arc::new(SelfCollisionModel::new(
        model.clone(),
        &SelfCollisionOptions::default(),
    ));
    let checker = CollisionChecker::new(
        agent,
        Arc::new(StaticObstacles::new(library())),
        Pose::IDENTITY,
    );
    let mut rng = fastrand::Rng::with_seed(42);
    let random: Vec<Vec<f32>> = (0..1000)
        .map(|_| model.random_configuration(&mut rng).into_vec())
        .collect();
    let mut free = Vec::new();
    for _ in 0..200_000 {
        if free.len() == 1000 {
            break;
        }
        let q = model.random_configuration(&mut rng).into_vec();
        if checker.is_config_free(&q) {
            free.push(q);
        }
    }
    (checker, random, free)
}

fn bench_models(c: &mut Criterion) {
    let mut models = vec![("hand_written", hand_written())];
    match (real_pr2(false), real_pr2(true)) {
        (Some(rule), Some(hulls)) => {
            models.push(("real_meshes", rule));
            models.push(("real_hulls_only", hulls));
        }
        _ => eprintln!("../shared/robots absent: the real PR2 is left out"),
    }
    let mut g = c.benchmark_group("pr2_models");
    g.throughput(Throughput::Elements(1000));
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(3));
    for (name, model) in models {
        let shapes: usize = model.links().iter().map(|l| l.collisions.len()).sum();
        let (checker, random, free) = setup(model);
        let path = free_paths(&checker, &free, &mut fastrand::Rng::with_seed(7));
        eprintln!(
            "{name}: {shapes} collision shapes, {} self pairs checked, {} of 1000 random \
             configurations free, {} free configurations found, {} on free paths",
            checker.self_collision_model().checked_pair_count(),
            random.iter().filter(|q| checker.is_config_free(q)).count(),
            free.len(),
            path.len()
        );
        g.bench_function(format!("{name}/random_1000"), |b| {
            b.iter(|| {
                random
                    .iter()
                    .filter(|q| checker.is_config_free(black_box(q)))
                    .count()
            })
        });
        g.bench_function(format!("{name}/free_1000"), |b| {
            b.iter(|| {
                free.iter()
                    .filter(|q| checker.is_config_free(black_box(q)))
                    .count()
            })
        });
        g.bench_function(format!("{name}/path_1000"), |b| {
            b.iter(|| {
                path.iter()
                    .filter(|q| checker.is_config_free(black_box(q)))
                    .count()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_models);
criterion_main!(benches);
