//! Self-collision of an agent: which pairs of its links to test, found once per agent model
//! (adjacent, default-colliding, always-colliding and never-colliding pairs are left out, as
//! MoveIt's setup assistant does for its SRDF).

use std::fmt;
use std::sync::Arc;

use parry3d::math::Pose;
use parry3d::shape::SharedShape;

use super::intersects;
use crate::agent::{AgentModel, ModelError};

/// How the self-collision pairs to ignore are found.
#[derive(Debug, Clone, PartialEq)]
pub struct SelfCollisionOptions {
    /// Random configurations sampled to find the pairs that always collide.
    pub samples: usize,
    /// Seed of the sampling.
    pub seed: u64,
    /// A pair colliding in at least this fraction of the samples is ignored (MoveIt's default
    /// is 0.95).
    pub always_fraction: f32,
}

impl Default for SelfCollisionOptions {
    fn default() -> Self {
        SelfCollisionOptions {
            samples: 1000,
            seed: 0,
            always_fraction: 0.95,
        }
    }
}

/// Why a pair of links is not checked for self-collision.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AllowedReason {
    /// A link and its parent link (one joint apart).
    Adjacent,
    /// They collide in the default configuration.
    Default,
    /// They collide in (almost) every sampled configuration.
    Always,
    /// The model's SRDF says so (`<disable_collisions>`).
    Srdf,
    /// Their relative pose depends on at most one joint (the two fingers of a gripper, for
    /// example), and a sweep of that joint's whole range at `SWEEP_STEPS` + 1 values found no
    /// contact, so they never collide.
    Never,
}

/// Resolution of the sweep behind [`AllowedReason::Never`].
pub const SWEEP_STEPS: usize = 2000;

/// The degrees of freedom that move link `b` relative to link `a` (mimic joints count as
/// their master), sorted and deduplicated.
fn relative_dofs(model: &AgentModel, a: usize, b: usize) -> Vec<usize> {
    let path = |mut l: usize| {
        let mut v = vec![l];
        while let Some(p) = model.links()[l].parent {
            v.push(p);
            l = p;
        }
        v
    };
    let (pa, pb) = (path(a), path(b));
    let mut dofs = Vec::new();
    for (p, other) in [(&pa, &pb), (&pb, &pa)] {
        for &l in p {
            if other.contains(&l) {
                break; // the common ancestor
            }
            let j = &model.joints()[model.links()[l].parent_joint.expect("non-root")];
            let dof = j
                .dof
                .or_else(|| j.mimic.and_then(|m| model.joints()[m.master].dof));
            dofs.extend(dof);
        }
    }
    dofs.sort_unstable();
    dofs.dedup();
    dofs
}

/// A pair of links left out of self-collision checks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AllowedPair {
    /// First link's name.
    pub link_a: String,
    /// Second link's name.
    pub link_b: String,
    /// Why.
    pub reason: AllowedReason,
}

/// One collision shape of the agent, flattened out of its link.
#[derive(Clone)]
pub(super) struct ShapeEntry {
    pub(super) link: usize,
    pub(super) local_pose: Pose,
    pub(super) shape: SharedShape,
    pub(super) radius: f32,
}

/// An agent model's collision shapes and its self-collision pair list. Build once per model.
#[derive(Clone)]
pub struct SelfCollisionModel {
    pub(super) model: Arc<AgentModel>,
    pub(super) shapes: Vec<ShapeEntry>,
    /// Shape index pairs to test for self-collision.
    pub(super) pairs: Vec<(u16, u16)>,
    /// 0, 1, .. shapes.len() - 1.
    pub(super) all_shapes: Vec<u16>,
    allowed: Vec<AllowedPair>,
}

impl fmt::Debug for SelfCollisionModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SelfCollisionModel")
            .field("model", &self.model.name())
            .field("shapes", &self.shapes.len())
            .field("pairs", &self.pairs.len())
            .field("allowed", &self.allowed)
            .finish()
    }
}

