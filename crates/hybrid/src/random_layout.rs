//! Random layouts of a scene (`bench library --layout random`): the movable
//! objects put anywhere sensible in the room and the people seated or standing at the counter,
//! one layout per seed, where `bench library`'s nudges ([`crate::experiment::randomize`]) only
//! move things by a few centimetres.
//!
//! A layout is *sensible* when:
//! - every movable object rests on a free spot of a support surface of the room's furniture
//!   (the desk, the platform, the POS stand, the table, any level of the shelf), on any face (a
//!   box stands on its long edge, on its short edge or lies flat; a cylinder stands), turned
//!   any way about the vertical, inside its surface by 1 cm, 2 cm clear of every other object's
//!   footprint, touching nothing but its support and supported by it;
//! - the robot can pick it up, as the GTP's `pick` finds on the finished layout: from its
//!   station for an object the domain picks where the robot stands (the library's books: no
//!   method drives before their compound tasks), after driving to it (`navigate-to`, then
//!   `pick`) for an object the domain drives to ([`LayoutRules::driven_to`]; the library's POS
//!   machine, method m9);
//! - each person sits on their chair, moved with them along the counter by up to 0.45 m and
//!   turned by up to 15 degrees (when the scene seats them), or stands on free floor facing
//!   the counter (within 20 degrees), and a patch of the counter's top of at least
//!   [`SHARED_PATCH_POINTS`] points 5 cm apart seated, [`STANDING_PATCH_POINTS`] standing, is
//!   within the person's reach at effort level 1 (extending the arm) and the robot's from its
//!   station: where things are handed over and made accessible;
//! - the robot stays at its station.
//!
//! A draw that breaks a rule is drawn again; a layout none of whose draws work after
//! [`LAYOUT_ATTEMPTS`] attempts is an error. The same seed gives the same layout.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use geometry::effort::stances;
use geometry::facts::{FactParams, on, reachable_effort};
use geometry::perception::{reach_origins, within_reach};
use geometry::scene::{AgentId, AgentKind, ObjectId, pose_from_xyz_rpy};
use geometry::world::{BodyOwner, World, base_pose};
use gtp::planner::{CallOptions, Planner, PlannerConfig};
use parry3d::math::{Pose, Vector};
use serde::Serialize;

use crate::layout::{Footprints, LoadedScene, SceneText, Surface, surfaces};

/// Whole-layout attempts before a seed is given up.
pub const LAYOUT_ATTEMPTS: usize = 12;
/// Draws (surface, face, turn, spot) per object before the attempt is given up.
const OBJECT_DRAWS: usize = 400;
/// Draws of a person's place before the attempt is given up.
const PERSON_DRAWS: usize = 200;
/// Rounds of re-placing the objects the robot cannot pick.
const PICK_ROUNDS: usize = 6;
/// Counter-top points (5 cm apart) both a seated person and the robot must reach.
pub const SHARED_PATCH_POINTS: usize = 25;
/// The same for a standing person, who reaches a counter's top at effort level 1 only near its
/// edge (the shoulder about 0.65 m above a 0.75 m top, the arm 0.7 m long: in the library, 16
/// points at best, over 400 standing places drawn): a strip about 10 x 20 cm.
pub const STANDING_PATCH_POINTS: usize = 8;
/// An object's footprint is this far inside its surface's edge (metres).
pub(crate) const EDGE_MARGIN: f32 = 0.01;
/// Clearance between footprints on a surface (metres).
pub(crate) const CLEARANCE: f32 = 0.02;
/// A person keeps this far from the robot's body and the furniture (metres).
const PERSON_CLEARANCE: f32 = 0.05;
/// Base poses `navigate-to` must each let the robot pick an object the domain drives to.
const NAVIGATE_POSES: usize = 3;
/// Time limit of one GTP check (pick, navigate-to): a safety net far above what a check takes.
const CHECK_LIMIT: Duration = Duration::from_secs(20);

/// The planner of a generator's GTP checks: its trajectory queries end at their node or check
/// budget, never at the default second of wall-clock time, so that a seed gives the same layout
/// however loaded the machine is.
pub(crate) fn check_planner() -> Planner {
    let mut config = PlannerConfig::default();
    config.rrt.time_limit = CHECK_LIMIT;
    Planner::with_config(config)
}

