//! Objects at rest after a step: each movable object not in a hand must lie on something (its
//! bottom within the gap tolerance of a surface under it), and none may penetrate another body.

use std::collections::BTreeSet;

use parry3d::bounding_volume::BoundingVolume;
use parry3d::query;

use crate::Options;
use crate::bodies::{Owner, Placed, depth, links_at, objects_at};
use crate::model::{Plan, Step};
use crate::report::{Fault, FaultKind, Report};
use crate::world::World;

/// A rest fault's identity: kind, the object, the other body (the object itself when unsupported).
pub type RestKey = (FaultKind, usize, Owner);

/// Check the rest state after `step` (`None`: the initial scene). Faults already present at the
/// previous check (`before`) are not repeated; returns this check's keys.
pub fn check_rest(
    plan: &Plan,
    world: &World,
    step: Option<&Step>,
    opts: &Options,
    before: &BTreeSet<RestKey>,
    report: &mut Report,
) -> BTreeSet<RestKey> {
    let mut everything = objects_at(plan, &world.objects, &[]);
    for a in 0..plan.agents.len() {
        everything.extend(links_at(plan, a, &world.agents[a]));
    }
    let mut keys = BTreeSet::new();
    for o in (0..plan.objects.len()).filter(|&o| plan.objects[o].movable) {
        let mine: Vec<&Placed> = everything
            .iter()
            .filter(|p| p.owner == Owner::Object(o))
            .collect();
        let others: Vec<&Placed> = everything
            .iter()
            .filter(|p| p.owner != Owner::Object(o))
            .collect();
        let mut found = penetrations(plan, world, o, &mine, &others, opts);
        // An object in something rests on nothing: the penetration is the fault to report.
        if found.is_empty() {
            found.extend(support(plan, world, o, &mine, &others, opts));
        }
        for (key, depth_mm, detail) in found {
            if !before.contains(&key) {
                report
                    .faults
                    .push(rest_fault(plan, step, key, depth_mm, detail));
            }
            keys.insert(key);
        }
    }
    keys
}

type Found = (RestKey, f32, String);

/// Bodies that object `o` penetrates by more than the depth tolerance (each pair once; the
/// hand that holds `o` up to the grasp tolerance).
fn penetrations(
    plan: &Plan,
    world: &World,
    o: usize,
    mine: &[&Placed],
    others: &[&Placed],
    opts: &Options,
) -> Vec<Found> {
    let hand = world.holds[o].as_ref();
    let mut worst: Vec<(Owner, f32, f32)> = Vec::new();
    for b in others {
        let limit = match b.owner {
            Owner::Object(j) if plan.objects[j].movable && j < o => continue,
            Owner::Held(_) => continue,
            Owner::Link(a, l) if hand.is_some_and(|h| h.agent == a && h.hand.contains(&l)) => {
                opts.grasp_depth
            }
            _ => opts.depth,
        };
        let d = mine.iter().map(|m| depth(m, b)).fold(0.0f32, f32::max);
        if d > limit {
            match worst.iter_mut().find(|(w, _, _)| *w == b.owner) {
                Some(w) => w.1 = w.1.max(d),
                None => worst.push((b.owner, d, limit)),
            }
        }
    }
    let detail = |limit: f32| {
        if limit == opts.depth {
            String::new()
        } else {
            format!(
                "held deeper than the {:.0} mm grasp tolerance",
                limit * 1000.0
            )
        }
    };
    worst
        .into_iter()
        .map(|(b, d, limit)| ((FaultKind::Penetration, o, b), d * 1000.0, detail(limit)))
        .collect()
}

/// `o` is supported when some other body lies within the gap of it with the contact normal
/// pointing down from `o` (the body is under it). Objects in a hand are not checked.
fn support(
    plan: &Plan,
    world: &World,
    o: usize,
    mine: &[&Placed],
    others: &[&Placed],
    opts: &Options,
) -> Option<Found> {
    if world.holds[o].is_some() {
        return None;
    }
    let gap = opts.gap + 1e-4;
    let under = |m: &Placed, b: &Placed| {
        m.aabb.loosened(gap).intersects(&b.aabb)
            && matches!(
                query::contact(&m.pose, &*m.shape, &b.pose, &*b.shape, gap),
                Ok(Some(c)) if c.normal1.z < -0.5
            )
    };
    if mine.iter().any(|m| others.iter().any(|b| under(m, b))) {
        return None;
    }
    let (gap_mm, detail) = gap_below(plan, mine, others);
    Some((
        (FaultKind::Unsupported, o, Owner::Object(o)),
        gap_mm,
        detail,
    ))
}

/// The nearest body whose box lies under the object's bottom and overlaps its footprint.
fn gap_below(plan: &Plan, mine: &[&Placed], others: &[&Placed]) -> (f32, String) {
    let bottom = mine
        .iter()
        .map(|m| m.aabb.mins.z)
        .fold(f32::INFINITY, f32::min);
    let mut best: Option<(f32, &Placed)> = None;
    for m in mine {
        for b in others {
            let overlap_xy = m.aabb.mins.x <= b.aabb.maxs.x
                && m.aabb.maxs.x >= b.aabb.mins.x
                && m.aabb.mins.y <= b.aabb.maxs.y
                && m.aabb.maxs.y >= b.aabb.mins.y;
            if !overlap_xy || b.aabb.maxs.z > bottom + 0.05 {
                continue;
            }
            if let Ok(d) = query::distance(&m.pose, &*m.shape, &b.pose, &*b.shape) {
                let d = d.distance;
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, b));
                }
            }
        }
    }
    match best {
        Some((d, b)) => (
            d * 1000.0,
            format!("nearest body below: {}", b.owner.name(plan)),
        ),
        None => (0.0, "nothing under it".to_string()),
    }
}

fn rest_fault(
    plan: &Plan,
    step: Option<&Step>,
    key: RestKey,
    depth_mm: f32,
    detail: String,
) -> Fault {
    let (kind, o, other) = key;
    let b = if kind == FaultKind::Unsupported {
        "nothing within the gap under it".to_string()
    } else {
        other.name(plan)
    };
    Fault {
        kind,
        step: step.map(|s| s.index),
        action: step.map_or("initial scene".to_string(), |s| s.action.clone()),
        trajectory: None,
        trajectory_index: None,
        frame: None,
        a: Owner::Object(o).name(plan),
        b,
        depth_mm,
        configs: 1,
        detail,
    }
}
