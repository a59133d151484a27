//! The real PR2 and Panda of `../shared/robots` (ROS descriptions, collision meshes referenced
//! as `package://`) load with their meshes as convex pieces.

mod common;

use std::path::PathBuf;

use geometry::agent::{AgentModel, ConvexMode, MeshOptions, PackagePath, Primitive};

fn robots() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots")
}

fn load(urdf: &str, modes: &[(&str, ConvexMode)]) -> AgentModel {
    let path = robots().join(urdf);
    let text = std::fs::read_to_string(&path).expect("the URDF reads");
    let options = MeshOptions {
        packages: PackagePath {
            urdf_dir: path.parent().unwrap().to_path_buf(),
            scene_dirs: vec![robots()],
        },
        modes: modes.iter().map(|(l, m)| (l.to_string(), *m)).collect(),
    };
    AgentModel::from_urdf_str_with(&text, &path.display().to_string(), &options)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The real PR2 with the meshes decomposed as the library scenes have them (the right upper
/// arm and forearm, the torso lift link).
fn real_pr2_as_in_the_library() -> AgentModel {
    let decompose = ["r_upper_arm_link", "r_forearm_link", "torso_lift_link"];
    let modes: Vec<(&str, ConvexMode)> = decompose
        .iter()
        .map(|l| (*l, ConvexMode::Decompose))
        .collect();
    load("pr2_description/urdf/robot.xml", &modes)
}

/// The degrees of freedom of the PR2's right arm (its SRDF's chain; the test models carry no
/// SRDF).
fn right_arm(model: &AgentModel) -> Vec<usize> {
    common::PR2_RIGHT_ARM
        .iter()
        .map(|j| model.dof_index(j).unwrap())
        .collect()
}

fn convex_pieces(model: &AgentModel) -> usize {
    model
        .links()
        .iter()
        .flat_map(|l| &l.collisions)
        .filter(|c| matches!(c.primitive, Primitive::Convex { .. }))
        .count()
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn the_real_pr2_loads_with_its_meshes() {
    let pr2 = load("pr2_description/urdf/robot.xml", &[]);
    // 37 mesh collision elements of the URDF, each at least one convex piece.
    assert!(convex_pieces(&pr2) >= 37, "{}", convex_pieces(&pr2));
    let base = pr2.link("base_link").unwrap();
    assert!(matches!(
        base.collisions[0].primitive,
        Primitive::Convex { .. }
    ));
    for l in pr2.links() {
        for c in &l.collisions {
            if let Primitive::Convex { vertices, .. } = c.primitive {
                assert!(vertices >= 4, "{}: {vertices} vertices", l.name);
                assert!(
                    c.bounding_radius > 0.0 && c.bounding_radius < 1.0,
                    "{}",
                    l.name
                );
            }
        }
    }
    // The visual meshes are all present: no warning.
    assert!(pr2.load_warnings().is_empty(), "{:?}", pr2.load_warnings());
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn the_real_panda_loads_with_its_meshes() {
    let panda = load("panda_description/urdf/panda.urdf", &[]);
    assert!(convex_pieces(&panda) >= 11, "{}", convex_pieces(&panda));
    let hand = panda.link("panda_hand").unwrap();
    assert!(!hand.collisions.is_empty());
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn a_link_forced_to_decompose_gives_several_pieces() {
    let hull = load("panda_description/urdf/panda.urdf", &[]);
    let parts = load(
        "panda_description/urdf/panda.urdf",
        &[("panda_link0", ConvexMode::Decompose)],
    );
    assert_eq!(hull.link("panda_link0").unwrap().collisions.len(), 1);
    assert!(parts.link("panda_link0").unwrap().collisions.len() >= 2);
}

/// What the rule made of each collision mesh (run with `--nocapture`).
#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn report_convex_pieces() {
    for urdf in [
        "pr2_description/urdf/robot.xml",
        "panda_description/urdf/panda.urdf",
    ] {
        let t = std::time::Instant::now();
        let m = load(urdf, &[]);
        let (mut pieces, mut vertices) = (0, 0);
        for l in m.links() {
            for c in &l.collisions {
                if let Primitive::Convex {
                    vertices: v,
                    pieces: n,
                } = c.primitive
                {
                    pieces += 1;
                    vertices += v;
                    println!("  {}: piece of {n}, {v} vertices", l.name);
                }
            }
        }
        println!(
            "{urdf}: {} links, {pieces} convex pieces, {vertices} hull vertices, loaded in {:?}",
            m.links().len(),
            t.elapsed()
        );
    }
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn the_real_srdfs_are_read() {
    let pr2 = load("pr2_description/urdf/robot.xml", &[])
        .with_srdf_file(robots().join("pr2_description/srdf/robot.xml"))
        .unwrap_or_else(|e| panic!("{e}"));
    // The end effectors name no parent group: the groups whose chains end at their parent link.
    assert_eq!(pr2.arm_names(), vec!["right_arm", "left_arm"]);
    let s = pr2.semantics();
    assert_eq!(s.virtual_joints[0].1, "planar");
    assert_eq!(
        s.group("arms").unwrap().subgroups,
        vec!["left_arm", "right_arm"]
    );
    let panda = load("panda_description/urdf/panda.urdf", &[])
        .with_srdf_file(robots().join("panda_moveit_config/config/panda.srdf"))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(panda.arm_names(), vec!["panda_arm"]);
    assert_eq!(
        panda.semantics().passive_joints,
        vec!["panda_finger_joint2"]
    );
    assert!(panda.semantics().disabled_collisions.len() >= 30);
}

/// Each collision mesh file's fill of its hull and what the rule made of it (`--nocapture`).
#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn report_fill_ratios() {
    use geometry::agent::convex::convex_mesh;
    for urdf in [
        "pr2_description/urdf/robot.xml",
        "panda_description/urdf/panda.urdf",
    ] {
        let path = robots().join(urdf);
        let text = std::fs::read_to_string(&path).unwrap();
        let packages = PackagePath {
            urdf_dir: path.parent().unwrap().to_path_buf(),
            scene_dirs: vec![robots()],
        };
        let mut seen = std::collections::BTreeSet::new();
        for block in text.split("<collision").skip(1) {
            let block = block.split("</collision>").next().unwrap();
            let Some(start) = block.find("filename=\"") else {
                continue;
            };
            let uri = &block[start + 10..];
            let uri = &uri[..uri.find('"').unwrap()];
            if !seen.insert(uri.to_string()) {
                continue;
            }
            let file = packages.resolve(uri).unwrap();
            let m = convex_mesh(&file, [1.0; 3], ConvexMode::Auto).unwrap();
            let name = file.file_name().unwrap().to_string_lossy();
            let fill = m.fill.map_or("open".to_string(), |f| format!("{f:.2}"));
            println!(
                "{name}: {} triangles, fill {fill}, {} pieces",
                m.triangles,
                m.pieces.len()
            );
        }
    }
}

/// A motion check by conservative advancement on the real PR2 (convex pieces with climbing
/// supports, bounding boxes and balls) agrees with 2,000 evenly spaced configurations: a
/// motion of the right arm on which they find a collision is reported, one on which they
/// find none is free.
#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn motion_checks_on_the_real_pr2_find_what_dense_sampling_finds() {
    use geometry::collision::{CollisionChecker, SelfCollisionModel, SelfCollisionOptions};
    use parry3d::math::Pose;
    use std::sync::Arc;

    let model = Arc::new(real_pr2_as_in_the_library());
    let options = SelfCollisionOptions::default();
    let self_model = Arc::new(SelfCollisionModel::new(model.clone(), &options));
    let mut checker = CollisionChecker::new(self_model, common::table_and_slab(), Pose::IDENTITY);
    let arm = right_arm(&model);
    let template = model.default_configuration().into_vec();
    checker.set_fixed_joints(&template, &arm);
    let (hit, free) = common::motions_agree_with_sampling(
        &model,
        (&checker, &[&checker]),
        (&template, &arm),
        (3, 120, 2000),
    );
    assert!(hit > 5 && free > 5, "{hit} colliding, {free} free");
}

#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn the_real_pr2s_elbow_and_rolling_forearm_are_proven_apart() {
    use geometry::collision::{AllowedReason, SelfCollisionModel, SelfCollisionOptions};
    use std::sync::Arc;

    // The forearm decomposed as the library scenes have it: its pieces pass within 2 mm of
    // the elbow's at some roll angles, where parry's intersection test calls them touching.
    let model = Arc::new(load(
        "pr2_description/urdf/robot.xml",
        &[("r_forearm_link", ConvexMode::Decompose)],
    ));
    let s = SelfCollisionModel::new(model, &SelfCollisionOptions::default());
    let reason = |a: &str, b: &str| {
        s.allowed_pairs()
            .iter()
            .find(|p| (p.link_a == a && p.link_b == b) || (p.link_a == b && p.link_b == a))
            .map(|p| p.reason)
    };
    assert_eq!(
        reason("r_elbow_flex_link", "r_forearm_link"),
        Some(AllowedReason::Never)
    );
    // Two joints apart (the elbow and the roll): still checked.
    assert!(s.is_checked("r_upper_arm_link", "r_forearm_link").unwrap());
}

/// Pair cells never free a collision of the real PR2 (decomposed as the library scenes have
/// it): the upper arm and the forearm roll link in its clevis, a millimetre or two apart at
/// most elbow and roll angles, are the pairs they were made for (see
/// `common::pair_cells_are_sound`).
#[test]
#[ignore = "needs ../shared/robots beside the checkout; .ci/run runs it when present"]
fn pair_cells_never_free_a_collision_of_the_real_pr2() {
    use geometry::collision::{CollisionChecker, SelfCollisionModel, SelfCollisionOptions};
    use parry3d::math::Pose;
    use std::sync::Arc;

    let model = Arc::new(real_pr2_as_in_the_library());
    let checker = |pair_cells: bool| {
        let options = SelfCollisionOptions {
            pair_cells,
            ..SelfCollisionOptions::default()
        };
        let m = Arc::new(SelfCollisionModel::new(model.clone(), &options));
        CollisionChecker::new(m, common::table_and_slab(), Pose::IDENTITY)
    };
    let with = checker(true);
    let pairs = with.self_collision_model().pairs_with_cells();
    assert!(
        pairs.contains(&("r_upper_arm_link", "r_forearm_roll_link")),
        "{pairs:?}"
    );
    let arm = right_arm(&model);
    let template = model.default_configuration().into_vec();
    common::pair_cells_are_sound(
        &model,
        (&with, &checker(false)),
        (&template, &arm),
        (5, 4000),
    );
}
