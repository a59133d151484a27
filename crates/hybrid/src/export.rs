//! The plan JSON of `docs/plan-json.md`: the scene, the decomposition tree, and per step the
//! shared literals that changed, the geometric solution and its trajectories with every link's
//! pose per frame (so a viewer needs no kinematics).

use std::collections::BTreeMap;

use geometry::world::World;
use gtp::solution::SolutionSummary;
use htn::planner::Outcome;
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::{ConvexPolyhedron, Cylinder, SharedShape};
use serde_json::{Value, json};

use crate::run::Run;

mod trajectory;

pub use trajectory::{JointTracker, TimingOptions, joint_limits, joint_positions};
use trajectory::{TrajectoryContext, trajectory_json};

/// A pose as `{"t": [x, y, z], "q": [x, y, z, w]}`.
pub fn pose_json(p: Pose) -> Value {
    let (t, q) = (p.translation, p.rotation);
    json!({ "t": short3(t), "q": [short(q.x), short(q.y), short(q.z), short(q.w)] })
}

/// `x` as the shortest decimal that reads back as the same `f32` (`0.85`, where the `f32`
/// widened to `f64` prints as `0.8500000238418579`): a plan JSON is mostly such numbers
/// (about a tenth smaller so); a reader that parses `f32` gets every number bit for bit.
fn short(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// [`short`] of each coordinate.
fn short3(v: Vector) -> [f64; 3] {
    [short(v.x), short(v.y), short(v.z)]
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
        json!({ "box": { "half_extents": short3(h) } })
    } else if let Some(c) = shape.as_capsule() {
        let (a, b) = (c.segment.a, c.segment.b);
        json!({ "capsule": { "a": short3(a), "b": short3(b), "radius": short(c.radius) } })
    } else if let Some(b) = shape.as_ball() {
        json!({ "capsule": { "a": [0.0, 0.0, 0.0], "b": [0.0, 0.0, 0.0], "radius": short(b.radius) } })
    } else if let Some(c) = shape.as_shape::<Cylinder>() {
        // parry's cylinders stand along y, the viewer's along z: a quarter turn about x.
        let turn = Pose::from_parts(
            Vector::ZERO,
            Rotation::from_axis_angle(Vector::X, std::f32::consts::FRAC_PI_2),
        );
        return vec![json!({
            "shape": { "cylinder": { "radius": short(c.radius), "half_height": short(c.half_height) } },
            "pose": pose_json(pose * turn),
        })];
    } else if let Some(m) = shape.as_trimesh() {
        let v: Vec<[f64; 3]> = m.vertices().iter().map(|p| short3(*p)).collect();
        json!({ "mesh": { "vertices": v, "triangles": m.indices() } })
    } else if let Some(m) = shape.as_shape::<ConvexPolyhedron>() {
        let (v, t) = m.to_trimesh();
        let v: Vec<[f64; 3]> = v.iter().map(|p| short3(*p)).collect();
        json!({ "mesh": { "vertices": v, "triangles": t } })
    } else {
        // Every shape the scene and URDF loaders build is one of the above; anything else is
        // shown by its bounding box rather than dropped.
        let aabb = shape.compute_local_aabb();
        let (c, h) = (aabb.center(), aabb.half_extents());
        return vec![json!({
            "shape": { "box": { "half_extents": short3(h) } },
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
    let mut files = MeshFiles::default();
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
                    let mut link = json!({ "name": l.name, "shapes": shapes });
                    if !l.visuals.is_empty() {
                        link["visuals"] = l.visuals.iter().map(|v| files.visual_json(v)).collect();
                    }
                    link
                })
                .collect();
            let name = |l: usize| model.links()[l].name.clone();
            // What the SRDF says the links are for, so that a checker needs no link names.
            let hands: Vec<Value> = a
                .hand_links
                .iter()
                .map(|&h| {
                    let touching: Vec<String> = model.hand_links(h).into_iter().map(name).collect();
                    json!({ "tool_link": name(h), "links": touching })
                })
                .collect();
            json!({
                "name": a.name(),
                "kind": a.kind().to_string(),
                "eye_link": model.links().get(a.eye_link).map(|l| l.name.clone()),
                "head_pivot_link": a.head_pivot_link().map(name),
                "shoulder_links": a.shoulder_links.iter().map(|&l| name(l)).collect::<Vec<_>>(),
                "hands": hands,
                // The link pairs the robot's SRDF says may touch (`<disable_collisions>`): left
                // out of the self-collision checks, as MoveIt leaves them out.
                "disabled_collisions": model.semantics().disabled_collisions,
                "links": links,
                "link_poses": link_poses_json(world, id, world.agent_state(id).link_poses()),
                "urdf": model.urdf(),
                "joint_positions": joint_positions(world, id),
            })
        })
        .collect();
    json!({ "objects": objects, "agents": agents })
}

/// The visual mesh files of a plan, numbered in the order first met: the viewer loads file `n`
/// as `mesh/n.EXT` (`htngtp view` serves exactly these files).
#[derive(Default)]
struct MeshFiles {
    index: BTreeMap<std::path::PathBuf, usize>,
}

