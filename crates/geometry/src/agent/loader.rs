//! URDF (as parsed by `urdf-rs`) to [`AgentModel`], with validation.

use super::*;

struct Ctx<'a> {
    text: &'a str,
    source_name: &'a str,
    meshes: &'a MeshOptions,
    warnings: std::cell::RefCell<Vec<String>>,
}

impl Ctx<'_> {
    /// An `Invalid` error located at the element `<tag ... name="name"`, when found.
    fn invalid(&self, tag: &str, name: &str, message: String) -> ModelError {
        ModelError::Invalid {
            source_name: self.source_name.to_string(),
            line: locate(self.text, tag, name),
            message,
        }
    }
}

/// 1-based line of the first `<tag` element whose `name` attribute is `name`.
fn locate(text: &str, tag: &str, name: &str) -> Option<usize> {
    let open = format!("<{tag}");
    let mut from = 0;
    while let Some(pos) = text[from..].find(&open) {
        let start = from + pos;
        let after = start + open.len();
        let end = text[after..]
            .find('>')
            .map(|e| after + e)
            .unwrap_or(text.len());
        let head = &text[after..end];
        if head.starts_with(|c: char| c.is_whitespace())
            && (head.contains(&format!("name=\"{name}\""))
                || head.contains(&format!("name='{name}'")))
        {
            return Some(text[..start].matches('\n').count() + 1);
        }
        from = after;
    }
    None
}

/// The line of the text that `message` quotes (between backticks or square brackets), as
/// an attribute value: urdf-rs quotes the bad value but gives no position.
fn locate_quoted(text: &str, message: &str) -> Option<usize> {
    let quoted = |open: char, close: char| -> Option<&str> {
        let start = message.find(open)? + open.len_utf8();
        let end = start + message[start..].find(close)?;
        Some(&message[start..end])
    };
    let needle = quoted('`', '`').or_else(|| quoted('[', ']'))?;
    if needle.trim().is_empty() {
        return None;
    }
    let pos = text
        .find(&format!("\"{needle}\""))
        .or_else(|| text.find(&format!("'{needle}'")))?;
    Some(text[..pos].matches('\n').count() + 1)
}

fn finite3(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn to_pose(o: &urdf_rs::Pose) -> Pose {
    let [r, p, y] = o.rpy.0;
    let rot = Rotation::from_rotation_z(y as f32)
        * Rotation::from_rotation_y(p as f32)
        * Rotation::from_rotation_x(r as f32);
    Pose::from_parts(
        Vector::new(o.xyz[0] as f32, o.xyz[1] as f32, o.xyz[2] as f32),
        rot.normalize(),
    )
}

/// The collision shapes of one URDF `<collision>` element: one for a primitive, one per convex
/// piece for a mesh.
fn convert_geometry(
    ctx: &Ctx,
    link: &str,
    c: &urdf_rs::Collision,
) -> Result<Vec<CollisionShape>, ModelError> {
    let bad = |m: String| ctx.invalid("link", link, format!("link '{link}': collision {m}"));
    if !finite3(&c.origin.xyz) || !finite3(&c.origin.rpy) {
        return Err(bad(format!(
            "origin has a non-finite number (xyz {:?}, rpy {:?})",
            c.origin.xyz.0, c.origin.rpy.0
        )));
    }
    let pos = |v: f64, what: &str| -> Result<f32, ModelError> {
        if v.is_finite() && v > 0.0 {
            Ok(v as f32)
        } else {
            Err(bad(format!(
                "{what} must be a positive finite number, got {v}"
            )))
        }
    };
    let origin = to_pose(&c.origin);
    let (shape, local_pose, primitive, bounding_radius) = match &c.geometry {
        urdf_rs::Geometry::Box { size } => {
            let h = Vector::new(
                pos(size[0], "box size x")?,
                pos(size[1], "box size y")?,
                pos(size[2], "box size z")?,
            ) * 0.5;
            (
                SharedShape::cuboid(h.x, h.y, h.z),
                origin,
                Primitive::Box { half_extents: h },
                h.length(),
            )
        }
        urdf_rs::Geometry::Sphere { radius } => {
            let r = pos(*radius, "sphere radius")?;
            (
                SharedShape::ball(r),
                origin,
                Primitive::Sphere { radius: r },
                r,
            )
        }
        urdf_rs::Geometry::Cylinder { radius, length } => {
            let r = pos(*radius, "cylinder radius")?;
            let l = pos(*length, "cylinder length")?;
            // parry's cylinder is along y; URDF's along z.
            let quarter = Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2);
            (
                SharedShape::cylinder(l / 2.0, r),
                origin * Pose::from_rotation(quarter),
                Primitive::Cylinder {
                    radius: r,
                    length: l,
                },
                (r * r + l * l / 4.0).sqrt(),
            )
        }
        urdf_rs::Geometry::Capsule { radius, length } => {
            let r = pos(*radius, "capsule radius")?;
            let l = pos(*length, "capsule length")?;
            (
                SharedShape::capsule_z(l / 2.0, r),
                origin,
                Primitive::Capsule {
                    radius: r,
                    length: l,
                },
                r + l / 2.0,
            )
        }
        urdf_rs::Geometry::Mesh { filename, scale } => {
            return collision_mesh(ctx, link, filename, scale.as_ref(), origin).map_err(bad);
        }
    };
    Ok(vec![CollisionShape {
        local_pose,
        shape,
        primitive,
        bounding_radius,
    }])
}

