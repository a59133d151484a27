//! Collision truths on constructed cases.

mod common;

use common::{boxed, posture};
use std::sync::Arc;

use geometry::agent::AgentModel;
use geometry::collision::{
    AllowedReason, CollisionChecker, Contact, HeldObject, Obstacle, SelfCollisionModel,
    SelfCollisionOptions, StaticObstacles,
};
use parry3d::math::{Pose, Vector};
use parry3d::shape::SharedShape;

fn model(name: &str) -> Arc<AgentModel> {
    let path = format!("{}/../../models/{name}", env!("CARGO_MANIFEST_DIR"));
    Arc::new(AgentModel::from_urdf_file(&path).unwrap_or_else(|e| panic!("{e}")))
}

fn self_model(name: &str) -> Arc<SelfCollisionModel> {
    Arc::new(SelfCollisionModel::new(
        model(name),
        &SelfCollisionOptions::default(),
    ))
}

fn pr2_checker(obstacles: Vec<Obstacle>) -> CollisionChecker {
    CollisionChecker::new(
        self_model("pr2.urdf"),
        Arc::new(StaticObstacles::new(obstacles)),
        Pose::IDENTITY,
    )
}

/// The right tool frame of the PR2 at the zero configuration, base at the origin.
const R_TOOL: Vector = Vector::new(0.951, -0.188, 0.739675);

#[test]
fn zero_configurations_and_postures_are_free() {
    let c = pr2_checker(vec![]);
    let q = c.model().default_configuration();
    assert_eq!(c.first_collision(q.as_slice()), None);
    let h = self_model("human.urdf");
    let c = CollisionChecker::new(
        h.clone(),
        Arc::new(StaticObstacles::empty()),
        Pose::IDENTITY,
    );
    for name in ["sitting", "standing"] {
        let mut q = h.model().default_configuration();
        q.set_many(&posture(h.model(), name)).unwrap();
        assert_eq!(c.collisions(q.as_slice()), vec![]);
    }
}

#[test]
fn gripper_inside_a_box_collides_and_far_box_is_free() {
    let q = self_model("pr2.urdf").model().default_configuration();
    let c = pr2_checker(vec![boxed("crate", R_TOOL, Vector::splat(0.05))]);
    assert!(!c.is_config_free(q.as_slice()));
    match c.first_collision(q.as_slice()) {
        Some(Contact::Obstacle { link, obstacle }) => {
            assert_eq!(obstacle, "crate");
            assert!(link.starts_with("r_gripper"), "{link}");
        }
        other => panic!("{other:?}"),
    }
    let c = pr2_checker(vec![boxed(
        "crate",
        Vector::new(3.0, 3.0, 0.5),
        Vector::splat(0.3),
    )]);
    assert!(c.is_config_free(q.as_slice()));
}

#[test]
fn table_under_the_arm() {
    let q = self_model("pr2.urdf").model().default_configuration();
    // Upper arm capsule: radius 0.07 around z = 0.739675, so its bottom is at 0.6697.
    let table = |top: f32| {
        boxed(
            "table",
            Vector::new(0.9, 0.0, top / 2.0),
            Vector::new(0.4, 0.6, top / 2.0),
        )
    };
    assert!(pr2_checker(vec![table(0.65)]).is_config_free(q.as_slice()));
    assert!(!pr2_checker(vec![table(0.70)]).is_config_free(q.as_slice()));
    // Moving the base back clears the high table.
    let mut c = pr2_checker(vec![table(0.70)]);
    c.set_base(Pose::from_translation(Vector::new(-1.5, 0.0, 0.0)));
    assert!(c.is_config_free(q.as_slice()));
}

#[test]
fn folded_arm_hits_the_torso() {
    let c = pr2_checker(vec![]);
    let mut q = c.model().default_configuration();
    q.set_many(&[
        ("r_shoulder_pan_joint", 0.7),
        ("r_upper_arm_roll_joint", -std::f32::consts::FRAC_PI_2),
        ("r_elbow_flex_joint", -2.3),
    ])
    .unwrap();
    let all = c.collisions(q.as_slice());
    assert!(
        all.iter()
            .any(|k| matches!(k, Contact::SelfCollision { link_a, link_b }
            if link_a == "torso_lift_link" && link_b.starts_with("r_gripper"))),
        "{all:?}"
    );
    assert!(!c.is_config_free(q.as_slice()));
    // Without self-collision checks the same configuration is free (no obstacles).
    let mut c2 = c.clone();
    c2.set_self_collision(false);
    assert!(c2.is_config_free(q.as_slice()));
    // Unfolded, it is free.
    q.set("r_elbow_flex_joint", 0.0).unwrap();
    q.set("r_shoulder_pan_joint", 0.0).unwrap();
    assert!(c.is_config_free(q.as_slice()));
}

