//! Forward kinematics: the pose in the world of every link of an agent, given the base pose and
//! a joint configuration.
//!
//! Links are stored parents first (see [`crate::agent`]), so all link poses come out of one
//! forward pass: `pose[child] = pose[parent] * joint.transform(value)`.

use parry3d::math::Pose;

use crate::agent::{AgentModel, CollisionShape, ModelError};

impl AgentModel {
    /// World poses of all links (indexed like [`AgentModel::links`]) for base pose `base` and
    /// configuration `q` (one value per degree of freedom).
    ///
    /// # Panics
    /// If `q.len() != self.dof()` (a programming error; check configurations from outside with
    /// [`AgentModel::configuration`]).
    pub fn link_poses(&self, base: Pose, q: &[f32]) -> Vec<Pose> {
        let mut out = Vec::with_capacity(self.links().len());
        self.link_poses_into(base, q, &mut out);
        out
    }

    /// As [`AgentModel::link_poses`], writing into `out` (cleared first) to avoid allocating.
    pub fn link_poses_into(&self, base: Pose, q: &[f32], out: &mut Vec<Pose>) {
        assert_eq!(
            q.len(),
            self.dof(),
            "configuration length does not match agent model '{}'",
            self.name()
        );
        out.clear();
        out.push(base);
        for (j, joint) in self.joints().iter().enumerate() {
            let value = self.joint_value(j, q);
            let p = out[joint.parent] * joint.transform(value);
            out.push(p);
        }
    }

    /// World pose of the link called `name` (walks only the path from the root).
    pub fn link_pose(&self, base: Pose, q: &[f32], name: &str) -> Result<Pose, ModelError> {
        if q.len() != self.dof() {
            return Err(ModelError::WrongLength {
                model: self.name().to_string(),
                expected: self.dof(),
                got: q.len(),
            });
        }
        let id = self.link_id(name)?;
        Ok(self.link_pose_by_id(base, q, id))
    }

    /// World pose of link `id` (walks only the path from the root).
    pub fn link_pose_by_id(&self, base: Pose, q: &[f32], id: usize) -> Pose {
        let mut path = Vec::new();
        let mut cur = id;
        while let Some(j) = self.links()[cur].parent_joint {
            path.push(j);
            cur = self.joints()[j].parent;
        }
        let mut p = base;
        for &j in path.iter().rev() {
            p *= self.joints()[j].transform(self.joint_value(j, q));
        }
        p
    }

    /// World poses of every collision shape, as `(link index, shape, world pose)`.
    pub fn posed_shapes<'a>(
        &'a self,
        base: Pose,
        q: &[f32],
    ) -> Vec<(usize, &'a CollisionShape, Pose)> {
        let poses = self.link_poses(base, q);
        let mut out = Vec::new();
        for (i, link) in self.links().iter().enumerate() {
            for c in &link.collisions {
                out.push((i, c, poses[i] * c.local_pose));
            }
        }
        out
    }
}
