//! The convex pieces of mesh files kept on disk between runs: a real robot's decompositions
//! (VHACD) take about a second per process to compute and never change for a given file.
//!
//! One JSON file per mesh file content, scale and mode, in `$HTNGTP_CACHE_DIR`, else
//! `$XDG_CACHE_HOME/htngtp`, else `~/.cache/htngtp` (`HTNGTP_CACHE_DIR=off` turns the cache
//! off). An entry holds its full key and is used only where the key matches: the mesh file's
//! bytes (two independent 64-bit hashes and the length), the scale, the mode, the rule's
//! constants and this crate's version. The pieces' points are stored as `f32` bits, and each
//! piece's hull is rebuilt from them by the same computation as when it was made, so an entry
//! gives exactly the pieces the computation would. A cache that cannot be read or written is
//! ignored: the pieces are then computed, as without it.

use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use parry3d::math::Vector;
use serde::{Deserialize, Serialize};

use super::convex::{ConvexMesh, ConvexMode, ConvexPiece, DECOMPOSE_BELOW, MAX_PIECES, piece};

/// What an entry is valid for.
#[derive(Serialize, Deserialize, PartialEq, Debug)]
struct Key {
    version: String,
    content: [u64; 2],
    length: u64,
    scale: [u32; 3],
    mode: String,
    max_pieces: u32,
    decompose_below: u32,
}

/// One piece: its centre and the points its hull is made from, as `f32` bits.
#[derive(Serialize, Deserialize)]
struct Piece {
    centre: [u32; 3],
    points: Vec<[u32; 3]>,
}

#[derive(Serialize, Deserialize)]
struct Entry {
    key: Key,
    triangles: usize,
    fill: Option<u32>,
    pieces: Vec<Piece>,
}

/// The folder of the cache, or `None` where it is off or no home is known.
pub(super) fn folder() -> Option<PathBuf> {
    match std::env::var_os("HTNGTP_CACHE_DIR") {
        Some(dir) if dir == "off" || dir.is_empty() => None,
        Some(dir) => Some(PathBuf::from(dir)),
        None => std::env::var_os("XDG_CACHE_HOME")
            .filter(|d| !d.is_empty())
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
            .map(|d| d.join("htngtp")),
    }
}

fn key(bytes: &[u8], scale: [f32; 3], mode: ConvexMode) -> Key {
    let hash = |seed: u64| {
        let mut h = DefaultHasher::new();
        seed.hash(&mut h);
        bytes.hash(&mut h);
        h.finish()
    };
    Key {
        version: env!("CARGO_PKG_VERSION").to_string(),
        content: [hash(0x68746e67), hash(0x67747021)],
        length: bytes.len() as u64,
        scale: scale.map(f32::to_bits),
        mode: format!("{mode:?}"),
        max_pieces: MAX_PIECES,
        decompose_below: DECOMPOSE_BELOW.to_bits(),
    }
}

fn file_of(folder: &Path, key: &Key) -> PathBuf {
    let mut h = DefaultHasher::new();
    format!("{key:?}").hash(&mut h);
    folder
        .join("convex")
        .join(format!("{:016x}{:016x}.json", key.content[0], h.finish()))
}

/// The cached pieces of the mesh file whose bytes are `bytes`, or `None` (no cache, no entry,
/// or an entry for another key or unreadable).
pub(super) fn load(
    folder: &Path,
    bytes: &[u8],
    scale: [f32; 3],
    mode: ConvexMode,
) -> Option<ConvexMesh> {
    let key = key(bytes, scale, mode);
    let text = std::fs::read(file_of(folder, &key)).ok()?;
    let entry: Entry = serde_json::from_slice(&text).ok()?;
    if entry.key != key {
        return None;
    }
    let bits = |v: [u32; 3]| Vector::from(v.map(f32::from_bits));
    let pieces = entry
        .pieces
        .iter()
        .map(|p| piece(bits(p.centre), p.points.iter().map(|&q| bits(q)).collect()))
        .collect::<Option<Vec<ConvexPiece>>>()?;
    Some(ConvexMesh {
        pieces,
        triangles: entry.triangles,
        fill: entry.fill.map(f32::from_bits),
    })
}

