//! A robot's gripper as collision boxes in its tool frame, for the planner's cheap pre-checks
//! (a grasp against its object, the gripper at a placement, on an approach or a retreat) before
//! any inverse kinematics.
//!
//! The boxes come from the robot's own model ([`GripperModel::of_arm`]): the collision shapes of
//! the links of the arm's SRDF end effector (the links of its group's joints and the link they
//! hang from: the palm and the fingers), placed in the tool frame by the URDF's joints with the
//! fingers where a jaw opening puts them (the finger joint at the value whose gap between the
//! pads, measured over the joint's range, is the opening, as [`crate::robot::set_opening`]
//! drives it; half the opening for sliding fingers whose pads meet closed). A box shape is its own
//! box; any other shape (a mesh's convex pieces) is boxed by its bounding box in the tool frame
//! where the opening puts it, which only widens the pre-check, and stays tight as a turning
//! finger swings (the bounding box of the finger's own frame, turned with it, would reach across
//! the jaws and out beyond the finger).
//!
//! Convention (a gripper tool frame as ROS robots define it): x points forward out of the palm (the
//! approach direction), y is the axis along which the two fingers close, z completes the frame.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use geometry::agent::{AgentModel, Joint, JointKind};
use geometry::collision::HullBounds;
use parry3d::math::{Pose, Vector};
use parry3d::query;
use parry3d::shape::{Cuboid, Shape, SharedShape};

/// The widest jaw opening the planner uses (metres), whatever a gripper allows: the objects of
/// the shipped scenes are shaped for it (the PR2's 9 cm). Opened wider, the Fetch-like robot's
/// gripper (10 cm) hits the shelf beside the POS machine it takes (`htngtp gtp
/// domains/library/scene-fetch.toml pick pos-machine` finds no grasp). A gripper that opens
/// less is used to its own limit.
pub const OPENING_CAP: f32 = 0.09;

/// The widest gap (metres) between a sliding finger's pads at its closed end for which its
/// value is taken as half the opening; pads farther apart (Baxter's, 1.8 cm) are measured.
const SLIDING_PADS_MEET: f32 = 0.002;

/// A gripper's boxes (pose in the tool frame, half extents) per jaw opening (its bits).
type BoxesByOpening = HashMap<u32, Vec<(Pose, Cuboid)>>;

/// The most jaw openings whose boxes a gripper keeps (the grasp widths of a scene's objects
/// are far fewer).
const MAX_CACHED_OPENINGS: usize = 4096;

/// A collision shape of a gripper link, as the pre-check boxes it: a box shape is its own
/// (oriented) box; any other shape is boxed where the opening puts it, by its bounding box in
/// the tool frame (`shape`, at `in_link`), which stays tight as a turning finger swings.
#[derive(Clone, Debug)]
struct LinkBox {
    in_link: Pose,
    cuboid: Cuboid,
    /// The shape itself when it is not a box.
    shape: Option<SharedShape>,
    /// For a large hull, its bounding boxes without visiting every vertex.
    bounds: Option<HullBounds>,
}

/// How a joint between the gripper's root and one of its links takes its value from the
/// opening: the gripper's joint (or one mimicking it) at `multiplier * value + offset`, `value`
/// the finger joint's ([`GripperModel::joint_value`]),
/// any other joint at its value in the model's default configuration (`multiplier` 0).
#[derive(Clone, Debug)]
struct PathJoint {
    joint: Joint,
    multiplier: f32,
    offset: f32,
}

/// One link of the gripper with geometry: the joints from the gripper's root down to it, and
/// its boxes.
#[derive(Clone, Debug)]
struct GripperLink {
    path: Vec<PathJoint>,
    boxes: Vec<LinkBox>,
}

/// The gripper of one arm, read from the robot's URDF and SRDF; see the module docs.
#[derive(Clone, Debug)]
pub struct GripperModel {
    /// The tool frame's joints from the gripper's root (fixed ones, as a rule).
    tool_path: Vec<PathJoint>,
    links: Vec<GripperLink>,
    /// The widest jaw opening the planner uses: the model's ([`GripperModel::model_opening`]),
    /// at most [`OPENING_CAP`] (metres; 0 without a gripper joint, a person's hand).
    pub max_opening: f32,
    /// The finger joint's limits as an opening, to clamp openings to.
    opening_range: (f32, f32),
    /// (jaw gap, finger joint value) pairs from the narrowest gap to the widest, measured
    /// between the fingers' boxes over the joint's range (from its lower limit or from its
    /// upper, whichever closes the jaws), for a turning finger (the PR2's) and for a sliding one
    /// whose pads stand apart closed (Baxter's, 1.8 cm); empty for other sliding fingers and
    /// without fingers on both sides of the jaws: the joint's value is then half the opening.
    gaps: Vec<(f32, f32)>,
    /// A key of the dimensions (what depends on the gripper's shape, as grasp sets, is cached
    /// by it).
    key: u64,
    /// The boxes per jaw opening (its bits) already computed, for grippers with shapes boxed
    /// where the opening puts them (their bounding boxes visit every vertex of a mesh).
    by_opening: Option<Arc<Mutex<BoxesByOpening>>>,
}

