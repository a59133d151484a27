//! The second convex rule, applied where a scene's posture is known: a collision mesh whose hull
//! overlaps another link in the scene's initial posture, where a convex decomposition of the
//! mesh does not, is decomposed.
//!
//! A hull fills the mesh's concavities. The fill rule of `agent::convex` decomposes a mesh that
//! fills less than half of its hull, but a mesh that fills its hull well can still have a notch
//! where another link rests in a tucked posture: the real Fetch's torso-lift link, whose hull
//! covers the shoulder in the Fetch's usual tuck, so that its arm starts in self-collision.
//! Links the scene names in `hull_links` or `decompose_links` keep what it says.

use std::collections::HashMap;

use parry3d::math::Pose;
use parry3d::query;

use crate::agent::{AgentModel, ConvexMode, Primitive};

/// The links of `model` that collide with another link in configuration `q` (self-collision,
/// the pairs the model checks), among those that collide as one hull of a mesh and that
/// `explicit` leaves to the rules.
pub(super) fn colliding_hull_links(
    model: &AgentModel,
    q: &[f32],
    explicit: &HashMap<String, ConvexMode>,
) -> Vec<String> {
    let is_hull = |name: &str| {
        !explicit.contains_key(name)
            && model.link_id(name).is_ok_and(|l| {
                let collisions = &model.links()[l].collisions;
                collisions
                    .iter()
                    .any(|c| matches!(c.primitive, Primitive::Convex { pieces: 1, .. }))
            })
    };
    let mut found: Vec<String> = self_collisions(model, q)
        .into_iter()
        .flat_map(|(a, b)| [a, b])
        .filter(|l| is_hull(l))
        .collect();
    found.sort();
    found.dedup();
    found
}

/// The pairs of links (names) whose shapes intersect in `q` but not in the model's default
/// configuration, other than a link and its parent and the pairs its SRDF disables: the pairs
/// a self-collision model checks that collide in `q` (it also leaves out, by sampling, pairs
/// that always or never collide; the first collide in the default configuration too, the
/// second nowhere).
pub(super) fn self_collisions(model: &AgentModel, q: &[f32]) -> Vec<(String, String)> {
    let default = model.default_configuration();
    let before = contacts(model, default.as_slice());
    let name = |l: usize| model.links()[l].name.clone();
    contacts(model, q)
        .into_iter()
        .filter(|p| !before.contains(p))
        .map(|(a, b)| (name(a), name(b)))
        .collect()
}

/// The pairs of links `a < b` whose shapes intersect in `q`, less a link and its parent and
/// the pairs the SRDF disables.
fn contacts(model: &AgentModel, q: &[f32]) -> Vec<(usize, usize)> {
    let links = model.links();
    let disabled = &model.semantics().disabled_collisions;
    let skip = |a: usize, b: usize| {
        links[a].parent == Some(b)
            || links[b].parent == Some(a)
            || disabled.iter().any(|(x, y)| {
                let (x, y) = (x.as_str(), y.as_str());
                let (na, nb) = (links[a].name.as_str(), links[b].name.as_str());
                (x, y) == (na, nb) || (x, y) == (nb, na)
            })
    };
    let shapes = model.posed_shapes(Pose::IDENTITY, q);
    let mut found = Vec::new();
    for (i, (la, ca, pa)) in shapes.iter().enumerate() {
        for (lb, cb, pb) in &shapes[i + 1..] {
            let (a, b) = ((*la).min(*lb), (*la).max(*lb));
            if a == b || found.contains(&(a, b)) {
                continue;
            }
            let r = ca.bounding_radius + cb.bounding_radius;
            if (pa.translation - pb.translation).length() > r || skip(a, b) {
                continue;
            }
            if query::intersection_test(pa, &*ca.shape.0, pb, &*cb.shape.0)
                .map_or(true, |t| t.intersecting)
            {
                found.push((a, b));
            }
        }
    }
    found
}