#[test]
fn human_arm_through_the_body_collides() {
    let h = self_model("human.urdf");
    let c = CollisionChecker::new(
        h.clone(),
        Arc::new(StaticObstacles::empty()),
        Pose::IDENTITY,
    );
    let mut q = h.model().default_configuration();
    q.set("r_shoulder_roll_joint", 0.3).unwrap();
    let all = c.collisions(q.as_slice());
    assert!(
        all.contains(&Contact::SelfCollision {
            link_a: "torso_link".into(),
            link_b: "r_upper_arm_link".into()
        }),
        "{all:?}"
    );
}

#[test]
fn held_book_hits_the_table() {
    let m = self_model("pr2.urdf");
    let q = m.model().default_configuration();
    // Table top at 0.64 under the gripper only (the arm itself clears it).
    let table = boxed(
        "table",
        Vector::new(1.1, -0.188, 0.32),
        Vector::new(0.3, 0.4, 0.32),
    );
    let c = CollisionChecker::new(
        m.clone(),
        Arc::new(StaticObstacles::new(vec![table])),
        Pose::IDENTITY,
    );
    assert!(c.is_config_free(q.as_slice()));
    let book = SharedShape::cuboid(0.1, 0.075, 0.05);
    // Hanging 6 cm below the tool frame, the book's bottom is at 0.63: into the table.
    let low = HeldObject::new(
        m.model(),
        "grey-book",
        book.clone(),
        "r_gripper_tool_frame",
        Pose::from_translation(Vector::new(0.0, 0.0, -0.06)),
    )
    .unwrap();
    let c_low = c.clone().with_held_object(low);
    assert_eq!(
        c_low.first_collision(q.as_slice()),
        Some(Contact::HeldObstacle {
            object: "grey-book".into(),
            obstacle: "table".into()
        })
    );
    // Held between the fingers, the book clears the table, and touching the gripper is allowed.
    let held = HeldObject::new(
        m.model(),
        "grey-book",
        book.clone(),
        "r_gripper_tool_frame",
        Pose::IDENTITY,
    )
    .unwrap();
    let touching = held.touching_links(m.model());
    assert!(
        touching.contains(&"r_gripper_palm_link") && touching.contains(&"r_gripper_l_finger_link")
    );
    assert!(!touching.contains(&"r_forearm_link"));
    let c_ok = c.clone().with_held_object(held);
    assert!(
        c_ok.is_config_free(q.as_slice()),
        "{:?}",
        c_ok.collisions(q.as_slice())
    );
    // Held 45 cm back along the arm, the book is around the elbow: it hits the robot.
    let back = HeldObject::new(
        m.model(),
        "grey-book",
        book,
        "r_gripper_tool_frame",
        Pose::from_translation(Vector::new(-0.45, 0.0, 0.0)),
    )
    .unwrap();
    let hits = c.clone().with_held_object(back).collisions(q.as_slice());
    assert!(
        hits.iter().any(|k| matches!(k, Contact::HeldLink { link, .. } if link.starts_with("r_elbow") || link.starts_with("r_forearm") || link.starts_with("r_upper_arm"))),
        "{hits:?}"
    );
}

#[test]
fn adjacent_pairs_skipped_real_pairs_checked() {
    let s = self_model("pr2.urdf");
    assert!(
        !s.is_checked("r_upper_arm_link", "r_elbow_flex_link")
            .unwrap()
    );
    for (a, b) in [
        ("torso_lift_link", "r_upper_arm_link"),
        ("torso_lift_link", "r_gripper_palm_link"),
        ("base_link", "r_forearm_link"),
        ("r_gripper_palm_link", "l_gripper_palm_link"),
        ("r_upper_arm_link", "r_forearm_link"),
        ("head_tilt_link", "l_gripper_l_finger_link"),
    ] {
        assert!(s.is_checked(a, b).unwrap(), "{a} {b}");
    }
    assert!(s.is_checked("no_link", "base_link").is_err());
    // The fingers move relative to each other by one joint only and never touch.
    let fingers = s
        .allowed_pairs()
        .iter()
        .find(|p| p.link_a == "r_gripper_l_finger_link" && p.link_b == "r_gripper_r_finger_link")
        .expect("finger pair allowed");
    assert_eq!(fingers.reason, AllowedReason::Never);
    let h = self_model("human.urdf");
    assert!(h.is_checked("torso_link", "r_upper_arm_link").unwrap());
    assert!(h.is_checked("r_hand_link", "l_hand_link").unwrap());
    assert!(h.is_checked("head_link", "r_hand_link").unwrap());
}