impl GripperModel {
    /// The gripper at the end of arm chain `arm` of `model`, with its tool frame at `tool_link`
    /// and its finger joint at configuration index `dof` (none for a person's hand). The links:
    /// those of the arm's SRDF end-effector group (its `link`s, its joints' child links with what
    /// hangs from them) and the links its joints hang from (the palm); without an end effector,
    /// the tool frame's nearest link with geometry and what hangs from it (a person's hand).
    pub fn of_arm(
        model: &AgentModel,
        arm: &str,
        tool_link: usize,
        (dof, followers): (Option<usize>, &[usize]),
    ) -> GripperModel {
        let links = effector_links(model, arm, tool_link);
        let root = common_root(model, &links, tool_link);
        let q = model.default_configuration().into_vec();
        let path = |link: usize| joint_path(model, root, link, (dof, followers), &q);
        let boxes = links
            .iter()
            .map(|&l| GripperLink {
                path: path(l),
                boxes: link_boxes(model, l),
            })
            .filter(|l| !l.boxes.is_empty())
            .collect();
        let range = dof.map_or((0.0, 0.0), |k| {
            let lim = model.dof_limits()[k];
            (2.0 * lim.lower.max(0.0), 2.0 * lim.upper.max(0.0))
        });
        let mut gripper = GripperModel {
            tool_path: path(tool_link),
            links: boxes,
            max_opening: range.1.min(OPENING_CAP),
            opening_range: range,
            gaps: Vec::new(),
            key: 0,
            by_opening: None,
        };
        if let Some(k) = dof {
            let sliding = model.joints()[model.dof_joint(k)].kind == JointKind::Prismatic;
            gripper.measure_gaps(model.dof_limits()[k], sliding);
        }
        gripper.key = gripper.dimensions_key();
        if gripper
            .links
            .iter()
            .any(|l| l.boxes.iter().any(|b| b.shape.is_some()))
        {
            gripper.by_opening = Some(Arc::default());
        }
        gripper
    }

    /// The gripper of the model's arm `arm` (an SRDF group with a chain and an end effector):
    /// its tool frame the chain's tip, its finger joint the end effector group's first joint
    /// that mimics none, as the planner's [`crate::robot::RobotSetup`] reads them.
    pub fn of_named_arm(model: &AgentModel, arm: &str) -> Result<GripperModel, String> {
        let chain = model.chain(arm).map_err(|e| e.to_string())?;
        let (dof, followers) = finger_dofs(model, arm);
        Ok(GripperModel::of_arm(
            model,
            arm,
            chain.tip_link,
            (dof, &followers),
        ))
    }

    /// The boxes (in the tool frame) with the jaws `opening` metres apart, clamped to the
    /// finger joint's range.
    pub fn at(&self, opening: f32) -> Gripper {
        let opening = opening.clamp(self.opening_range.0, self.opening_range.1);
        let Some(cache) = &self.by_opening else {
            let boxes = self.boxes_at_value(self.joint_value(opening));
            return Gripper { boxes, opening };
        };
        let mut cache = cache.lock().unwrap_or_else(|e| e.into_inner());
        if cache.len() >= MAX_CACHED_OPENINGS {
            cache.clear();
        }
        let boxes = cache
            .entry(opening.to_bits())
            .or_insert_with(|| self.boxes_at_value(self.joint_value(opening)))
            .clone();
        Gripper { boxes, opening }
    }

    /// The finger joint's value for a jaw opening: the value whose measured gap is the opening
    /// (interpolated); half the opening where the gap was not measured.
    pub fn joint_value(&self, opening: f32) -> f32 {
        let Some(&(first_gap, first)) = self.gaps.first() else {
            return opening / 2.0;
        };
        if opening <= first_gap {
            return first;
        }
        for w in self.gaps.windows(2) {
            let ((g0, v0), (g1, v1)) = (w[0], w[1]);
            if opening <= g1 {
                let t = if g1 > g0 {
                    (opening - g0) / (g1 - g0)
                } else {
                    1.0
                };
                return v0 + t * (v1 - v0);
            }
        }
        self.gaps.last().map_or(first, |&(_, v)| v)
    }

    /// The jaw opening of finger joint value `value`: the inverse of
    /// [`GripperModel::joint_value`] (the measured gap at the value, interpolated; twice the
    /// value where the gap was not measured), within the opening range.
    pub fn opening_at(&self, value: f32) -> f32 {
        let (lo, hi) = self.opening_range;
        if self.gaps.is_empty() {
            return (2.0 * value).clamp(lo, hi);
        }
        for w in self.gaps.windows(2) {
            let ((g0, v0), (g1, v1)) = (w[0], w[1]);
            let (vmin, vmax) = (v0.min(v1), v0.max(v1));
            if (vmin..=vmax).contains(&value) && v1 != v0 {
                return g0 + (value - v0) / (v1 - v0) * (g1 - g0);
            }
        }
        // Past the measured values: the nearer end's gap.
        let (first, last) = (self.gaps[0], self.gaps[self.gaps.len() - 1]);
        if (value - first.1).abs() <= (value - last.1).abs() {
            first.0
        } else {
            last.0
        }
    }