/// Keeps `mesh`, made from the mesh file whose bytes are `bytes`, for later runs; written to
/// a temporary file and renamed, so that a reader never sees half an entry. Failures are
/// ignored.
pub(super) fn store(
    folder: &Path,
    bytes: &[u8],
    scale: [f32; 3],
    mode: ConvexMode,
    mesh: &ConvexMesh,
) {
    let key = key(bytes, scale, mode);
    let path = file_of(folder, &key);
    let bits = |v: Vector| [v.x, v.y, v.z].map(f32::to_bits);
    let entry = Entry {
        key,
        triangles: mesh.triangles,
        fill: mesh.fill.map(f32::to_bits),
        pieces: mesh
            .pieces
            .iter()
            .map(|p| Piece {
                centre: bits(p.centre),
                points: p.points.iter().map(|&q| bits(q)).collect(),
            })
            .collect(),
    };
    let Ok(text) = serde_json::to_vec(&entry) else {
        return;
    };
    static WRITES: AtomicU64 = AtomicU64::new(0);
    let n = WRITES.fetch_add(1, Ordering::Relaxed);
    let temporary = path.with_extension(format!("{}-{n}.tmp", std::process::id()));
    let written = path
        .parent()
        .is_some_and(|dir| std::fs::create_dir_all(dir).is_ok())
        && std::fs::write(&temporary, text).is_ok()
        && std::fs::rename(&temporary, &path).is_ok();
    if !written {
        let _ = std::fs::remove_file(&temporary);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::agent::convex::make_convex;
    use crate::mesh_file::MeshData;

    /// A U of three boxes (a gripper's jaws).
    fn u_shape() -> MeshData {
        let mut mesh = MeshData {
            vertices: Vec::new(),
            triangles: Vec::new(),
        };
        for (lo, hi) in [
            ([0.0, 0.0, 0.0], [0.1, 0.02, 0.02]),
            ([0.0, 0.0, 0.02], [0.02, 0.02, 0.1]),
            ([0.08, 0.0, 0.02], [0.1, 0.02, 0.1]),
        ] {
            let base = mesh.vertices.len() as u32;
            for k in 0..8 {
                let pick = |axis: usize| {
                    if k >> axis & 1 == 0 {
                        lo[axis]
                    } else {
                        hi[axis]
                    }
                };
                mesh.vertices.push(Vector::new(pick(0), pick(1), pick(2)));
            }
            for [a, b, c] in [
                [0, 2, 1],
                [1, 2, 3],
                [4, 5, 6],
                [5, 7, 6],
                [0, 1, 4],
                [1, 5, 4],
                [2, 6, 3],
                [3, 6, 7],
                [0, 4, 2],
                [2, 4, 6],
                [1, 3, 5],
                [3, 7, 5],
            ] {
                mesh.triangles.push([base + a, base + b, base + c]);
            }
        }
        mesh
    }

    fn points_of(mesh: &ConvexMesh) -> Vec<Vec<Vector>> {
        let hull = |p: &ConvexPiece| p.shape.as_convex_polyhedron().unwrap().points().to_vec();
        mesh.pieces
            .iter()
            .map(|p| [vec![p.centre], hull(p)].concat())
            .collect()
    }

    #[test]
    fn an_entry_gives_back_exactly_the_pieces_stored() {
        let folder = std::env::temp_dir().join(format!("htngtp-cache-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&folder);
        let (bytes, scale) = (b"the mesh file".as_slice(), [1.0, 2.0, 1.0]);
        let made = make_convex(&u_shape(), scale, ConvexMode::Decompose).unwrap();
        assert!(made.pieces.len() > 1, "the U in pieces");
        assert!(
            load(&folder, bytes, scale, ConvexMode::Decompose).is_none(),
            "empty cache"
        );
        store(&folder, bytes, scale, ConvexMode::Decompose, &made);
        let found = load(&folder, bytes, scale, ConvexMode::Decompose).expect("stored");
        assert_eq!(points_of(&found), points_of(&made));
        assert_eq!((found.triangles, found.fill), (made.triangles, made.fill));
        // Another file content, scale or mode is another entry.
        assert!(load(&folder, b"another file", scale, ConvexMode::Decompose).is_none());
        assert!(load(&folder, bytes, [1.0; 3], ConvexMode::Decompose).is_none());
        assert!(load(&folder, bytes, scale, ConvexMode::Hull).is_none());
        // A damaged entry is ignored.
        let entry = file_of(&folder, &key(bytes, scale, ConvexMode::Decompose));
        std::fs::write(&entry, "{\"key\": ").unwrap();
        assert!(load(&folder, bytes, scale, ConvexMode::Decompose).is_none());
        let _ = std::fs::remove_dir_all(&folder);
    }
}