/// Many obstacles (the BVH broad phase) give the same answers as testing every obstacle.
#[test]
fn bvh_broad_phase_agrees_with_brute_force() {
    let m = self_model("pr2.urdf");
    let mut rng = fastrand::Rng::with_seed(11);
    let mut obstacles = Vec::new();
    for i in 0..60 {
        let c = Vector::new(
            rng.f32() * 2.4 - 1.0,
            rng.f32() * 2.4 - 1.2,
            rng.f32() * 1.6,
        );
        let h = Vector::new(
            0.02 + rng.f32() * 0.1,
            0.02 + rng.f32() * 0.1,
            0.02 + rng.f32() * 0.1,
        );
        obstacles.push(boxed(&format!("o{i}"), c, h));
    }
    let set = Arc::new(StaticObstacles::new(obstacles.clone()));
    let mut c = CollisionChecker::new(m.clone(), set, Pose::IDENTITY);
    c.set_self_collision(false);
    let (mut free, mut hit) = (0, 0);
    for _ in 0..200 {
        let q = m.model().random_configuration(&mut rng);
        let brute = m
            .model()
            .posed_shapes(Pose::IDENTITY, q.as_slice())
            .iter()
            .any(|(_, s, p)| {
                obstacles.iter().any(|o| {
                    parry3d::query::intersection_test(p, &*s.shape.0, &o.pose, &*o.shape.0)
                        .unwrap()
                        .intersecting
                })
            });
        assert_eq!(c.is_config_free(q.as_slice()), !brute);
        if brute { hit += 1 } else { free += 1 }
    }
    assert!(free > 10 && hit > 10, "free {free} hit {hit}");
    let fewer = c.obstacles().without(&["o1", "o2"]);
    assert_eq!(fewer.len(), 58);
}

/// With the unmoving joints cached, answers are the same as full checks, including collisions
/// of the unmoving part and configurations that move other joints.
#[test]
fn fixed_joints_cache_gives_the_same_answers() {
    let m = self_model("pr2.urdf");
    let model = m.model().clone();
    let mut template = model.default_configuration();
    template
        .set_many(&[("torso_lift_joint", 0.15), ("l_shoulder_lift_joint", -0.2)])
        .unwrap();
    let template = template.into_vec();
    let left_tool = model
        .link_pose(Pose::IDENTITY, &template, "l_gripper_tool_frame")
        .unwrap()
        .translation;
    let obstacles = Arc::new(StaticObstacles::new(vec![
        boxed(
            "table",
            Vector::new(0.95, 0.0, 0.36),
            Vector::new(0.4, 0.6, 0.36),
        ),
        boxed(
            "book",
            Vector::new(0.8, -0.2, 0.75),
            Vector::new(0.1, 0.07, 0.03),
        ),
        boxed(
            "shelf",
            Vector::new(0.2, 0.9, 0.8),
            Vector::new(0.4, 0.15, 0.8),
        ),
        // Touches the left gripper in the template: an unmoving collision.
        boxed("post", left_tool, Vector::new(0.05, 0.05, 0.05)),
    ]));
    let chain = model.chain("right_arm").unwrap();
    let book = SharedShape::cuboid(0.1, 0.07, 0.03);
    let held =
        HeldObject::new(&model, "book", book, "r_gripper_tool_frame", Pose::IDENTITY).unwrap();
    let full = CollisionChecker::new(m.clone(), obstacles, Pose::IDENTITY).with_held_object(held);
    let mut fast = full.clone();
    fast.set_fixed_joints(&template, &chain.dofs);
    let mut rng = fastrand::Rng::with_seed(21);
    let names = |v: Vec<Contact>| {
        let mut v: Vec<String> = v.iter().map(|c| c.to_string()).collect();
        v.sort();
        v
    };
    let mut free = 0;
    for k in 0..400 {
        let r = model.random_configuration(&mut rng).into_vec();
        let mut q = template.clone();
        for &d in &chain.dofs {
            q[d] = r[d];
        }
        if k % 10 == 0 {
            q[model.dof_index("head_pan_joint").unwrap()] = 0.5; // not a moving joint
        }
        let expected = names(full.collisions(&q));
        assert_eq!(names(fast.collisions(&q)), expected);
        assert_eq!(fast.is_config_free(&q), full.is_config_free(&q));
        assert!(expected.iter().any(|c| c.contains("post")), "{expected:?}");
        let mut without_post = expected.clone();
        without_post.retain(|c| !c.contains("post"));
        free += without_post.is_empty() as usize;
    }
    assert!(free > 20, "free {free}");
}