    /// Whether the gripper's own collision shapes (not their boxes: a linkage's pieces, boxed,
    /// reach into the jaws), the jaws `opening` apart and the tool at `tool`, meet `shape` at
    /// `pose`; shape pairs parry cannot test count as meeting.
    pub fn shapes_meet(&self, opening: f32, tool: &Pose, shape: &dyn Shape, pose: &Pose) -> bool {
        let opening = opening.clamp(self.opening_range.0, self.opening_range.1);
        let value = self.joint_value(opening);
        let to_tool = *tool * pose_along(&self.tool_path, value).inverse();
        self.links.iter().any(|link| {
            let at_link = to_tool * pose_along(&link.path, value);
            link.boxes.iter().any(|b| {
                let meet = |at: &Pose, own: &dyn Shape| {
                    query::intersection_test(at, own, pose, shape)
                        .map(|hit| hit.intersecting)
                        .unwrap_or(true)
                };
                // A hull is tested where its box meets the shape (the box test is cheap).
                let (boxed, cuboid) = b.at(at_link);
                meet(&boxed, &cuboid)
                    && match (&b.shape, &b.bounds) {
                        (Some(own), bounds) => {
                            let at = at_link * b.in_link;
                            bounds
                                .as_ref()
                                .and_then(|h| h.intersects(&at, shape, pose))
                                .unwrap_or_else(|| meet(&at, &**own))
                        }
                        (None, _) => true,
                    }
            })
        })
    }

    /// The boxes in the tool frame with the finger joint at `value`.
    fn boxes_at_value(&self, value: f32) -> Vec<(Pose, Cuboid)> {
        let to_tool = pose_along(&self.tool_path, value).inverse();
        let mut boxes = Vec::new();
        for link in &self.links {
            let pose = to_tool * pose_along(&link.path, value);
            boxes.extend(link.boxes.iter().map(|b| b.at(pose)));
        }
        boxes
    }

    /// Measures the finger joint's jaw gap over its range (`gaps`), and sets the opening range
    /// and the widest opening from it. The gap is along the tool frame's y (the closing axis)
    /// between the inner faces of the boxes that move with the joint, those on +y against those
    /// on -y; without boxes on both sides the joint's value is taken as half the opening.
    fn measure_gaps(&mut self, limits: geometry::agent::JointLimits, sliding: bool) {
        const STEPS: usize = 64;
        let mut measured: Vec<(f32, f32)> = Vec::with_capacity(STEPS + 1);
        for i in 0..=STEPS {
            let value = limits.lower + (limits.upper - limits.lower) * i as f32 / STEPS as f32;
            let Some(gap) = self.finger_gap(value) else {
                return;
            };
            measured.push((gap, value));
        }
        // The jaws open as the value grows (the PR2's) or as it falls (a Robotiq 2F-85's
        // knuckle closes them as it grows): walk from the value of the narrower end.
        if measured[STEPS].0 < measured[0].0 {
            measured.reverse();
        }
        let mut gaps: Vec<(f32, f32)> = Vec::with_capacity(STEPS + 1);
        for (gap, value) in measured {
            // Keep the gap growing: a joint past its widest is not used.
            if gaps.last().is_none_or(|&(g, _)| gap > g) {
                gaps.push((gap, value));
            }
        }
        // Sliding fingers whose pads meet closed keep their joint's convention (the value is
        // half the opening; the shipped models leave a millimetre between their pads).
        if sliding
            && gaps
                .first()
                .is_some_and(|&(closed, _)| closed <= SLIDING_PADS_MEET)
        {
            return;
        }
        if let (Some(&(lo, _)), Some(&(hi, _))) = (gaps.first(), gaps.last()) {
            self.opening_range = (lo.max(0.0), hi.max(0.0));
            self.max_opening = self.opening_range.1.min(OPENING_CAP);
            self.gaps = gaps;
        }
    }

    /// The gap between the fingertips' inner faces along the tool frame's y with the finger
    /// joint at `value`: on each side (+y, -y) the moving box that reaches furthest forward
    /// (along x, the approach), the pad that closes on the object; `None` without moving boxes
    /// on both sides.
    fn finger_gap(&self, value: f32) -> Option<f32> {
        let to_tool = pose_along(&self.tool_path, value).inverse();
        // Per side: (forward reach, inner face).
        let (mut left, mut right) = (None::<(f32, f32)>, None::<(f32, f32)>);
        for link in self
            .links
            .iter()
            .filter(|l| l.path.iter().any(|p| p.multiplier != 0.0))
        {
            let pose = to_tool * pose_along(&link.path, value);
            for b in &link.boxes {
                let (at, cuboid) = b.at(pose);
                let aabb = cuboid.compute_aabb(&at);
                let (side, face) = if aabb.center().y >= 0.0 {
                    (&mut left, aabb.mins.y)
                } else {
                    (&mut right, aabb.maxs.y)
                };
                if side.is_none_or(|(reach, _)| aabb.maxs.x > reach) {
                    *side = Some((aabb.maxs.x, face));
                }
            }
        }
        let (left, right) = (left?.1, right?.1);
        Some(left - right)
    }

    /// The widest jaw opening of the model: the measured gap at the finger joint's widest
    /// end, or twice its upper limit where the gap is not measured.
    pub fn model_opening(&self) -> f32 {
        self.opening_range.1
    }