/// What a random layout keeps and where it serves.
#[derive(Clone, Debug)]
pub struct LayoutRules {
    /// The counter people are served at (the library's `desk`).
    pub counter: String,
    /// Objects the domain drives to before it picks them (the library's `pos-machine`, m9);
    /// the others must be picked from the robot's station.
    pub driven_to: Vec<String>,
}

impl Default for LayoutRules {
    fn default() -> Self {
        LayoutRules {
            counter: "desk".into(),
            driven_to: vec!["pos-machine".into()],
        }
    }
}

/// Where a layout put an object.
#[derive(Clone, Debug, Serialize)]
pub struct ObjectPlacement {
    pub name: String,
    /// The furniture it rests on.
    pub support: String,
    /// `edge` (on its long edge), `end` (on its short edge), `flat` or `upright` (a cylinder).
    pub face: &'static str,
    pub xyz: [f32; 3],
    pub yaw_deg: f32,
}

/// Where a layout put a person.
#[derive(Clone, Debug, Serialize)]
pub struct PersonPlacement {
    pub name: String,
    pub sitting: bool,
    /// Base x, y (metres) and yaw (degrees).
    pub base: [f32; 3],
}

/// Where a random room put a piece of furniture (`--layout room`).
#[derive(Clone, Debug, Serialize)]
pub struct FurniturePlacement {
    pub name: String,
    /// `desk`, `counter`, `reading-table`, `side-table`, `bookshelf`, `cart` or `chair`.
    pub kind: &'static str,
    /// Centre on the floor (metres) and yaw (degrees).
    pub base: [f32; 3],
    /// Half sizes of its footprint along its own axes (metres).
    pub half_extents: [f32; 2],
    /// Height of its top support surface (metres; 0 for a chair).
    pub top: f32,
}

/// What a layout is, in short (for reports).
#[derive(Clone, Debug, Default, Serialize)]
pub struct LayoutSummary {
    /// The furniture of a random room (empty for a layout of the scene's own furniture).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub furniture: Vec<FurniturePlacement>,
    /// The robot's station in a random room: base x, y (metres) and yaw (degrees).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub station: Option<[f32; 3]>,
    /// Fixed clutter objects of a random room (books on shelves, things on tops).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub clutter: Vec<ObjectPlacement>,
    pub objects: Vec<ObjectPlacement>,
    pub people: Vec<PersonPlacement>,
    /// Whole-layout attempts it took (1: the first).
    pub attempts: usize,
}

impl LayoutSummary {
    /// One line: `grey-book table edge, pos-machine shelf flat; member standing`.
    pub fn line(&self) -> String {
        let objects: Vec<String> = self
            .objects
            .iter()
            .map(|o| format!("{} {} {}", o.name, o.support, o.face))
            .collect();
        let people: Vec<String> = self
            .people
            .iter()
            .map(|p| {
                let posture = if p.sitting { "seated" } else { "standing" };
                format!("{} {posture}", p.name)
            })
            .collect();
        let line = format!("{}; {}", objects.join(", "), people.join(", "));
        if self.furniture.is_empty() {
            return line;
        }
        let furniture: Vec<String> = self
            .furniture
            .iter()
            .map(|f| match f.kind {
                "chair" => f.name.clone(),
                _ => format!("{} ({} {:.2} m)", f.name, f.kind, f.top),
            })
            .collect();
        format!(
            "{}; {} clutter; {line}",
            furniture.join(", "),
            self.clutter.len()
        )
    }
}

/// A generated layout: the world, its scene text (TOML, agents' paths absolute) and a summary.
pub struct Layout {
    pub world: World,
    pub toml: String,
    pub summary: LayoutSummary,
}

impl crate::experiment::LayoutSource for RandomLayouts {
    fn generate(&self, seed: u64) -> Result<Layout, String> {
        RandomLayouts::generate(self, seed)
    }
}

/// The generator of one scene's random layouts.
pub struct RandomLayouts {
    text: SceneText,
    base_dir: PathBuf,
    source: String,
    world: World,
    rules: LayoutRules,
    planner: Arc<Planner>,
}

impl std::fmt::Debug for RandomLayouts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RandomLayouts")
            .field("source", &self.source)
            .field("rules", &self.rules)
            .finish_non_exhaustive()
    }
}