/// The file a mesh element names, which must exist; the error names the URI and every place
/// searched.
fn mesh_path(ctx: &Ctx, uri: &str) -> Result<std::path::PathBuf, String> {
    let path = ctx
        .meshes
        .packages
        .resolve(uri)
        .map_err(|e| format!("mesh '{uri}': {}", e.message))?;
    if path.is_file() {
        return Ok(path);
    }
    let how = if uri.starts_with("package://") {
        "in its package"
    } else if uri.starts_with("file://") {
        "as an absolute path"
    } else {
        "relative to the URDF's folder"
    };
    Err(format!(
        "mesh '{uri}': file `{}` ({how}) not found",
        path.display()
    ))
}

/// A collision mesh as convex pieces ([`convex`]), checked for numbers and caps.
fn collision_mesh(
    ctx: &Ctx,
    link: &str,
    uri: &str,
    scale: Option<&urdf_rs::Vec3>,
    origin: Pose,
) -> Result<Vec<CollisionShape>, String> {
    let scale = scale.map(|s| s.0).unwrap_or([1.0; 3]);
    if !scale.iter().all(|s| s.is_finite() && *s != 0.0) {
        return Err(format!(
            "mesh '{uri}': scale {scale:?} must be finite and non-zero"
        ));
    }
    let path = mesh_path(ctx, uri)?;
    let mode = ctx
        .meshes
        .modes
        .get(link)
        .copied()
        .unwrap_or(ConvexMode::Auto);
    let mesh = convex::convex_mesh(&path, scale.map(|s| s as f32), mode)
        .map_err(|e| format!("mesh '{uri}' ({}): {e}", path.display()))?;
    Ok(mesh
        .pieces
        .iter()
        .map(|piece| CollisionShape {
            local_pose: convex::piece_pose(origin, piece),
            shape: piece.shape.clone(),
            primitive: Primitive::Convex {
                vertices: piece
                    .shape
                    .as_convex_polyhedron()
                    .map_or(0, |p| p.points().len()),
                pieces: mesh.pieces.len(),
            },
            bounding_radius: piece.radius,
        })
        .collect())
}

/// The visual meshes of a link whose files exist; a visual mesh that names no file, or has a
/// bad scale or origin, is a warning (planning does not need it). Files are not read here.
fn visuals(ctx: &Ctx, robot: &urdf_rs::Robot, link: &urdf_rs::Link) -> Vec<VisualMesh> {
    let mut out = Vec::new();
    for v in &link.visual {
        let urdf_rs::Geometry::Mesh { filename, scale } = &v.geometry else {
            continue;
        };
        let scale = scale.as_ref().map(|s| s.0).unwrap_or([1.0; 3]);
        let found = if !scale.iter().all(|s| s.is_finite() && *s != 0.0) {
            Err(format!(
                "mesh '{filename}': scale {scale:?} must be finite and non-zero"
            ))
        } else if !finite3(&v.origin.xyz) || !finite3(&v.origin.rpy) {
            Err(format!("mesh '{filename}': origin has a non-finite number"))
        } else {
            mesh_path(ctx, filename)
        };
        match found {
            Ok(path) => out.push(VisualMesh {
                uri: filename.clone(),
                path: std::fs::canonicalize(&path).unwrap_or(path),
                local_pose: to_pose(&v.origin),
                scale: Vector::new(scale[0] as f32, scale[1] as f32, scale[2] as f32),
                colour: material_colour(robot, v.material.as_ref()),
            }),
            Err(e) => {
                let line = locate(ctx.text, "link", &link.name)
                    .map(|l| format!(":{l}"))
                    .unwrap_or_default();
                ctx.warnings.borrow_mut().push(format!(
                    "{}{line}: link '{}': visual {e} (not needed for planning)",
                    ctx.source_name, link.name
                ));
            }
        }
    }
    out
}

