use gtp::solution::Phase;
use htn::planner::{Outcome, PlannerOptions, Strategy};
use hybrid::{RunOptions, plan_files};
use std::path::Path;

#[test]
fn scratch() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../domains/library");
    let mut options = RunOptions::default();
    options.planner = PlannerOptions {
        strategy: Strategy::Chronological,
        seed: 1,
        ..PlannerOptions::default()
    };
    options.oracle.seed = 1;
    let run = plan_files(
        &dir.join("domain.hddl"),
        &dir.join("lend-and-debit.hddl"),
        &dir.join("scene.toml"),
        &options,
    )
    .unwrap();
    let Outcome::Found { plan } = &run.result.outcome else {
        panic!()
    };
    let planner = run.oracle.planner();
    let mut before = &run.initial;
    for a in &plan.actions {
        let Some(g) = &a.geometric else { continue };
        let summary: gtp::solution::SolutionSummary =
            serde_json::from_value(g.payload["summary"].clone()).unwrap();
        let setup = planner.robot(before).unwrap();
        let mut w = before.clone();
        let desk = w.object_id("desk").unwrap();
        for t in &summary.trajectories {
            if t.phase != Phase::Return {
                continue;
            }
            let arm = setup.arms.iter().find(|x| x.name == t.arm).unwrap();
            let mut q = w.agent_state(setup.agent).q.clone();
            gtp::robot::set_opening(&setup.model, arm, &mut q, t.gripper_opening);
            let base = w.agent_state(setup.agent).base;
            let path = gtp::rrt::JointPath {
                waypoints: t.waypoints.clone(),
            };
            for (k, qa) in path.densify(&arm.space, 0.01).iter().enumerate() {
                gtp::robot::set_arm_values(arm, &mut q, qa);
                w.set_agent_config(setup.agent, base, &q);
                let poses = w.agent_state(setup.agent).link_poses().to_vec();
                if k % 20 == 0 {
                    let f = setup
                        .model
                        .links()
                        .iter()
                        .position(|l| l.name == "r_gripper_r_finger_link")
                        .unwrap();
                    eprintln!(
                        "{} k={k} finger {:?} q={:?}",
                        a.name, poses[f].translation, qa
                    );
                }
                for (li, l) in setup.model.links().iter().enumerate() {
                    for c in &l.collisions {
                        let p = poses[li] * c.local_pose;
                        let dp = w.object_shape_pose(desk);
                        if let Ok(Some(ct)) =
                            parry3d::query::contact(&p, &*c.shape, &dp, &*w.object(desk).shape, 0.0)
                        {
                            if ct.dist < -0.002 {
                                eprintln!("{} k={k} {} vs desk depth {}", a.name, l.name, -ct.dist);
                            }
                        }
                    }
                }
            }
        }
        before = run.oracle.solution_world(&g.payload).unwrap();
    }
}