/// An object in the other gripper is in the moving arm's way: the right gripper meets a book
/// the left gripper holds out in front of it, with or without the fixed-joints cache; the
/// left gripper itself may touch its book.
#[test]
fn what_the_other_gripper_holds_blocks_the_moving_arm() {
    let m = self_model("pr2.urdf");
    let model = m.model().clone();
    let q = model.default_configuration().into_vec();
    let left = model
        .link_pose(Pose::IDENTITY, &q, "l_gripper_tool_frame")
        .unwrap();
    let book = SharedShape::cuboid(0.1, 0.07, 0.03);
    let in_hand = HeldObject::new(
        &model,
        "book",
        book.clone(),
        "l_gripper_tool_frame",
        Pose::IDENTITY,
    )
    .unwrap();
    let mut c = CollisionChecker::new(
        m.clone(),
        Arc::new(StaticObstacles::empty()),
        Pose::IDENTITY,
    );
    c.add_other_held_object(in_hand);
    assert!(c.is_config_free(&q), "{:?}", c.collisions(&q));
    // The same book held out where the right gripper is.
    let out = HeldObject::new(
        &model,
        "book",
        book,
        "l_gripper_tool_frame",
        left.inverse() * Pose::from_translation(R_TOOL),
    )
    .unwrap();
    let mut c = CollisionChecker::new(
        m.clone(),
        Arc::new(StaticObstacles::empty()),
        Pose::IDENTITY,
    );
    c.add_other_held_object(out);
    let hit = |c: &CollisionChecker| {
        c.collisions(&q).into_iter().any(|k| {
            matches!(k, Contact::HeldLink { ref object, ref link } if object == "book" && link.starts_with("r_gripper"))
        })
    };
    assert!(hit(&c), "{:?}", c.collisions(&q));
    let mut fast = c.clone();
    fast.set_fixed_joints(&q, &model.chain("right_arm").unwrap().dofs);
    assert!(hit(&fast) && !fast.is_config_free(&q));
}

/// A book carried in one hand must not pass through the book held in the other (fig4, give,
/// transfer). The two held objects are tested against each other.
#[test]
fn the_two_held_objects_are_checked_against_each_other() {
    let m = self_model("pr2.urdf");
    let model = m.model().clone();
    let q = model.default_configuration().into_vec();
    let tool = |link: &str| model.link_pose(Pose::IDENTITY, &q, link).unwrap();
    let (left, right) = (tool("l_gripper_tool_frame"), tool("r_gripper_tool_frame"));
    // Both books 0.6 m in front of the midpoint of the grippers, 10 mm apart: overlapping.
    let mid = (left.translation + right.translation) * 0.5 + Vector::X * 0.6;
    let held = |link: &str, frame: Pose, dy: f32| {
        let at = Pose::from_translation(mid + Vector::Y * dy);
        HeldObject::new(
            &model,
            link,
            SharedShape::cuboid(0.1, 0.07, 0.03),
            link,
            frame.inverse() * at,
        )
        .unwrap()
    };
    let checker = |dy: f32| {
        let mut c = CollisionChecker::new(
            m.clone(),
            Arc::new(StaticObstacles::empty()),
            Pose::IDENTITY,
        );
        c.set_held_object(Some(held("l_gripper_tool_frame", left, 0.0)));
        c.add_other_held_object(held("r_gripper_tool_frame", right, dy));
        c
    };
    let pair = |c: &CollisionChecker| {
        c.collisions(&q)
            .into_iter()
            .any(|k| matches!(k, Contact::HeldObjects { .. }))
    };
    assert!(pair(&checker(0.01)), "{:?}", checker(0.01).collisions(&q));
    assert!(!pair(&checker(0.2)), "{:?}", checker(0.2).collisions(&q));
}

