//! A small CPU renderer: ray casting against the world's bodies through a BVH (parry's `Bvh`
//! and `RayCast`), from a pinhole camera (an agent's eye) or an orthographic one (from above).
//!
//! [`render`] fills an *id buffer* (which body each pixel sees), a depth buffer and a shaded
//! colour image; [`Rendered::save_png`] writes the picture. Pixel visibility
//! ([`crate::visibility`]) uses the same [`Camera`] and [`SceneBvh`]. [`render_visual`] draws
//! the agents' links by their URDF visual meshes where they have any (read on first use and
//! kept per file and scale: planning never reads them), by their collision shapes otherwise.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use parry3d::bounding_volume::Aabb;
use parry3d::math::{Pose, Rotation, Vector};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query::Ray;
use parry3d::shape::SharedShape;

use crate::scene::AgentId;
use crate::world::{Body, BodyOwner, World};

/// How a camera maps pixels to rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// A pinhole camera with these full horizontal and vertical fields of view (radians).
    Perspective { fov_x: f32, fov_y: f32 },
    /// Parallel rays; the image covers `width` x `height` metres.
    Orthographic { width: f32, height: f32 },
}

/// A camera: a pose in the eye convention (x forward, y left, z up) and a projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub pose: Pose,
    pub projection: Projection,
}

impl Camera {
    /// A perspective camera at `eye` looking at `target` with z as close to world up as possible.
    pub fn look_at(eye: Vector, target: Vector, fov_x: f32, fov_y: f32) -> Camera {
        Camera {
            pose: Pose::from_parts(eye, look_rotation(target - eye)),
            projection: Projection::Perspective { fov_x, fov_y },
        }
    }

    /// An orthographic camera looking straight down on `area` (image up = world +y, right = +x).
    pub fn top(area: &Aabb, aspect: f32) -> Camera {
        let c = area.center();
        let he = area.half_extents();
        let (mut w, mut h) = (2.0 * he.x * 1.05, 2.0 * he.y * 1.05);
        if w / h < aspect {
            w = h * aspect;
        } else {
            h = w / aspect;
        }
        // Frame: forward -z, left -x, up +y (right-handed).
        let rot = Rotation::from_mat3(&parry3d::math::Mat3::from_cols(
            Vector::new(0.0, 0.0, -1.0),
            Vector::new(-1.0, 0.0, 0.0),
            Vector::new(0.0, 1.0, 0.0),
        ));
        Camera {
            pose: Pose::from_parts(Vector::new(c.x, c.y, area.maxs.z + 1.0), rot),
            projection: Projection::Orthographic {
                width: w,
                height: h,
            },
        }
    }

    /// The ray through image-plane coordinates `(u, v)`, both in -1..1 (u to the right, v up).
    /// Directions are not normalised (ray parameters are distances along the camera's forward axis
    /// for perspective cameras).
    #[inline]
    pub fn ray(&self, u: f32, v: f32) -> Ray {
        let r = self.pose.rotation;
        match self.projection {
            Projection::Perspective { fov_x, fov_y } => {
                let (tx, ty) = ((0.5 * fov_x).tan(), (0.5 * fov_y).tan());
                let d = r * Vector::new(1.0, -u * tx, v * ty);
                Ray::new(self.pose.translation, d)
            }
            Projection::Orthographic { width, height } => {
                let o = self.pose.translation
                    + r * Vector::new(0.0, -0.5 * u * width, 0.5 * v * height);
                Ray::new(o, r * Vector::X)
            }
        }
    }

    /// Image-plane coordinates `(u, v)` of a world point, or `None` behind a perspective camera.
    pub fn project(&self, p: Vector) -> Option<(f32, f32)> {
        let l = self.pose.inverse_transform_point(p);
        match self.projection {
            Projection::Perspective { fov_x, fov_y } => {
                if l.x <= 1e-6 {
                    return None;
                }
                let (tx, ty) = ((0.5 * fov_x).tan(), (0.5 * fov_y).tan());
                Some((-l.y / (l.x * tx), l.z / (l.x * ty)))
            }
            Projection::Orthographic { width, height } => {
                Some((-2.0 * l.y / width, 2.0 * l.z / height))
            }
        }
    }
}

/// Rotation whose x axis points along `dir` and whose z axis is as close to world up as possible.
pub fn look_rotation(dir: Vector) -> Rotation {
    let x = dir.normalize_or(Vector::X);
    let up = if x.z.abs() > 0.999 {
        Vector::X
    } else {
        Vector::Z
    };
    let y = up.cross(x).normalize();
    let z = x.cross(y);
    Rotation::from_mat3(&parry3d::math::Mat3::from_cols(x, y, z))
}

