//! Benchmarks of the world side: one pixel-visibility query at 64x64, the mightability maps of
//! both agents of the library scene, the whole shared-literal table, and a full render.
//!
//! Run: `cargo bench -p geometry --bench world` (add `-- visibility` etc. to pick one).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use geometry::effort::aim_head;
use geometry::facts::{FactParams, effort_table};
use geometry::mightability::{Mightability, MightabilityParams};
use geometry::render::{agent_camera, render};
use geometry::visibility::visibility_from;
use geometry::world::World;

fn library() -> World {
    World::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../domains/library/scene.toml"
    ))
    .expect("library scene")
}

fn bench_visibility(c: &mut Criterion) {
    let world = library();
    let mut g = c.benchmark_group("visibility_64x64");
    for (agent, object) in [
        ("pr2", "grey-book"),
        ("member", "grey-book"),
        ("member", "platform"),
    ] {
        let a = world.agent_id(agent).unwrap();
        let o = world.object_id(object).unwrap();
        let st = world.agent_state(a);
        let mut q = st.q.clone();
        let eye = aim_head(&world, a, st.base, &mut q, world.object_aabb(o).center());
        let fov = world.agent(a).fov;
        g.bench_function(format!("{agent}->{object}"), |b| {
            b.iter(|| black_box(visibility_from(&world, o, &eye, fov, 64)))
        });
    }
    g.finish();
}

fn bench_maps(c: &mut Criterion) {
    let world = library();
    let mut g = c.benchmark_group("mightability");
    g.sample_size(10);
    g.bench_function("both_agents_5cm", |b| {
        b.iter(|| {
            black_box(Mightability::compute(
                &world,
                &MightabilityParams::default(),
            ))
        })
    });
    g.finish();
}

fn bench_facts(c: &mut Criterion) {
    let world = library();
    let mut g = c.benchmark_group("facts");
    g.sample_size(10);
    g.bench_function("effort_table_library", |b| {
        b.iter(|| black_box(effort_table(&world, None, &FactParams::default())))
    });
    g.finish();
}

fn bench_render(c: &mut Criterion) {
    let world = library();
    let a = world.agent_id("member").unwrap();
    let cam = agent_camera(&world, a);
    let mut g = c.benchmark_group("render");
    g.sample_size(10);
    g.bench_function("member_view_320x240", |b| {
        b.iter(|| black_box(render(&world, &cam, 320, 240)))
    });
    g.finish();
}

criterion_group!(
    benches,
    bench_visibility,
    bench_maps,
    bench_facts,
    bench_render
);
criterion_main!(benches);
