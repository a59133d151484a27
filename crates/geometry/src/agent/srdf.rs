//! The semantic description of an agent, read from MoveIt's SRDF format: which links and joints
//! make the arms, the hands or grippers, the head (eyes) and the torso, the named postures and
//! the link pairs that may touch. Nothing in the code names a link or joint of a particular robot
//! or person: it asks the SRDF.
//!
//! Elements read (others are ignored):
//! * `<group name="..">` with `<chain base_link=".." tip_link=".."/>`, `<joint name=".."/>`,
//!   `<link name=".."/>` (which brings its parent joint, after the joints named, as in
//!   MoveIt). Groups htngtp gives a meaning to: an **arm** is any group that an `end_effector`
//!   names as its `parent_group` (its chain runs from the shoulder's parent to the tool frame or
//!   hand; a group of joints that form a chain is that chain, as in MoveIt); `head`: a chain
//!   whose tip is the eye or camera link, its first two movable joints pan and tilt;
//!   `torso_yaw`, `torso_pitch`, `torso_lift`: one joint each.
//!   A group's `<group name=".."/>` children are its subgroups (declared groups).
//! * `<virtual_joint name=".." type="planar|floating|fixed" parent_frame=".." child_link=".."/>`:
//!   how the root link is placed in the world (the scene places it: htngtp's base is planar);
//!   groups may name the virtual joint among their joints. `<passive_joint name=".."/>`: a
//!   joint no controller drives, or a virtual joint (recorded).
//! * `<end_effector name=".." parent_link=".." group=".." parent_group=".."/>`: the hand or
//!   gripper of the arm `parent_group` (without one, as MoveIt does: the group whose chain ends
//!   at `parent_link`, else the one with the fewest joints whose chain holds it and none of the
//!   end effector's movable joints); its `group`'s first joint that mimics none is the
//!   gripper's joint (none for a person's hand), and the others that mimic none with its kind
//!   and limits follow it (fingers each on a joint of its own).
//! * `<group_state name=".." group="..">` with `<joint name=".." value=".."/>`: a named posture
//!   (a mimic joint's value is skipped: it follows its master)
//!   (`standing` for a person who may stand up, the effort level that allows it).
//! * `<disable_collisions link1=".." link2=".." reason=".."/>`: link pairs that may touch
//!   (left out of self-collision checks, besides the pairs the model's own analysis leaves out).
//!
//! Every name is checked against the URDF model; errors say `file:line:col`.

use super::xml::{self, Element, Pos};
use super::{AgentModel, ModelError};

/// A group of joints and links.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Group {
    pub name: String,
    /// `(base_link, tip_link)` of its chain, if it has one.
    pub chain: Option<(String, String)>,
    pub joints: Vec<String>,
    pub links: Vec<String>,
    /// Groups it includes (`<group name=".."/>` children).
    pub subgroups: Vec<String>,
}

/// A hand or gripper at the end of an arm.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EndEffector {
    pub name: String,
    /// The tool frame (where a held object is carried).
    pub parent_link: String,
    /// The group of the gripper's joints.
    pub group: String,
    /// The arm it ends.
    pub parent_group: Option<String>,
}

/// A named posture of a group.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GroupState {
    pub name: String,
    pub group: String,
    /// Joint values (radians or metres), in document order.
    pub values: Vec<(String, f32)>,
}

/// Everything an SRDF declares that htngtp uses.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Semantics {
    /// The file it was read from (empty when none was).
    pub source_name: String,
    pub groups: Vec<Group>,
    pub end_effectors: Vec<EndEffector>,
    pub group_states: Vec<GroupState>,
    /// `(link1, link2)` pairs that may touch.
    pub disabled_collisions: Vec<(String, String)>,
    /// The virtual joints: name, type (`planar`, `floating`, `fixed`) and child link.
    pub virtual_joints: Vec<(String, String, String)>,
    /// Joints no controller drives.
    pub passive_joints: Vec<String>,
}

impl Semantics {
    /// The group called `name`.
    pub fn group(&self, name: &str) -> Option<&Group> {
        self.groups.iter().find(|g| g.name == name)
    }

    /// The arms: the groups an end effector names as its parent, in document order.
    pub fn arms(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for e in &self.end_effectors {
            if let Some(p) = e.parent_group.as_deref().filter(|p| !out.contains(p)) {
                out.push(p);
            }
        }
        out
    }

