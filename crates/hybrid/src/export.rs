//! The plan JSON of `docs/plan-json.md`: the scene, the decomposition tree, and per step the
//! shared literals that changed, the geometric solution and its trajectories with every link's
//! pose per frame (so a viewer needs no kinematics).

use std::collections::BTreeMap;

use geometry::world::World;
use gtp::solution::{SolutionSummary, Trajectory};
use htn::planner::Outcome;
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::{ConvexPolyhedron, Cylinder, SharedShape};
use serde_json::{Value, json};

use crate::run::Run;
use crate::timing;

/// Largest joint change between two frames of an exported trajectory (radians or metres).
const FRAME_STEP: f32 = 0.04;

/// A pose as `{"t": [x, y, z], "q": [x, y, z, w]}`.
pub fn pose_json(p: Pose) -> Value {
    let (t, q) = (p.translation, p.rotation);
    json!({ "t": [t.x, t.y, t.z], "q": [q.x, q.y, q.z, q.w] })
}

/// The pieces of `shape` placed at `pose`, each `{shape, pose}` in the viewer's vocabulary
/// (box, cylinder along z, capsule, mesh).
pub fn shape_parts(shape: &SharedShape, pose: Pose) -> Vec<Value> {
    if let Some(c) = shape.as_compound() {
        return c
            .shapes()
            .iter()
            .flat_map(|(p, s)| shape_parts(s, pose * *p))
            .collect();
    }
    let described = if let Some(b) = shape.as_cuboid() {
        let h = b.half_extents;
        json!({ "box": { "half_extents": [h.x, h.y, h.z] } })
    } else if let Some(c) = shape.as_capsule() {
        let (a, b) = (c.segment.a, c.segment.b);
        json!({ "capsule": { "a": [a.x, a.y, a.z], "b": [b.x, b.y, b.z], "radius": c.radius } })
    } else if let Some(b) = shape.as_ball() {
        json!({ "capsule": { "a": [0.0, 0.0, 0.0], "b": [0.0, 0.0, 0.0], "radius": b.radius } })
    } else if let Some(c) = shape.as_shape::<Cylinder>() {
        // parry's cylinders stand along y, the viewer's along z: a quarter turn about x.
        let turn = Pose::from_parts(
            Vector::ZERO,
            Rotation::from_axis_angle(Vector::X, std::f32::consts::FRAC_PI_2),
        );
        return vec![json!({
            "shape": { "cylinder": { "radius": c.radius, "half_height": c.half_height } },
            "pose": pose_json(pose * turn),
        })];
    } else if let Some(m) = shape.as_trimesh() {
        let v: Vec<[f32; 3]> = m.vertices().iter().map(|p| [p.x, p.y, p.z]).collect();
        json!({ "mesh": { "vertices": v, "triangles": m.indices() } })
    } else if let Some(m) = shape.as_shape::<ConvexPolyhedron>() {
        let (v, t) = m.to_trimesh();
        let v: Vec<[f32; 3]> = v.iter().map(|p| [p.x, p.y, p.z]).collect();
        json!({ "mesh": { "vertices": v, "triangles": t } })
    } else {
        // Every shape the scene and URDF loaders build is one of the above; anything else is
        // shown by its bounding box rather than dropped.
        let aabb = shape.compute_local_aabb();
        let (c, h) = (aabb.center(), aabb.half_extents());
        return vec![json!({
            "shape": { "box": { "half_extents": [h.x, h.y, h.z] } },
            "pose": pose_json(pose * Pose::from_translation(c)),
        })];
    };
    vec![json!({ "shape": described, "pose": pose_json(pose) })]
}

fn colour(c: [u8; 3]) -> Value {
    json!([
        c[0] as f32 / 255.0,
        c[1] as f32 / 255.0,
        c[2] as f32 / 255.0
    ])
}

