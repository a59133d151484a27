//! From JSON text to [`Plan`]: a walk over `serde_json::Value` that knows the path of every
//! value, so a missing key or a wrong type is reported as `steps[3].gtp.trajectories[0].frames[7]...`.

use parry3d::math::{Pose, Rotation, Vector};
use parry3d::shape::SharedShape;
use serde_json::Value;

use crate::error::InputError;
use crate::kinematics::Kinematics;
use crate::model::{
    Agent, AgentKind, Frame, Hand, JointPoint, JointTrajectory, Link, Object, Part, Plan, Step,
    Trajectory,
};

type Res<T> = Result<T, InputError>;

/// A JSON value and the path that leads to it.
#[derive(Clone, Copy)]
struct Node<'a> {
    v: &'a Value,
    path: &'a str,
}

/// The extent of the world: every number of a plan JSON (coordinates, sizes, quaternion
/// components) lies within this many metres of 0, as the planner's scenes do.
pub const EXTENT: f64 = 1000.0;
/// The smallest size of a shape (half extent, radius, half height), in metres.
pub const MIN_SIZE: f32 = 1e-6;

/// Parse the text of a plan file (`file` names it in syntax errors).
pub fn parse_plan(text: &str, file: &str) -> Res<Plan> {
    let v: Value = serde_json::from_str(text).map_err(|e| InputError::Syntax {
        file: file.to_string(),
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })?;
    plan(Node { v: &v, path: "" })
}

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

impl<'a> Node<'a> {
    /// The value under `key`; absent (or null) is an error.
    fn get<T>(self, key: &str, f: impl FnOnce(Node) -> Res<T>) -> Res<T> {
        let path = join(self.path, key);
        match self.v.get(key) {
            Some(v) if !v.is_null() => f(Node { v, path: &path }),
            _ => Err(InputError::Missing { path }),
        }
    }

    /// The value under `key`, `None` when absent or null.
    fn opt<T>(self, key: &str, f: impl FnOnce(Node) -> Res<T>) -> Res<Option<T>> {
        let path = join(self.path, key);
        match self.v.get(key) {
            Some(v) if !v.is_null() => f(Node { v, path: &path }).map(Some),
            _ => Ok(None),
        }
    }

    fn array<T>(self, mut f: impl FnMut(Node) -> Res<T>) -> Res<Vec<T>> {
        let items = self
            .v
            .as_array()
            .ok_or_else(|| InputError::bad(self.path, "expected an array"))?;
        let mut out = Vec::with_capacity(items.len());
        for (i, v) in items.iter().enumerate() {
            let path = format!("{}[{i}]", self.path);
            out.push(f(Node { v, path: &path })?);
        }
        Ok(out)
    }

    /// Key/value pairs of an object, in file order.
    fn entries<T>(self, mut f: impl FnMut(&str, Node) -> Res<T>) -> Res<Vec<T>> {
        let map = self
            .v
            .as_object()
            .ok_or_else(|| InputError::bad(self.path, "expected an object"))?;
        let mut out = Vec::with_capacity(map.len());
        for (k, v) in map {
            let path = join(self.path, k);
            out.push(f(k, Node { v, path: &path })?);
        }
        Ok(out)
    }

    fn str(self) -> Res<String> {
        self.v
            .as_str()
            .map(str::to_string)
            .ok_or_else(|| InputError::bad(self.path, "expected a string"))
    }

    /// A coordinate, size or quaternion component: finite and within [`EXTENT`] (`1e30` or
    /// `1e308`, which f32 makes infinite, would break the collision queries).
    fn f32(self) -> Res<f32> {
        match self.v.as_f64() {
            Some(x) if x.is_finite() && x.abs() <= EXTENT => Ok(x as f32),
            _ => Err(InputError::bad(
                self.path,
                format!("expected a finite number within ±{EXTENT} (metres)"),
            )),
        }
    }

    /// A size: at least [`MIN_SIZE`] (a degenerate shape breaks the collision queries).
    fn positive(self) -> Res<f32> {
        let x = self.f32()?;
        if x >= MIN_SIZE {
            Ok(x)
        } else {
            Err(InputError::bad(
                self.path,
                format!("expected a size of at least {MIN_SIZE} m"),
            ))
        }
    }