    /// The end effector at the end of arm `arm`.
    pub fn end_effector(&self, arm: &str) -> Option<&EndEffector> {
        self.end_effectors
            .iter()
            .find(|e| e.parent_group.as_deref() == Some(arm))
    }

    /// The posture called `name`, if declared.
    pub fn group_state(&self, name: &str) -> Option<&GroupState> {
        self.group_states.iter().find(|s| s.name == name)
    }
}

/// Where an SRDF is read from, for errors.
struct Source<'a> {
    name: &'a str,
}

impl Source<'_> {
    fn err(&self, at: Pos, message: impl Into<String>) -> ModelError {
        ModelError::Srdf {
            source_name: self.name.to_string(),
            line: at.line,
            col: at.col,
            message: message.into(),
        }
    }

    /// Attribute `key` of `e`, or an error naming the element.
    fn attr<'e>(&self, e: &'e Element, key: &str) -> Result<(&'e str, Pos), ModelError> {
        e.attr(key)
            .ok_or_else(|| self.err(e.at, format!("`<{}>` needs a `{key}` attribute", e.name)))
    }
}

/// Reads SRDF `text` for `model`; `source_name` names it in errors.
pub fn read(text: &str, source_name: &str, model: &AgentModel) -> Result<Semantics, ModelError> {
    let src = Source { name: source_name };
    let root = xml::parse(text).map_err(|e| src.err(e.at, e.message))?;
    if root.name != "robot" {
        return Err(src.err(
            root.at,
            format!("expected `<robot>`, found `<{}>`", root.name),
        ));
    }
    if let Some((name, at)) = root.attr("name").filter(|(n, _)| *n != model.name()) {
        return Err(src.err(
            at,
            format!("this SRDF describes `{name}`, the URDF `{}`", model.name()),
        ));
    }
    let mut s = Semantics {
        source_name: source_name.to_string(),
        ..Semantics::default()
    };
    for e in root.children.iter().filter(|e| e.name == "virtual_joint") {
        s.virtual_joints.push(virtual_joint(&src, e, model)?);
    }
    for e in &root.children {
        match e.name.as_str() {
            "group" => {
                s.groups.push(group(&src, e, model, &s.virtual_joints)?);
                // MoveIt's setup assistant may write a passive joint inside a group.
                for c in e.children.iter().filter(|c| c.name == "passive_joint") {
                    s.passive_joints
                        .push(joint_or_virtual(&src, c, model, &s.virtual_joints)?);
                }
            }
            "passive_joint" => {
                s.passive_joints
                    .push(joint_or_virtual(&src, e, model, &s.virtual_joints)?);
            }
            "end_effector" => s.end_effectors.push(end_effector(&src, e, model)?),
            "group_state" => s.group_states.push(group_state(&src, e, model)?),
            "disable_collisions" => {
                let (a, pa) = src.attr(e, "link1")?;
                let (b, pb) = src.attr(e, "link2")?;
                known_link(&src, model, a, pa)?;
                known_link(&src, model, b, pb)?;
                s.disabled_collisions.push((a.to_string(), b.to_string()));
            }
            _ => {}
        }
    }
    infer_parent_groups(&mut s, model);
    cross_check(&src, &root, &s)?;
    Ok(s)
}

/// An end effector without `parent_group` ends, as MoveIt infers it, a group whose chain
/// holds its `parent_link` and none of the end effector's own movable joints: the one whose
/// chain ends there, else the one with the fewest joints.
fn infer_parent_groups(s: &mut Semantics, model: &AgentModel) {
    for i in 0..s.end_effectors.len() {
        let e = &s.end_effectors[i];
        if e.parent_group.is_some() {
            continue;
        }
        let own: Vec<&String> = s
            .group(&e.group)
            .map(|g| g.joints.iter().collect())
            .unwrap_or_default();
        let holds = |g: &Group| {
            let Some((base, tip)) = &g.chain else {
                return None;
            };
            let chain = model.chain_between(base, tip).ok()?;
            let links = |j: &usize| model.links()[model.joints()[*j].child].name.as_str();
            let names: Vec<&str> = chain.joints.iter().map(links).collect();
            // Movable joints only: a gripper group given by its links brings their fixed
            // parent joints, which the arm's group may list too (xArm's `joint_tcp`).
            let shares = chain.joints.iter().any(|j| {
                let joint = &model.joints()[*j];
                joint.is_movable() && own.contains(&&joint.name)
            });
            (g.name != e.group
                && !shares
                && (tip == &e.parent_link || names.contains(&e.parent_link.as_str())))
            .then_some((tip != &e.parent_link, chain.dofs.len()))
        };
        let owner = s
            .groups
            .iter()
            .filter_map(|g| holds(g).map(|rank| (rank, g.name.clone())))
            .min()
            .map(|(_, name)| name);
        s.end_effectors[i].parent_group = owner;
    }
}

