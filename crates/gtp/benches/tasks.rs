//! The paper's Table II for the geometric tasks alone: each task called 100 times in the
//! library scene with seeds 1..=100 (first solution of each call), one planner shared by all
//! calls as in a planning session (grasp sets and the robot's self-collision model built once,
//! before the timing). Prints, per task: median, mean and 90th-percentile time, success %, and
//! the means of points tested, grasps tried, orientations tried and trajectory-planner calls.
//!
//! Run: `cargo bench -p gtp --bench tasks` (`GTP_BENCH_CALLS=20` for fewer calls; a task name
//! as argument to run only the tasks containing it). Target: each task's median <= 20 ms.

use geometry::world::World;
use gtp::planner::{CallOptions, Planner};

const PAPER: &[(&str, f64)] = &[
    ("make-accessible", 18.8),
    ("show", 13.3),
    ("give", 10.1),
    ("put-away", 51.0),
];

fn main() {
    let world = World::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../domains/library/scene.toml"
    ))
    .expect("library scene");
    let calls: u64 = std::env::var("GTP_BENCH_CALLS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100);
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let tasks: &[(&str, &[&str])] = &[
        ("make-accessible", &["grey-book", "member"]),
        ("show", &["grey-book", "member"]),
        ("give", &["grey-book", "member"]),
        ("put-away", &["grey-book", "member"]),
        ("put-away", &["pos-machine", "member"]),
        ("pick", &["grey-book"]),
        ("place-on", &["grey-book", "desk"]),
        ("pick-and-make-accessible", &["grey-book", "member"]),
        ("navigate-to", &["white-book"]),
        ("navigate-to", &["desk"]),
    ];
    let planner = Planner::new();
    println!(
        "\nTable II, geometric tasks only: {calls} seeded calls each, library scene, first solution\n"
    );
    println!(
        "| task | median ms | mean ms | p90 ms | succ % | pts | grasps | orts | calls | paper s | paper / ours (median) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for (task, args) in tasks {
        let label = format!("{task}({})", args.join(", "));
        if filter.as_ref().is_some_and(|f| !label.contains(f.as_str())) {
            continue;
        }
        // Warm-up: builds the grasp set and the robot model outside the timing.
        let _ = planner
            .run(&world, task, args, &CallOptions::seeded(0))
            .expect("task")
            .next();
        let mut times = Vec::new();
        let (mut ok, mut pts, mut grasps, mut orts, mut rrt) = (0, 0, 0, 0, 0);
        for seed in 1..=calls {
            let mut stream = planner
                .run(&world, task, args, &CallOptions::seeded(seed))
                .expect("task");
            let solved = stream.next().is_some();
            let st = stream.stats();
            times.push(st.time_s * 1e3);
            ok += solved as usize;
            pts += st.points;
            grasps += st.grasps;
            orts += st.orientations;
            rrt += st.planner_calls;
        }
        times.sort_by(f64::total_cmp);
        let n = times.len() as f64;
        let median = times[times.len() / 2];
        let mean = times.iter().sum::<f64>() / n;
        let p90 = times[((times.len() * 9) / 10).min(times.len() - 1)];
        let paper = PAPER.iter().find(|(t, _)| t == task).map(|p| p.1);
        println!(
            "| {label} | {median:.1} | {mean:.1} | {p90:.1} | {:.0} | {:.1} | {:.1} | {:.1} | {:.1} | {} | {} |",
            100.0 * ok as f64 / n,
            pts as f64 / n,
            grasps as f64 / n,
            orts as f64 / n,
            rrt as f64 / n,
            paper.map_or("-".into(), |p| format!("{p}")),
            paper.map_or("-".into(), |p| format!("{:.0}x", p * 1e3 / median)),
        );
    }
}