    fn floats<const N: usize>(self) -> Res<[f32; N]> {
        let v = self.array(|n| n.f32())?;
        v.try_into()
            .map_err(|_| InputError::bad(self.path, format!("expected {N} numbers")))
    }

    fn vector(self) -> Res<Vector> {
        let [x, y, z] = self.floats::<3>()?;
        Ok(Vector::new(x, y, z))
    }

    fn pose(self) -> Res<Pose> {
        let t = self.get("t", |n| n.vector())?;
        let [x, y, z, w] = self.get("q", |n| n.floats::<4>())?;
        let q = Rotation::from_xyzw(x, y, z, w);
        if q.length() < 1e-6 {
            return Err(InputError::bad(self.path, "zero quaternion"));
        }
        Ok(Pose::from_parts(t, q.normalize()))
    }
}

fn plan(root: Node) -> Res<Plan> {
    let (objects, agents) = root.get("scene", |s| {
        Ok((
            s.get("objects", |n| n.array(object))?,
            s.get("agents", |n| n.array(agent))?,
        ))
    })?;
    let mut p = Plan {
        status: root.opt("status", |n| n.str())?,
        objects,
        agents,
        steps: Vec::new(),
        initial_literals: root.opt("initial_literals", |n| n.array(|l| l.array(|a| a.str())))?,
    };
    p.steps = root.get("steps", |n| n.array(|s| step(s, &p)))?;
    Ok(p)
}

fn object(n: Node) -> Res<Object> {
    let name = n.get("name", |n| n.str())?;
    let movable = n.opt("movable", |n| {
        n.v.as_bool()
            .ok_or_else(|| InputError::bad(n.path, "expected true or false"))
    })?;
    let mut parts = Vec::new();
    if let Some((shape, pose)) = n.opt("shape", shape)? {
        parts.push(Part { shape, pose });
    }
    if let Some(more) = n.opt("parts", |n| n.array(part))? {
        parts.extend(more);
    }
    if parts.is_empty() {
        return Err(InputError::Missing {
            path: join(n.path, "shape"),
        });
    }
    Ok(Object {
        name,
        movable: movable.unwrap_or(false),
        parts,
        pose: n.get("pose", |n| n.pose())?,
    })
}

/// A shape with an optional pose in its owner's frame (an object's part, a link's shape).
fn part(n: Node) -> Res<Part> {
    let (shape, offset) = n.get("shape", shape)?;
    let pose = n.opt("pose", |n| n.pose())?.unwrap_or(Pose::IDENTITY);
    Ok(Part {
        shape,
        pose: pose * offset,
    })
}

/// A shape and the pose that puts parry's primitive where the format means it (parry's
/// cylinders stand along y, the format's along z; a sphere is a capsule with `a == b`).
fn shape(n: Node) -> Res<(SharedShape, Pose)> {
    if let Some(s) = n.opt("box", |b| {
        let [x, y, z] = b.get("half_extents", |n| n.floats::<3>())?;
        if x.min(y).min(z) < MIN_SIZE {
            return Err(InputError::bad(
                b.path,
                format!("half extents must be at least {MIN_SIZE} m"),
            ));
        }
        Ok((SharedShape::cuboid(x, y, z), Pose::IDENTITY))
    })? {
        return Ok(s);
    }
    if let Some(s) = n.opt("cylinder", |c| {
        let r = c.get("radius", |n| n.positive())?;
        let h = c.get("half_height", |n| n.positive())?;
        let turn = Pose::from_rotation(Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2));
        Ok((SharedShape::cylinder(h, r), turn))
    })? {
        return Ok(s);
    }
    if let Some(s) = n.opt("capsule", |c| {
        let a = c.get("a", |n| n.vector())?;
        let b = c.get("b", |n| n.vector())?;
        let r = c.get("radius", |n| n.positive())?;
        Ok(if a.distance(b) < 1e-7 {
            (SharedShape::ball(r), Pose::from_translation(a))
        } else {
            (SharedShape::capsule(a, b, r), Pose::IDENTITY)
        })
    })? {
        return Ok(s);
    }
    if let Some(s) = n.opt("mesh", |m| {
        let pts = m.get("vertices", |n| n.array(|v| v.vector()))?;
        SharedShape::convex_hull(&pts)
            .map(|s| (s, Pose::IDENTITY))
            .ok_or_else(|| InputError::bad(m.path, "the vertices span no volume"))
    })? {
        return Ok(s);
    }
    Err(InputError::bad(
        n.path,
        "expected one of `box`, `cylinder`, `capsule`, `mesh`",
    ))
}