/// A visual's colour: its material's own `<color>`, else that of the robot's top-level
/// material of the same name; `None` without one (or with a non-finite number).
fn material_colour(robot: &urdf_rs::Robot, m: Option<&urdf_rs::Material>) -> Option<[f32; 4]> {
    let m = m?;
    let color = m.color.as_ref().or_else(|| {
        robot
            .materials
            .iter()
            .find(|r| !m.name.is_empty() && r.name == m.name)
            .and_then(|r| r.color.as_ref())
    })?;
    let c = color.rgba.0;
    c.iter()
        .all(|x| x.is_finite())
        .then(|| c.map(|x| x.clamp(0.0, 1.0) as f32))
}

pub(super) fn load(
    text: &str,
    source_name: &str,
    meshes: &MeshOptions,
) -> Result<AgentModel, ModelError> {
    let ctx = Ctx {
        text,
        source_name,
        meshes,
        warnings: Default::default(),
    };
    let robot = parse_robot(text, source_name)?;
    let (urdf_link, urdf_joint) = unique_names(&ctx, &robot)?;
    let tree = Tree::of(&ctx, &robot, &urdf_link)?;
    let links = tree.links(&ctx, &robot, &urdf_link)?;
    let (mut joints, joint_index) = tree.joints(&ctx, &robot, &urdf_link)?;
    apply_mimics(&ctx, &robot, &tree, &urdf_joint, &joint_index, &mut joints)?;
    let dofs = DofColumns::of(&robot, &urdf_joint, &mut joints);
    let link_index = links
        .iter()
        .enumerate()
        .map(|(i, l)| (l.name.clone(), i))
        .collect();
    Ok(AgentModel {
        name: robot.name.clone(),
        source_name: source_name.to_string(),
        urdf: Arc::from(text),
        semantics: Arc::default(),
        links,
        joints,
        link_index,
        joint_index,
        dofs: Arc::new(DofTable {
            model: robot.name,
            names: dofs.names,
            limits: dofs.limits,
            index: dofs.index,
        }),
        dof_joints: dofs.joints,
        dof_velocity_limits: dofs.velocity_limits,
        dof_acceleration_limits: dofs.acceleration_limits,
        warnings: ctx.warnings.into_inner(),
    })
}

/// The URDF document read by urdf-rs; a syntax error names the line it quotes.
fn parse_robot(text: &str, source_name: &str) -> Result<urdf_rs::Robot, ModelError> {
    // urdf-rs should not panic, but a malformed document must never take the caller down.
    let parsed = std::panic::catch_unwind(|| urdf_rs::read_from_string(text));
    let robot = match parsed {
        Ok(Ok(r)) => r,
        Ok(Err(e)) => {
            let message = e.to_string();
            return Err(ModelError::Syntax {
                source_name: source_name.to_string(),
                line: locate_quoted(text, &message),
                message,
            });
        }
        Err(_) => {
            return Err(ModelError::Syntax {
                source_name: source_name.to_string(),
                line: None,
                message: "the URDF parser failed on this document".to_string(),
            });
        }
    };
    if robot.links.is_empty() {
        return Err(ModelError::Invalid {
            source_name: source_name.to_string(),
            line: None,
            message: format!("robot '{}' has no <link>", robot.name),
        });
    }
    Ok(robot)
}

/// Names to their index in the URDF document.
type NameIndex<'r> = HashMap<&'r str, usize>;

