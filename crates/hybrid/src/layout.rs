//! Generated scenes: the library scene's text edited in memory (objects removed, moved, added)
//! and free spots on support surfaces, for the scale benchmark ([`crate::scale`]) and the
//! randomized layouts of `bench library --layout random`.

use std::path::{Path, PathBuf};

use geometry::scene::{ObjectId, Scene};
use geometry::world::World;
use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Vector};

/// A scene's text as a TOML table, to edit before it is read.
#[derive(Clone)]
pub struct SceneText {
    table: toml::Table,
}

/// A new movable or fixed object of a generated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct NewObject {
    pub name: String,
    pub shape: NewShape,
    pub xyz: [f32; 3],
    /// Roll, pitch, yaw in degrees (the scene format's `rpy`).
    pub rpy: [f32; 3],
    pub colour: [u8; 3],
    pub movable: bool,
}

/// The shape of a [`NewObject`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NewShape {
    /// Half extents.
    Box([f32; 3]),
    Cylinder {
        radius: f32,
        half_height: f32,
    },
}

/// A scene file read for a generator: its text with absolute file paths (so that the scenes
/// made from it load from anywhere), its folder, its name for messages, and its world.
pub(crate) struct LoadedScene {
    pub text: SceneText,
    pub base_dir: PathBuf,
    pub source: String,
    pub world: World,
}

impl LoadedScene {
    /// Reads the scene file `scene` and builds its world.
    pub(crate) fn read(scene: &Path) -> Result<LoadedScene, String> {
        let mut text = SceneText::load(scene)?;
        let base_dir = scene
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        text.absolute_paths(&base_dir);
        let source = scene.display().to_string();
        let world = text.world(&source, &base_dir)?;
        Ok(LoadedScene {
            text,
            base_dir,
            source,
            world,
        })
    }
}