/// The world's bodies with a BVH over their bounding boxes, for ray queries.
pub struct SceneBvh<'a> {
    pub bodies: Vec<Body<'a>>,
    pub aabbs: Vec<Aabb>,
    bvh: Bvh,
}

/// A ray hit: which body, at which ray parameter, with which world normal.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub body: usize,
    pub toi: f32,
    pub normal: Vector,
}

impl<'a> SceneBvh<'a> {
    /// Every body of the world.
    pub fn new(world: &'a World) -> SceneBvh<'a> {
        SceneBvh::from_bodies(world.bodies())
    }

    /// A chosen set of bodies.
    pub fn from_bodies(bodies: Vec<Body<'a>>) -> SceneBvh<'a> {
        let aabbs: Vec<Aabb> = bodies
            .iter()
            .map(|b| b.shape.compute_aabb(&b.pose))
            .collect();
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &aabbs);
        SceneBvh { bodies, aabbs, bvh }
    }

    /// The closest hit along `ray` within `max_toi`.
    pub fn cast(&self, ray: &Ray, max_toi: f32) -> Option<Hit> {
        if self.bodies.is_empty() {
            return None;
        }
        let (leaf, _) = self.bvh.cast_ray(ray, max_toi, |leaf, best| {
            let b = &self.bodies[leaf as usize];
            b.shape.cast_ray(&b.pose, ray, best, true)
        })?;
        let b = &self.bodies[leaf as usize];
        let hit = b
            .shape
            .cast_ray_and_get_normal(&b.pose, ray, max_toi, true)?;
        Some(Hit {
            body: leaf as usize,
            toi: hit.time_of_impact,
            normal: hit.normal,
        })
    }

    /// Whether any body other than those `skip` accepts blocks `ray` before `max_toi`.
    pub fn blocked(&self, ray: &Ray, max_toi: f32, skip: impl Fn(BodyOwner) -> bool) -> bool {
        for leaf in self
            .bvh
            .leaves(|node| node.cast_ray(ray, max_toi) < max_toi)
        {
            let b = &self.bodies[leaf as usize];
            if skip(b.owner) {
                continue;
            }
            if b.shape.intersects_ray(&b.pose, ray, max_toi) {
                return true;
            }
        }
        false
    }
}

/// A rendered image: for every pixel (row-major, row 0 at the top) the body seen, its depth
/// (ray parameter) and the shaded colour.
pub struct Rendered {
    pub width: usize,
    pub height: usize,
    /// Who owns the body each pixel sees (`None`: floor or background).
    pub ids: Vec<Option<BodyOwner>>,
    pub depth: Vec<f32>,
    /// RGB, 3 bytes per pixel.
    pub rgb: Vec<u8>,
}

impl Rendered {
    /// Number of pixels showing `owner`.
    pub fn count(&self, owner: BodyOwner) -> usize {
        self.ids.iter().filter(|&&o| o == Some(owner)).count()
    }

    /// Writes the colour image as a PNG file.
    pub fn save_png(&self, path: &Path) -> Result<(), String> {
        let img =
            image::RgbImage::from_raw(self.width as u32, self.height as u32, self.rgb.clone())
                .ok_or_else(|| "image buffer has the wrong size".to_string())?;
        // Encoded in memory, then written whole: a buffered file writer would drop the error
        // of its last flush (a full disk) and report success.
        let mut png = std::io::Cursor::new(Vec::new());
        img.write_to(&mut png, image::ImageFormat::Png)
            .map_err(|e| format!("{}: cannot encode PNG: {e}", path.display()))?;
        std::fs::write(path, png.into_inner())
            .map_err(|e| format!("{}: cannot write PNG: {e}", path.display()))
    }
}

/// The camera of an agent's eye (its current head pose) with its field of view.
pub fn agent_camera(world: &World, agent: AgentId) -> Camera {
    let info = world.agent(agent);
    Camera {
        pose: world.eye_pose(agent),
        projection: Projection::Perspective {
            fov_x: info.fov[0],
            fov_y: info.fov[1],
        },
    }
}

fn shade(colour: [u8; 3], normal: Vector, view_dir: Vector) -> [u8; 3] {
    let sun = Vector::new(0.35, 0.25, 0.9).normalize();
    let n = if normal.dot(view_dir) > 0.0 {
        -normal
    } else {
        normal
    };
    let diffuse = n.dot(sun).max(0.0);
    let head = n.dot(-view_dir.normalize()).max(0.0);
    let k = 0.30 + 0.45 * diffuse + 0.30 * head;
    let f = |c: u8| ((c as f32 * k).min(255.0)) as u8;
    [f(colour[0]), f(colour[1]), f(colour[2])]
}

/// Renders the world from `camera` at `width` x `height` pixels, in parallel over rows.
/// The floor (z = 0) is drawn as a grey checkerboard (it owns no pixels in the id buffer).
pub fn render(world: &World, camera: &Camera, width: usize, height: usize) -> Rendered {
    let scene = SceneBvh::from_bodies(outside(world.bodies(), camera));
    render_scene(&scene, camera, width, height)
}

/// `bodies` but those the camera is inside of: an eye inside its own sensor's housing (the real
/// PR2's camera in the hull of its Kinect) sees out of it, as the visibility test's eye does.
fn outside<'a>(bodies: Vec<Body<'a>>, camera: &Camera) -> Vec<Body<'a>> {
    let eye = camera.pose.translation;
    bodies
        .into_iter()
        .filter(|b| !b.shape.contains_point(&b.pose, eye))
        .collect()
}

