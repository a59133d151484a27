//! A URDF collision mesh as convex geometry: its convex hull, or a convex decomposition where
//! the hull would fill a hollow that matters.
//!
//! The rule ([`ConvexMode::Auto`]): a mesh is decomposed (parry3d's VHACD, exact hulls of its
//! parts) when it is closed and consistently wound (every edge shared by two triangles that
//! run it in opposite directions, after welding equal vertices)
//! and its volume is below [`DECOMPOSE_BELOW`] of its hull's: the hull would then fill more
//! than half of the space the mesh leaves free, as between a gripper's jaws or inside a
//! U-shaped link. Any other mesh (open, or filling its hull well) collides as its hull, the
//! usual practice of MoveIt and of physics engines. A scene overrides the rule per link
//! (`hull_links`, `decompose_links`). Results are cached in memory per file, scale and mode for
//! the life of the process, and on disk between runs (see `convex_cache`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

use parry3d::math::{Pose, Vector};
use parry3d::shape::SharedShape;
use parry3d::transformation::vhacd::VHACDParameters;

use super::convex_cache;
use crate::mesh_file;

/// A closed mesh filling less than this fraction of its hull is decomposed ([`ConvexMode::Auto`]).
pub const DECOMPOSE_BELOW: f32 = 0.5;
/// The most convex pieces a decomposition may give.
pub const MAX_PIECES: u32 = 16;

/// How a collision mesh becomes convex geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ConvexMode {
    /// By the rule of this module: hull, or decomposition of a closed mesh filling its hull badly.
    Auto,
    /// Always the convex hull.
    Hull,
    /// Always a convex decomposition.
    Decompose,
}

/// One convex piece of a mesh, centred: `shape`'s vertices are relative to `centre`.
#[derive(Clone)]
pub struct ConvexPiece {
    /// Where the piece's frame is in the mesh's frame (the centre of its bounding box).
    pub centre: Vector,
    /// The convex polyhedron.
    pub shape: SharedShape,
    /// Radius of the sphere about `centre` that holds the piece.
    pub radius: f32,
    /// The points `shape` is the hull of (relative to `centre`), as the disk cache keeps them.
    pub points: Vec<Vector>,
}

/// A mesh file as convex pieces, with what the rule measured.
#[derive(Clone)]
pub struct ConvexMesh {
    /// The pieces (one for a hull).
    pub pieces: Vec<ConvexPiece>,
    /// Triangles of the mesh read.
    pub triangles: usize,
    /// The mesh's volume over its hull's (`None` for an open mesh).
    pub fill: Option<f32>,
}

type Key = (PathBuf, [u32; 3], ConvexMode);

/// The convex geometry of the mesh file `path` scaled by `scale`, made by `mode`; cached per
/// file, scale and mode. The error is a sentence without the file name.
pub fn convex_mesh(
    path: &Path,
    scale: [f32; 3],
    mode: ConvexMode,
) -> Result<Arc<ConvexMesh>, String> {
    static CACHE: OnceLock<Mutex<HashMap<Key, Arc<ConvexMesh>>>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    let key = (canonical, scale.map(f32::to_bits), mode);
    if let Some(found) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return Ok(found.clone());
    }
    // The disk cache, where there is one and the file reads.
    let disk = convex_cache::folder().zip(std::fs::read(path).ok());
    let found = disk
        .as_ref()
        .and_then(|(dir, bytes)| convex_cache::load(dir, bytes, scale, mode));
    let made = match found {
        Some(found) => Arc::new(found),
        None => {
            let made = guarded_convex(&mesh_file::read_mesh(path)?, scale, mode)?;
            if let Some((dir, bytes)) = &disk {
                convex_cache::store(dir, bytes, scale, mode, &made);
            }
            Arc::new(made)
        }
    };
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(key, made.clone());
    Ok(made)
}