impl SceneText {
    /// The scene file at `path`, read as TOML (errors name the file).
    pub fn load(path: &Path) -> Result<SceneText, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let table = text
            .parse::<toml::Table>()
            .map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(SceneText { table })
    }

    fn objects_mut(&mut self) -> Result<&mut Vec<toml::Value>, String> {
        self.table
            .get_mut("objects")
            .and_then(toml::Value::as_array_mut)
            .ok_or_else(|| "the scene has no [[objects]]".to_string())
    }

    /// The object entry named `name`.
    fn object_mut(&mut self, name: &str) -> Result<&mut toml::Table, String> {
        self.objects_mut()?
            .iter_mut()
            .filter_map(toml::Value::as_table_mut)
            .find(|o| o.get("name").and_then(toml::Value::as_str) == Some(name))
            .ok_or_else(|| format!("the scene has no object `{name}`"))
    }

    /// Removes the objects named in `names` (absent ones are ignored).
    pub fn remove(&mut self, names: &[&str]) -> Result<(), String> {
        self.objects_mut()?.retain(|o| {
            let n = o.get("name").and_then(toml::Value::as_str).unwrap_or("");
            !names.contains(&n)
        });
        Ok(())
    }

    /// Moves object `name` by `d` (metres, world frame; its rotation unchanged).
    pub fn shift(&mut self, name: &str, d: [f32; 3]) -> Result<(), String> {
        let o = self.object_mut(name)?;
        let pose = o
            .entry("pose")
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let pose = pose
            .as_table_mut()
            .ok_or_else(|| format!("`{name}`: pose is not a table"))?;
        let xyz = xyz_of(pose).map_err(|e| format!("`{name}`: {e}"))?;
        let moved: Vec<toml::Value> = (0..3)
            .map(|k| toml::Value::Float(f64::from(xyz[k] + d[k])))
            .collect();
        pose.insert("xyz".into(), toml::Value::Array(moved));
        Ok(())
    }

    /// Adds a copy of object `name` called `copy`, moved to `xyz`.
    pub fn duplicate(&mut self, name: &str, copy: &str, xyz: [f32; 3]) -> Result<(), String> {
        let mut o = self.object_mut(name)?.clone();
        o.insert("name".into(), toml::Value::String(copy.into()));
        let mut pose = toml::Table::new();
        pose.insert("xyz".into(), floats(&xyz));
        o.insert("pose".into(), toml::Value::Table(pose));
        self.objects_mut()?.push(toml::Value::Table(o));
        Ok(())
    }

    /// Adds `object`.
    pub fn add(&mut self, object: &NewObject) -> Result<(), String> {
        let mut o = toml::Table::new();
        o.insert("name".into(), toml::Value::String(object.name.clone()));
        o.insert("shape".into(), object.shape.to_toml());
        o.insert("pose".into(), pose_table(object.xyz, object.rpy));
        o.insert("colour".into(), colour(object.colour));
        o.insert("movable".into(), toml::Value::Boolean(object.movable));
        self.objects_mut()?.push(toml::Value::Table(o));
        Ok(())
    }

    /// Adds the fixed piece of furniture `f` (its parts, its support surfaces).
    pub fn add_furniture(&mut self, f: &NewFurniture) -> Result<(), String> {
        let mut o = toml::Table::new();
        o.insert("name".into(), toml::Value::String(f.name.clone()));
        o.insert("colour".into(), colour(f.colour));
        o.insert(
            "pose".into(),
            pose_table([f.xy[0], f.xy[1], 0.0], [0.0, 0.0, f.yaw_deg]),
        );
        let parts = f
            .parts
            .iter()
            .map(|(shape, xyz)| {
                let mut p = toml::Table::new();
                p.insert("shape".into(), shape.to_toml());
                p.insert("pose".into(), pose_table(*xyz, [0.0; 3]));
                toml::Value::Table(p)
            })
            .collect();
        o.insert("parts".into(), toml::Value::Array(parts));
        if !f.surfaces.is_empty() {
            o.insert("support".into(), toml::Value::Boolean(true));
            let surfaces = f
                .surfaces
                .iter()
                .map(|(centre, half)| {
                    let mut s = toml::Table::new();
                    s.insert("centre".into(), floats(centre));
                    s.insert("half_extents".into(), floats(half));
                    toml::Value::Table(s)
                })
                .collect();
            o.insert("surfaces".into(), toml::Value::Array(surfaces));
        }
        self.objects_mut()?.push(toml::Value::Table(o));
        Ok(())
    }

    /// The names of the fixed objects (furniture).
    pub fn fixed_objects(&self) -> Vec<String> {
        self.table
            .get("objects")
            .and_then(toml::Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(toml::Value::as_table)
            .filter(|o| o.get("movable").and_then(toml::Value::as_bool) != Some(true))
            .filter_map(|o| o.get("name").and_then(toml::Value::as_str))
            .map(str::to_string)
            .collect()
    }

    /// Sets the scene's `[scene] bounds` (the region of the mightability maps).
    pub fn set_bounds(&mut self, min: [f32; 3], max: [f32; 3]) -> Result<(), String> {
        let scene = self
            .table
            .entry("scene")
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .ok_or("[scene] is not a table")?;
        let mut b = toml::Table::new();
        b.insert("min".into(), floats(&min));
        b.insert("max".into(), floats(&max));
        scene.insert("bounds".into(), toml::Value::Table(b));
        Ok(())
    }

    /// Sets the pose of object `name` to `pose` (a world pose, written as the scene format's
    /// `xyz` and `rpy` in degrees).
    pub fn set_object_pose(&mut self, name: &str, pose: Pose) -> Result<(), String> {
        let (yaw, pitch, roll) = pose.rotation.to_euler(parry3d::glamx::EulerRot::ZYX);
        let t = pose.translation;
        let rpy = [roll, pitch, yaw].map(f32::to_degrees);
        let o = self.object_mut(name)?;
        let mut table = toml::Table::new();
        table.insert("xyz".into(), floats(&[t.x, t.y, t.z]));
        table.insert("rpy".into(), floats(&rpy));
        o.insert("pose".into(), toml::Value::Table(table));
        Ok(())
    }

    /// The agent entry named `name`.
    fn agent_mut(&mut self, name: &str) -> Result<&mut toml::Table, String> {
        self.table
            .get_mut("agents")
            .and_then(toml::Value::as_array_mut)
            .and_then(|a| {
                a.iter_mut()
                    .filter_map(toml::Value::as_table_mut)
                    .find(|o| o.get("name").and_then(toml::Value::as_str) == Some(name))
            })
            .ok_or_else(|| format!("the scene has no agent `{name}`"))
    }

    /// Sets joint `joint` of agent `name` to `value` (its `[agents.joints]` entry).
    pub fn set_joint(&mut self, name: &str, joint: &str, value: f32) -> Result<(), String> {
        let agent = self.agent_mut(name)?;
        let joints = agent
            .entry("joints")
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .ok_or_else(|| format!("agent `{name}`: joints is not a table"))?;
        joints.insert(joint.into(), toml::Value::Float(f64::from(value)));
        Ok(())
    }

    /// Makes the agents' `urdf` and `srdf` paths absolute, resolved from `base_dir`, so that the
    /// text can be written to any folder and read again.
    pub fn absolute_paths(&mut self, base_dir: &Path) {
        let Some(agents) = self
            .table
            .get_mut("agents")
            .and_then(toml::Value::as_array_mut)
        else {
            return;
        };
        for agent in agents.iter_mut().filter_map(toml::Value::as_table_mut) {
            for key in ["urdf", "srdf"] {
                if let Some(toml::Value::String(p)) = agent.get_mut(key) {
                    let joined = base_dir.join(&*p);
                    let path = std::fs::canonicalize(&joined).unwrap_or(joined);
                    *p = path.display().to_string();
                }
            }
        }
    }

    /// The scene's text (TOML), as [`SceneText::world`] reads it.
    pub fn to_toml(&self) -> Result<String, String> {
        toml::to_string(&self.table).map_err(|e| e.to_string())
    }

    /// Sets agent `name`'s base `(x, y, yaw in degrees)`.
    pub fn set_base(&mut self, name: &str, base: [f32; 3]) -> Result<(), String> {
        let agent = self.agent_mut(name)?;
        let mut b = toml::Table::new();
        for (k, v) in ["x", "y", "yaw"].iter().zip(base) {
            b.insert((*k).into(), toml::Value::Float(f64::from(v)));
        }
        agent.insert("base".into(), toml::Value::Table(b));
        Ok(())
    }

    /// Sets agent `name`'s `sitting` flag.
    pub fn set_sitting(&mut self, name: &str, sitting: bool) -> Result<(), String> {
        let agent = self.agent_mut(name)?;
        agent.insert("sitting".into(), toml::Value::Boolean(sitting));
        Ok(())
    }

    /// The world of this text; `source` names it in errors, `base_dir` resolves the URDF paths.
    pub fn world(&self, source: &str, base_dir: &Path) -> Result<World, String> {
        let text = self.to_toml()?;
        let scene =
            Scene::from_str(&text, source, base_dir, "generated").map_err(|e| e.to_string())?;
        World::from_scene(scene).map_err(|e| e.to_string())
    }
}