/// The faces a box may rest on: name and the turn (roll, pitch; radians) that puts it there,
/// ordered as the scene's books stand (on the long edge) first.
pub(crate) const BOX_FACES: [(&str, [f32; 2]); 3] = [
    ("edge", [0.0, std::f32::consts::FRAC_PI_2]),
    ("end", [std::f32::consts::FRAC_PI_2, 0.0]),
    ("flat", [0.0, 0.0]),
];

impl RandomLayouts {
    /// The generator for the scene file `scene`.
    pub fn new(scene: &Path, rules: LayoutRules) -> Result<RandomLayouts, String> {
        let LoadedScene {
            text,
            base_dir,
            source,
            world,
        } = LoadedScene::read(scene)?;
        if world.object_id(&rules.counter).is_none() {
            return Err(format!("{source}: no counter `{}`", rules.counter));
        }
        robot_of(&world)?;
        Ok(RandomLayouts {
            text,
            base_dir,
            source,
            world,
            rules,
            planner: Arc::new(check_planner()),
        })
    }

    /// The layout of `seed`: the first of [`LAYOUT_ATTEMPTS`] attempts that is sensible (see
    /// the module docs).
    pub fn generate(&self, seed: u64) -> Result<Layout, String> {
        let mut last = String::new();
        for attempt in 0..LAYOUT_ATTEMPTS {
            let mut rng = fastrand::Rng::with_seed(seed ^ ((attempt as u64) << 48));
            match self.attempt(&mut rng, seed) {
                Ok((text, mut summary)) => {
                    summary.attempts = attempt + 1;
                    let toml = text.to_toml()?;
                    let source = format!("{} (layout of seed {seed})", self.source);
                    let world = text.world(&source, &self.base_dir)?;
                    return Ok(Layout {
                        world,
                        toml,
                        summary,
                    });
                }
                Err(e) => last = e,
            }
        }
        Err(format!(
            "no sensible layout in {LAYOUT_ATTEMPTS} attempts; the last: {last}"
        ))
    }

    /// One attempt: the people placed, then the objects, then the objects the robot cannot
    /// pick placed again; the scene text of the result.
    fn attempt(
        &self,
        rng: &mut fastrand::Rng,
        seed: u64,
    ) -> Result<(SceneText, LayoutSummary), String> {
        let mut w = self.world.clone();
        let mut text = self.text.clone();
        let mut objects = movable(&w);
        // Largest footprint first: the big things find room while there is most.
        objects.sort_by(|&a, &b| area(&w, b).total_cmp(&area(&w, a)));
        for (k, &id) in objects.iter().enumerate() {
            park(&mut w, id, k);
        }
        let mut people = Vec::new();
        for person in w.agent_ids().collect::<Vec<_>>() {
            if w.agent(person).kind() == AgentKind::Human {
                people.push(self.place_person(&mut w, &mut text, person, rng)?);
            }
        }
        let placer = Placer {
            start: &self.world,
            rules: &self.rules,
            planner: &self.planner,
        };
        let summary_objects = placer.place_all(&mut w, &mut text, &objects, rng, seed)?;
        Ok((
            text,
            LayoutSummary {
                objects: summary_objects,
                people,
                attempts: 0,
                ..LayoutSummary::default()
            },
        ))
    }

    /// Seats `person` on their chair moved along the counter, or stands them on free floor
    /// facing it, where they and the robot share a patch of the counter (see the module docs);
    /// edits `text` to match.
    fn place_person(
        &self,
        w: &mut World,
        text: &mut SceneText,
        person: AgentId,
        rng: &mut fastrand::Rng,
    ) -> Result<PersonPlacement, String> {
        let name = w.agent(person).name().to_string();
        let start = w.agent_state(person).clone();
        let chair = if w.agent(person).spec.sitting {
            chair_of(w, start.base)
        } else {
            None
        };
        // Seated on the chair (when there is one) or standing, half the time each.
        let seat = chair.filter(|_| rng.bool());
        let counter = self.counter_surface(w)?;
        for _ in 0..PERSON_DRAWS {
            let placement = match seat {
                Some(chair) => self.seat(w, person, chair, &start, rng),
                None => self.stand(w, person, &counter, &start.q, rng),
            };
            if !self.person_is_free(w, person, seat)
                || !self.serves(w, person, &counter, seat.is_some())
            {
                continue;
            }
            if let Some(chair) = seat {
                text.set_object_pose(&w.object(chair).name, w.object_pose(chair))?;
            } else {
                text.set_sitting(&name, false)?;
                let model = &w.agent(person).model;
                for (dof, value) in model.posture("standing") {
                    let joint = model.dof_names()[dof].clone();
                    text.set_joint(&name, &joint, value)?;
                }
            }
            text.set_base(&name, placement)?;
            return Ok(PersonPlacement {
                name,
                sitting: seat.is_some(),
                base: placement,
            });
        }
        Err(format!(
            "no place for `{name}` at `{}` in {PERSON_DRAWS} draws",
            self.rules.counter
        ))
    }

