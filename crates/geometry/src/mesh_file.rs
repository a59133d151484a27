//! Triangle-mesh files for scene objects: Wavefront OBJ and STL (ASCII and binary).
//!
//! A small reader of our own: vertices and triangles only (normals, texture coordinates,
//! materials and groups are ignored); polygons with more than three corners are fanned into
//! triangles. Errors name the line (OBJ, ASCII STL) or byte offset (binary STL).

use std::path::Path;

use parry3d::math::Vector;

/// A triangle soup read from a file: vertices in file units, triangles as vertex indices.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    pub vertices: Vec<Vector>,
    pub triangles: Vec<[u32; 3]>,
}

/// Reads an OBJ or STL file, chosen by the extension (`.obj`, `.stl`; case-insensitive).
/// The error is a sentence without the file name (the caller adds it).
pub fn read_mesh(path: &Path) -> Result<MeshData, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read mesh file: {e}"))?;
    let mesh = match ext.as_str() {
        "obj" => parse_obj(&String::from_utf8_lossy(&bytes))?,
        "stl" => parse_stl(&bytes)?,
        _ => {
            return Err(format!(
                "unknown mesh format `.{ext}` (expected .obj or .stl)"
            ));
        }
    };
    check_mesh(&mesh)?;
    Ok(mesh)
}

fn check_mesh(mesh: &MeshData) -> Result<(), String> {
    if mesh.triangles.is_empty() {
        return Err("mesh has no triangles".into());
    }
    if let Some(v) = mesh.vertices.iter().find(|v| !v.is_finite()) {
        return Err(format!("mesh has a non-finite vertex {v:?}"));
    }
    Ok(())
}

/// Parses Wavefront OBJ text: `v x y z [w]` and `f a b c ...` with `a`, `a/t`, `a//n`, `a/t/n`
/// forms and negative (relative) indices.
pub fn parse_obj(text: &str) -> Result<MeshData, String> {
    let mut mesh = MeshData::default();
    for (lineno, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let Some(tag) = words.next() else { continue };
        let at = |msg: String| format!("line {}: {msg}", lineno + 1);
        match tag {
            "v" => {
                let mut c = [0.0f32; 3];
                for (i, slot) in c.iter_mut().enumerate() {
                    let w = words
                        .next()
                        .ok_or_else(|| at(format!("vertex needs 3 coordinates, found {i}")))?;
                    *slot = w
                        .parse::<f32>()
                        .map_err(|_| at(format!("`{w}` is not a number")))?;
                    if !slot.is_finite() {
                        return Err(at(format!("vertex coordinate `{w}` is not finite")));
                    }
                }
                mesh.vertices.push(Vector::new(c[0], c[1], c[2]));
            }
            "f" => {
                let mut corners = Vec::with_capacity(4);
                for w in words {
                    let first = w.split('/').next().unwrap_or("");
                    let idx: i64 = first
                        .parse()
                        .map_err(|_| at(format!("face index `{w}` is not an integer")))?;
                    let n = mesh.vertices.len() as i64;
                    let resolved = if idx > 0 { idx - 1 } else { n + idx };
                    if idx == 0 || resolved < 0 || resolved >= n {
                        return Err(at(format!(
                            "face index {idx} out of range (1..={n} vertices so far)"
                        )));
                    }
                    corners.push(resolved as u32);
                }
                if corners.len() < 3 {
                    return Err(at(format!(
                        "face needs at least 3 corners, found {}",
                        corners.len()
                    )));
                }
                for k in 1..corners.len() - 1 {
                    mesh.triangles
                        .push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {} // vt, vn, o, g, s, usemtl, mtllib...: not needed for geometry
        }
    }
    Ok(mesh)
}

/// Parses an STL file, ASCII (`solid ... facet ... vertex x y z ...`) or binary (80-byte header,
/// triangle count, 50 bytes per triangle). A file starting with `solid` whose size matches the
/// binary layout exactly is read as binary (some exporters write `solid` in binary headers).
pub fn parse_stl(bytes: &[u8]) -> Result<MeshData, String> {
    let binary_size_matches = bytes.len() >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len())
    };
    let looks_ascii = bytes.trim_ascii_start().starts_with(b"solid");
    if looks_ascii && !binary_size_matches {
        parse_stl_ascii(&String::from_utf8_lossy(bytes))
    } else {
        parse_stl_binary(bytes)
    }
}