fn agent(n: Node) -> Res<Agent> {
    let name = n.get("name", |n| n.str())?;
    let kind = match n.get("kind", |n| n.str())?.as_str() {
        "robot" => AgentKind::Robot,
        "human" => AgentKind::Human,
        other => {
            return Err(InputError::bad(
                &join(n.path, "kind"),
                format!("`{other}`: expected `robot` or `human`"),
            ));
        }
    };
    let links = n.get("links", |n| {
        n.array(|l| {
            Ok(Link {
                name: l.get("name", |n| n.str())?,
                parts: l.opt("shapes", |n| n.array(part))?.unwrap_or_default(),
            })
        })
    })?;
    let mut a = Agent {
        name,
        kind,
        eye: None,
        head_pivot: None,
        shoulders: Vec::new(),
        hands: Vec::new(),
        disabled: Vec::new(),
        links,
        link_poses: Vec::new(),
        kinematics: None,
        joint_positions: n
            .opt("joint_positions", |n| {
                n.entries(|k, v| Ok((k.to_string(), number(v)?)))
            })?
            .unwrap_or_default()
            .into_iter()
            .collect(),
    };
    if let Some(text) = n.opt("urdf", |n| n.str())? {
        let k =
            Kinematics::from_urdf(&text).map_err(|e| InputError::bad(&join(n.path, "urdf"), e))?;
        a.kinematics = Some(k);
    }
    if let Some(eye) = n.opt("eye_link", |n| n.str())? {
        a.eye = Some(a.link(&eye).ok_or_else(|| {
            InputError::bad(&join(n.path, "eye_link"), format!("no link `{eye}`"))
        })?);
    }
    a.head_pivot = n.opt("head_pivot_link", |n| link_index(n, &a))?;
    a.shoulders = n
        .opt("shoulder_links", |n| n.array(|n| link_index(n, &a)))?
        .unwrap_or_default();
    a.hands = n
        .opt("hands", |n| {
            n.array(|h| {
                Ok(Hand {
                    tool: h.get("tool_link", |n| link_index(n, &a))?,
                    links: h.get("links", |n| n.array(|n| link_index(n, &a)))?,
                })
            })
        })?
        .unwrap_or_default();
    a.disabled = n
        .opt("disabled_collisions", |n| {
            n.array(|pair| {
                let names = pair.array(|n| link_index(n, &a))?;
                match names[..] {
                    [i, j] => Ok((i, j)),
                    _ => Err(InputError::bad(pair.path, "expected two link names")),
                }
            })
        })?
        .unwrap_or_default();
    a.link_poses = n.get("link_poses", |n| link_poses(n, &a))?;
    Ok(a)
}

/// The index of the link `n` names in agent `a`.
fn link_index(n: Node, a: &Agent) -> Res<usize> {
    let name = n.str()?;
    a.link(&name)
        .ok_or_else(|| InputError::bad(n.path, format!("no link `{name}`")))
}

/// A complete set of link poses, in the agent's link order.
fn link_poses(n: Node, a: &Agent) -> Res<Vec<Pose>> {
    let mut out: Vec<Option<Pose>> = vec![None; a.links.len()];
    n.entries(|k, v| {
        let i = a
            .link(k)
            .ok_or_else(|| InputError::bad(v.path, format!("`{}` has no link `{k}`", a.name)))?;
        out[i] = Some(v.pose()?);
        Ok(())
    })?;
    out.into_iter()
        .zip(&a.links)
        .map(|(p, l)| {
            p.ok_or_else(|| InputError::Missing {
                path: join(n.path, &l.name),
            })
        })
        .collect()
}