    /// The counter's (first) support surface.
    fn counter_surface(&self, w: &World) -> Result<Surface, String> {
        let id = w
            .object_id(&self.rules.counter)
            .ok_or_else(|| format!("no counter `{}`", self.rules.counter))?;
        surfaces(w)
            .into_iter()
            .find(|s| s.support == id)
            .ok_or_else(|| format!("`{}` offers no support surface", self.rules.counter))
    }

    /// Moves the chair and the person seated on it together; returns the person's base.
    fn seat(
        &self,
        w: &mut World,
        person: AgentId,
        chair: ObjectId,
        start: &geometry::world::AgentState,
        rng: &mut fastrand::Rng,
    ) -> [f32; 3] {
        let chair_start = self.world.object_pose(chair);
        let turn = (rng.f32() * 2.0 - 1.0) * 15f32.to_radians();
        let shift = Vector::new(
            -0.05 + rng.f32() * 0.15,
            (rng.f32() * 2.0 - 1.0) * 0.45,
            0.0,
        );
        let about = chair_start.translation;
        let moved = |p: Pose| -> Pose {
            let spin =
                Pose::from_parts(Vector::ZERO, parry3d::math::Rotation::from_rotation_z(turn));
            let local = Pose::from_translation(p.translation - about);
            let rotated = spin * local;
            Pose::from_parts(
                rotated.translation + about + shift,
                spin.rotation * p.rotation,
            )
        };
        w.set_object_pose(chair, moved(chair_start));
        let base = moved(start.base);
        w.set_agent_config(person, base, &start.q);
        base_xyyaw(base)
    }

    /// Stands the person on the floor 0.2 to 0.5 m out from a random point of the counter's
    /// edge, facing the counter (within 20 degrees); returns their base.
    fn stand(
        &self,
        w: &mut World,
        person: AgentId,
        counter: &Surface,
        q: &[f32],
        rng: &mut fastrand::Rng,
    ) -> [f32; 3] {
        // A point of the edge (sides weighted by length) and the outward normal there.
        let (edge, out) = counter.edge_point(rng.f32());
        let at = edge + out * (0.2 + rng.f32() * 0.3);
        let yaw = (-out.y).atan2(-out.x) + (rng.f32() * 2.0 - 1.0) * 20f32.to_radians();
        stand_at(w, person, q, [at.x, at.y, yaw])
    }

    /// Whether the person's body keeps clear of every object (their chair aside), the robot
    /// and the scene's bounds.
    fn person_is_free(&self, w: &World, person: AgentId, chair: Option<ObjectId>) -> bool {
        person_is_free(w, person, chair, self.world.bounds())
    }

    /// Whether the person and the robot share a patch of the counter (see [`serves`]).
    fn serves(&self, w: &World, person: AgentId, counter: &Surface, sitting: bool) -> bool {
        serves(w, person, counter, sitting)
    }
}

/// Stands `person` (the SRDF's `standing` posture over `q`) at base `(x, y, yaw in radians)`;
/// returns the base as the scene format writes it.
pub(crate) fn stand_at(w: &mut World, person: AgentId, q: &[f32], at: [f32; 3]) -> [f32; 3] {
    let mut standing = q.to_vec();
    for (dof, value) in w.agent(person).model.posture("standing") {
        standing[dof] = value;
    }
    let base = base_pose(at[0], at[1], at[2]);
    w.set_agent_config(person, base, &standing);
    base_xyyaw(base)
}