impl SelfCollisionModel {
    /// Flattens the model's shapes and computes the pairs to check (see the module docs).
    pub fn new(model: Arc<AgentModel>, options: &SelfCollisionOptions) -> SelfCollisionModel {
        let mut shapes = Vec::new();
        for (i, link) in model.links().iter().enumerate() {
            for c in &link.collisions {
                shapes.push(ShapeEntry {
                    link: i,
                    local_pose: c.local_pose,
                    shape: c.shape.clone(),
                    radius: c.bounding_radius,
                });
            }
        }
        let nl = model.links().len();
        // Link-level pair status: None = check, Some(reason) = ignore.
        let mut status: Vec<Option<AllowedReason>> = vec![None; nl * nl];
        let key = |a: usize, b: usize| a.min(b) * nl + a.max(b);
        for (i, link) in model.links().iter().enumerate() {
            if link.collisions.is_empty() {
                continue;
            }
            if let Some(p) = link.parent
                && !model.links()[p].collisions.is_empty()
            {
                status[key(i, p)] = Some(AllowedReason::Adjacent);
            }
            // Shapes of one link never collide with each other.
            status[key(i, i)] = Some(AllowedReason::Adjacent);
        }
        for (a, b) in &model.semantics().disabled_collisions {
            if let (Ok(a), Ok(b)) = (model.link_id(a), model.link_id(b)) {
                status[key(a, b)].get_or_insert(AllowedReason::Srdf);
            }
        }
        let mut candidate_links = Vec::new();
        for a in 0..nl {
            for b in a + 1..nl {
                if !model.links()[a].collisions.is_empty()
                    && !model.links()[b].collisions.is_empty()
                    && status[key(a, b)].is_none()
                {
                    candidate_links.push((a, b));
                }
            }
        }
        let mut poses = Vec::new();
        let link_pairs_colliding = |q: &[f32], poses: &mut Vec<Pose>, out: &mut Vec<bool>| {
            model.link_poses_into(Pose::IDENTITY, q, poses);
            out.clear();
            for &(a, b) in &candidate_links {
                out.push(links_collide(&model, poses, a, b));
            }
        };
        let mut hits = Vec::new();
        let default = model.default_configuration();
        link_pairs_colliding(default.as_slice(), &mut poses, &mut hits);
        for (k, &(a, b)) in candidate_links.iter().enumerate() {
            if hits[k] {
                status[key(a, b)] = Some(AllowedReason::Default);
            }
        }
        let mut counts = vec![0usize; candidate_links.len()];
        let mut rng = fastrand::Rng::with_seed(options.seed);
        for _ in 0..options.samples {
            let q = model.random_configuration(&mut rng);
            link_pairs_colliding(q.as_slice(), &mut poses, &mut hits);
            for (c, &h) in counts.iter_mut().zip(&hits) {
                *c += h as usize;
            }
        }
        if options.samples > 0 {
            for (k, &(a, b)) in candidate_links.iter().enumerate() {
                let fraction = counts[k] as f32 / options.samples as f32;
                if status[key(a, b)].is_none() && fraction >= options.always_fraction {
                    status[key(a, b)] = Some(AllowedReason::Always);
                }
            }
        }
        // Pairs whose relative pose depends on at most one degree of freedom: sweep it.
        for &(a, b) in &candidate_links {
            if status[key(a, b)].is_some() {
                continue;
            }
            let dofs = relative_dofs(&model, a, b);
            let never = match dofs.as_slice() {
                [] => true, // rigidly connected and apart in the default configuration
                [d] => {
                    let limits = model.dof_limits()[*d];
                    let (lo, hi) = if limits.is_bounded() {
                        (limits.lower, limits.upper)
                    } else {
                        (-std::f32::consts::PI, std::f32::consts::PI)
                    };
                    let mut q = default.as_slice().to_vec();
                    (0..=SWEEP_STEPS).all(|k| {
                        q[*d] = lo + (hi - lo) * k as f32 / SWEEP_STEPS as f32;
                        model.link_poses_into(Pose::IDENTITY, &q, &mut poses);
                        !links_collide(&model, &poses, a, b)
                    })
                }
                _ => false,
            };
            if never {
                status[key(a, b)] = Some(AllowedReason::Never);
            }
        }
        let mut pairs = Vec::new();
        for i in 0..shapes.len() {
            for j in i + 1..shapes.len() {
                if status[key(shapes[i].link, shapes[j].link)].is_none() {
                    pairs.push((i as u16, j as u16));
                }
            }
        }
        let mut allowed = Vec::new();
        for a in 0..nl {
            for b in a + 1..nl {
                if let Some(reason) = status[key(a, b)] {
                    allowed.push(AllowedPair {
                        link_a: model.links()[a].name.clone(),
                        link_b: model.links()[b].name.clone(),
                        reason,
                    });
                }
            }
        }
        SelfCollisionModel {
            model,
            all_shapes: (0..shapes.len() as u16).collect(),
            shapes,
            pairs,
            allowed,
        }
    }

    /// The agent model.
    pub fn model(&self) -> &Arc<AgentModel> {
        &self.model
    }

    /// Link pairs left out of self-collision checks, and why.
    pub fn allowed_pairs(&self) -> &[AllowedPair] {
        &self.allowed
    }

    /// Number of shape pairs tested for self-collision.
    pub fn checked_pair_count(&self) -> usize {
        self.pairs.len()
    }

    /// Whether links `a` and `b` (names) are checked against each other.
    pub fn is_checked(&self, a: &str, b: &str) -> Result<bool, ModelError> {
        let (a, b) = (self.model.link_id(a)?, self.model.link_id(b)?);
        Ok(self.pairs.iter().any(|&(i, j)| {
            let (la, lb) = (self.shapes[i as usize].link, self.shapes[j as usize].link);
            (la == a && lb == b) || (la == b && lb == a)
        }))
    }
}

fn links_collide(model: &AgentModel, poses: &[Pose], a: usize, b: usize) -> bool {
    for ca in &model.links()[a].collisions {
        let pa = poses[a] * ca.local_pose;
        for cb in &model.links()[b].collisions {
            let pb = poses[b] * cb.local_pose;
            if (pa.translation - pb.translation).length() <= ca.bounding_radius + cb.bounding_radius
                && intersects(&pa, &*ca.shape.0, &pb, &*cb.shape.0)
            {
                return true;
            }
        }
    }
    false
}