fn step(n: Node, p: &Plan) -> Res<Step> {
    let index = n.get("index", |n| {
        n.v.as_u64()
            .map(|i| i as usize)
            .ok_or_else(|| InputError::bad(n.path, "expected a step index"))
    })?;
    let literals = |n: Node| n.array(|l| l.array(|a| a.str()));
    let mut s = Step {
        index,
        action: n.get("action", |n| n.str())?,
        added: n.opt("added", literals)?.unwrap_or_default(),
        deleted: n.opt("deleted", literals)?.unwrap_or_default(),
        target: None,
        trajectories: Vec::new(),
        object_poses: Vec::new(),
    };
    if let Some((target, trajs)) = n.opt("gtp", |g| gtp(g, p))? {
        s.target = target;
        s.trajectories = trajs;
    }
    s.object_poses = n
        .opt("object_poses", |n| {
            n.entries(|k, v| Ok((object_index(p, k, v.path)?, v.pose()?)))
        })?
        .unwrap_or_default();
    Ok(s)
}

fn object_index(p: &Plan, name: &str, path: &str) -> Res<usize> {
    p.object(name)
        .ok_or_else(|| InputError::bad(path, format!("no object `{name}` in the scene")))
}

fn gtp(g: Node, p: &Plan) -> Res<(Option<usize>, Vec<Trajectory>)> {
    let args = g.opt("args", |n| n.array(|a| a.str()))?.unwrap_or_default();
    let target = args.first().and_then(|name| p.object(name));
    let trajs = g.opt("trajectories", |n| n.array(|t| trajectory(t, p)))?;
    Ok((target, trajs.unwrap_or_default()))
}

fn trajectory(n: Node, p: &Plan) -> Res<Trajectory> {
    let name = n.get("agent", |n| n.str())?;
    let agent = p
        .agent(&name)
        .ok_or_else(|| InputError::bad(&join(n.path, "agent"), format!("no agent `{name}`")))?;
    let holding = n.opt("holding", |h| object_index(p, &h.str()?, h.path))?;
    let a = &p.agents[agent];
    let frames = n.get("frames", |n| {
        n.array(|f| {
            Ok(Frame {
                link_poses: f.get("link_poses", |n| link_poses(n, a))?,
                held_pose: f.opt("held_pose", |n| n.pose())?,
                time: f.opt("t", number)?,
            })
        })
    })?;
    if frames.is_empty() {
        return Err(InputError::bad(&join(n.path, "frames"), "no frames"));
    }
    Ok(Trajectory {
        agent,
        label: n.opt("label", |n| n.str())?.unwrap_or_default(),
        holding,
        frames,
        joint_trajectory: n.opt("joint_trajectory", joint_trajectory)?,
    })
}

/// A finite number (a joint value, velocity, limit or time).
fn number(n: Node) -> Res<f64> {
    match n.v.as_f64() {
        Some(x) if x.is_finite() => Ok(x),
        _ => Err(InputError::bad(n.path, "expected a finite number")),
    }
}

/// A list of `len` finite numbers.
fn numbers(n: Node, len: usize) -> Res<Vec<f64>> {
    let v = n.array(number)?;
    if v.len() != len {
        return Err(InputError::bad(
            n.path,
            format!(
                "expected {len} numbers (one per joint name), found {}",
                v.len()
            ),
        ));
    }
    Ok(v)
}

fn joint_trajectory(n: Node) -> Res<JointTrajectory> {
    let joint_names = n.get("joint_names", |n| n.array(|s| s.str()))?;
    let len = joint_names.len();
    let limits = |n: Node| {
        let v = numbers(n, len)?;
        if v.iter().any(|x| *x <= 0.0) {
            return Err(InputError::bad(n.path, "expected positive limits"));
        }
        Ok(v)
    };
    let velocity_limits = n.get("velocity_limits", limits)?;
    let acceleration_limits = n.get("acceleration_limits", limits)?;
    let waypoints = n.opt("waypoints", |n| n.array(|w| numbers(w, len)))?;
    let points = n.get("points", |n| {
        n.array(|p| {
            Ok(JointPoint {
                positions: p.get("positions", |n| numbers(n, len))?,
                velocities: p.get("velocities", |n| numbers(n, len))?,
                time: p.get("time_from_start", number)?,
                gripper: p.opt("gripper_position", number)?,
            })
        })
    })?;
    Ok(JointTrajectory {
        joint_names,
        velocity_limits,
        acceleration_limits,
        waypoints,
        gripper_joint: n.opt("gripper_joint", |n| n.str())?,
        gripper_followers: n
            .opt("gripper_followers", |n| n.array(|n| n.str()))?
            .unwrap_or_default(),
        points,
    })
}