/// Whether the person's body keeps clear of every object (their chair aside, the movable
/// ones too), [`PERSON_CLEARANCE`] from the furniture when standing, the robot, and the
/// scene's bounds (`fallback` when the scene names none).
pub(crate) fn person_is_free(
    w: &World,
    person: AgentId,
    chair: Option<ObjectId>,
    fallback: parry3d::bounding_volume::Aabb,
) -> bool {
    let bodies = w.bodies();
    let theirs: Vec<_> = bodies
        .iter()
        .filter(|b| matches!(b.owner, BodyOwner::Agent(a, _) if a == person))
        .collect();
    let bounds = w.scene().bounds.unwrap_or(fallback);
    let inside = theirs.iter().all(|b| {
        let bb = b.shape.compute_aabb(&b.pose);
        bb.mins.x >= bounds.mins.x
            && bb.mins.y >= bounds.mins.y
            && bb.maxs.x <= bounds.maxs.x
            && bb.maxs.y <= bounds.maxs.y
    });
    inside
        && bodies.iter().all(|other| {
            let gap = match other.owner {
                BodyOwner::Agent(a, _) if a == person => return true,
                BodyOwner::Object(o) if Some(o) == chair => return true,
                BodyOwner::Object(o) if w.object(o).movable => return true,
                // Seated, the knees go under the counter: touching nothing is enough.
                BodyOwner::Object(_) if chair.is_some() => 0.0,
                _ => PERSON_CLEARANCE,
            };
            theirs.iter().all(|b| {
                parry3d::query::distance(
                    &b.pose,
                    b.shape.as_ref(),
                    &other.pose,
                    other.shape.as_ref(),
                )
                .is_ok_and(|d| d.distance > gap)
            })
        })
}

/// Whether the person and the robot (from its station) both reach at least
/// [`SHARED_PATCH_POINTS`] points of the counter's top, 5 cm apart, at effort level 1
/// ([`STANDING_PATCH_POINTS`] when the person stands).
pub(crate) fn serves(w: &World, person: AgentId, counter: &Surface, sitting: bool) -> bool {
    let needed = if sitting {
        SHARED_PATCH_POINTS
    } else {
        STANDING_PATCH_POINTS
    };
    shared_points(w, person, counter) >= needed
}

/// What puts movable objects on a world's support surfaces where the robot picks them up:
/// shared by the random layouts and the random rooms ([`crate::room_layout`]).
pub(crate) struct Placer<'a> {
    /// The world the objects' starting turns are read from (an object that is not book-like
    /// keeps its turn but for the yaw).
    pub start: &'a World,
    pub rules: &'a LayoutRules,
    pub planner: &'a Planner,
}