/// A new fixed piece of furniture of a generated scene: parts (boxes and cylinders placed in its
/// frame, upright), standing on the floor at `xy` turned by `yaw_deg`.
#[derive(Clone, Debug, PartialEq)]
pub struct NewFurniture {
    pub name: String,
    pub xy: [f32; 2],
    pub yaw_deg: f32,
    /// Each part's shape and centre in the furniture's frame.
    pub parts: Vec<(NewShape, [f32; 3])>,
    /// Support rectangles in its frame: centre and half extents (none: not a support).
    pub surfaces: Vec<([f32; 3], [f32; 2])>,
    pub colour: [u8; 3],
}

impl NewShape {
    /// The scene format's `shape` table.
    fn to_toml(self) -> toml::Value {
        let mut shape = toml::Table::new();
        match self {
            NewShape::Box(h) => {
                shape.insert("box".into(), floats(&h));
            }
            NewShape::Cylinder {
                radius,
                half_height,
            } => {
                let mut c = toml::Table::new();
                c.insert("radius".into(), toml::Value::Float(f64::from(radius)));
                c.insert(
                    "half_height".into(),
                    toml::Value::Float(f64::from(half_height)),
                );
                shape.insert("cylinder".into(), toml::Value::Table(c));
            }
        }
        toml::Value::Table(shape)
    }
}