fn parse_stl_binary(bytes: &[u8]) -> Result<MeshData, String> {
    if bytes.len() < 84 {
        return Err(format!(
            "binary STL is {} bytes, shorter than its 84-byte header",
            bytes.len()
        ));
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    let need = 84 + n * 50;
    if bytes.len() < need {
        return Err(format!(
            "binary STL declares {n} triangles ({need} bytes) but has {} bytes",
            bytes.len()
        ));
    }
    let mut mesh = MeshData::default();
    let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    for t in 0..n {
        let base = 84 + t * 50 + 12; // skip the facet normal
        let first = mesh.vertices.len() as u32;
        for k in 0..3 {
            let o = base + k * 12;
            let v = Vector::new(f(o), f(o + 4), f(o + 8));
            if !v.is_finite() {
                return Err(format!("triangle {t} (byte {o}) has a non-finite vertex"));
            }
            mesh.vertices.push(v);
        }
        mesh.triangles.push([first, first + 1, first + 2]);
    }
    Ok(mesh)
}

fn parse_stl_ascii(text: &str) -> Result<MeshData, String> {
    let mut mesh = MeshData::default();
    let mut pending: Vec<u32> = Vec::with_capacity(3);
    for (lineno, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let at = |msg: String| format!("line {}: {msg}", lineno + 1);
        match words.next() {
            Some("vertex") => {
                let mut c = [0.0f32; 3];
                for (i, slot) in c.iter_mut().enumerate() {
                    let w = words
                        .next()
                        .ok_or_else(|| at(format!("vertex needs 3 coordinates, found {i}")))?;
                    *slot = w
                        .parse::<f32>()
                        .map_err(|_| at(format!("`{w}` is not a number")))?;
                    if !slot.is_finite() {
                        return Err(at(format!("vertex coordinate `{w}` is not finite")));
                    }
                }
                pending.push(mesh.vertices.len() as u32);
                mesh.vertices.push(Vector::new(c[0], c[1], c[2]));
            }
            Some("endloop") => {
                if pending.len() < 3 {
                    return Err(at(format!(
                        "facet loop has {} vertices, expected 3",
                        pending.len()
                    )));
                }
                for k in 1..pending.len() - 1 {
                    mesh.triangles
                        .push([pending[0], pending[k], pending[k + 1]]);
                }
                pending.clear();
            }
            _ => {}
        }
    }
    if !pending.is_empty() {
        return Err("file ends inside a facet loop (missing `endloop`)".into());
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_quad_is_fanned() {
        let m = parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3//3 -1\n").unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn obj_bad_index_names_line() {
        let e = parse_obj("v 0 0 0\nf 1 2 3\n").unwrap_err();
        assert!(e.starts_with("line 2:"), "{e}");
    }

    #[test]
    fn stl_ascii_and_binary_agree() {
        let ascii = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                     vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let a = parse_stl(ascii.as_bytes()).unwrap();
        let mut bin = vec![0u8; 80];
        bin.extend_from_slice(&1u32.to_le_bytes());
        bin.extend_from_slice(&[0u8; 12]);
        for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for c in v {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        bin.extend_from_slice(&[0u8; 2]);
        let b = parse_stl(&bin).unwrap();
        assert_eq!(a.vertices, b.vertices);
        assert_eq!(a.triangles, b.triangles);
        assert!(parse_stl(&bin[..100]).is_err());
    }
}