impl Placer<'_> {
    /// Puts each of `objects` on a free spot (see the module docs), then puts again those the
    /// robot cannot pick up, for [`PICK_ROUNDS`] rounds; writes their poses into `text`.
    pub(crate) fn place_all(
        &self,
        w: &mut World,
        text: &mut SceneText,
        objects: &[ObjectId],
        rng: &mut fastrand::Rng,
        seed: u64,
    ) -> Result<Vec<ObjectPlacement>, String> {
        let mut placed: BTreeMap<usize, ObjectPlacement> = BTreeMap::new();
        for &id in objects {
            placed.insert(id.0, self.place_object(w, id, rng)?);
        }
        for round in 0..PICK_ROUNDS {
            let failed: Vec<(ObjectId, String)> = objects
                .iter()
                .filter_map(|&id| self.picks(w, id, seed).err().map(|e| (id, e)))
                .collect();
            let Some((_, why)) = failed.first() else {
                break;
            };
            if round + 1 == PICK_ROUNDS {
                return Err(why.clone());
            }
            for (k, &(id, _)) in failed.iter().enumerate() {
                park(w, id, k);
            }
            for &(id, _) in &failed {
                placed.insert(id.0, self.place_object(w, id, rng)?);
            }
        }
        let mut out = Vec::new();
        for &id in objects {
            text.set_object_pose(&w.object(id).name, w.object_pose(id))?;
            if let Some(p) = placed.remove(&id.0) {
                out.push(p);
            }
        }
        Ok(out)
    }

    /// Puts `id` on a random free spot of a random support surface (see the module docs).
    fn place_object(
        &self,
        w: &mut World,
        id: ObjectId,
        rng: &mut fastrand::Rng,
    ) -> Result<ObjectPlacement, String> {
        let name = w.object(id).name.clone();
        let all = surfaces(w);
        if all.is_empty() {
            return Err("the scene has no support surface".into());
        }
        let faces: &[(&str, [f32; 2])] = match w.object(id).kind {
            geometry::scene::ShapeKind::Box { half_extents } if book_like(half_extents) => {
                &BOX_FACES
            }
            _ => &[("as-in-scene", [0.0, 0.0])],
        };
        // The turn the object has in the scene it came from (by name: ids differ in a room).
        let start = self
            .start
            .object_id(&name)
            .map(|i| self.start.object_pose(i).rotation)
            .unwrap_or(parry3d::math::Rotation::IDENTITY);
        let robot = robot_of(w)?;
        let level = if self.rules.driven_to.contains(&name) {
            geometry::effort::MAX_EFFORT
        } else {
            1
        };
        let params = FactParams {
            max_effort: level,
            ..FactParams::default()
        };
        for _ in 0..OBJECT_DRAWS {
            let s = all[rng.usize(..all.len())];
            let (face, [roll, pitch]) = faces[rng.usize(..faces.len())];
            let yaw = rng.f32() * std::f32::consts::TAU;
            let rotation = if face == "as-in-scene" {
                parry3d::math::Rotation::from_rotation_z(yaw) * start
            } else {
                pose_from_xyz_rpy([0.0; 3], [roll, pitch, yaw]).rotation
            };
            w.set_object_pose(id, Pose::from_parts(Vector::ZERO, rotation));
            let local = w.object_aabb(id);
            let half = [local.half_extents().x, local.half_extents().y];
            park(w, id, 0);
            let taken = Footprints::of(w);
            let Some(spot) = taken.draw(&s, half, EDGE_MARGIN, CLEARANCE, 1, rng) else {
                continue;
            };
            let c = local.center();
            let at = Vector::new(spot.x - c.x, spot.y - c.y, s.centre.z - local.mins.z + 2e-4);
            w.set_object_pose(id, Pose::from_parts(at, rotation));
            if !rests_free(w, id, &s) {
                continue;
            }
            if reachable_effort(w, robot, id, &params).is_none() {
                continue;
            }
            return Ok(ObjectPlacement {
                name,
                support: w.object(s.support).name.clone(),
                face,
                xyz: [at.x, at.y, at.z],
                yaw_deg: yaw.to_degrees(),
            });
        }
        park(w, id, 0);
        Err(format!("no free spot for `{name}` in {OBJECT_DRAWS} draws"))
    }

    /// Whether the robot picks `id` up in `w`: from its station, or (objects the domain drives
    /// to) from each of the first [`NAVIGATE_POSES`] base poses `navigate-to` finds (the one a
    /// plan drives to depends on its seed). The base stays where it is (`robot-effort` 1): a
    /// pick that needs a base move is not what the layout promises.
    fn picks(&self, w: &World, id: ObjectId, seed: u64) -> Result<(), String> {
        let name = w.object(id).name.clone();
        let options = CallOptions {
            seed,
            constraints: vec![("robot-effort".into(), "1".into())],
            deadline: Some(Instant::now() + CHECK_LIMIT),
        };
        let pick = |from: &World| -> Result<(), String> {
            let mut s = self
                .planner
                .run(from, "pick", &[&name], &options)
                .map_err(|e| e.to_string())?;
            match s.next() {
                Some(_) => Ok(()),
                None => Err(s
                    .failure()
                    .map(|f| f.to_string())
                    .unwrap_or_else(|| "no grasp".into())),
            }
        };
        let why = match pick(w) {
            Ok(()) => return Ok(()),
            Err(e) => e,
        };
        if self.rules.driven_to.contains(&name) {
            let stream = self
                .planner
                .run(w, "navigate-to", &[&name], &options)
                .map_err(|e| e.to_string())?;
            let poses: Vec<World> = stream.take(NAVIGATE_POSES).map(|s| s.world).collect();
            if poses.is_empty() {
                return Err(format!(
                    "the robot drives nowhere `{name}` is in reach: {why}"
                ));
            }
            return poses.iter().try_for_each(|from| {
                pick(from)
                    .map_err(|e| format!("after driving, the robot cannot pick `{name}`: {e}"))
            });
        }
        Err(format!("the robot cannot pick `{name}` up: {why}"))
    }
}