/// A pair the SRDF's `<disable_collisions>` names is left out, with that reason.
#[test]
fn srdf_disabled_pairs_are_not_checked() {
    let pr2 = model("pr2.urdf");
    let srdf = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/pr2.srdf"))
        .unwrap()
        .replace(
            "</robot>",
            "<disable_collisions link1=\"r_gripper_palm_link\" link2=\"l_gripper_palm_link\" reason=\"test\"/></robot>",
        );
    let with = (*pr2).clone().with_srdf_str(&srdf, "pr2.srdf").unwrap();
    let s = SelfCollisionModel::new(Arc::new(with), &SelfCollisionOptions::default());
    assert!(
        !s.is_checked("r_gripper_palm_link", "l_gripper_palm_link")
            .unwrap()
    );
    let pair = s
        .allowed_pairs()
        .iter()
        .find(|p| p.link_a == "r_gripper_palm_link" && p.link_b == "l_gripper_palm_link")
        .expect("the palms allowed");
    assert_eq!(pair.reason, AllowedReason::Srdf);
}

/// A motion check by conservative advancement agrees with dense sampling: a motion on which
/// 4,000 evenly spaced configurations find a collision is reported, one on which they find
/// none is free, with or without the fixed-joints cache; a 2 mm slab that the arm sweeps
/// through between two free ends is found.
#[test]
fn motion_checks_find_what_dense_sampling_finds() {
    let m = self_model("pr2.urdf");
    let model = m.model().clone();
    let template = model.default_configuration().into_vec();
    let obstacles = common::table_and_slab();
    let chain = model.chain("right_arm").unwrap();
    let book = SharedShape::cuboid(0.1, 0.07, 0.03);
    let held =
        HeldObject::new(&model, "book", book, "r_gripper_tool_frame", Pose::IDENTITY).unwrap();
    let full = CollisionChecker::new(m.clone(), obstacles, Pose::IDENTITY).with_held_object(held);
    let mut fast = full.clone();
    fast.set_fixed_joints(&template, &chain.dofs);
    // Every other motion checked with the fixed-joints cache. (A contact briefer than the
    // sampling's step would be found only by the motion check: none among these.)
    let (hit, free) = common::motions_agree_with_sampling(
        &model,
        (&full, &[&full, &fast]),
        (&template, &chain.dofs),
        (5, 300, 4000),
    );
    assert!(hit > 20 && free > 20, "{hit} colliding, {free} free");
    // The right arm swung through the slab: both ends free, the middle not.
    let swing = |yaw: f32| {
        let mut q = template.clone();
        q[model.dof_index("r_shoulder_pan_joint").unwrap()] = yaw;
        q
    };
    let (a, b) = (swing(-0.1), swing(-0.9));
    assert!(full.is_config_free(&a) && full.is_config_free(&b));
    let c = fast.check_motion(&a, &b, 1e-4);
    assert!(
        matches!(&c.contact, Some(Contact::Obstacle { obstacle, .. }
            | Contact::HeldObstacle { obstacle, .. }) if obstacle == "slab"),
        "{c:?}"
    );
}