/// [`make_convex`], with a panic of parry's hull or VHACD (on degenerate input) turned into an
/// error: a bad mesh must not take the caller down.
pub fn guarded_convex(
    mesh: &mesh_file::MeshData,
    scale: [f32; 3],
    mode: ConvexMode,
) -> Result<ConvexMesh, String> {
    std::panic::catch_unwind(|| make_convex(mesh, scale, mode))
        .map_err(|_| "the convex hull computation failed on this mesh (degenerate?)".to_string())?
}

/// The convex pieces of `mesh` scaled by `scale`.
pub fn make_convex(
    mesh: &mesh_file::MeshData,
    scale: [f32; 3],
    mode: ConvexMode,
) -> Result<ConvexMesh, String> {
    let s = Vector::from(scale);
    let vertices: Vec<Vector> = mesh.vertices.iter().map(|v| *v * s).collect();
    let hull = SharedShape::convex_hull(&vertices)
        .ok_or("the mesh's vertices span no volume (flat or degenerate); use a primitive")?;
    let hull_volume = hull.mass_properties(1.0).mass();
    let fill = closed_volume(&vertices, &mesh.triangles)
        .filter(|_| hull_volume > 0.0)
        .map(|v| v / hull_volume);
    let decompose = match mode {
        ConvexMode::Hull => false,
        ConvexMode::Decompose => true,
        ConvexMode::Auto => fill.is_some_and(|f| f < DECOMPOSE_BELOW),
    };
    let shapes = if decompose {
        decomposition(&vertices, &mesh.triangles)
    } else {
        vec![hull]
    };
    let pieces = shapes
        .into_iter()
        .filter_map(|s| centred(&s))
        .collect::<Vec<_>>();
    if pieces.is_empty() {
        return Err("the convex decomposition gave no piece with volume".into());
    }
    Ok(ConvexMesh {
        pieces,
        triangles: mesh.triangles.len(),
        fill,
    })
}

/// Exact convex hulls of the parts VHACD finds.
fn decomposition(vertices: &[Vector], triangles: &[[u32; 3]]) -> Vec<SharedShape> {
    let params = VHACDParameters {
        max_convex_hulls: MAX_PIECES,
        ..VHACDParameters::default()
    };
    let compound = SharedShape::convex_decomposition_with_params(vertices, triangles, &params);
    match compound.as_compound() {
        Some(c) => c.shapes().iter().map(|(_, s)| s.clone()).collect(),
        None => vec![compound],
    }
}

/// `shape` (a convex polyhedron) moved so that its bounding box is centred on its frame.
fn centred(shape: &SharedShape) -> Option<ConvexPiece> {
    let poly = shape.as_convex_polyhedron()?;
    let aabb = shape.compute_local_aabb();
    let centre = aabb.center();
    piece(centre, poly.points().iter().map(|p| *p - centre).collect())
}

/// The piece centred at `centre` that is the hull of `points` (relative to `centre`).
pub(super) fn piece(centre: Vector, points: Vec<Vector>) -> Option<ConvexPiece> {
    let radius = points.iter().map(|p| p.length()).fold(0.0, f32::max);
    let shape = SharedShape::convex_hull(&points)?;
    Some(ConvexPiece {
        centre,
        shape,
        radius,
        points,
    })
}

