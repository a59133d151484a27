//! The state the checker replays: object poses, each agent's posture, and who holds what.

use parry3d::math::Pose;

use crate::bodies::hand_of;
use crate::model::Plan;

/// An object in an agent's hand.
#[derive(Clone, Debug)]
pub struct Hold {
    pub agent: usize,
    /// The hand link nearest the object when the hold began; the object rides with it.
    pub link: usize,
    /// The links of the hand it is in (its declared `hands` entry), which may touch the object.
    pub hand: Vec<usize>,
}

/// Poses of everything at one moment of the plan.
#[derive(Clone)]
pub struct World {
    pub objects: Vec<Pose>,
    pub agents: Vec<Vec<Pose>>,
    pub holds: Vec<Option<Hold>>,
}

impl World {
    /// The initial scene: nothing held.
    pub fn initial(plan: &Plan) -> Self {
        World {
            objects: plan.objects.iter().map(|o| o.pose).collect(),
            agents: plan.agents.iter().map(|a| a.link_poses.clone()).collect(),
            holds: vec![None; plan.objects.len()],
        }
    }

    /// Agent `a` takes object `o`, posed at `held` while the agent's links are at `links`.
    pub fn grasp(&mut self, plan: &Plan, a: usize, o: usize, links: &[Pose], held: &Pose) {
        self.holds[o] = hand_of(&plan.agents[a], links, held).map(|(link, hand)| Hold {
            agent: a,
            link,
            hand,
        });
    }
}