fn virtual_joint(
    src: &Source,
    e: &Element,
    model: &AgentModel,
) -> Result<(String, String, String), ModelError> {
    let (name, _) = src.attr(e, "name")?;
    let (kind, kat) = src.attr(e, "type")?;
    if !matches!(kind, "planar" | "floating" | "fixed") {
        return Err(src.err(
            kat,
            format!("virtual joint `{name}`: type `{kind}` (expected planar, floating or fixed)"),
        ));
    }
    let (child, cat) = src.attr(e, "child_link")?;
    known_link(src, model, child, cat)?;
    Ok((name.to_string(), kind.to_string(), child.to_string()))
}

fn known_link(src: &Source, model: &AgentModel, name: &str, at: Pos) -> Result<(), ModelError> {
    model.link_id(name).map(|_| ()).map_err(|_| {
        src.err(
            at,
            format!("unknown link `{name}` (not in {})", model.source_name()),
        )
    })
}

/// The name of element `e` naming a joint: a joint of the model, or a virtual joint (a group
/// may list it; MoveIt's Baxter marks its planar `world_joint` passive).
fn joint_or_virtual(
    src: &Source,
    e: &Element,
    model: &AgentModel,
    virtual_joints: &[(String, String, String)],
) -> Result<String, ModelError> {
    let (name, at) = src.attr(e, "name")?;
    if !virtual_joints.iter().any(|(v, _, _)| v == name) {
        known_joint(src, model, name, at)?;
    }
    Ok(name.to_string())
}

fn known_joint(src: &Source, model: &AgentModel, name: &str, at: Pos) -> Result<usize, ModelError> {
    model.joint_id(name).ok_or_else(|| {
        src.err(
            at,
            format!("unknown joint `{name}` (not in {})", model.source_name()),
        )
    })
}

fn group(
    src: &Source,
    e: &Element,
    model: &AgentModel,
    virtual_joints: &[(String, String, String)],
) -> Result<Group, ModelError> {
    let mut g = Group {
        name: src.attr(e, "name")?.0.to_string(),
        ..Group::default()
    };
    for c in &e.children {
        match c.name.as_str() {
            "chain" => {
                let (base, pb) = src.attr(c, "base_link")?;
                let (tip, pt) = src.attr(c, "tip_link")?;
                known_link(src, model, base, pb)?;
                known_link(src, model, tip, pt)?;
                model
                    .chain_between(base, tip)
                    .map_err(|err| src.err(c.at, err.to_string()))?;
                g.chain = Some((base.to_string(), tip.to_string()));
            }
            "joint" => g
                .joints
                .push(joint_or_virtual(src, c, model, virtual_joints)?),
            "group" => g.subgroups.push(src.attr(c, "name")?.0.to_string()),
            "link" => {
                let (name, at) = src.attr(c, "name")?;
                known_link(src, model, name, at)?;
                g.links.push(name.to_string());
            }
            _ => {}
        }
    }
    if g.chain.is_none() {
        g.chain = joints_chain(model, &g.joints);
    }
    // As MoveIt reads a group: a link brings its parent joint (after the joints named).
    for l in &g.links {
        let parent = model.link(l).ok().and_then(|l| l.parent_joint);
        if let Some(j) = parent.map(|j| model.joints()[j].name.clone())
            && !g.joints.contains(&j)
        {
            g.joints.push(j);
        }
    }
    Ok(g)
}

