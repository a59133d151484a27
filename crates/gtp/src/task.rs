//! The paper's geometric tasks and their constraints.
//!
//! Each task is a set of constraints with thresholds that have defaults and can be set per
//! call ([`Constraints`]). Defaults follow `../shared/notes/geometry-facts.md` (beside the checkout) section 6 and the
//! paper's experiment.

use std::fmt;
use std::time::Duration;

use serde::{Deserialize, Serialize};

/// The kinds of geometric task.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TaskKind {
    /// `pick(o)`: grasp o and lift it.
    Pick,
    /// `place-on(o, s)`: put o on a support surface of s.
    PlaceOn,
    /// `show(o, h)`: hold o where h sees it.
    Show,
    /// `give(o, h)`: hold o where h sees and reaches it.
    Give,
    /// `make-accessible(o, h)`: put o where h sees enough of it and reaches it at low effort.
    MakeAccessible,
    /// `put-away(o, h)`: put o where h sees none of it and cannot reach it at low effort.
    PutAway,
    /// `navigate-to(target)`: drive the robot's base to a pose from which target is reachable.
    NavigateTo,
    /// `pick-and-make-accessible(o, h)`: pick with the grasp chosen for the placement.
    PickAndMakeAccessible,
    /// `take(o, h)`: h takes o, held out by the robot, into a hand; the robot lets go and
    /// draws its gripper back (the geometric side of the paper's WAITTAKE).
    Take,
}

impl TaskKind {
    /// Every task kind, in the order of the paper.
    pub const ALL: [TaskKind; 9] = [
        TaskKind::Pick,
        TaskKind::PlaceOn,
        TaskKind::Show,
        TaskKind::Give,
        TaskKind::MakeAccessible,
        TaskKind::PutAway,
        TaskKind::NavigateTo,
        TaskKind::PickAndMakeAccessible,
        TaskKind::Take,
    ];

    /// The task's name as written in domains and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TaskKind::Pick => "pick",
            TaskKind::PlaceOn => "place-on",
            TaskKind::Show => "show",
            TaskKind::Give => "give",
            TaskKind::MakeAccessible => "make-accessible",
            TaskKind::PutAway => "put-away",
            TaskKind::NavigateTo => "navigate-to",
            TaskKind::PickAndMakeAccessible => "pick-and-make-accessible",
            TaskKind::Take => "take",
        }
    }

    /// The parameters the task takes, by role.
    pub fn parameters(self) -> &'static [&'static str] {
        match self {
            TaskKind::Pick => &["object"],
            TaskKind::PlaceOn => &["object", "support"],
            TaskKind::NavigateTo => &["target"],
            _ => &["object", "human"],
        }
    }

    /// Parses a task name; accepts `_` for `-`, any case, the paper's short forms (`makeacc`,
    /// `putaway`, `hide`, `navto`, `puton`) and its compound tasks, PICK grouped with the task
    /// after it (`pick-and-show`, `pick-and-give`, `pick-and-put-away`, `pick-and-place-on`):
    /// the placing and handing-over tasks grasp the object themselves when it is not held yet,
    /// choosing the grasp with the placement in view, which is what the compound task asks.
    pub fn from_name(name: &str) -> Option<TaskKind> {
        let n = name.to_ascii_lowercase().replace('_', "-");
        let n = match n.as_str() {
            "pick-and-show" => "show",
            "pick-and-give" => "give",
            "pick-and-put-away" => "put-away",
            "pick-and-place-on" | "pick-and-put-on" => "place-on",
            other => other,
        };
        Some(match n {
            "pick" => TaskKind::Pick,
            "place-on" | "placeon" | "put-on" | "puton" | "place" => TaskKind::PlaceOn,
            "show" => TaskKind::Show,
            "give" => TaskKind::Give,
            "make-accessible" | "makeaccessible" | "make-acc" | "makeacc" => {
                TaskKind::MakeAccessible
            }
            "put-away" | "putaway" | "hide" => TaskKind::PutAway,
            "navigate-to" | "navigateto" | "navto" | "nav-to" => TaskKind::NavigateTo,
            "pick-and-make-accessible"
            | "pickmakeaccessible"
            | "pick-make-accessible"
            | "pickmakeacc" => TaskKind::PickAndMakeAccessible,
            "take" | "hand-over" | "handover" | "waittake" => TaskKind::Take,
            _ => return None,
        })
    }

    /// Whether the task ends with the object resting on a support (else held, or no object).
    pub fn places(self) -> bool {
        matches!(
            self,
            TaskKind::PlaceOn
                | TaskKind::MakeAccessible
                | TaskKind::PutAway
                | TaskKind::PickAndMakeAccessible
        )
    }

    /// Whether the task ends with the object held in the air in front of a human.
    pub fn hands_over(self) -> bool {
        matches!(self, TaskKind::Show | TaskKind::Give)
    }
}