/// The scene part of the plan JSON: objects and agents of `world`.
pub fn scene_json(world: &World) -> Value {
    let objects: Vec<Value> = world
        .object_ids()
        .map(|id| {
            let o = world.object(id);
            json!({
                "name": o.name,
                "movable": o.movable,
                "color": colour(o.colour),
                "parts": shape_parts(&o.shape, o.shape_offset),
                "pose": pose_json(world.object_pose(id)),
            })
        })
        .collect();
    let agents: Vec<Value> = world
        .agent_ids()
        .map(|id| {
            let a = world.agent(id);
            let model = &a.model;
            let links: Vec<Value> = model
                .links()
                .iter()
                .map(|l| {
                    let shapes: Vec<Value> = l
                        .collisions
                        .iter()
                        .flat_map(|c| shape_parts(&c.shape, c.local_pose))
                        .map(|mut v| {
                            v["color"] = colour(a.spec.colour);
                            v
                        })
                        .collect();
                    json!({ "name": l.name, "shapes": shapes })
                })
                .collect();
            json!({
                "name": a.name(),
                "kind": a.kind().to_string(),
                "eye_link": model.links().get(a.eye_link).map(|l| l.name.clone()),
                "links": links,
                "link_poses": link_poses_json(world, id, world.agent_state(id).link_poses()),
            })
        })
        .collect();
    json!({ "objects": objects, "agents": agents })
}

fn link_poses_json(world: &World, agent: geometry::scene::AgentId, poses: &[Pose]) -> Value {
    let model = &world.agent(agent).model;
    let map: serde_json::Map<String, Value> = model
        .links()
        .iter()
        .zip(poses)
        .map(|(l, p)| (l.name.clone(), pose_json(*p)))
        .collect();
    Value::Object(map)
}

/// The frames of one trajectory, starting from the agent's configuration in `world`: every
/// link's pose and the held object's pose per frame. Returns the world with the agent at the
/// trajectory's end.
/// The gripper moves to the trajectory's opening over its first frames (from where the world
/// has it), so that frames join up across trajectories and steps.
const GRIPPER_FRAMES: usize = 5;

fn trajectory_json(world: &World, t: &Trajectory, arm: Option<&gtp::robot::Arm>) -> (Value, World) {
    let mut world = world.clone();
    let Some(agent) = world.agent_id(&t.agent) else {
        return (Value::Null, world);
    };
    let model = world.agent(agent).model.clone();
    // What a held object follows: the robot arm's tool frame, else the tip of the agent's chain
    // of that name (a person's hand).
    let tool_link = arm
        .map(|a| a.tool_link)
        .or_else(|| attached_link(&world, agent, t))
        .or_else(|| model.chain(&t.arm).ok().map(|c| c.tip_link));
    let dof: Vec<Option<usize>> = t
        .joints
        .iter()
        .map(|j| model.dof_names().iter().position(|n| n == j))
        .collect();
    // Densify: consecutive waypoints are straight joint-space segments.
    let mut points: Vec<Vec<f32>> = Vec::new();
    for w in t.waypoints.windows(2) {
        let d = w[0]
            .iter()
            .zip(&w[1])
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        let n = ((d / FRAME_STEP).ceil() as usize).clamp(1, 60);
        for k in 0..n {
            let s = k as f32 / n as f32;
            points.push(
                w[0].iter()
                    .zip(&w[1])
                    .map(|(a, b)| a + (b - a) * s)
                    .collect(),
            );
        }
    }
    if let Some(last) = t.waypoints.last() {
        points.push(last.clone());
    }
    let mut frames = Vec::with_capacity(points.len());
    // The gripper's joint: from its value in the world to the trajectory's opening.
    let gripper = arm.and_then(|a| a.gripper_dof).map(|k| {
        let from = world.agent_state(agent).q[k];
        let to = model.dof_limits()[k].clamp(t.gripper_opening / 2.0);
        (k, from, to)
    });
    for (j, p) in points.iter().enumerate() {
        let state = world.agent_state(agent);
        let (mut base, mut q) = (state.base, state.q.clone());
        if let Some((k, from, to)) = gripper {
            let s = (j as f32 / GRIPPER_FRAMES as f32).min(1.0);
            q[k] = from + (to - from) * s;
        }
        let (mut bx, mut by, mut byaw) = (base.translation.x, base.translation.y, None);
        for (i, v) in p.iter().enumerate() {
            match (
                t.joints.get(i).map(String::as_str),
                dof.get(i).copied().flatten(),
            ) {
                (Some("base_x"), _) => bx = *v,
                (Some("base_y"), _) => by = *v,
                (Some("base_yaw"), _) => byaw = Some(*v),
                (_, Some(d)) => q[d] = *v,
                _ => {}
            }
        }
        if t.joints.iter().any(|j| j.starts_with("base_")) {
            // Base poses are pure turns about z.
            let yaw = byaw.unwrap_or_else(|| 2.0 * base.rotation.z.atan2(base.rotation.w));
            base = geometry::world::base_pose(bx, by, yaw);
        }
        world.set_agent_config(agent, base, &q);
        let poses = world.agent_state(agent).link_poses();
        let held = match (&t.held, tool_link) {
            (Some(h), Some(link)) => pose_json(poses[link] * Pose::from(h.object_in_tool)),
            _ => Value::Null,
        };
        frames.push(
            json!({ "link_poses": link_poses_json(&world, agent, poses), "held_pose": held }),
        );
    }
    let value = json!({
        "agent": t.agent,
        "label": t.phase,
        "holding": t.held.as_ref().map(|h| h.object.clone()),
        "frames": frames,
        "joint_trajectory": joint_trajectory_json(&model, t),
    });
    (value, world)
}

