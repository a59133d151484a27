//! Triangle-mesh files: Wavefront OBJ, STL (ASCII and binary) and COLLADA (`.dae`), read with
//! the `mesh-loader` crate, for scene objects and for the collision meshes of URDF links.
//!
//! Vertices and triangles only (normals, texture coordinates and materials are dropped). A
//! COLLADA file's nodes' transforms are applied by `mesh-loader`, its `<unit meter="..">` here
//! (to every length, translations included);
//! its `<up_axis>` is not, as in ROS (rviz and MoveIt's `geometric_shapes` reset the root
//! transform that would turn a Y-up file): ROS meshes are drawn in their link's frame, z up.
//! Errors are one sentence without the file name (the caller adds it). Files over
//! [`MAX_TRIANGLES`] triangles or [`MAX_VERTICES`] vertices are refused.

use std::path::Path;

use parry3d::math::Vector;

/// The most triangles a mesh file may have.
pub const MAX_TRIANGLES: usize = 250_000;
/// The most vertices a mesh file may have (an STL file has three per triangle).
pub const MAX_VERTICES: usize = 3 * MAX_TRIANGLES;

/// A triangle soup read from a file: vertices in file units, triangles as vertex indices.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    pub vertices: Vec<Vector>,
    pub triangles: Vec<[u32; 3]>,
}

/// Reads an OBJ, STL or COLLADA file, chosen by the extension (`.obj`, `.stl`, `.dae`;
/// case-insensitive). The error is a sentence without the file name (the caller adds it).
pub fn read_mesh(path: &Path) -> Result<MeshData, String> {
    let ext = extension(path);
    if !matches!(ext.as_str(), "obj" | "stl" | "dae") {
        return Err(format!(
            "unknown mesh format `.{ext}` (expected .obj, .stl or .dae)"
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read mesh file: {e}"))?;
    parse_mesh(&bytes, path)
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

/// Parses the bytes of a mesh file; `path` gives the format by its extension.
pub fn parse_mesh(bytes: &[u8], path: &Path) -> Result<MeshData, String> {
    let ext = extension(path);
    if ext == "stl" {
        check_stl_size(bytes)?;
    }
    // mesh-loader picks the format by the extension given; lower-case it so `.STL` reads too.
    let named = Path::new("mesh").with_extension(&ext);
    // A material library an OBJ names is not needed for geometry: read as empty.
    let loader = mesh_loader::Loader::default()
        .merge_meshes(true)
        .custom_reader(|_| Ok(Vec::new()));
    // mesh-loader scales a COLLADA file's vertices by its unit before its node transforms,
    // leaving their translations unscaled; COLLADA's unit applies to every length of the
    // document, so the unit is read out here and applied to the result.
    let (bytes, unit) = if ext == "dae" {
        collada_without_unit(bytes)?
    } else {
        (std::borrow::Cow::Borrowed(bytes), 1.0)
    };
    let parsed = quietly(|| loader.load_from_slice(&bytes, &named));
    let scene = match parsed {
        Ok(Ok(scene)) => scene,
        Ok(Err(e)) => {
            return Err(format!(
                "not a valid .{ext} file: {}",
                clean(&e.to_string())
            ));
        }
        Err(_) => return Err(format!("the .{ext} reader failed on this file")),
    };
    let mut mesh = MeshData::default();
    for m in scene.meshes {
        let first = mesh.vertices.len() as u32;
        mesh.vertices
            .extend(m.vertices.iter().map(|v| Vector::new(v[0], v[1], v[2])));
        mesh.triangles.extend(
            m.faces
                .iter()
                .map(|f| [f[0] + first, f[1] + first, f[2] + first]),
        );
    }
    if unit != 1.0 {
        for v in &mut mesh.vertices {
            *v *= unit;
        }
    }
    check_mesh(&mesh, &ext)?;
    Ok(mesh)
}

/// A COLLADA document with its `<unit meter="..">` set to 1, and that unit.
fn collada_without_unit(bytes: &[u8]) -> Result<(std::borrow::Cow<'_, [u8]>, f32), String> {
    let text = String::from_utf8_lossy(bytes);
    let Some(at) = text.find("<unit") else {
        return Ok((std::borrow::Cow::Borrowed(bytes), 1.0));
    };
    let end = at + text[at..].find('>').unwrap_or(text.len() - at);
    let head = &text[at..end];
    let Some(m) = head.find("meter=") else {
        return Ok((std::borrow::Cow::Borrowed(bytes), 1.0));
    };
    let quote_at = at + m + "meter=".len();
    let quote = text[quote_at..]
        .chars()
        .next()
        .filter(|c| *c == '"' || *c == '\'');
    let Some(quote) = quote else {
        return Err("COLLADA <unit meter=..> is not quoted".into());
    };
    let value_at = quote_at + 1;
    let value_end = value_at
        + text[value_at..]
            .find(quote)
            .ok_or("COLLADA <unit meter=..> is not closed")?;
    let value = &text[value_at..value_end];
    let unit: f32 = value
        .trim()
        .parse()
        .ok()
        .filter(|u: &f32| u.is_finite() && *u > 0.0)
        .ok_or_else(|| format!("COLLADA <unit meter=\"{value}\"> is not a positive number"))?;
    let edited = format!("{}1{}", &text[..value_at], &text[value_end..]);
    Ok((std::borrow::Cow::Owned(edited.into_bytes()), unit))
}

/// `f()`, or `Err(())` when it panics; the panic prints nothing (mesh-loader can panic on a
/// malformed COLLADA file, which is an error of the input, reported as such by the caller).
fn quietly<T>(f: impl FnOnce() -> T + std::panic::UnwindSafe) -> Result<T, ()> {
    thread_local! {
        static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(|q| q.get()) {
                previous(info);
            }
        }));
    });
    QUIET.with(|q| q.set(true));
    let result = std::panic::catch_unwind(f);
    QUIET.with(|q| q.set(false));
    result.map_err(|_| ())
}