    /// A key of the gripper's dimensions: two grippers with the same key have the same boxes
    /// at every opening.
    pub fn key(&self) -> u64 {
        self.key
    }

    fn dimensions_key(&self) -> u64 {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        let (lo, hi) = self.opening_range;
        let openings = [lo, 0.5 * (lo + hi), hi];
        for o in openings {
            for (pose, cuboid) in self.at(o).boxes {
                let p = pose.translation;
                let r = pose.rotation;
                let e = cuboid.half_extents;
                for x in [p.x, p.y, p.z, r.x, r.y, r.z, r.w, e.x, e.y, e.z] {
                    x.to_bits().hash(&mut h);
                }
            }
            o.to_bits().hash(&mut h);
        }
        h.finish()
    }
}

/// The links of the arm's gripper: see [`GripperModel::of_arm`].
fn effector_links(model: &AgentModel, arm: &str, tool_link: usize) -> Vec<usize> {
    let sem = model.semantics();
    let group = sem
        .end_effector(arm)
        .and_then(|e| sem.group(&e.group))
        .filter(|g| !g.joints.is_empty() || !g.links.is_empty());
    let Some(group) = group else {
        return model.hand_links(tool_link);
    };
    let mut out: Vec<usize> = group
        .links
        .iter()
        .filter_map(|n| model.link_id(n).ok())
        .collect();
    for j in group.joints.iter().filter_map(|n| model.joint_id(n)) {
        let joint = &model.joints()[j];
        out.push(joint.parent);
        out.extend((0..model.links().len()).filter(|&l| model.is_descendant(l, joint.child)));
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// The nearest link above every gripper link and the tool frame (the palm, as a rule).
fn common_root(model: &AgentModel, links: &[usize], tool_link: usize) -> usize {
    let mut root = tool_link;
    loop {
        if links.iter().all(|&l| model.is_descendant(l, root)) {
            return root;
        }
        match model.links()[root].parent {
            Some(p) => root = p,
            None => return root,
        }
    }
}

/// The finger joints of arm `arm`'s end effector: the gripper's joint, the first of its group
/// that mimics none (none for a person's hand), and the others that mimic none with its kind
/// and limits, which move with it (fingers each on a joint of its own, as the Fetch's). A group
/// without movable joints (MoveIt's Baxter hands, chains of fixed joints that leave the fingers
/// out) gives the movable joints that hang below its links instead.
pub fn finger_dofs(model: &AgentModel, arm: &str) -> (Option<usize>, Vec<usize>) {
    let sem = model.semantics();
    let Some(g) = sem.end_effector(arm).and_then(|e| sem.group(&e.group)) else {
        return (None, Vec::new());
    };
    let mut dofs: Vec<usize> = g
        .joints
        .iter()
        .filter_map(|j| model.dof_index(j).ok())
        .collect();
    if dofs.is_empty() {
        dofs = dofs_below(model, g);
    }
    let Some(&first) = dofs.first() else {
        return (None, Vec::new());
    };
    let kind = |k: usize| model.joints()[model.dof_joint(k)].kind;
    let limits = model.dof_limits();
    let followers = dofs[1..]
        .iter()
        .copied()
        .filter(|&k| k != first && kind(k) == kind(first) && limits[k] == limits[first])
        .collect();
    (Some(first), followers)
}

/// The degrees of freedom of the joints below group `g`'s links (its links, its joints' child
/// links, its chain's links), in the model's joint order.
fn dofs_below(model: &AgentModel, g: &geometry::agent::srdf::Group) -> Vec<usize> {
    let joints = model.joints();
    let mut tops: Vec<usize> = g
        .links
        .iter()
        .filter_map(|n| model.link_id(n).ok())
        .collect();
    tops.extend(
        g.joints
            .iter()
            .filter_map(|n| model.joint_id(n))
            .map(|j| joints[j].child),
    );
    if let Some(chain) = g
        .chain
        .as_ref()
        .and_then(|(b, t)| model.chain_between(b, t).ok())
    {
        tops.push(chain.root_link);
        tops.extend(chain.joints.iter().map(|&j| joints[j].child));
    }
    joints
        .iter()
        .filter(|j| {
            tops.iter()
                .any(|&t| j.child != t && model.is_descendant(j.child, t))
        })
        .filter_map(|j| j.dof)
        .collect()
}

/// The joints from `root` down to `link`, each with how the opening sets its value (the
/// gripper's joint and its followers the opening's, their mimics in proportion).
fn joint_path(
    model: &AgentModel,
    root: usize,
    link: usize,
    (dof, followers): (Option<usize>, &[usize]),
    q: &[f32],
) -> Vec<PathJoint> {
    let mut path = Vec::new();
    let mut at = link;
    while at != root {
        let Some(j) = model.links()[at].parent_joint else {
            break;
        };
        let joint = &model.joints()[j];
        let master = joint.mimic.map(|m| (model.joints()[m.master].dof, m));
        let (multiplier, offset) = match (joint.dof, master) {
            (Some(d), _) if Some(d) == dof || followers.contains(&d) => (1.0, 0.0),
            (_, Some((Some(d), m))) if Some(d) == dof => (m.multiplier, m.offset),
            _ => (0.0, model.joint_value(j, q)),
        };
        path.push(PathJoint {
            joint: joint.clone(),
            multiplier,
            offset,
        });
        at = joint.parent;
    }
    path.reverse();
    path
}

/// The link's collision shapes as boxes in its frame.
fn link_boxes(model: &AgentModel, link: usize) -> Vec<LinkBox> {
    model.links()[link]
        .collisions
        .iter()
        .map(|c| match c.shape.as_cuboid() {
            Some(cuboid) => LinkBox {
                in_link: c.local_pose,
                cuboid: *cuboid,
                shape: None,
                bounds: None,
            },
            None => {
                let aabb = c.shape.compute_local_aabb();
                LinkBox {
                    in_link: c.local_pose,
                    cuboid: Cuboid::new(aabb.half_extents()),
                    shape: Some(c.shape.clone()),
                    bounds: HullBounds::of(&c.shape),
                }
            }
        })
        .collect()
}

impl LinkBox {
    /// The box (its pose in the tool frame, its half extents) with the link at `link` in the
    /// tool frame.
    fn at(&self, link: Pose) -> (Pose, Cuboid) {
        let pose = link * self.in_link;
        match &self.shape {
            None => (pose, self.cuboid),
            Some(shape) => {
                let aabb = match &self.bounds {
                    Some(bounds) => bounds.aabb(&pose),
                    None => shape.compute_aabb(&pose),
                };
                (
                    Pose::from_translation(aabb.center()),
                    Cuboid::new(aabb.half_extents()),
                )
            }
        }
    }
}

/// The pose a joint path puts its link at (in the path's root frame) with the finger joint at
/// `value`.
fn pose_along(path: &[PathJoint], value: f32) -> Pose {
    path.iter().fold(Pose::IDENTITY, |pose, p| {
        pose * p.joint.transform(p.multiplier * value + p.offset)
    })
}

/// The gripper's collision boxes for one jaw opening.
#[derive(Clone, Debug)]
pub struct Gripper {
    /// Each box with its pose in the tool frame.
    pub boxes: Vec<(Pose, Cuboid)>,
    /// The jaw opening these boxes were built for.
    pub opening: f32,
}

impl Gripper {
    /// Whether the gripper, with its tool frame at `tool` (world), intersects `shape` at `pose`.
    pub fn intersects(&self, tool: &Pose, shape: &dyn Shape, pose: &Pose) -> bool {
        self.boxes.iter().any(|(local, cuboid)| {
            let at = *tool * *local;
            query::intersection_test(&at, cuboid, pose, shape)
                .map(|hit| hit.intersecting)
                // Unsupported shape pairs count as colliding: never claim a free grasp we cannot check.
                .unwrap_or(true)
        })
    }

    /// The smallest box, in the tool frame, holding every box (for tests and reports).
    pub fn bounds(&self) -> (Vector, Vector) {
        let mut lo = Vector::splat(f32::INFINITY);
        let mut hi = Vector::splat(f32::NEG_INFINITY);
        for (pose, cuboid) in &self.boxes {
            let aabb = cuboid.compute_aabb(pose);
            lo = lo.min(aabb.mins);
            hi = hi.max(aabb.maxs);
        }
        (lo, hi)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A shipped robot model with its SRDF (`models/NAME.urdf`, `.srdf`).
    pub(crate) fn model(name: &str) -> AgentModel {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/");
        AgentModel::from_urdf_file(format!("{dir}{name}.urdf"))
            .and_then(|m| m.with_srdf_file(format!("{dir}{name}.srdf")))
            .expect("shipped model")
    }

    /// The PR2's right gripper, read from its model.
    pub(crate) fn pr2_gripper() -> GripperModel {
        GripperModel::of_named_arm(&model("pr2"), "right_arm").expect("arm")
    }

    fn close(a: Vector, b: Vector) -> bool {
        (a - b).abs().max_element() < 1e-5
    }

    /// Fingers each on a joint of its own (the Fetch's), the SRDF's gripper group naming
    /// both: the second follows the first, and the gripper's boxes are those of the same
    /// gripper whose second finger mimics the first.
    #[test]
    fn a_second_finger_on_its_own_joint_moves_with_the_first() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/");
        let urdf = std::fs::read_to_string(format!("{dir}pr2.urdf")).unwrap();
        let mimic = r#"<mimic joint="r_gripper_l_finger_joint" multiplier="1" offset="0"/>"#;
        assert!(urdf.contains(mimic));
        let own = AgentModel::from_urdf_str(&urdf.replace(mimic, ""), "pr2.urdf")
            .and_then(|m| m.with_srdf_file(format!("{dir}pr2.srdf")))
            .unwrap();
        let (dof, followers) = finger_dofs(&own, "right_arm");
        let name = |k: usize| own.dof_names()[k].as_str();
        assert_eq!(dof.map(name), Some("r_gripper_l_finger_joint"));
        assert_eq!(
            followers.iter().map(|&k| name(k)).collect::<Vec<_>>(),
            ["r_gripper_r_finger_joint"]
        );
        let (a, b) = (
            GripperModel::of_named_arm(&own, "right_arm").unwrap(),
            pr2_gripper(),
        );
        for opening in [0.02, 0.06, 0.09] {
            let (a, b) = (a.at(opening), b.at(opening));
            assert_eq!(a.boxes.len(), b.boxes.len());
            for ((pa, ca), (pb, cb)) in a.boxes.iter().zip(&b.boxes) {
                assert!(
                    close(pa.translation, pb.translation),
                    "{opening}: {pa:?} {pb:?}"
                );
                assert!(close(ca.half_extents, cb.half_extents));
            }
        }
        // With the mimic, no follower.
        assert!(finger_dofs(&model("pr2"), "right_arm").1.is_empty());
    }

    #[test]
    fn the_pr2_gripper_is_its_palm_and_two_fingers() {
        let g = pr2_gripper();
        assert!((g.max_opening - 0.09).abs() < 1e-6);
        let at = g.at(0.04);
        assert_eq!(at.boxes.len(), 3);
        // The palm link's box (0.029 .. 0.125 ahead of the palm frame, the tool frame 0.18
        // ahead), the fingers 0.12 long from 0.077, 2 cm thick outside the opening (and the
        // model's 0.5 mm gap), 3 cm wide.
        let (lo, hi) = at.bounds();
        assert!(
            close(lo, Vector::new(0.029 - 0.18, -0.05, -0.024)),
            "{lo:?}"
        );
        assert!(close(hi, Vector::new(0.197 - 0.18, 0.05, 0.024)), "{hi:?}");
        let finger = |side: f32| {
            at.boxes.iter().any(|(pose, c)| {
                let b = c.compute_aabb(pose);
                let (inner, outer) = (side * 0.0205, side * 0.0405);
                close(b.mins, Vector::new(0.077 - 0.18, inner.min(outer), -0.015))
                    && close(b.maxs, Vector::new(0.197 - 0.18, inner.max(outer), 0.015))
            })
        };
        assert!(finger(1.0) && finger(-1.0), "{:?}", at.boxes);
        // Wider than the finger joint allows: clamped.
        assert_eq!(g.at(0.5).opening, g.max_opening);
    }

    #[test]
    fn fingers_sit_outside_the_opening() {
        let g = pr2_gripper().at(0.04);
        // A 3 cm cube between the jaws touches neither finger nor the palm.
        let cube = Cuboid::new(Vector::splat(0.015));
        assert!(!g.intersects(&Pose::IDENTITY, &cube, &Pose::IDENTITY));
        // A 5 cm cube does.
        let big = Cuboid::new(Vector::splat(0.025));
        assert!(g.intersects(&Pose::IDENTITY, &big, &Pose::IDENTITY));
        // Pushed back 6 cm it meets the palm even when it fits between the fingers.
        let back = Pose::from_translation(Vector::new(-0.08, 0.0, 0.0));
        assert!(g.intersects(&Pose::IDENTITY, &cube, &back));
    }

    #[test]
    fn each_robot_gets_its_own_gripper() {
        let fetch = GripperModel::of_named_arm(&model("fetch"), "arm").expect("arm");
        // The Fetch's fingers travel 0.05 m each: a 10 cm jaw opening, the PR2's 9 cm; the
        // planner opens either at most 9 cm.
        assert!((fetch.model_opening() - 0.10).abs() < 1e-6);
        assert!((fetch.max_opening - OPENING_CAP).abs() < 1e-6);
        let (_, hi) = fetch.at(0.1).bounds();
        assert!((hi.y - 0.0705).abs() < 1e-5, "{hi:?}");
        assert_ne!(fetch.key(), pr2_gripper().key());
        // The PR2's two grippers are the same (one grasp set serves both).
        let left = GripperModel::of_named_arm(&model("pr2"), "left_arm").expect("arm");
        assert_eq!(left.key(), pr2_gripper().key());
    }
    /// A one-joint arm ending in a palm with two fingers on revolute joints (the second
    /// mimicking the first), each with a 1 cm pad 8 cm ahead of its knuckle.
    fn turning_finger_model() -> AgentModel {
        turning_finger_model_with(r#"<box size="0.02 0.01 0.02"/>"#)
    }

    /// [`turning_finger_model`] with each pad the geometry `pad` (URDF) 8 cm ahead of its knuckle.
    fn turning_finger_model_with(pad: &str) -> AgentModel {
        turning_finger_model_turned(pad, 1.0)
    }

    /// [`turning_finger_model_with`], the fingers' joints turning them in at `sense` -1 (a
    /// Robotiq 2F-85's knuckles close the jaws as their value grows): each finger then sits
    /// turned out by 0.5 rad at 0, straight at the upper limit.
    fn turning_finger_model_turned(pad: &str, sense: f32) -> AgentModel {
        let yaw = if sense < 0.0 { 0.5 } else { 0.0 };
        let finger = |side: &str, y: f32, axis: f32, mimic: &str| {
            let (axis, yaw) = (axis * sense, yaw * axis);
            format!(
                r#"<link name="{side}_finger"><collision><origin xyz="0.08 0 0"/><geometry>{pad}</geometry></collision></link>
                <joint name="{side}_finger_joint" type="revolute"><parent link="palm"/><child link="{side}_finger"/>
                  <origin xyz="0.02 {y} 0" rpy="0 0 {yaw}"/><axis xyz="0 0 {axis}"/><limit lower="0" upper="0.5" effort="1" velocity="1"/>{mimic}</joint>"#
            )
        };
        let urdf = format!(
            r#"<robot name="turning"><link name="base"/><link name="wrist"/>
            <joint name="wrist_joint" type="revolute"><parent link="base"/><child link="wrist"/><axis xyz="1 0 0"/>
              <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
            <link name="palm"><collision><geometry><box size="0.04 0.06 0.04"/></geometry></collision></link>
            <joint name="palm_joint" type="fixed"><parent link="wrist"/><child link="palm"/></joint>
            <link name="tool"/><joint name="tool_joint" type="fixed"><parent link="palm"/><child link="tool"/><origin xyz="0.1 0 0"/></joint>
            {}{}</robot>"#,
            finger("l", 0.015, 1.0, ""),
            finger("r", -0.015, -1.0, r#"<mimic joint="l_finger_joint"/>"#)
        );
        let srdf = r#"<robot name="turning"><group name="arm"><chain base_link="base" tip_link="tool"/></group>
            <group name="hand"><joint name="l_finger_joint"/><joint name="r_finger_joint"/></group>
            <end_effector name="ee" parent_link="tool" group="hand" parent_group="arm"/></robot>"#;
        AgentModel::from_urdf_str(&urdf, "turning.urdf")
            .and_then(|m| m.with_srdf_str(srdf, "turning.srdf"))
            .expect("test model")
    }

    #[test]
    fn a_turning_finger_opens_the_jaws_by_the_gap_measured_between_its_pads() {
        let gripper = GripperModel::of_named_arm(&turning_finger_model(), "arm").expect("arm");
        // Closed (0 rad) the pads' inner faces are 2 x (0.015 - 0.005) = 20 mm apart; at the
        // upper limit each pad has swung out by about 0.08 sin 0.5.
        let (lo, hi) = gripper.opening_range;
        assert!((lo - 0.02).abs() < 1e-3, "closed gap {lo}");
        assert!(hi > 0.07 && hi < 0.1, "widest gap {hi}");
        assert_eq!(gripper.max_opening, hi.min(OPENING_CAP));
        for opening in [0.03, 0.05, 0.07] {
            let value = gripper.joint_value(opening);
            assert!(value > 0.0 && value < 0.5, "{opening}: {value}");
            let gap = gripper.finger_gap(value).expect("pads on both sides");
            assert!((gap - opening).abs() < 1e-3, "{opening}: gap {gap}");
        }
        // Wider openings widen the boxes' span along the closing axis.
        let span = |o: f32| {
            let (lo, hi) = gripper.at(o).bounds();
            hi.y - lo.y
        };
        assert!(span(0.07) > span(0.03) + 0.03);
    }

    #[test]
    fn a_finger_that_closes_as_its_joint_turns_on_opens_the_jaws_as_it_turns_back() {
        let model = turning_finger_model_turned(r#"<box size="0.02 0.01 0.02"/>"#, -1.0);
        let gripper = GripperModel::of_named_arm(&model, "arm").expect("arm");
        // Straight at the upper limit (0.5 rad): the pads 20 mm apart; turned out at 0.
        let (lo, hi) = gripper.opening_range;
        assert!((lo - 0.02).abs() < 1e-3, "closed gap {lo}");
        assert!(hi > 0.07 && hi < 0.1, "widest gap {hi}");
        let mut last = f32::INFINITY;
        for opening in [0.03, 0.05, 0.07] {
            let value = gripper.joint_value(opening);
            assert!(
                value > 0.0 && value < 0.5 && value < last,
                "{opening}: {value}"
            );
            last = value;
            let gap = gripper.finger_gap(value).expect("pads on both sides");
            assert!((gap - opening).abs() < 1e-3, "{opening}: gap {gap}");
            let back = gripper.opening_at(value);
            assert!((back - opening).abs() < 1e-4, "{opening}: {back}");
        }
    }

    /// Baxter-like: each finger slides out along y from pads whose inner faces stand 9 mm off
    /// the centre line closed (an 18 mm gap), the second finger mimicking the first; the
    /// SRDF's hand group is `hand` (its end effector's).
    fn sliding_finger_model(hand: &str) -> AgentModel {
        let finger = |side: &str, sign: f32, mimic: &str| {
            format!(
                r#"<link name="{side}"><collision><origin xyz="0.08 {y} 0"/><geometry><box size="0.02 0.01 0.02"/></geometry></collision></link>
                <joint name="{side}_joint" type="prismatic"><parent link="palm"/><child link="{side}"/>
                  <axis xyz="0 {sign} 0"/><limit lower="0" upper="0.02" effort="1" velocity="1"/>{mimic}</joint>"#,
                y = sign * 0.014
            )
        };
        let urdf = format!(
            r#"<robot name="sliding"><link name="base"/>
            <link name="palm"><collision><geometry><box size="0.02 0.06 0.02"/></geometry></collision></link>
            <joint name="wrist" type="revolute"><parent link="base"/><child link="palm"/><axis xyz="1 0 0"/>
              <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
            <link name="tool"/><joint name="tool_joint" type="fixed"><parent link="palm"/><child link="tool"/><origin xyz="0.08 0 0"/></joint>
            {}{}</robot>"#,
            finger("l", 1.0, ""),
            finger("r", -1.0, r#"<mimic joint="l_joint"/>"#)
        );
        let srdf = format!(
            r#"<robot name="sliding"><group name="arm"><chain base_link="base" tip_link="tool"/></group>
            <group name="hand">{hand}</group>
            <end_effector name="ee" parent_link="tool" group="hand" parent_group="arm"/></robot>"#
        );
        AgentModel::from_urdf_str(&urdf, "sliding.urdf")
            .and_then(|m| m.with_srdf_str(&srdf, "sliding.srdf"))
            .expect("test model")
    }

    #[test]
    fn sliding_fingers_whose_pads_stand_apart_closed_are_measured() {
        let model = sliding_finger_model(r#"<joint name="l_joint"/><joint name="r_joint"/>"#);
        let gripper = GripperModel::of_named_arm(&model, "arm").expect("arm");
        let (lo, hi) = gripper.opening_range;
        assert!(
            (lo - 0.018).abs() < 1e-4 && (hi - 0.058).abs() < 1e-4,
            "{lo} {hi}"
        );
        assert!((gripper.joint_value(0.03) - 0.006).abs() < 1e-4);
        assert!((gripper.opening_at(0.006) - 0.03).abs() < 1e-4);
    }

    #[test]
    fn a_hand_group_of_fixed_joints_finds_the_fingers_below_it() {
        // MoveIt's Baxter: the hand group a chain of fixed joints, the fingers left out.
        let model = sliding_finger_model(r#"<chain base_link="palm" tip_link="tool"/>"#);
        let (dof, _) = finger_dofs(&model, "arm");
        assert_eq!(dof, model.dof_index("l_joint").ok());
        let gripper = GripperModel::of_named_arm(&model, "arm").expect("arm");
        assert!((gripper.model_opening() - 0.058).abs() < 1e-4);
    }

    #[test]
    fn the_gripper_shapes_meet_less_than_their_boxes() {
        // Ball pads (1 cm radius): a 4 mm cube off a pad's centre along the diagonal, 1.5 cm
        // away (its nearest corner 1.15 cm), sits in the corner of the ball's box but misses
        // the ball.
        let model = turning_finger_model_with(r#"<sphere radius="0.01"/>"#);
        let gripper = GripperModel::of_named_arm(&model, "arm").expect("arm");
        let opening = 0.05;
        let at = gripper.at(opening);
        let (pad, _) = at
            .boxes
            .iter()
            .find(|(p, c)| p.translation.y > 0.0 && (c.half_extents.x - 0.01).abs() < 1e-6)
            .expect("the left pad");
        let corner = pad.translation + Vector::splat(0.015 / 3f32.sqrt());
        let cube = Cuboid::new(Vector::splat(0.002));
        let pose = Pose::from_translation(corner);
        assert!(at.intersects(&Pose::IDENTITY, &cube, &pose));
        assert!(!gripper.shapes_meet(opening, &Pose::IDENTITY, &cube, &pose));
        // At the pad's centre, both meet it.
        let pose = Pose::from_translation(pad.translation);
        assert!(gripper.shapes_meet(opening, &Pose::IDENTITY, &cube, &pose));
    }

    #[test]
    fn a_turning_finger_that_is_no_box_is_boxed_where_it_is() {
        // Ball pads (1 cm radius): whatever the finger's turn, each pad's box is the ball's own
        // bounds in the tool frame, a 2 cm cube around it. Boxed in the finger's frame and
        // turned with it, the box would be wider by up to 41 % (its corners swung out), reaching
        // across the jaws and out beyond the finger.
        let model = turning_finger_model_with(r#"<sphere radius="0.01"/>"#);
        let gripper = GripperModel::of_named_arm(&model, "arm").expect("arm");
        let value = 0.4;
        let opening = gripper
            .finger_gap(value)
            .expect("pads on both sides of the jaws");
        let at = gripper.at(opening);
        let pads: Vec<_> = at
            .boxes
            .iter()
            .filter(|(_, c)| (c.half_extents - Vector::splat(0.01)).abs().max_element() < 1e-6)
            .collect();
        assert_eq!(pads.len(), 2, "{:?}", at.boxes);
        for (pose, _) in pads {
            // Upright and centred on the pad, which has swung out by 0.08 sin 0.4 (the knuckles
            // 1.5 cm off the centre line).
            assert!(pose.rotation.to_axis_angle().1.abs() < 1e-6, "{pose:?}");
            let y = pose.translation.y.abs();
            assert!((y - (0.015 + 0.08 * value.sin())).abs() < 1e-4, "{pose:?}");
        }
        // The same boxes again (remembered per opening).
        assert_eq!(
            format!("{:?}", gripper.at(opening).boxes),
            format!("{:?}", at.boxes)
        );
    }

    #[test]
    fn a_sliding_finger_takes_half_the_opening() {
        let gripper = pr2_gripper();
        assert_eq!(gripper.joint_value(0.06), 0.03);
        assert_eq!(gripper.opening_at(0.03), 0.06);
    }
}
