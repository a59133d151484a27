//! Prints the grasps of a box for a robot's gripper:
//! `cargo run -p gtp --example grasps -- HX HY HZ [URDF SRDF ARM]` (default: the PR2's right arm).
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let models = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/");
    let urdf = args.get(3).cloned().unwrap_or(format!("{models}pr2.urdf"));
    let srdf = args.get(4).cloned().unwrap_or(format!("{models}pr2.srdf"));
    let arm = args.get(5).map_or("right_arm", String::as_str);
    let model = geometry::agent::AgentModel::from_urdf_file(urdf)
        .and_then(|m| m.with_srdf_file(srdf))
        .unwrap();
    let gripper = gtp::gripper::GripperModel::of_named_arm(&model, arm).unwrap();
    let a: Vec<f32> = args.iter().take(3).map(|s| s.parse().unwrap()).collect();
    let b = parry3d::shape::Cuboid::new(parry3d::math::Vector::new(a[0], a[1], a[2]));
    let set =
        gtp::grasp::generate_grasps(&b, &gtp::grasp::GraspParams::default(), &gripper).unwrap();
    println!(
        "{} grasps, {} pairs, {} colliding",
        set.grasps.len(),
        set.antipodal_pairs,
        set.colliding
    );
    for g in &set.grasps {
        let t = g.tool_in_object.translation;
        let x = g.tool_in_object.rotation * parry3d::math::Vector::X;
        println!(
            "{:.3} at ({:.3} {:.3} {:.3}) approach ({:.2} {:.2} {:.2}) w {:.3}",
            g.score, t.x, t.y, t.z, x.x, x.y, x.z, g.width
        );
    }
}
