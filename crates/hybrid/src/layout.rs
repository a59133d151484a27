//! Generated scenes: the library scene's text edited in memory (objects removed, moved, added)
//! and free spots on support surfaces, for the scale benchmark ([`crate::scale`]) and the
//! randomized layouts of `bench library --layout random`.

use std::path::Path;

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
        let mut shape = toml::Table::new();
        match object.shape {
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
        o.insert("shape".into(), toml::Value::Table(shape));
        let mut pose = toml::Table::new();
        pose.insert("xyz".into(), floats(&object.xyz));
        pose.insert("rpy".into(), floats(&object.rpy));
        o.insert("pose".into(), toml::Value::Table(pose));
        let colour = object
            .colour
            .iter()
            .map(|&c| toml::Value::Integer(i64::from(c)))
            .collect();
        o.insert("colour".into(), toml::Value::Array(colour));
        o.insert("movable".into(), toml::Value::Boolean(object.movable));
        self.objects_mut()?.push(toml::Value::Table(o));
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

/// A support surface of a world, in world coordinates (the support's rotation about the
/// vertical is ignored: the library's furniture stands square to the axes).
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub support: ObjectId,
    /// Centre of the rectangle, world frame (z: its height).
    pub centre: Vector,
    pub half_extents: [f32; 2],
}

/// Every support surface of `world`'s fixed objects.
pub fn surfaces(world: &World) -> Vec<Surface> {
    world
        .object_ids()
        .filter(|&id| !world.object(id).movable)
        .flat_map(|id| {
            let pose = world.object_pose(id);
            world.object(id).surfaces.iter().map(move |s| Surface {
                support: id,
                centre: pose * s.centre,
                half_extents: s.half_extents,
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

    /// A random free spot for a rectangle of half sizes `half` on surface `s` (inside it by
    /// `margin`), `clear` from every footprint; `None` after `tries` draws.
    pub fn draw(
        &self,
        s: &Surface,
        half: [f32; 2],
        margin: f32,
        clear: f32,
        tries: usize,
        rng: &mut fastrand::Rng,
    ) -> Option<Vector> {
        let room = [
            s.half_extents[0] - half[0] - margin,
            s.half_extents[1] - half[1] - margin,
        ];
        if room[0] < 0.0 || room[1] < 0.0 {
            return None;
        }
        (0..tries).find_map(|_| {
            let c = Vector::new(
                s.centre.x + (rng.f32() * 2.0 - 1.0) * room[0],
                s.centre.y + (rng.f32() * 2.0 - 1.0) * room[1],
                s.centre.z,
            );
            self.is_free(s, c, half, clear).then_some(c)
        })
    }
}