/// The velocity and acceleration limits of the joint `name` of `model`: the planar base's
/// defaults for `base_x`, `base_y` and `base_yaw`, else the URDF's velocity limit (or
/// [`timing::DEFAULT_JOINT_VELOCITY`] where it declares none) and its URDF 1.2 acceleration
/// limit (or [`timing::DEFAULT_JOINT_ACCELERATION`], as for the shipped models).
fn joint_limits(model: &geometry::agent::AgentModel, name: &str) -> (f64, f64) {
    match name {
        "base_x" | "base_y" => (
            timing::BASE_LINEAR_VELOCITY,
            timing::BASE_LINEAR_ACCELERATION,
        ),
        "base_yaw" => (
            timing::BASE_ANGULAR_VELOCITY,
            timing::BASE_ANGULAR_ACCELERATION,
        ),
        _ => {
            let dof = model.dof_index(name).ok();
            (
                dof.and_then(|d| model.dof_velocity_limit(d))
                    .map_or(timing::DEFAULT_JOINT_VELOCITY, f64::from),
                dof.and_then(|d| model.dof_acceleration_limit(d))
                    .map_or(timing::DEFAULT_JOINT_ACCELERATION, f64::from),
            )
        }
    }
}

/// The timed joint trajectory of `t` (see `docs/plan-json.md`): its waypoints joined by
/// rest-to-rest trapezoidal profiles within each joint's limits. `null` when the waypoints
/// cannot be timed (mismatched lengths or non-finite values, which the planner never writes).
fn joint_trajectory_json(model: &geometry::agent::AgentModel, t: &Trajectory) -> Value {
    let (velocity, acceleration): (Vec<f64>, Vec<f64>) =
        t.joints.iter().map(|j| joint_limits(model, j)).unzip();
    let waypoints: Vec<Vec<f64>> = t
        .waypoints
        .iter()
        .map(|w| w.iter().map(|&x| f64::from(x)).collect())
        .collect();
    let Ok(points) = timing::time_path(&waypoints, &velocity, &acceleration) else {
        return Value::Null;
    };
    let points: Vec<Value> = points
        .into_iter()
        .map(|p| {
            json!({
                "positions": p.positions,
                "velocities": p.velocities,
                "time_from_start": p.time,
            })
        })
        .collect();
    json!({
        "agent": t.agent,
        "group": t.arm,
        "joint_names": t.joints,
        "velocity_limits": velocity,
        "acceleration_limits": acceleration,
        "waypoints": waypoints,
        "points": points,
    })
}

/// The link of `agent` that the object `t` carries is attached to in `world` (a drive carries
/// what the grippers hold).
fn attached_link(world: &World, agent: geometry::scene::AgentId, t: &Trajectory) -> Option<usize> {
    let o = world.object_id(&t.held.as_ref()?.object)?;
    world
        .attachment(o)
        .filter(|a| a.agent == agent)
        .map(|a| a.link)
}