/// Of `decomposed` (links just decomposed), those that still collide in `q`: their
/// decomposition did not help, and they go back to their hulls.
pub(super) fn still_colliding(model: &AgentModel, q: &[f32], decomposed: &[String]) -> Vec<String> {
    let pairs = self_collisions(model, q);
    decomposed
        .iter()
        .filter(|l| pairs.iter().any(|(a, b)| a == *l || b == *l))
        .cloned()
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::agent::{MeshOptions, PackagePath};
    use crate::scene::SceneError;

    /// An L-shaped prism as an ASCII STL: it fills 0.71 of its hull (kept as a hull by the fill
    /// rule), and its notch (x, z in 0.1..0.3) is inside the hull but outside the L.
    fn l_prism_stl() -> String {
        let outline = [
            (0.0, 0.0),
            (0.3, 0.0),
            (0.3, 0.1),
            (0.1, 0.1),
            (0.1, 0.3),
            (0.0, 0.3),
        ];
        let v = |(x, z): (f32, f32), y: f32| format!("vertex {x} {y} {z}");
        let mut tris = Vec::new();
        // The caps (y = -0.05 facing -y, y = 0.05 facing +y), as two rectangles each.
        for quad in [[0, 1, 2, 3], [0, 3, 4, 5]] {
            let p = quad.map(|i| outline[i]);
            for (a, b, c) in [(0, 1, 2), (0, 2, 3)] {
                tris.push([v(p[a], -0.05), v(p[b], -0.05), v(p[c], -0.05)]);
                tris.push([v(p[a], 0.05), v(p[c], 0.05), v(p[b], 0.05)]);
            }
        }
        // The sides, one rectangle per edge of the outline.
        for i in 0..outline.len() {
            let (p, q) = (outline[i], outline[(i + 1) % outline.len()]);
            tris.push([v(p, -0.05), v(p, 0.05), v(q, 0.05)]);
            tris.push([v(p, -0.05), v(q, 0.05), v(q, -0.05)]);
        }
        let facets: String = tris
            .iter()
            .map(|[a, b, c]| {
                format!("facet normal 0 0 0\nouter loop\n{a}\n{b}\n{c}\nendloop\nendfacet\n")
            })
            .collect();
        format!("solid l\n{facets}endsolid l\n")
    }

    /// A body with the L and, two joints away, a 4 cm cube on a slide: at 0 the cube is 0.3 m
    /// clear of the L; at -0.4 it sits in the L's notch.
    fn urdf() -> &'static str {
        r#"<robot name="l_bot">
  <link name="body"><collision><geometry><mesh filename="l.stl"/></geometry></collision></link>
  <link name="mount"/>
  <link name="block"><collision><geometry><box size="0.04 0.04 0.04"/></geometry></collision></link>
  <joint name="fix" type="fixed"><parent link="body"/><child link="mount"/></joint>
  <joint name="slide" type="prismatic"><parent link="mount"/><child link="block"/>
    <origin xyz="0.6 0 0.2"/><axis xyz="1 0 0"/><limit lower="-0.5" upper="0" effort="1" velocity="1"/></joint>
</robot>"#
    }

    #[test]
    fn a_hull_that_swallows_a_link_in_the_initial_posture_is_decomposed() {
        let dir = std::env::temp_dir().join(format!("htngtp-swallow-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("l.stl"), l_prism_stl()).unwrap();
        let meshes = MeshOptions {
            packages: PackagePath {
                urdf_dir: dir.clone(),
                scene_dirs: Vec::new(),
            },
            modes: HashMap::new(),
        };
        let load = |m: &MeshOptions| -> Result<AgentModel, SceneError> {
            Ok(AgentModel::from_urdf_str_with(urdf(), "l_bot.urdf", m).unwrap())
        };
        let pieces = |m: &AgentModel| m.links()[m.link_id("body").unwrap()].collisions.len();
        let model = load(&meshes).unwrap();
        assert_eq!(pieces(&model), 1, "the fill rule keeps the L's hull");
        let (tucked, clear) = ([-0.4f32], [0.0f32]);
        assert_eq!(
            colliding_hull_links(&model, &tucked, &meshes.modes),
            ["body"]
        );
        assert!(colliding_hull_links(&model, &clear, &meshes.modes).is_empty());

        let decomposed =
            super::super::decompose_swallowing_hulls(model, &tucked, meshes.clone(), load).unwrap();
        assert!(pieces(&decomposed) > 1, "decomposed");
        assert!(
            self_collisions(&decomposed, &tucked).is_empty(),
            "the block fits the notch"
        );
        // Where the scene names the link, it keeps what the scene says.
        let mut named = meshes.clone();
        named.modes.insert("body".into(), ConvexMode::Hull);
        let kept = load(&named).unwrap();
        assert!(colliding_hull_links(&kept, &tucked, &named.modes).is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