impl MeshFiles {
    /// A visual as `{uri, file, source, pose, scale, color?}`.
    fn visual_json(&mut self, v: &geometry::agent::VisualMesh) -> Value {
        let next = self.index.len();
        let n = *self.index.entry(v.path.clone()).or_insert(next);
        let ext = v
            .path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        let mut out = json!({
            "uri": format!("mesh/{n}.{ext}"),
            "file": v.path.display().to_string(),
            "source": v.uri,
            "pose": pose_json(v.local_pose),
            "scale": short3(v.scale),
        });
        if let Some(c) = v.colour {
            out["color"] = json!([short(c[0]), short(c[1]), short(c[2])]);
        }
        out
    }
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

/// The plan JSON of a finished run (see `docs/plan-json.md`), timed with the default
/// [`TimingOptions`].
pub fn plan_json(run: &Run, domain: &str, problem: &str) -> Value {
    plan_json_with(run, domain, problem, &TimingOptions::default())
}

/// The plan JSON of a finished run, its joint trajectories timed with `opts`.
pub fn plan_json_with(run: &Run, domain: &str, problem: &str, opts: &TimingOptions) -> Value {
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
        let mut tracker = JointTracker::of_world(&world);
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
                // The tool link of the arm that last carried an object in this step.
                let mut held_link = None;
                if let Some(s) = summary {
                    for t in &s.trajectories {
                        let arm = robot
                            .as_ref()
                            .filter(|r| world.agent(r.agent).name() == t.agent)
                            .and_then(|r| r.arms.iter().find(|arm| arm.name == t.arm));
                        if let (Some(a), Some(_)) = (arm, &t.held) {
                            held_link = Some(a.tool_link);
                        }
                        let cx = TrajectoryContext {
                            arm,
                            held_link,
                            opts,
                        };
                        let (v, after) = trajectory_json(&world, t, &cx, &mut tracker);
                        trajectories.push(v);
                        world = after;
                    }
                }
                if let Some(after) = run.oracle.solution_world(g.solution) {
                    // The solution's world, with the grippers as the trajectories left them.
                    let fingers: Vec<(geometry::scene::AgentId, usize, f32)> = robot
                        .iter()
                        .flat_map(|r| {
                            r.arms.iter().flat_map(|a| {
                                let fingers =
                                    a.gripper_dof.into_iter().chain(a.gripper_followers.clone());
                                let q = &world.agent_state(r.agent).q;
                                fingers.map(|k| (r.agent, k, q[k])).collect::<Vec<_>>()
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
                });
                // Moved in, not copied by `json!`: the frames are most of a plan.
                gtp["trajectories"] = Value::Array(trajectories);
            }
            let mut step = json!({
                "index": i, "id": a.id, "action": a.name, "args": a.args,
                "added": added, "deleted": deleted,
                "object_poses": moved.clone(),
            });
            step["gtp"] = gtp;
            steps.push(step);
        }
    }
    let mut plan = json!({
        "format": "htngtp-plan",
        "version": 1,
        "domain": domain,
        "problem": problem,
        "status": status,
        "message": message,
        "initial_literals": run.oracle.initial_literals().iter().map(atom_json).collect::<Vec<_>>(),
        "tree": tree,
        "root": root,
        "stats": {
            "nodes": run.result.stats.nodes,
            "htn_backtracks": run.result.stats.htn_backtracks,
            "gtp_backtracks": run.result.stats.geo_backtracks,
            "discrepancy_round": run.result.stats.discrepancy_round,
            "gtp_replays": run.oracle.replays(),
            "time_ms": run.result.stats.time_s * 1e3,
            "gtp_tasks": run.oracle.task_stats(),
        },
    });
    plan["scene"] = scene_json(&run.initial);
    plan["steps"] = Value::Array(steps);
    plan
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn visual_mesh_files_are_numbered_once_each_with_their_extension() {
        let visual = |path: &str, colour| geometry::agent::VisualMesh {
            uri: format!("package://bot/{path}"),
            path: std::path::PathBuf::from(format!("/robots/bot/{path}")),
            local_pose: Pose::from_translation(Vector::new(0.0, 0.0, 0.5)),
            scale: Vector::new(1.0, 1.0, 2.0),
            colour,
        };
        let mut files = MeshFiles::default();
        let a = files.visual_json(&visual("arm.DAE", Some([0.5, 0.25, 1.0, 1.0])));
        let b = files.visual_json(&visual("hand.stl", None));
        let again = files.visual_json(&visual("arm.DAE", None));
        assert_eq!(a["uri"], "mesh/0.dae");
        assert_eq!(b["uri"], "mesh/1.stl");
        assert_eq!(again["uri"], "mesh/0.dae");
        assert_eq!(a["file"], "/robots/bot/arm.DAE");
        assert_eq!(a["source"], "package://bot/arm.DAE");
        assert_eq!(a["scale"], json!([1.0, 1.0, 2.0]));
        assert_eq!(a["pose"]["t"], json!([0.0, 0.0, 0.5]));
        assert_eq!(a["color"], json!([0.5, 0.25, 1.0]));
        assert!(b.get("color").is_none());
    }

    #[test]
    fn numbers_are_written_short_and_read_back_as_the_same_f32() {
        let pose = Pose::from_translation(Vector::new(0.85, -1.01, 1e-7));
        assert_eq!(
            serde_json::to_string(&pose_json(pose)["t"]).unwrap(),
            "[0.85,-1.01,1e-7]"
        );
        let mut rng = fastrand::Rng::with_seed(7);
        for _ in 0..10_000 {
            let x = f32::from_bits(rng.u32(..));
            if x.is_finite() {
                let text = serde_json::to_string(&json!(short(x))).unwrap();
                assert_eq!(text.parse::<f32>().unwrap(), x, "{text}");
            }
        }
    }
}