/// Link and joint names to their URDF indices; names must be unique and non-empty.
fn unique_names<'r>(
    ctx: &Ctx,
    robot: &'r urdf_rs::Robot,
) -> Result<(NameIndex<'r>, NameIndex<'r>), ModelError> {
    let source_name = ctx.source_name;
    // Names must be unique and non-empty.
    let mut urdf_link: HashMap<&str, usize> = HashMap::new();
    for (i, l) in robot.links.iter().enumerate() {
        if l.name.trim().is_empty() {
            return Err(ModelError::Invalid {
                source_name: source_name.to_string(),
                line: None,
                message: "a <link> has an empty name".to_string(),
            });
        }
        if urdf_link.insert(l.name.as_str(), i).is_some() {
            return Err(ctx.invalid(
                "link",
                &l.name,
                format!("link '{}' is defined twice", l.name),
            ));
        }
    }
    let mut urdf_joint: HashMap<&str, usize> = HashMap::new();
    for (i, j) in robot.joints.iter().enumerate() {
        if j.name.trim().is_empty() {
            return Err(ModelError::Invalid {
                source_name: source_name.to_string(),
                line: None,
                message: "a <joint> has an empty name".to_string(),
            });
        }
        if urdf_joint.insert(j.name.as_str(), i).is_some() {
            return Err(ctx.invalid(
                "joint",
                &j.name,
                format!("joint '{}' is defined twice", j.name),
            ));
        }
    }
    Ok((urdf_link, urdf_joint))
}

/// The link tree of a URDF document: parent joint and children per URDF link, and the links in
/// topological order (breadth first from the one root).
struct Tree {
    parent_joint_of: Vec<Option<usize>>,
    children_of: Vec<Vec<usize>>,
    order: Vec<usize>,
    new_index: Vec<usize>,
}

impl Tree {
    fn of(
        ctx: &Ctx,
        robot: &urdf_rs::Robot,
        urdf_link: &HashMap<&str, usize>,
    ) -> Result<Tree, ModelError> {
        let source_name = ctx.source_name;
        // Tree structure: each link has at most one parent joint; exactly one root.
        let mut parent_joint_of: Vec<Option<usize>> = vec![None; robot.links.len()];
        let mut children_of: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
        for (ji, j) in robot.joints.iter().enumerate() {
            let p = *urdf_link.get(j.parent.link.as_str()).ok_or_else(|| {
                ctx.invalid(
                    "joint",
                    &j.name,
                    format!(
                        "joint '{}': parent link '{}' is not defined",
                        j.name, j.parent.link
                    ),
                )
            })?;
            let c = *urdf_link.get(j.child.link.as_str()).ok_or_else(|| {
                ctx.invalid(
                    "joint",
                    &j.name,
                    format!(
                        "joint '{}': child link '{}' is not defined",
                        j.name, j.child.link
                    ),
                )
            })?;
            if p == c {
                return Err(ctx.invalid(
                    "joint",
                    &j.name,
                    format!(
                        "joint '{}' connects link '{}' to itself",
                        j.name, j.parent.link
                    ),
                ));
            }
            if let Some(other) = parent_joint_of[c] {
                return Err(ctx.invalid(
                    "joint",
                    &j.name,
                    format!(
                        "link '{}' has two parent joints ('{}' and '{}'); a URDF is a tree",
                        j.child.link, robot.joints[other].name, j.name
                    ),
                ));
            }
            parent_joint_of[c] = Some(ji);
            children_of[p].push(c);
        }
        let roots: Vec<usize> = (0..robot.links.len())
            .filter(|&i| parent_joint_of[i].is_none())
            .collect();
        if roots.is_empty() {
            return Err(ModelError::Invalid {
                source_name: source_name.to_string(),
                line: None,
                message: "every link has a parent joint: the joints form a cycle".to_string(),
            });
        }
        if roots.len() > 1 {
            let names: Vec<&str> = roots
                .iter()
                .map(|&i| robot.links[i].name.as_str())
                .collect();
            return Err(ctx.invalid(
                "link",
                names[1],
                format!(
                    "the links are not one tree: {} links have no parent joint ({})",
                    names.len(),
                    names.join(", ")
                ),
            ));
        }
        // Topological order (breadth first from the root); links not reached lie on a cycle.
        let mut order = vec![roots[0]];
        let mut k = 0;
        while k < order.len() {
            let l = order[k];
            order.extend(children_of[l].iter().copied());
            k += 1;
        }
        if order.len() != robot.links.len() {
            let reached: std::collections::HashSet<usize> = order.iter().copied().collect();
            let on_cycle = (0..robot.links.len())
                .find(|i| !reached.contains(i))
                .unwrap_or(0);
            let name = &robot.links[on_cycle].name;
            return Err(ctx.invalid(
                "link",
                name,
                format!(
                    "link '{name}' is not connected to the root '{}': its joints form a cycle",
                    robot.links[roots[0]].name
                ),
            ));
        }
        let mut new_index = vec![0usize; robot.links.len()];
        for (n, &old) in order.iter().enumerate() {
            new_index[old] = n;
        }
        Ok(Tree {
            parent_joint_of,
            children_of,
            order,
            new_index,
        })
    }