fn pose_table(xyz: [f32; 3], rpy: [f32; 3]) -> toml::Value {
    let mut pose = toml::Table::new();
    pose.insert("xyz".into(), floats(&xyz));
    pose.insert("rpy".into(), floats(&rpy));
    toml::Value::Table(pose)
}

fn colour(c: [u8; 3]) -> toml::Value {
    toml::Value::Array(
        c.iter()
            .map(|&c| toml::Value::Integer(i64::from(c)))
            .collect(),
    )
}

fn floats(v: &[f32]) -> toml::Value {
    toml::Value::Array(
        v.iter()
            .map(|&x| toml::Value::Float(f64::from((x * 1e4).round() / 1e4)))
            .collect(),
    )
}

fn xyz_of(pose: &toml::Table) -> Result<[f32; 3], String> {
    let Some(v) = pose.get("xyz") else {
        return Ok([0.0; 3]);
    };
    let a = v.as_array().ok_or("pose.xyz is not an array")?;
    let mut out = [0.0f32; 3];
    for (k, x) in a.iter().take(3).enumerate() {
        out[k] = x
            .as_float()
            .or_else(|| x.as_integer().map(|i| i as f64))
            .ok_or("pose.xyz holds a value that is not a number")? as f32;
    }
    Ok(out)
}

/// A support surface of a world, in world coordinates: a rectangle turned by its support's
/// yaw (furniture stands upright; a tilt is ignored).
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub support: ObjectId,
    /// Centre of the rectangle, world frame (z: its height).
    pub centre: Vector,
    pub half_extents: [f32; 2],
    /// The rectangle's turn about the vertical (radians): its first half extent lies along
    /// `(cos yaw, sin yaw)`.
    pub yaw: f32,
}

impl Surface {
    /// The world point of the surface's local `(u, v)` (along its half extents), `dz` above it.
    pub fn at(&self, u: f32, v: f32, dz: f32) -> Vector {
        let (s, c) = self.yaw.sin_cos();
        self.centre + Vector::new(c * u - s * v, s * u + c * v, dz)
    }

    /// The half extents, along the surface's own axes, of the rectangle that holds a world
    /// x-y rectangle of half sizes `half` (an object's footprint as its bounding box has it).
    pub fn local_half(&self, half: [f32; 2]) -> [f32; 2] {
        let (s, c) = self.yaw.sin_cos();
        let (s, c) = (s.abs(), c.abs());
        [c * half[0] + s * half[1], s * half[0] + c * half[1]]
    }

    /// A point of the rectangle's edge and the outward normal there (world frame, z 0), for
    /// `t` in `[0, 1)` along its perimeter (the sides weighted by their length).
    pub fn edge_point(&self, t: f32) -> (Vector, Vector) {
        let [hx, hy] = self.half_extents;
        let t = t.clamp(0.0, 1.0) * 4.0 * (hx + hy);
        let along = |u: f32, h: f32| -h + (u / (2.0 * h)).min(1.0) * 2.0 * h;
        let (u, v, out) = if t < 2.0 * hx {
            (along(t, hx), hy, [0.0, 1.0])
        } else if t < 4.0 * hx {
            (along(t - 2.0 * hx, hx), -hy, [0.0, -1.0])
        } else if t < 4.0 * hx + 2.0 * hy {
            (hx, along(t - 4.0 * hx, hy), [1.0, 0.0])
        } else {
            (-hx, along(t - 4.0 * hx - 2.0 * hy, hy), [-1.0, 0.0])
        };
        let p = self.at(u, v, 0.0);
        let n = self.at(out[0], out[1], 0.0) - self.centre;
        (Vector::new(p.x, p.y, 0.0), Vector::new(n.x, n.y, 0.0))
    }