/// A base motion checked whole agrees with dense sampling of the base's path (4,000 poses),
/// holding a book; a 2 mm wall the robot drives through between two free poses is found.
#[test]
fn base_motion_checks_find_what_dense_sampling_finds() {
    let m = self_model("pr2.urdf");
    let model = m.model().clone();
    let q = model.default_configuration().into_vec();
    let obstacles = Arc::new(StaticObstacles::new(vec![
        boxed(
            "table",
            Vector::new(2.0, 0.0, 0.36),
            Vector::new(0.4, 0.6, 0.36),
        ),
        boxed(
            "wall",
            Vector::new(0.0, 2.0, 1.0),
            Vector::new(1.5, 0.001, 1.0),
        ),
        boxed(
            "post",
            Vector::new(-1.5, -1.0, 1.0),
            Vector::new(0.1, 0.1, 1.0),
        ),
    ]));
    let book = SharedShape::cuboid(0.1, 0.07, 0.03);
    let held =
        HeldObject::new(&model, "book", book, "r_gripper_tool_frame", Pose::IDENTITY).unwrap();
    let mut checker =
        CollisionChecker::new(m.clone(), obstacles, Pose::IDENTITY).with_held_object(held);
    checker.set_self_collision(false);
    let at = |c: &mut CollisionChecker, p: [f32; 3]| {
        c.set_base(geometry::world::base_pose(p[0], p[1], p[2]));
        c.is_config_free(&q)
    };
    let mut rng = fastrand::Rng::with_seed(9);
    let (mut hit, mut free) = (0, 0);
    let mut probe = checker.clone();
    for k in 0..200 {
        let from = [
            rng.f32() * 4.0 - 2.0,
            rng.f32() * 4.0 - 2.0,
            rng.f32() * 6.0 - 3.0,
        ];
        let to = [
            from[0] + rng.f32() * 2.0 - 1.0,
            from[1] + rng.f32() * 2.0 - 1.0,
            from[2] + rng.f32() * 3.0 - 1.5,
        ];
        if !at(&mut probe, from) {
            continue;
        }
        let sampled = (1..=4000).any(|s| {
            let t = s as f32 / 4000.0;
            !at(
                &mut probe,
                [0, 1, 2].map(|i| from[i] + t * (to[i] - from[i])),
            )
        });
        let found = checker
            .check_base_motion(&q, from, to, 1e-4)
            .contact
            .is_some();
        assert_eq!(
            found, sampled,
            "motion {k}: dense sampling finds a collision: {sampled}"
        );
        if sampled {
            hit += 1;
        } else {
            free += 1;
        }
    }
    assert!(hit > 20 && free > 20, "{hit} colliding, {free} free");
    let (from, to) = ([0.0, 1.2, 0.0], [0.0, 2.8, 0.0]);
    assert!(at(&mut probe, from) && at(&mut probe, to));
    let c = checker.check_base_motion(&q, from, to, 1e-4);
    assert!(
        matches!(&c.contact, Some(Contact::Obstacle { obstacle, .. }
            | Contact::HeldObstacle { obstacle, .. }) if obstacle == "wall"),
        "{c:?}"
    );
}

/// Pair cells (links whose relative pose depends on two joints, such as the upper arm and the
/// forearm two joints down) never free a configuration or a motion that collides: checked
/// against the same checker without them, over random configurations and motions of the right
/// arm and the torso's lift (see `common::pair_cells_are_sound`).
#[test]
fn pair_cells_never_free_a_collision() {
    let with = self_model("pr2.urdf");
    let model = with.model().clone();
    let options = SelfCollisionOptions {
        pair_cells: false,
        ..SelfCollisionOptions::default()
    };
    let without = Arc::new(SelfCollisionModel::new(model.clone(), &options));
    assert!(without.pairs_with_cells().is_empty());
    let pairs = with.pairs_with_cells();
    assert!(
        pairs.contains(&("r_upper_arm_link", "r_forearm_link")),
        "{pairs:?}"
    );
    let checker = |m: &Arc<SelfCollisionModel>| {
        CollisionChecker::new(m.clone(), common::table_and_slab(), Pose::IDENTITY)
    };
    let template = model.default_configuration().into_vec();
    // The right arm and the torso's lift (a prismatic joint under the shoulders).
    let mut dofs = model.chain("right_arm").unwrap().dofs;
    dofs.push(model.dof_index("torso_lift_joint").unwrap());
    common::pair_cells_are_sound(
        &model,
        (&checker(&with), &checker(&without)),
        (&template, &dofs),
        (3, 2000),
    );
}