/// mesh-loader's message without the placeholder file name it was given.
fn clean(message: &str) -> String {
    message
        .replace(" (mesh.stl)", "")
        .replace(" (mesh.obj)", "")
        .replace(" (mesh.dae)", "")
}

/// A binary STL's declared triangle count against its size (an ASCII file starts with `solid`
/// and does not match the binary layout).
fn check_stl_size(bytes: &[u8]) -> Result<(), String> {
    let declared = (bytes.len() >= 84)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize);
    let binary_size = declared.and_then(|n| n.checked_mul(50)?.checked_add(84));
    if binary_size == Some(bytes.len()) {
        return Ok(());
    }
    if bytes.trim_ascii_start().starts_with(b"solid") {
        return Ok(());
    }
    match declared {
        None => Err(format!(
            "binary STL is {} bytes, shorter than its 84-byte header",
            bytes.len()
        )),
        Some(n) => Err(format!(
            "binary STL declares {n} triangles ({} bytes) but has {} bytes (truncated?)",
            binary_size.map_or("too many".to_string(), |b| b.to_string()),
            bytes.len()
        )),
    }
}

fn check_mesh(mesh: &MeshData, ext: &str) -> Result<(), String> {
    if mesh.triangles.is_empty() {
        let what = if ext == "dae" {
            "mesh has no triangles (a COLLADA file needs <triangles> or <polylist> in a \
             <geometry> that its <visual_scene> instantiates)"
        } else {
            "mesh has no triangles"
        };
        return Err(what.into());
    }
    if mesh.triangles.len() > MAX_TRIANGLES {
        return Err(format!(
            "mesh has {} triangles, more than the {MAX_TRIANGLES} allowed (simplify it, \
             e.g. with a decimation filter)",
            mesh.triangles.len()
        ));
    }
    if mesh.vertices.len() > MAX_VERTICES {
        return Err(format!(
            "mesh has {} vertices, more than the {MAX_VERTICES} allowed",
            mesh.vertices.len()
        ));
    }
    if let Some(v) = mesh.vertices.iter().find(|v| !v.is_finite()) {
        return Err(format!("mesh has a non-finite vertex {v:?}"));
    }
    let n = mesh.vertices.len() as u32;
    if mesh.triangles.iter().flatten().any(|&i| i >= n) {
        return Err("a triangle names a vertex the mesh does not have".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_quad_is_fanned() {
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3//3 -1\n";
        let m = parse_mesh(obj.as_bytes(), Path::new("q.obj")).unwrap();
        assert_eq!(m.triangles.len(), 2);
    }

    #[test]
    fn obj_bad_index_names_line() {
        let e = parse_mesh(b"v 0 0 0\nf 1 2 3\n", Path::new("q.obj")).unwrap_err();
        assert!(e.contains("obj"), "{e}");
    }

    #[test]
    fn stl_ascii_and_binary_agree() {
        let ascii = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                     vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let a = parse_mesh(ascii.as_bytes(), Path::new("t.stl")).unwrap();
        let mut bin = vec![0u8; 80];
        bin.extend_from_slice(&1u32.to_le_bytes());
        bin.extend_from_slice(&[0u8; 12]);
        for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for c in v {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        bin.extend_from_slice(&[0u8; 2]);
        let b = parse_mesh(&bin, Path::new("t.STL")).unwrap();
        assert_eq!(a.vertices, b.vertices);
        assert_eq!(a.triangles, b.triangles);
        let e = parse_mesh(&bin[..100], Path::new("t.stl")).unwrap_err();
        assert!(e.contains("declares 1 triangles"), "{e}");
    }
}