    /// The links in topological order with their collision shapes.
    fn links(
        &self,
        ctx: &Ctx,
        robot: &urdf_rs::Robot,
        urdf_link: &HashMap<&str, usize>,
    ) -> Result<Vec<Link>, ModelError> {
        let Tree {
            parent_joint_of,
            children_of,
            order,
            new_index,
        } = self;
        // Links.
        let mut links = Vec::with_capacity(order.len());
        for &old in order {
            let l = &robot.links[old];
            let mut collisions = Vec::with_capacity(l.collision.len());
            for c in &l.collision {
                collisions.extend(convert_geometry(ctx, &l.name, c)?);
            }
            let visuals = visuals(ctx, robot, l);
            let parent = parent_joint_of[old]
                .map(|j| new_index[urdf_link[robot.joints[j].parent.link.as_str()]]);
            links.push(Link {
                name: l.name.clone(),
                parent,
                parent_joint: parent_joint_of[old].map(|_| new_index[old] - 1),
                children: children_of[old].iter().map(|&c| new_index[c]).collect(),
                collisions,
                visuals,
            });
        }
        Ok(links)
    }

    /// The joints in child-link order (joint n has child link n + 1), and their index by name.
    fn joints(
        &self,
        ctx: &Ctx,
        robot: &urdf_rs::Robot,
        urdf_link: &HashMap<&str, usize>,
    ) -> Result<(Vec<Joint>, HashMap<String, usize>), ModelError> {
        let mut joints = Vec::with_capacity(self.order.len() - 1);
        let mut joint_index = HashMap::new();
        for &old_link in &self.order[1..] {
            let ji = self.parent_joint_of[old_link].expect("non-root link has a parent joint");
            let j = &robot.joints[ji];
            let mut joint = convert_joint(ctx, j)?;
            joint.parent = self.new_index[urdf_link[j.parent.link.as_str()]];
            joint.child = self.new_index[old_link];
            joint_index.insert(j.name.clone(), joints.len());
            joints.push(joint);
        }
        Ok((joints, joint_index))
    }
}

/// One URDF joint converted (its `parent` and `child` are set by the caller).
fn convert_joint(ctx: &Ctx, j: &urdf_rs::Joint) -> Result<Joint, ModelError> {
    let bad = |m: String| ctx.invalid("joint", &j.name, format!("joint '{}': {m}", j.name));
    let kind = match j.joint_type {
        urdf_rs::JointType::Fixed => JointKind::Fixed,
        urdf_rs::JointType::Revolute => JointKind::Revolute,
        urdf_rs::JointType::Continuous => JointKind::Continuous,
        urdf_rs::JointType::Prismatic => JointKind::Prismatic,
        ref other => {
            return Err(bad(format!(
                "type {other:?} is not supported (fixed, revolute, continuous or \
                 prismatic; the scene places the base)"
            )
            .to_lowercase()));
        }
    };
    if !finite3(&j.origin.xyz) || !finite3(&j.origin.rpy) {
        return Err(bad(format!(
            "origin has a non-finite number (xyz {:?}, rpy {:?})",
            j.origin.xyz.0, j.origin.rpy.0
        )));
    }
    let [ax, ay, az] = j.axis.xyz.0;
    let norm = (ax * ax + ay * ay + az * az).sqrt();
    let mut axis = Vector::X;
    if kind != JointKind::Fixed {
        if !norm.is_finite() || norm < 1e-9 {
            return Err(bad(format!(
                "axis {:?} is not a finite non-zero vector",
                j.axis.xyz.0
            )));
        }
        axis = Vector::new((ax / norm) as f32, (ay / norm) as f32, (az / norm) as f32);
    }
    let limits = match kind {
        JointKind::Fixed | JointKind::Continuous => JointLimits::UNLIMITED,
        JointKind::Revolute | JointKind::Prismatic => {
            let (lo, hi) = (j.limit.lower, j.limit.upper);
            if !lo.is_finite() || !hi.is_finite() {
                return Err(bad(format!(
                    "limits [{lo}, {hi}] must be finite (use a continuous joint for an \
                     unlimited rotation)"
                )));
            }
            if lo >= hi {
                return Err(bad(format!(
                    "lower limit {lo} must be below upper limit {hi} (a missing <limit> \
                     reads as [0, 0])"
                )));
            }
            JointLimits {
                lower: lo as f32,
                upper: hi as f32,
            }
        }
    };
    Ok(Joint {
        name: j.name.clone(),
        kind,
        parent: 0,
        child: 0,
        origin: to_pose(&j.origin),
        axis,
        limits,
        dof: None,
        mimic: None,
    })
}

