//! Lists the robot's collisions in the scene's start configuration (debugging aid).
use std::sync::Arc;
fn main() {
    let world = geometry::world::World::load(std::env::args().nth(1).unwrap()).unwrap();
    let setup = gtp::robot::RobotSetup::new(&world).unwrap();
    let obstacles = Arc::new(gtp::robot::obstacles(&world, setup.agent, &[]));
    let st = world.agent_state(setup.agent);
    let checker =
        geometry::collision::CollisionChecker::new(setup.self_model.clone(), obstacles, st.base);
    for c in checker.collisions(&st.q) {
        println!("{c}");
    }
    for a in &setup.arms {
        let dof = a.gripper_dof.map(|k| setup.model.dof_names()[k].clone());
        println!(
            "{}: gripper joint {dof:?}, wrist to tool {:.3} m, wrist reach {:.3} m",
            a.name, a.wrist_to_tool, a.wrist_reach
        );
    }
}
