//! The mesh readers and the convex hull on mutated STL (binary and ASCII), OBJ and COLLADA
//! files: every mutation gives a mesh or an error, never a panic or a hang.

use std::path::Path;

use geometry::agent::ConvexMode;
use geometry::agent::convex::make_convex;
use geometry::mesh_file::parse_mesh;

const DAE: &str = r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="0.01"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="12">0 0 0 1 0 0 0 1 0 0 0 1</float_array>
      <technique_common><accessor source="#pa" count="4" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="4"><input semantic="VERTEX" source="#v" offset="0"/>
      <p>0 2 1 0 1 3 1 2 3 2 0 3</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n">
    <matrix>1 0 0 0.5 0 1 0 0 0 0 1 0 0 0 0 1</matrix>
    <instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"##;

const OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";

fn tetra() -> [[[f32; 3]; 3]; 4] {
    let (a, b, c, d) = (
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    );
    [[a, c, b], [a, b, d], [b, c, d], [c, a, d]]
}

fn binary_stl() -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&4u32.to_le_bytes());
    for t in tetra() {
        b.extend_from_slice(&[0u8; 12]);
        for v in t {
            for c in v {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
    }
    b
}

fn ascii_stl() -> String {
    let mut s = String::from("solid t\n");
    for t in tetra() {
        s.push_str("facet normal 0 0 0\nouter loop\n");
        for v in t {
            s.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        s.push_str("endloop\nendfacet\n");
    }
    s + "endsolid t\n"
}

/// `seed` with one random edit: a byte changed, a span cut or doubled, a truncation.
fn mutate(seed: &[u8], rng: &mut fastrand::Rng) -> Vec<u8> {
    let mut b = seed.to_vec();
    if b.is_empty() {
        return b;
    }
    let i = rng.usize(..b.len());
    match rng.u8(..4) {
        0 => b[i] = rng.u8(..),
        1 => b.truncate(i),
        2 => {
            let j = rng.usize(i..b.len());
            b.drain(i..j);
        }
        _ => {
            let j = rng.usize(i..b.len());
            let span = b[i..j].to_vec();
            b.splice(i..i, span);
        }
    }
    b
}

#[test]
fn the_seeds_read_and_the_collada_transforms_apply() {
    let dae = parse_mesh(DAE.as_bytes(), Path::new("t.dae")).unwrap();
    // unit 0.01 m and the node's translation by 0.5 units along x.
    let max_x = dae.vertices.iter().map(|v| v.x).fold(f32::MIN, f32::max);
    assert!((max_x - 0.015).abs() < 1e-6, "{max_x}");
    for (bytes, name) in [
        (binary_stl(), "t.stl"),
        (ascii_stl().into_bytes(), "t.stl"),
        (OBJ.as_bytes().to_vec(), "t.obj"),
    ] {
        let m = parse_mesh(&bytes, Path::new(name)).unwrap();
        assert_eq!(m.triangles.len(), 4, "{name}");
    }
}

#[test]
fn mutated_meshes_give_a_mesh_or_an_error() {
    let seeds: [(Vec<u8>, &str); 4] = [
        (binary_stl(), "t.stl"),
        (ascii_stl().into_bytes(), "t.stl"),
        (OBJ.as_bytes().to_vec(), "t.obj"),
        (DAE.as_bytes().to_vec(), "t.dae"),
    ];
    let mut rng = fastrand::Rng::with_seed(7);
    let (mut read, mut refused) = (0, 0);
    for round in 0..3000 {
        let (seed, name) = &seeds[round % seeds.len()];
        let bytes = mutate(seed, &mut rng);
        match parse_mesh(&bytes, Path::new(name)) {
            Ok(mesh) => {
                read += 1;
                let made = std::panic::catch_unwind(|| {
                    make_convex(&mesh, [1.0; 3], ConvexMode::Auto).map(|m| m.pieces.len())
                });
                assert!(made.is_ok(), "the hull panicked on a mutated {name}");
            }
            Err(e) => {
                refused += 1;
                assert!(!e.is_empty());
            }
        }
    }
    assert!(read > 0 && refused > 0, "{read} read, {refused} refused");
}