/// A configuration checked at many base poses answers as the full check at each, but where
/// the robot is within a millimetre of the scene (the exact tests' tolerance band): a grid of
/// poses and headings through a room of furniture, holding a book, in a free posture and in
/// one whose arm hits the torso.
#[test]
fn base_sweeps_answer_as_the_full_check() {
    let m = self_model("pr2.urdf");
    let model = m.model().clone();
    let scene = vec![
        boxed(
            "table",
            Vector::new(1.5, 0.0, 0.36),
            Vector::new(0.4, 0.6, 0.36),
        ),
        boxed(
            "shelf",
            Vector::new(-1.0, 1.2, 0.8),
            Vector::new(0.4, 0.15, 0.8),
        ),
        boxed(
            "wall",
            Vector::new(0.0, -2.0, 1.0),
            Vector::new(3.0, 0.05, 1.0),
        ),
    ];
    let book = SharedShape::cuboid(0.1, 0.07, 0.03);
    let tool = "r_gripper_tool_frame";
    let held = HeldObject::new(&model, "book", book.clone(), tool, Pose::IDENTITY).unwrap();
    let obstacles = Arc::new(StaticObstacles::new(scene.clone()));
    let checker =
        CollisionChecker::new(m.clone(), obstacles, Pose::IDENTITY).with_held_object(held);
    // The robot's and the book's signed distance to the scene (negative: the depth).
    let nearest = |base: Pose, q: &[f32]| {
        let mut parts = geometry::collision::agent_obstacles(&model, base, q, "r");
        let at = model.link_pose(base, q, tool).unwrap();
        parts.push(Obstacle {
            name: "book".into(),
            pose: at,
            shape: book.clone(),
        });
        let pairs = parts.iter().flat_map(|p| scene.iter().map(move |o| (p, o)));
        pairs
            .filter_map(|(p, o)| {
                parry3d::query::contact(&p.pose, &*p.shape.0, &o.pose, &*o.shape.0, 1.0)
                    .unwrap()
                    .map(|c| c.dist)
            })
            .fold(f32::INFINITY, f32::min)
    };
    let free_q = model.default_configuration().into_vec();
    let mut folded = model.default_configuration();
    folded
        .set_many(&[
            ("r_shoulder_pan_joint", 0.7),
            ("r_upper_arm_roll_joint", -std::f32::consts::FRAC_PI_2),
            ("r_elbow_flex_joint", -2.3),
        ])
        .unwrap();
    let folded = folded.into_vec();
    let (mut answers, mut in_band) = ([0usize; 2], 0);
    for q in [&free_q, &folded] {
        let mut sweep = checker.base_sweep(q);
        let mut full = checker.clone();
        for i in -30..=30 {
            for j in -30..=30 {
                let yaw = (i * 7 + j * 3) as f32 * 0.1;
                let base = geometry::world::base_pose(i as f32 * 0.1, j as f32 * 0.1, yaw);
                full.set_base(base);
                let expected = full.is_config_free(q);
                if sweep.is_free_at(base) != expected {
                    let d = nearest(base, q);
                    assert!(
                        d.abs() < 1e-3,
                        "at {i} {j}: {expected} by the full check, {d} m"
                    );
                    in_band += 1;
                }
                answers[expected as usize] += 1;
            }
        }
    }
    // Both answers occur, near the furniture and away from it; the band is thin.
    assert!(answers[0] > 2000 && answers[1] > 500, "{answers:?}");
    assert!(in_band <= 5, "{in_band} answers differ within the band");
}

/// A fork turning about x on a base (two prongs, at z = +-0.06 along x from 0.1 to 0.4), and
/// `more` (URDF elements) beside it, with its self-collision pairs.
fn fork_with(more: &str) -> Arc<SelfCollisionModel> {
    let urdf = format!(
        r#"<robot name="fork">
      <link name="base"/>
      <joint name="turn" type="revolute">
        <parent link="base"/><child link="fork"/><axis xyz="1 0 0"/>
        <limit lower="-3" upper="3" effort="1" velocity="1"/>
      </joint>
      <link name="fork">
        <collision><origin xyz="0.25 0 0.06"/><geometry><box size="0.3 0.04 0.02"/></geometry></collision>
        <collision><origin xyz="0.25 0 -0.06"/><geometry><box size="0.3 0.04 0.02"/></geometry></collision>
      </link>
      {more}
    </robot>"#
    );
    let model = Arc::new(AgentModel::from_urdf_str(&urdf, "fork.urdf").unwrap());
    Arc::new(SelfCollisionModel::new(
        model,
        &SelfCollisionOptions::default(),
    ))
}

