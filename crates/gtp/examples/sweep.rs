//! Runs every task over many seeds and re-checks each first solution (trajectories at 4x finer
//! resolution, thresholds re-measured): `cargo run --release -p gtp --example sweep -- SCENE N`.
use geometry::visibility::{Aim, visibility_for_agent};
use gtp::planner::{CallOptions, Planner};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let world = geometry::world::World::load(&args[0]).unwrap();
    let n: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(30);
    let planner = Planner::new();
    let member = world.agent_id("member").unwrap();
    let tasks: &[(&str, &[&str])] = &[
        ("make-accessible", &["grey-book", "member"]),
        ("show", &["grey-book", "member"]),
        ("give", &["grey-book", "member"]),
        ("put-away", &["grey-book", "member"]),
        ("put-away", &["pos-machine", "member"]),
        ("place-on", &["grey-book", "desk"]),
    ];
    let mut bad = 0;
    for (task, a) in tasks {
        let o = world.object_id(a[0]).unwrap();
        for seed in 1..=n {
            let mut stream = planner
                .run(&world, task, a, &CallOptions::seeded(seed))
                .unwrap();
            let Some(s) = stream.next() else {
                println!(
                    "{task} {a:?} seed {seed}: no solution: {}",
                    stream.failure().unwrap()
                );
                bad += 1;
                continue;
            };
            let res = planner.config().rrt.resolution / 4.0;
            if let Err(e) = gtp::verify::recheck_trajectories(&planner, &world, &s.summary, res) {
                println!("{task} {a:?} seed {seed}: re-check: {e}");
                bad += 1;
            }
            let r = planner.config().visibility_resolution;
            let v = visibility_for_agent(&s.world, member, o, Aim::Current, r)
                .fraction()
                .max(visibility_for_agent(&s.world, member, o, Aim::AtTarget, r).fraction());
            let ok = match *task {
                "make-accessible" => v >= 0.5,
                "show" | "give" => v >= 0.9,
                "put-away" => v <= 0.0,
                _ => true,
            };
            if !ok {
                println!("{task} {a:?} seed {seed}: visibility {v}");
                bad += 1;
            }
        }
    }
    println!("{bad} problems");
}