/// The enclosed volume of a closed, consistently wound triangle mesh (every edge shared by
/// exactly two triangles that run it in opposite directions, once equal vertices are welded),
/// `None` otherwise (open, or wound inconsistently: its signed volume would mean nothing).
fn closed_volume(vertices: &[Vector], triangles: &[[u32; 3]]) -> Option<f32> {
    let mut id: HashMap<[u32; 3], u32> = HashMap::new();
    let weld: Vec<u32> = vertices
        .iter()
        .map(|v| {
            let n = id.len() as u32;
            *id.entry([v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
                .or_insert(n)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    let mut volume = 0.0f64;
    for t in triangles {
        let w = t.map(|i| weld[i as usize]);
        for k in 0..3 {
            let (a, b) = (w[k], w[(k + 1) % 3]);
            // +1 for a -> b, +1000 for b -> a: a closed, consistently wound surface has every
            // edge once each way (1001).
            let count = edges.entry((a.min(b), a.max(b))).or_default();
            *count += if a < b { 1 } else { 1000 };
        }
        let [a, b, c] = t.map(|i| {
            let v = vertices[i as usize];
            [v.x as f64, v.y as f64, v.z as f64]
        });
        let cross = [
            b[1] * c[2] - b[2] * c[1],
            b[2] * c[0] - b[0] * c[2],
            b[0] * c[1] - b[1] * c[0],
        ];
        volume += (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]) / 6.0;
    }
    edges
        .values()
        .all(|&n| n == 1001)
        .then_some(volume.abs() as f32)
}

/// The pose of a piece in the link frame, given the URDF element's origin.
pub fn piece_pose(origin: Pose, piece: &ConvexPiece) -> Pose {
    origin * Pose::from_translation(piece.centre)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed box mesh from (0,0,0) to `size`.
    fn box_mesh(lo: [f32; 3], hi: [f32; 3]) -> mesh_file::MeshData {
        let c = |i: usize| {
            Vector::new(
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            )
        };
        let vertices = (0..8).map(c).collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        mesh_file::MeshData {
            vertices,
            triangles,
        }
    }

    #[test]
    fn a_box_is_its_own_hull() {
        let m = make_convex(
            &box_mesh([0.0; 3], [1.0, 2.0, 3.0]),
            [1.0; 3],
            ConvexMode::Auto,
        )
        .unwrap();
        assert_eq!(m.pieces.len(), 1);
        assert!((m.fill.unwrap() - 1.0).abs() < 1e-4);
        assert!((m.pieces[0].centre - Vector::new(0.5, 1.0, 1.5)).length() < 1e-5);
    }

    #[test]
    fn a_u_shape_is_decomposed_and_keeps_its_gap() {
        // Two jaws joined by a bridge: a U whose hull fills the gap between the jaws.
        let mut u = box_mesh([0.0, 0.0, 0.0], [0.1, 1.0, 1.0]);
        for (lo, hi) in [
            ([0.9, 0.0, 0.0], [1.0, 1.0, 1.0]),
            ([0.1, 0.0, 0.0], [0.9, 1.0, 0.1]),
        ] {
            let other = box_mesh(lo, hi);
            let n = u.vertices.len() as u32;
            u.vertices.extend(other.vertices);
            u.triangles
                .extend(other.triangles.iter().map(|t| t.map(|i| i + n)));
        }
        // Three boxes touching, not one closed surface: forced decomposition.
        let m = make_convex(&u, [1.0; 3], ConvexMode::Decompose).unwrap();
        assert!(m.pieces.len() >= 2, "{} pieces", m.pieces.len());
        let gap = Vector::new(0.5, 0.5, 0.6);
        let inside = m.pieces.iter().any(|p| {
            p.shape
                .contains_point(&Pose::from_translation(p.centre), gap)
        });
        assert!(!inside, "a piece fills the gap between the jaws");
        let hull = make_convex(&u, [1.0; 3], ConvexMode::Hull).unwrap();
        let p = &hull.pieces[0];
        assert!(
            p.shape
                .contains_point(&Pose::from_translation(p.centre), gap)
        );
    }

    #[test]
    fn scale_applies_per_axis() {
        let m = make_convex(
            &box_mesh([0.0; 3], [1.0; 3]),
            [2.0, 1.0, 0.5],
            ConvexMode::Hull,
        )
        .unwrap();
        let aabb = m.pieces[0].shape.compute_local_aabb();
        let he = aabb.half_extents();
        assert!((he - Vector::new(1.0, 0.5, 0.25)).length() < 1e-5, "{he:?}");
    }
}