/// A link of several shapes is followed against an obstacle as one body until they are
/// near, then shape by shape: a rod along the axis of a turning fork, between its prongs
/// (inside the link's box all along), is never hit; a peg beside the axis is, by a prong.
#[test]
fn a_rod_between_the_prongs_of_a_turning_fork_is_missed_and_a_peg_beside_it_is_hit() {
    let agent = fork_with("");
    let rod = boxed(
        "rod",
        Vector::new(0.25, 0.0, 0.0),
        Vector::new(0.15, 0.01, 0.01),
    );
    let peg = boxed(
        "peg",
        Vector::new(0.25, 0.06, 0.0),
        Vector::new(0.02, 0.005, 0.005),
    );
    let checker = |obstacles: Vec<Obstacle>| {
        CollisionChecker::new(
            agent.clone(),
            Arc::new(StaticObstacles::new(obstacles)),
            Pose::IDENTITY,
        )
    };
    let (a, b) = ([0.0], [2.5]);
    let rod_only = checker(vec![rod.clone()]);
    for q in [0.0, 0.7, 1.6, 2.5] {
        assert!(rod_only.is_config_free(&[q]), "{q}");
    }
    let c = rod_only.check_motion(&a, &b, 1e-4);
    assert!(c.contact.is_none(), "{c:?}");
    let c = checker(vec![rod, peg]).check_motion(&a, &b, 1e-4);
    assert!(
        matches!(&c.contact, Some(Contact::Obstacle { link, obstacle }) if link == "fork" && obstacle == "peg"),
        "{c:?}"
    );
}

/// A near pair of links of several shapes each is followed shape against link, then shape by
/// shape: a fixed rod between the prongs of a turning fork is never hit; the peg beside it, on
/// the same link, is, by a prong.
#[test]
fn the_prongs_of_a_turning_fork_miss_the_links_rod_between_them_and_hit_its_peg() {
    let agent = fork_with(
        r#"<joint name="hold" type="fixed"><parent link="base"/><child link="rod"/></joint>
      <link name="rod">
        <collision><origin xyz="0.25 0 0"/><geometry><box size="0.3 0.02 0.02"/></geometry></collision>
        <collision><origin xyz="0.25 0.06 0"/><geometry><box size="0.04 0.01 0.01"/></geometry></collision>
      </link>"#,
    );
    assert!(agent.is_checked("fork", "rod").unwrap());
    let checker = CollisionChecker::new(agent, Arc::new(StaticObstacles::empty()), Pose::IDENTITY);
    let c = checker.check_motion(&[0.0], &[0.5], 1e-4);
    assert!(c.contact.is_none(), "{c:?}");
    let c = checker.check_motion(&[0.0], &[2.5], 1e-4);
    assert!(
        matches!(&c.contact, Some(Contact::SelfCollision { link_a, link_b })
            if link_a == "fork" && link_b == "rod"),
        "{c:?}"
    );
}

/// A pair's separating axis, kept from one check for the next, never hides a collision: a bar
/// turned from 5 mm beside a post into it is found to hit it, and free again when turned back.
#[test]
fn a_separating_axis_kept_between_checks_never_hides_a_collision() {
    let joint = |name: &str, parent: &str, child: &str| {
        format!(
            r#"<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>
            <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>"#
        )
    };
    // Three joints: the pair's pose depends on more than two, so no cells prove it apart.
    let urdf = format!(
        r#"<robot name="bar">
      <link name="base"/>
      <joint name="mount" type="fixed"><parent link="base"/><child link="post"/><origin xyz="0 0.5 0"/></joint>
      <link name="post"><collision><geometry><box size="0.05 0.05 0.5"/></geometry></collision></link>
      {}<link name="a"/>{}<link name="b"/>{}
      <link name="bar"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.4 0.04 0.04"/></geometry></collision></link>
    </robot>"#,
        joint("ja", "base", "a"),
        joint("jb", "a", "b"),
        joint("jc", "b", "bar")
    );
    let model = Arc::new(AgentModel::from_urdf_str(&urdf, "bar.urdf").unwrap());
    let agent = Arc::new(SelfCollisionModel::new(
        model,
        &SelfCollisionOptions::default(),
    ));
    let checker = CollisionChecker::new(
        agent.clone(),
        Arc::new(StaticObstacles::empty()),
        Pose::IDENTITY,
    );
    let (beside, into) = ([1.4708, 0.0, 0.0], [0.8, 0.7708, 0.0]);
    for _ in 0..3 {
        assert!(checker.is_config_free(&beside));
        assert!(!checker.is_config_free(&into));
        assert!(
            matches!(
                checker.first_collision(&into),
                Some(Contact::SelfCollision { .. })
            ),
            "the bar in the post"
        );
    }
}