/// Renders the world as [`render`] does, but with every agent link that has URDF visual meshes
/// drawn by them (placed at the link's pose times the visual's origin, scaled, in the
/// material's colour or else the agent's); links without visual meshes, or whose meshes cannot
/// be read, are drawn by their collision shapes. Also returns one warning per visual mesh file
/// that could not be read.
pub fn render_visual(
    world: &World,
    camera: &Camera,
    width: usize,
    height: usize,
) -> (Rendered, Vec<String>) {
    let drawn = VisualBodies::of(world);
    let scene = SceneBvh::from_bodies(outside(drawn.bodies(), camera));
    (render_scene(&scene, camera, width, height), drawn.warnings)
}

/// What agent `agent` sees from its eye ([`agent_camera`]), drawn as [`render_visual`] does,
/// but for the housing of the eye: a visual mesh of a link fixed to the eye link (a head's
/// screen, a camera's case) whose box holds the eye is left out, its link drawn by its
/// collision shapes, which [`render`] leaves out where they hold the eye. A visual mesh is a
/// shell (often open), so the eye inside it would see nothing but its walls (Baxter's head
/// camera, inside its screen's mesh).
pub fn render_eye_view(
    world: &World,
    agent: AgentId,
    width: usize,
    height: usize,
) -> (Rendered, Vec<String>) {
    let camera = agent_camera(world, agent);
    let drawn = VisualBodies::seen_by(world, Some(agent));
    let scene = SceneBvh::from_bodies(outside(drawn.bodies(), &camera));
    (render_scene(&scene, &camera, width, height), drawn.warnings)
}

/// The shapes a picture with visual meshes draws, owned (visual meshes are built here).
pub struct VisualBodies {
    shapes: Vec<(BodyOwner, SharedShape, parry3d::math::Pose, [u8; 3])>,
    /// One line per visual mesh file that could not be read (its link is drawn by its
    /// collision shapes).
    pub warnings: Vec<String>,
}

impl VisualBodies {
    /// The world's objects, and its agents' links by their visual meshes where they have any.
    pub fn of(world: &World) -> VisualBodies {
        VisualBodies::seen_by(world, None)
    }

    /// [`VisualBodies::of`], seen from the eye of `viewer` where given: the visual meshes of
    /// its eye's housing left out (see [`render_eye_view`]).
    fn seen_by(world: &World, viewer: Option<AgentId>) -> VisualBodies {
        let mut shapes = Vec::new();
        let mut warnings = Vec::new();
        let mut by_visuals = std::collections::HashSet::new();
        for a in world.agent_ids() {
            let info = world.agent(a);
            let poses = world.agent_state(a).link_poses();
            // The eye's housing: links fixed to the eye link whose visual mesh's box holds it.
            let eye = viewer.filter(|&v| v == a).map(|_| {
                (
                    world.eye_pose(a).translation,
                    info.model.rigid_links(info.eye_link),
                )
            });
            for (li, link) in info.model.links().iter().enumerate() {
                let housed = eye.as_ref().is_some_and(|(eye, housing)| {
                    housing.contains(&li)
                        && link.visuals.iter().any(|v| {
                            visual_shape(&v.path, v.scale).is_ok_and(|s| {
                                s.compute_aabb(&(poses[li] * v.local_pose))
                                    .contains_local_point(*eye)
                            })
                        })
                });
                if housed {
                    continue;
                }
                let mut drawn = Vec::new();
                for v in &link.visuals {
                    match visual_shape(&v.path, v.scale) {
                        Ok(shape) => {
                            let colour = v.colour.map_or(info.spec.colour, |c| {
                                [0, 1, 2].map(|k| (c[k] * 255.0).round() as u8)
                            });
                            drawn.push((
                                BodyOwner::Agent(a, li),
                                shape,
                                poses[li] * v.local_pose,
                                colour,
                            ));
                        }
                        Err(e) => warnings.push(format!(
                            "agent '{}': link '{}': visual mesh '{}' ({}): {e}; drawn by its \
                             collision shapes",
                            info.name(),
                            link.name,
                            v.uri,
                            v.path.display()
                        )),
                    }
                }
                if !drawn.is_empty() {
                    by_visuals.insert((a, li));
                    shapes.extend(drawn);
                }
            }
        }
        for b in world.bodies() {
            let replaced =
                matches!(b.owner, BodyOwner::Agent(a, li) if by_visuals.contains(&(a, li)));
            if !replaced {
                shapes.push((b.owner, b.shape.clone(), b.pose, b.colour));
            }
        }
        VisualBodies { shapes, warnings }
    }

