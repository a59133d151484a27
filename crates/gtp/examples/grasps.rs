//! Prints the grasps of a box: `cargo run -p gtp --example grasps -- HX HY HZ`.
fn main() {
    let a: Vec<f32> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    let b = parry3d::shape::Cuboid::new(parry3d::math::Vector::new(a[0], a[1], a[2]));
    let set = gtp::grasp::generate_grasps(&b, &gtp::grasp::GraspParams::default()).unwrap();
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