/// The plan JSON of a finished run (see `docs/plan-json.md`).
pub fn plan_json(run: &Run, domain: &str, problem: &str) -> Value {
    let (status, message) = match &run.result.outcome {
        Outcome::Found { .. } => ("solved", Value::Null),
        Outcome::Unsolvable => ("unsolvable", json!(run.failure_message())),
        Outcome::LimitReached { limit } => ("limit", json!(format!("stopped by the {limit}"))),
    };
    let mut tree = Vec::new();
    let mut steps = Vec::new();
    let mut root = Vec::new();
    if let Outcome::Found { plan } = &run.result.outcome {
        root = plan.root.clone();
        for d in &plan.decompositions {
            tree.push(json!({ "id": d.id, "task": d.task, "args": d.args, "method": d.method, "children": d.subtasks }));
        }
        let mut world = run.initial.clone();
        let robot = run.oracle.planner().robot(&world).ok();
        let mut moved: BTreeMap<String, Value> = BTreeMap::new();
        for (i, a) in plan.actions.iter().enumerate() {
            tree.push(json!({ "id": a.id, "action": a.name, "args": a.args, "step": i }));
            let mut gtp = Value::Null;
            let (mut added, mut deleted) = (Vec::new(), Vec::new());
            if let Some(g) = &a.geometric {
                added = g.add.iter().map(atom_json).collect();
                deleted = g.delete.iter().map(atom_json).collect();
                let summary = run.oracle.solution_summary(g.solution);
                let mut trajectories = Vec::new();
                if let Some(s) = summary {
                    for t in &s.trajectories {
                        let arm = robot
                            .as_ref()
                            .filter(|r| world.agent(r.agent).name() == t.agent)
                            .and_then(|r| r.arms.iter().find(|arm| arm.name == t.arm));
                        let (v, after) = trajectory_json(&world, t, arm);
                        trajectories.push(v);
                        world = after;
                    }
                }
                if let Some(after) = run.oracle.solution_world(g.solution) {
                    // The solution's world, with the grippers as the trajectories left them.
                    let fingers: Vec<(geometry::scene::AgentId, usize, f32)> = robot
                        .iter()
                        .flat_map(|r| {
                            r.arms.iter().filter_map(|a| {
                                a.gripper_dof
                                    .map(|k| (r.agent, k, world.agent_state(r.agent).q[k]))
                            })
                        })
                        .collect();
                    world = after.clone();
                    for (agent, k, v) in fingers {
                        let st = world.agent_state(agent);
                        let (base, mut q) = (st.base, st.q.clone());
                        q[k] = v;
                        world.set_agent_config(agent, base, &q);
                    }
                    for id in world.object_ids() {
                        let o = world.object(id);
                        if o.movable {
                            moved.insert(o.name.clone(), pose_json(world.object_pose(id)));
                        }
                    }
                }
                gtp = json!({
                    "task": g.task,
                    "args": g.args,
                    "summary": summary.map(summary_line),
                    "stats": summary.map(|s| json!({
                        "time_ms": s.stats.time_s * 1e3,
                        "points": s.stats.points,
                        "grasps": s.stats.grasps,
                        "orientations": s.stats.orientations,
                        "planner_calls": s.stats.planner_calls,
                    })),
                    "trajectories": trajectories,
                });
            }
            steps.push(json!({
                "index": i, "id": a.id, "action": a.name, "args": a.args,
                "added": added, "deleted": deleted, "gtp": gtp,
                "object_poses": moved.clone(),
            }));
        }
    }
    json!({
        "format": "htngtp-plan",
        "version": 1,
        "domain": domain,
        "problem": problem,
        "status": status,
        "message": message,
        "scene": scene_json(&run.initial),
        "initial_literals": run.oracle.initial_literals().iter().map(atom_json).collect::<Vec<_>>(),
        "tree": tree,
        "root": root,
        "steps": steps,
        "stats": {
            "nodes": run.result.stats.nodes,
            "htn_backtracks": run.result.stats.htn_backtracks,
            "gtp_backtracks": run.result.stats.geo_backtracks,
            "time_ms": run.result.stats.time_s * 1e3,
            "gtp_tasks": run.oracle.task_stats(),
        },
    })
}

fn atom_json(a: &htn::oracle::GroundAtom) -> Value {
    let mut v = vec![a.predicate.clone()];
    v.extend(a.args.iter().cloned());
    json!(v)
}

/// The short account of a solution shown per GS action: grasp, placement, visibility reached,
/// trajectory length.
pub fn summary_line(s: &SolutionSummary) -> Value {
    json!({
        "grasp": s.grasp.as_ref().map(|g| format!("{} grasp {}, jaw {:.3} m", g.arm, g.id.map(|i| i.to_string()).unwrap_or("(held)".into()), g.width)),
        "placement": s.placement.as_ref().map(|p| format!(
            "{} at ({:.2}, {:.2}, {:.2}), face {}, yaw {}",
            p.support.clone().unwrap_or_else(|| "in hand".into()),
            p.point[0], p.point[1], p.point[2], p.orientation, p.yaw_index)),
        "visibility": s.visibility,
        "reach_effort": s.reach_effort,
        "trajectory_length": s.trajectories.iter().map(|t| t.length).sum::<f32>(),
        "effort_level": s.effort_level,
    })
}