/// The chain a group given by its joints spans (MoveIt treats such a group as a chain): from
/// the parent link of its joint nearest the root to the child link of its deepest joint, when
/// the group's movable joints are exactly that chain's; `None` otherwise.
pub(super) fn joints_chain(model: &AgentModel, joints: &[String]) -> Option<(String, String)> {
    let ids: Vec<usize> = joints.iter().filter_map(|j| model.joint_id(j)).collect();
    let depth = |mut l: usize| {
        let mut d = 0;
        while let Some(p) = model.links()[l].parent {
            (d, l) = (d + 1, p);
        }
        d
    };
    let joint = |j: usize| &model.joints()[j];
    let top = *ids.iter().min_by_key(|&&j| depth(joint(j).parent))?;
    let deep = *ids.iter().max_by_key(|&&j| depth(joint(j).child))?;
    let base = &model.links()[joint(top).parent].name;
    let tip = &model.links()[joint(deep).child].name;
    let chain = model.chain_between(base, tip).ok()?;
    let movable = |v: &mut Vec<usize>| {
        v.retain(|&j| joint(j).is_movable());
        v.sort_unstable();
        v.dedup();
    };
    let (mut in_chain, mut in_group) = (chain.joints, ids);
    movable(&mut in_chain);
    movable(&mut in_group);
    (in_chain == in_group).then(|| (base.clone(), tip.clone()))
}

fn end_effector(src: &Source, e: &Element, model: &AgentModel) -> Result<EndEffector, ModelError> {
    let (parent_link, at) = src.attr(e, "parent_link")?;
    known_link(src, model, parent_link, at)?;
    Ok(EndEffector {
        name: src.attr(e, "name")?.0.to_string(),
        parent_link: parent_link.to_string(),
        group: src.attr(e, "group")?.0.to_string(),
        parent_group: e.attr("parent_group").map(|(g, _)| g.to_string()),
    })
}

fn group_state(src: &Source, e: &Element, model: &AgentModel) -> Result<GroupState, ModelError> {
    let mut s = GroupState {
        name: src.attr(e, "name")?.0.to_string(),
        group: src.attr(e, "group")?.0.to_string(),
        values: Vec::new(),
    };
    for c in e.children.iter().filter(|c| c.name == "joint") {
        let (name, at) = src.attr(c, "name")?;
        let j = known_joint(src, model, name, at)?;
        let (text, vat) = src.attr(c, "value")?;
        let value: f32 = text
            .trim()
            .parse()
            .ok()
            .filter(|v: &f32| v.is_finite())
            .ok_or_else(|| src.err(vat, format!("joint `{name}`: `{text}` is not a number")))?;
        if model.joints()[j].mimic.is_some() {
            // MoveIt's postures list mimic joints too; their value follows their master's.
            continue;
        }
        let Some(dof) = model.joints()[j].dof else {
            return Err(src.err(
                at,
                format!("joint `{name}` is fixed or mimics another: it takes no value"),
            ));
        };
        let lim = model.dof_limits()[dof];
        if !lim.contains(value) {
            return Err(src.err(
                vat,
                format!(
                    "joint `{name}`: {value} is outside its limits {} ..= {}",
                    lim.lower, lim.upper
                ),
            ));
        }
        s.values.push((name.to_string(), value));
    }
    Ok(s)
}

/// Group names used by end effectors and group states must be declared.
fn cross_check(src: &Source, root: &Element, s: &Semantics) -> Result<(), ModelError> {
    let declared = |name: &str| s.group(name).is_some();
    for e in root.children.iter().filter(|e| e.name == "end_effector") {
        for key in ["group", "parent_group"] {
            if let Some((g, at)) = e.attr(key).filter(|(g, _)| !declared(g)) {
                return Err(src.err(at, format!("no group `{g}` is declared")));
            }
        }
    }
    for e in root.children.iter().filter(|e| e.name == "group") {
        for c in e.children.iter().filter(|c| c.name == "group") {
            if let Some((g, at)) = c.attr("name").filter(|(g, _)| !declared(g)) {
                return Err(src.err(at, format!("subgroup `{g}` is not declared")));
            }
        }
    }
    for e in root.children.iter().filter(|e| e.name == "group_state") {
        if let Some((g, at)) = e.attr("group").filter(|(g, _)| !declared(g)) {
            return Err(src.err(at, format!("no group `{g}` is declared")));
        }
    }
    for arm in s.arms() {
        if s.group(arm).and_then(|g| g.chain.as_ref()).is_none() {
            let at = root
                .children
                .iter()
                .find(|e| e.attr("name").is_some_and(|(n, _)| n == arm))
                .map_or(root.at, |e| e.at);
            return Err(src.err(
                at,
                format!("group `{arm}` ends in an end effector, so it must be a `<chain>`"),
            ));
        }
    }
    Ok(())
}
