//! Mesh files written by tests: binary and ASCII STL of given triangles, the triangles of a
//! box. Shared by the mesh tests (`meshes.rs`) and the fuzz harness's seeds (`fuzz_support`),
//! each using a part.

#![allow(dead_code)]

/// A binary STL of `triangles` (each three corners), declaring `declared` triangles.
pub fn binary_stl(triangles: &[[[f32; 3]; 3]], declared: u32) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&declared.to_le_bytes());
    for t in triangles {
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

/// The 12 triangles of the box from `lo` to `hi`.
pub fn box_triangles(lo: [f32; 3], hi: [f32; 3]) -> Vec<[[f32; 3]; 3]> {
    let c = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    quads
        .iter()
        .flat_map(|q| [[c(q[0]), c(q[1]), c(q[2])], [c(q[0]), c(q[2]), c(q[3])]])
        .collect()
}

/// An ASCII STL of `triangles`.
pub fn ascii_stl(triangles: &[[[f32; 3]; 3]]) -> String {
    let mut s = String::from("solid mesh\n");
    for t in triangles {
        s.push_str(" facet normal 0 0 0\n  outer loop\n");
        for v in t {
            s.push_str(&format!("   vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        s.push_str("  endloop\n endfacet\n");
    }
    s.push_str("endsolid mesh\n");
    s
}