/// Sets each mimic joint's master, multiplier and offset.
fn apply_mimics(
    ctx: &Ctx,
    robot: &urdf_rs::Robot,
    tree: &Tree,
    urdf_joint: &HashMap<&str, usize>,
    joint_index: &HashMap<String, usize>,
    joints: &mut [Joint],
) -> Result<(), ModelError> {
    let order = &tree.order;
    let parent_joint_of = &tree.parent_joint_of;
    // Mimic joints, then degrees of freedom.
    for &old_link in &order[1..] {
        let j = &robot.joints[parent_joint_of[old_link].expect("has parent joint")];
        let Some(m) = &j.mimic else { continue };
        let bad = |msg: String| ctx.invalid("joint", &j.name, format!("joint '{}': {msg}", j.name));
        let me = joint_index[&j.name];
        if joints[me].kind == JointKind::Fixed {
            return Err(bad("a fixed joint cannot mimic another joint".into()));
        }
        let master = *joint_index
            .get(&m.joint)
            .ok_or_else(|| bad(format!("mimics joint '{}', which is not defined", m.joint)))?;
        let mult = m.multiplier.unwrap_or(1.0);
        let off = m.offset.unwrap_or(0.0);
        if !mult.is_finite() || !off.is_finite() {
            return Err(bad("mimic multiplier and offset must be finite".into()));
        }
        let master_joint = &robot.joints[urdf_joint[m.joint.as_str()]];
        if master_joint.mimic.is_some() || master_joint.joint_type == urdf_rs::JointType::Fixed {
            return Err(bad(format!(
                "mimics joint '{}', which is fixed or itself a mimic joint",
                m.joint
            )));
        }
        joints[me].mimic = Some(Mimic {
            master,
            multiplier: mult as f32,
            offset: off as f32,
        });
    }
    Ok(())
}

/// The degrees of freedom (movable joints that mimic none), one column per property.
struct DofColumns {
    names: Vec<String>,
    limits: Vec<JointLimits>,
    index: HashMap<String, usize>,
    joints: Vec<usize>,
    velocity_limits: Vec<Option<f32>>,
    acceleration_limits: Vec<Option<f32>>,
}

impl DofColumns {
    /// Numbers the degrees of freedom of `joints` (setting each one's `dof`).
    fn of(
        robot: &urdf_rs::Robot,
        urdf_joint: &HashMap<&str, usize>,
        joints: &mut [Joint],
    ) -> DofColumns {
        let mut names = Vec::new();
        let mut limits = Vec::new();
        let mut index = HashMap::new();
        let mut dof_joints = Vec::new();
        let mut dof_velocity_limits = Vec::new();
        let mut dof_acceleration_limits = Vec::new();
        let positive = |v: f64| (v.is_finite() && v > 0.0).then_some(v as f32);
        for (n, joint) in joints.iter_mut().enumerate() {
            if joint.kind != JointKind::Fixed && joint.mimic.is_none() {
                let limit = urdf_joint
                    .get(joint.name.as_str())
                    .map(|&i| &robot.joints[i].limit);
                dof_velocity_limits.push(limit.and_then(|l| positive(l.velocity)));
                dof_acceleration_limits.push(limit.and_then(|l| positive(l.acceleration)));
                joint.dof = Some(names.len());
                index.insert(joint.name.clone(), names.len());
                names.push(joint.name.clone());
                limits.push(joint.limits);
                dof_joints.push(n);
            }
        }
        DofColumns {
            names,
            limits,
            index,
            joints: dof_joints,
            velocity_limits: dof_velocity_limits,
            acceleration_limits: dof_acceleration_limits,
        }
    }
}