    /// The world points of a grid `step` apart over the surface, `dz` above it.
    pub fn grid(&self, step: f32, dz: f32) -> Vec<Vector> {
        let [hx, hy] = self.half_extents;
        let (nx, ny) = ((hx / step) as i32, (hy / step) as i32);
        (-nx..=nx)
            .flat_map(|i| (-ny..=ny).map(move |j| (i, j)))
            .map(|(i, j)| self.at(i as f32 * step, j as f32 * step, dz))
            .collect()
    }
}

/// Every support surface of `world`'s fixed objects.
pub fn surfaces(world: &World) -> Vec<Surface> {
    world
        .object_ids()
        .filter(|&id| !world.object(id).movable)
        .flat_map(|id| {
            let pose = world.object_pose(id);
            let (yaw, _, _) = pose.rotation.to_euler(parry3d::glamx::EulerRot::ZYX);
            world.object(id).surfaces.iter().map(move |s| Surface {
                support: id,
                centre: pose * s.centre,
                half_extents: s.half_extents,
                yaw,
            })
        })
        .collect()
}

/// Footprints (x-y rectangles) taken on surfaces: the objects of a world that stand on one, and
/// those the generator placed since.
#[derive(Clone, Debug, Default)]
pub struct Footprints {
    /// Each with the object it belongs to (`None`: placed by the generator).
    taken: Vec<(Option<ObjectId>, Aabb)>,
}

impl Footprints {
    /// The footprints of `world`'s objects (a surface's own support is skipped when a spot on
    /// it is tested).
    pub fn of(world: &World) -> Footprints {
        let taken = world
            .object_ids()
            .map(|id| (Some(id), world.object_aabb(id)))
            .collect();
        Footprints { taken }
    }

    /// Marks the rectangle `centre ± half` (x, y) at heights `z` taken.
    pub fn take(&mut self, centre: Vector, half: [f32; 2], z: [f32; 2]) {
        self.taken.push((
            None,
            Aabb::new(
                Vector::new(centre.x - half[0], centre.y - half[1], z[0]),
                Vector::new(centre.x + half[0], centre.y + half[1], z[1]),
            ),
        ));
    }

    /// Whether the rectangle `centre ± half` on surface `s` keeps `clear` metres from every
    /// footprint that reaches the height band just over the surface (its support's aside).
    pub fn is_free(&self, s: &Surface, centre: Vector, half: [f32; 2], clear: f32) -> bool {
        let (z0, z1) = (s.centre.z - 0.01, s.centre.z + 0.6);
        self.taken.iter().all(|(id, b)| {
            *id == Some(s.support)
                || b.maxs.z < z0
                || b.mins.z > z1
                || centre.x + half[0] + clear <= b.mins.x
                || centre.x - half[0] - clear >= b.maxs.x
                || centre.y + half[1] + clear <= b.mins.y
                || centre.y - half[1] - clear >= b.maxs.y
        })
    }

    /// A random free spot for a world x-y rectangle of half sizes `half` on surface `s` (inside
    /// it by `margin`, the surface turned as it is), `clear` from every footprint; `None` after
    /// `tries` draws.
    pub fn draw(
        &self,
        s: &Surface,
        half: [f32; 2],
        margin: f32,
        clear: f32,
        tries: usize,
        rng: &mut fastrand::Rng,
    ) -> Option<Vector> {
        let local = s.local_half(half);
        let room = [
            s.half_extents[0] - local[0] - margin,
            s.half_extents[1] - local[1] - margin,
        ];
        if room[0] < 0.0 || room[1] < 0.0 {
            return None;
        }
        (0..tries).find_map(|_| {
            let c = s.at(
                (rng.f32() * 2.0 - 1.0) * room[0],
                (rng.f32() * 2.0 - 1.0) * room[1],
                0.0,
            );
            self.is_free(s, c, half, clear).then_some(c)
        })
    }
}