/// Whether `id` touches nothing but its surface's support (agents kept [`CLEARANCE`] away),
/// and rests on it.
pub(crate) fn rests_free(w: &World, id: ObjectId, s: &Surface) -> bool {
    let shape = &w.object(id).shape;
    let pose = w.object_shape_pose(id);
    let free = w.bodies().iter().all(|b| match b.owner {
        BodyOwner::Object(o) if o == id => true,
        // Resting on its surface, not into the support's other parts (a shelf's boards).
        BodyOwner::Object(o) if o == s.support => {
            parry3d::query::contact(&pose, shape.as_ref(), &b.pose, b.shape.as_ref(), 0.0)
                .ok()
                .flatten()
                .is_none_or(|c| -c.dist <= geometry::world::CONTACT_TOLERANCE_M)
        }
        BodyOwner::Object(_) => {
            parry3d::query::intersection_test(&pose, shape.as_ref(), &b.pose, b.shape.as_ref())
                .is_ok_and(|i| !i.intersecting)
        }
        BodyOwner::Agent(..) => {
            parry3d::query::distance(&pose, shape.as_ref(), &b.pose, b.shape.as_ref())
                .is_ok_and(|d| d.distance >= CLEARANCE)
        }
    });
    free && on(w, id, s.support, 0.01)
}

/// How many points of the counter's top, 5 cm apart, the person and the robot (from its
/// station) both reach at effort level 1.
fn shared_points(w: &World, person: AgentId, counter: &Surface) -> usize {
    let Ok(robot) = robot_of(w) else {
        return 0;
    };
    let origins = |a: AgentId| -> Vec<Vector> {
        stances(w, a, 1, None)
            .first()
            .map(|s| reach_origins(w, a, s))
            .unwrap_or_default()
    };
    let (theirs, robots) = (origins(person), origins(robot));
    counter
        .grid(0.05, 0.05)
        .into_iter()
        .filter(|&p| within_reach(w, person, &theirs, p) && within_reach(w, robot, &robots, p))
        .count()
}

/// How many points of a surface, 5 cm apart, the robot reaches from its station at effort
/// level 1.
pub(crate) fn robot_reach_points(w: &World, s: &Surface) -> usize {
    let Ok(robot) = robot_of(w) else {
        return 0;
    };
    let origins = stances(w, robot, 1, None)
        .first()
        .map(|st| reach_origins(w, robot, st))
        .unwrap_or_default();
    s.grid(0.05, 0.05)
        .into_iter()
        .filter(|&p| within_reach(w, robot, &origins, p))
        .count()
}

/// Whether a box of these half extents is thin like a book (its smallest size under 0.4 of
/// the middle one): it may stand on its edge or end or lie flat; another box rests as the
/// scene puts it (a POS machine is not left on its end).
pub(crate) fn book_like(half: Vector) -> bool {
    let mut v = [half.x, half.y, half.z];
    v.sort_by(f32::total_cmp);
    v[0] < 0.4 * v[1]
}

/// The scene's robot.
pub(crate) fn robot_of(w: &World) -> Result<AgentId, String> {
    w.agent_ids()
        .find(|&a| w.agent(a).kind() == AgentKind::Robot)
        .ok_or_else(|| "the scene has no robot".to_string())
}

/// The movable objects no agent holds, in the scene's order.
pub(crate) fn movable(w: &World) -> Vec<ObjectId> {
    w.object_ids()
        .filter(|&id| w.object(id).movable && w.attachment(id).is_none())
        .collect()
}

/// Area of an object's footprint as the scene puts it (square metres).
pub(crate) fn area(w: &World, id: ObjectId) -> f32 {
    let e = w.object(id).local_aabb.half_extents();
    let mut v = [e.x, e.y, e.z];
    v.sort_by(f32::total_cmp);
    v[1] * v[2]
}

/// Moves `id` out of the way, far below the floor (slot `k` apart from the others), while the
/// layout is drawn.
pub(crate) fn park(w: &mut World, id: ObjectId, k: usize) {
    let spot = Vector::new(0.0, 3.0 * k as f32, -100.0 - 3.0 * id.0 as f32);
    w.set_object_pose(id, Pose::from_translation(spot));
}