    /// The bodies, borrowing the shapes.
    pub fn bodies(&self) -> Vec<Body<'_>> {
        self.shapes
            .iter()
            .map(|(owner, shape, pose, colour)| Body {
                owner: *owner,
                shape,
                pose: *pose,
                colour: *colour,
                radius: None,
            })
            .collect()
    }
}

/// A visual mesh file as a triangle mesh, scaled; read once per file and scale (errors too).
fn visual_shape(path: &Path, scale: Vector) -> Result<SharedShape, String> {
    type Cache = HashMap<(PathBuf, [u32; 3]), Result<SharedShape, String>>;
    static CACHE: OnceLock<Mutex<Cache>> = OnceLock::new();
    let key = (path.to_path_buf(), scale.to_array().map(f32::to_bits));
    let cache = CACHE.get_or_init(Default::default);
    if let Some(found) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return found.clone();
    }
    let made = crate::mesh_file::read_mesh(path).and_then(|m| {
        let vertices = m.vertices.iter().map(|v| *v * scale).collect();
        SharedShape::trimesh(vertices, m.triangles)
            .map_err(|e| format!("not a usable triangle mesh: {e:?}"))
    });
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(key, made.clone());
    made
}

/// Renders the bodies of `scene` from `camera` (see [`render`]).
fn render_scene(scene: &SceneBvh<'_>, camera: &Camera, width: usize, height: usize) -> Rendered {
    use rayon::prelude::*;
    let n = width * height;
    let mut ids = vec![None; n];
    let mut depth = vec![f32::INFINITY; n];
    let mut rgb = vec![0u8; n * 3];
    ids.par_chunks_mut(width)
        .zip(depth.par_chunks_mut(width))
        .zip(rgb.par_chunks_mut(width * 3))
        .enumerate()
        .for_each(|(j, ((id_row, d_row), c_row))| {
            let v = 1.0 - 2.0 * (j as f32 + 0.5) / height as f32;
            for i in 0..width {
                let u = 2.0 * (i as f32 + 0.5) / width as f32 - 1.0;
                let ray = camera.ray(u, v);
                let c = match scene.cast(&ray, 1e4) {
                    Some(hit) => {
                        let b = &scene.bodies[hit.body];
                        id_row[i] = Some(b.owner);
                        d_row[i] = hit.toi;
                        shade(b.colour, hit.normal, ray.dir)
                    }
                    None => {
                        if ray.dir.z < -1e-6 {
                            let t = -ray.origin.z / ray.dir.z;
                            let p = ray.point_at(t);
                            d_row[i] = t;
                            let check = ((p.x / 0.5).floor() + (p.y / 0.5).floor()) as i64 & 1;
                            let g = if check == 0 { 200 } else { 180 };
                            let fade = (1.0 / (1.0 + 0.02 * t * ray.dir.length())).max(0.6);
                            let g = (g as f32 * fade) as u8;
                            [g, g, g.saturating_add(6)]
                        } else {
                            [176, 200, 228]
                        }
                    }
                };
                c_row[3 * i..3 * i + 3].copy_from_slice(&c);
            }
        });
    // Outline: darken pixels whose neighbour sees another body, so touching objects stay apart.
    let mut out = rgb.clone();
    for j in 0..height {
        for i in 0..width {
            let k = j * width + i;
            let edge = (i + 1 < width && ids[k + 1] != ids[k])
                || (j + 1 < height && ids[k + width] != ids[k]);
            if edge && ids[k].is_some() {
                for c in &mut out[3 * k..3 * k + 3] {
                    *c = (*c as f32 * 0.45) as u8;
                }
            }
        }
    }
    Rendered {
        width,
        height,
        ids,
        depth,
        rgb: out,
    }
}