impl fmt::Display for TaskKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The thresholds of a task's constraints. [`Constraints::defaults`] gives each task's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Constraints {
    /// The object must show at least this fraction of its pixels to the human.
    pub min_visibility: Option<f32>,
    /// The object may show at most this fraction of its pixels to the human.
    pub max_visibility: Option<f32>,
    /// The human must reach the object at this effort level or lower.
    pub reach_within: Option<u8>,
    /// The human must not reach the object at this effort level or lower.
    pub unreachable_within: Option<u8>,
    /// Effort levels of the human searched, from 0 to this (the outer loop of the search).
    pub max_effort: u8,
    /// The robot's highest effort level: 1 extends the arm only, the base fixed; 2 also turns
    /// the base in place and 4 also steps it (up to 1 m), both tried inside the task when it
    /// finds nothing from where the robot stands (`crate::search::BaseMoves`).
    pub robot_effort: u8,
    /// Lift after grasping, and height of the approach above a placement (metres).
    pub lift: f32,
    /// Approach and retreat distance along the gripper's axis (metres).
    pub approach: f32,
    /// Time limit of one call (the paper: 60 s).
    pub time_limit: Duration,
    /// At most this many candidate points per effort level (the original: 15,000).
    pub max_points: usize,
}

impl Constraints {
    /// The default thresholds of `kind`.
    pub fn defaults(kind: TaskKind) -> Constraints {
        let base = Constraints {
            min_visibility: None,
            max_visibility: None,
            reach_within: None,
            unreachable_within: None,
            max_effort: 0,
            robot_effort: 4,
            lift: 0.15,
            approach: 0.10,
            time_limit: Duration::from_secs(60),
            max_points: 15_000,
        };
        match kind {
            TaskKind::Show => Constraints {
                min_visibility: Some(0.9),
                max_effort: 1,
                ..base
            },
            TaskKind::Give => Constraints {
                min_visibility: Some(0.9),
                reach_within: Some(1),
                max_effort: 1,
                ..base
            },
            TaskKind::MakeAccessible | TaskKind::PickAndMakeAccessible => Constraints {
                min_visibility: Some(0.5),
                reach_within: Some(1),
                max_effort: 1,
                ..base
            },
            TaskKind::PutAway => Constraints {
                max_visibility: Some(0.0),
                unreachable_within: Some(1),
                max_effort: 1,
                ..base
            },
            TaskKind::Take => Constraints {
                reach_within: Some(1),
                max_effort: 1,
                ..base
            },
            _ => base,
        }
    }

