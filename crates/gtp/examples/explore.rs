//! Runs one task in a scene and prints the outcome: `cargo run -p gtp --example explore --
//! SCENE TASK ARG... [--n N]`.
use gtp::planner::{CallOptions, Planner};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let world = geometry::world::World::load(&args[0]).expect("scene");
    let planner = Planner::new();
    let rest: Vec<&str> = args[2..].iter().map(String::as_str).collect();
    let t = std::time::Instant::now();
    let mut stream = planner
        .run(&world, &args[1], &rest, &CallOptions::default())
        .expect("task");
    for i in 0..3 {
        match stream.next() {
            Some(s) => {
                let sm = &s.summary;
                println!(
                    "#{i} level {} grasp {:?} placement {:?} vis {:?} reach {:?}",
                    sm.effort_level,
                    sm.grasp.as_ref().map(|g| (g.id, g.arm.clone())),
                    sm.placement.as_ref().map(|p| (
                        p.point,
                        p.support.clone(),
                        p.orientation,
                        p.yaw_index
                    )),
                    sm.visibility,
                    sm.reach_effort
                );
                println!("   trajectories {:?}", sm.trajectory_lengths());
            }
            None => {
                println!("failure: {}", stream.failure().unwrap());
                break;
            }
        }
        println!("   stats {:?} ({:?})", stream.stats(), t.elapsed());
    }
}