/// The fixed object nearest a seated person's base, within 0.5 m on the floor: their chair.
fn chair_of(w: &World, base: Pose) -> Option<ObjectId> {
    w.object_ids()
        .filter(|&id| !w.object(id).movable)
        .map(|id| {
            let d = (w.object_pose(id).translation - base.translation)
                .truncate()
                .length();
            (id, d)
        })
        .filter(|&(_, d)| d <= 0.5)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(id, _)| id)
}

/// A base pose as the scene format's `(x, y, yaw in degrees)`.
pub(crate) fn base_xyyaw(base: Pose) -> [f32; 3] {
    let (yaw, _, _) = base.rotation.to_euler(parry3d::glamx::EulerRot::ZYX);
    [base.translation.x, base.translation.y, yaw.to_degrees()]
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use geometry::world::Precision;

    fn generator() -> RandomLayouts {
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../domains/library/scene.toml");
        RandomLayouts::new(&scene, LayoutRules::default()).unwrap()
    }

    /// `seed` gives the same scene twice (text and world), `other` another one.
    pub(crate) fn assert_seeded(g: &dyn crate::experiment::LayoutSource, seed: u64, other: u64) {
        let (a, b, c) = (
            g.generate(seed).unwrap(),
            g.generate(seed).unwrap(),
            g.generate(other).unwrap(),
        );
        assert_eq!(a.toml, b.toml);
        let f = |l: &Layout| l.world.fingerprint(Precision::Exact);
        assert_eq!(f(&a), f(&b));
        assert_ne!(f(&a), f(&c));
    }

    #[test]
    fn the_same_seed_gives_the_same_layout_and_another_seed_another() {
        assert_seeded(&generator(), 5, 6);
    }

    #[test]
    fn layouts_are_free_of_collisions_with_every_object_supported() {
        let g = generator();
        let dir = std::env::temp_dir().join(format!("htngtp-layout-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut postures = std::collections::BTreeSet::new();
        for seed in 1..=4 {
            let l = g.generate(seed).unwrap();
            // Written elsewhere, the scene reads again (paths are absolute) and the load's
            // overlap check passes: no movable object starts inside anything.
            let path = dir.join(format!("layout-{seed}.toml"));
            std::fs::write(&path, &l.toml).unwrap();
            let w = World::load(&path).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
            for o in &l.summary.objects {
                let id = w.object_id(&o.name).unwrap();
                let support = w.object_id(&o.support).unwrap();
                assert!(
                    on(&w, id, support, 0.01),
                    "seed {seed}: {} off {}",
                    o.name,
                    o.support
                );
                assert!(
                    rests_free(&w, id, &support_surface(&w, id, support)),
                    "seed {seed}: {} touches something",
                    o.name
                );
            }
            assert_eq!(l.summary.objects.len(), movable(&g.world).len());
            for p in &l.summary.people {
                let a = w.agent_id(&p.name).unwrap();
                assert_eq!(w.agent(a).spec.sitting, p.sitting);
                let chair = p
                    .sitting
                    .then(|| chair_of(&w, w.agent_state(a).base))
                    .flatten();
                assert!(
                    g.person_is_free(&w, a, chair),
                    "seed {seed}: {} collides",
                    p.name
                );
                assert!(g.serves(&w, a, &g.counter_surface(&w).unwrap(), p.sitting));
                postures.insert(p.sitting);
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(postures.len(), 2, "seeds 1-4 seat and stand the member");
    }

    /// The surface of `support` under `id`.
    fn support_surface(w: &World, id: ObjectId, support: ObjectId) -> Surface {
        let z = w.object_aabb(id).mins.z;
        surfaces(w)
            .into_iter()
            .filter(|s| s.support == support)
            .min_by(|a, b| (a.centre.z - z).abs().total_cmp(&(b.centre.z - z).abs()))
            .unwrap()
    }

    #[test]
    fn a_scene_without_the_counter_is_an_error() {
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../domains/library/scene.toml");
        let rules = LayoutRules {
            counter: "bar".into(),
            ..LayoutRules::default()
        };
        let e = RandomLayouts::new(&scene, rules).err().unwrap();
        assert!(e.contains("no counter `bar`"), "{e}");
    }
}