    /// Sets one threshold by name (`min-visibility`, `max-visibility`, `reach-within`,
    /// `unreachable-within`, `max-effort`, `robot-effort`, `lift`, `approach`, `time-limit` in
    /// seconds, `max-points`); `none` clears an optional one.
    pub fn set(&mut self, key: &str, value: &str) -> Result<(), String> {
        let key = key.replace('_', "-");
        let float = || -> Result<f32, String> {
            value
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{key}: expected a number, found `{value}`"))
        };
        let level = || -> Result<u8, String> {
            value
                .parse::<u8>()
                .ok()
                .filter(|v| *v <= 4)
                .ok_or_else(|| format!("{key}: expected an effort level 0..4, found `{value}`"))
        };
        let none = value.eq_ignore_ascii_case("none");
        match key.as_str() {
            "min-visibility" => {
                self.min_visibility = if none {
                    None
                } else {
                    Some(fraction(&key, float()?)?)
                }
            }
            "max-visibility" => {
                self.max_visibility = if none {
                    None
                } else {
                    Some(fraction(&key, float()?)?)
                }
            }
            "reach-within" => self.reach_within = if none { None } else { Some(level()?) },
            "unreachable-within" => {
                self.unreachable_within = if none { None } else { Some(level()?) }
            }
            "max-effort" => self.max_effort = level()?,
            "robot-effort" => self.robot_effort = level()?,
            "lift" => self.lift = float()?.max(0.0),
            "approach" => self.approach = float()?.max(0.0),
            "time-limit" => {
                let s = float()?;
                // At most a year: a `Duration` cannot hold 1e20 s.
                if !(s > 0.0 && s <= 3.2e7) {
                    return Err(format!(
                        "time-limit: expected seconds > 0 and at most a year, found `{value}`"
                    ));
                }
                self.time_limit = Duration::from_secs_f32(s);
            }
            "max-points" => {
                self.max_points = value
                    .parse()
                    .map_err(|_| format!("max-points: expected a count, found `{value}`"))?
            }
            _ => {
                return Err(format!(
                    "unknown constraint `{key}` (expected min-visibility, max-visibility, \
                     reach-within, unreachable-within, max-effort, robot-effort, lift, approach, \
                     time-limit, max-points)"
                ));
            }
        }
        Ok(())
    }
}

fn fraction(key: &str, v: f32) -> Result<f32, String> {
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{key}: expected a fraction 0..1, found {v}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_aliases_parse() {
        for k in TaskKind::ALL {
            assert_eq!(TaskKind::from_name(k.name()), Some(k));
        }
        assert_eq!(
            TaskKind::from_name("MAKE_ACCESSIBLE"),
            Some(TaskKind::MakeAccessible)
        );
        assert_eq!(TaskKind::from_name("hide"), Some(TaskKind::PutAway));
        assert_eq!(TaskKind::from_name("fly"), None);
        // The paper's compound tasks, as domains and the command line write them.
        for (name, kind) in [
            ("pick-and-show", TaskKind::Show),
            ("pick_and_give", TaskKind::Give),
            ("pick-and-put-away", TaskKind::PutAway),
            ("pick-and-place-on", TaskKind::PlaceOn),
        ] {
            assert_eq!(TaskKind::from_name(name), Some(kind), "{name}");
        }
    }

    #[test]
    fn thresholds_default_per_task_and_can_be_set() {
        let c = Constraints::defaults(TaskKind::PutAway);
        assert_eq!(c.max_visibility, Some(0.0));
        assert_eq!(c.unreachable_within, Some(1));
        let mut c = Constraints::defaults(TaskKind::MakeAccessible);
        assert_eq!(c.min_visibility, Some(0.5));
        c.set("min-visibility", "0.9").unwrap();
        assert_eq!(c.min_visibility, Some(0.9));
        c.set("time_limit", "2.5").unwrap();
        assert!(
            c.set("time-limit", "1e20")
                .unwrap_err()
                .contains("at most a year")
        );
        assert_eq!(c.time_limit, Duration::from_millis(2500));
        assert!(
            c.set("min-visibility", "1.5")
                .unwrap_err()
                .contains("fraction")
        );
        assert!(
            c.set("colour", "red")
                .unwrap_err()
                .contains("unknown constraint")
        );
        c.set("reach-within", "none").unwrap();
        assert_eq!(c.reach_within, None);
    }
}
