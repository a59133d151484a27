//! A totally-ordered HTN plan: the primitive actions and the decomposition tree, printed in the
//! format of the International Planning Competition and read back from it.
//!
//! ```text
//! ==>
//! 3 pick grey-book
//! 4 say grey-title
//! root 0
//! 0 manage-order member -> m1 1 2
//! ...
//! <==
//! ```
//! Ids are integers unique across the plan; actions and tasks share them.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use crate::model::{Domain, Problem};
use crate::oracle::{GroundAtom, SolutionId};

/// A primitive action of the plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanAction {
    pub id: u32,
    pub name: String,
    pub args: Vec<String>,
    /// For a GS action, the geometric solution it took.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geometric: Option<GeoStep>,
}

/// The geometric solution a GS action took: the geometric task, the shared literals it made
/// true and false, and the back end's handle on the solution (grasp, placement, trajectory...).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeoStep {
    pub task: String,
    pub args: Vec<String>,
    pub add: Vec<GroundAtom>,
    pub delete: Vec<GroundAtom>,
    pub solution: SolutionId,
}

/// One decomposition: abstract task `id` was decomposed by `method` into `subtasks` (ids, in order).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Decomposition {
    pub id: u32,
    pub task: String,
    pub args: Vec<String>,
    pub method: String,
    pub subtasks: Vec<u32>,
}

/// A plan: actions in execution order, the ids of the initial task network, the decompositions.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub actions: Vec<PlanAction>,
    pub root: Vec<u32>,
    pub decompositions: Vec<Decomposition>,
}

/// A line of a plan text that could not be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("plan line {line}: {message}")]
pub struct PlanParseError {
    /// 1-based line in the plan text (0: the text as a whole).
    pub line: usize,
    pub message: String,
}

impl Plan {
    /// The plan in the competition format, between `==>` and `<==`.
    pub fn to_competition_format(&self) -> String {
        let mut s = String::from("==>\n");
        for a in &self.actions {
            let _ = write!(s, "{} {}", a.id, a.name);
            for x in &a.args {
                let _ = write!(s, " {x}");
            }
            s.push('\n');
        }
        s.push_str("root");
        for r in &self.root {
            let _ = write!(s, " {r}");
        }
        s.push('\n');
        for d in &self.decompositions {
            let _ = write!(s, "{} {}", d.id, d.task);
            for x in &d.args {
                let _ = write!(s, " {x}");
            }
            let _ = write!(s, " -> {}", d.method);
            for c in &d.subtasks {
                let _ = write!(s, " {c}");
            }
            s.push('\n');
        }
        s.push_str("<==\n");
        s
    }

    /// Reads a plan in the competition format. Text before `==>` (a planner's log) and after
    /// `<==` is ignored; without `==>` the whole text is read as the plan. Names keep their
    /// spelling: the strict validator matches them exactly, as the competition's verifier does.
    pub fn parse(text: &str) -> Result<Plan, PlanParseError> {
        let lines: Vec<&str> = text.lines().collect();
        let start = lines
            .iter()
            .position(|l| l.trim() == "==>")
            .map_or(0, |i| i + 1);
        let mut plan = Plan::default();
        let mut seen_root = false;
        let err = |line: usize, message: String| PlanParseError { line, message };
        for (i, raw) in lines.iter().enumerate().skip(start) {
            let n = i + 1;
            let line = raw.split(';').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            if line == "<==" {
                break;
            }
            let words: Vec<String> = line.split_whitespace().map(str::to_string).collect();
            if words[0] == "root" {
                if seen_root {
                    return Err(err(n, "a second `root` line".into()));
                }
                seen_root = true;
                for w in &words[1..] {
                    plan.root.push(parse_id(w).map_err(|m| err(n, m))?);
                }
                continue;
            }
            let id = parse_id(&words[0]).map_err(|m| {
                err(
                    n,
                    format!("{m} (expected `ID name args...`, `root IDs` or `ID task args -> method IDs`)"),
                )
            })?;
            if words.len() < 2 {
                return Err(err(n, format!("id {id} has no action or task name")));
            }
            if let Some(arrow) = words.iter().position(|w| w == "->") {
                if !seen_root {
                    return Err(err(n, "a decomposition line before the `root` line".into()));
                }
                let Some(method) = words.get(arrow + 1) else {
                    return Err(err(n, "expected a method name after `->`".into()));
                };
                if arrow < 2 {
                    return Err(err(n, "expected a task name before `->`".into()));
                }
                let subtasks = words[arrow + 2..]
                    .iter()
                    .map(|w| parse_id(w))
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(|m| err(n, m))?;
                plan.decompositions.push(Decomposition {
                    id,
                    task: words[1].clone(),
                    args: words[2..arrow].to_vec(),
                    method: method.clone(),
                    subtasks,
                });
            } else {
                if seen_root {
                    return Err(err(
                        n,
                        "an action line after the `root` line (expected `ID task args -> method IDs`)"
                            .into(),
                    ));
                }
                plan.actions.push(PlanAction {
                    id,
                    name: words[1].clone(),
                    args: words[2..].to_vec(),
                    geometric: None,
                });
            }
        }
        if !seen_root {
            return Err(err(0, "no `root` line".into()));
        }
        Ok(plan)
    }
}

impl Plan {
    /// The plan with every name case-folded, as the model stores names.
    pub fn lowercased(&self) -> Plan {
        let mut p = self.clone();
        p.map_names(|_, n| n.to_ascii_lowercase());
        p
    }

    /// Spells every name as `domain` and `problem` declare it (names of the model are
    /// case-folded; the competition's verifier wants them as the files write them).
    pub fn respell(&mut self, domain: &Domain, problem: &Problem) {
        self.map_names(|kind, n| {
            let d = &domain.spelling;
            match kind {
                NameKind::Task => d.tasks.of(n).to_string(),
                NameKind::Method => d.methods.of(n).to_string(),
                NameKind::Object => problem
                    .spelling
                    .objects
                    .declared(n)
                    .or_else(|| d.objects.declared(n))
                    .unwrap_or(n)
                    .to_string(),
            }
        });
    }

    /// Replaces every name (actions, tasks, methods, arguments) by `f(kind, name)`.
    fn map_names(&mut self, f: impl Fn(NameKind, &str) -> String) {
        let objects = |args: &mut Vec<String>| {
            for a in args.iter_mut() {
                *a = f(NameKind::Object, a);
            }
        };
        for a in &mut self.actions {
            a.name = f(NameKind::Task, &a.name);
            objects(&mut a.args);
        }
        for d in &mut self.decompositions {
            d.task = f(NameKind::Task, &d.task);
            d.method = f(NameKind::Method, &d.method);
            objects(&mut d.args);
        }
    }
}

/// The namespace of a name in a plan.
#[derive(Clone, Copy)]
enum NameKind {
    Task,
    Method,
    Object,
}

fn parse_id(w: &str) -> Result<u32, String> {
    w.parse::<u32>()
        .map_err(|_| format!("`{w}` is not an id (a non-negative integer)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_and_parse_round_trip() {
        let p = Plan {
            actions: vec![PlanAction {
                id: 1,
                name: "noop".into(),
                args: vec!["a".into()],
                geometric: None,
            }],
            root: vec![0],
            decompositions: vec![Decomposition {
                id: 0,
                task: "task1".into(),
                args: vec![],
                method: "donothing".into(),
                subtasks: vec![1],
            }],
        };
        let text = p.to_competition_format();
        assert_eq!(text, "==>\n1 noop a\nroot 0\n0 task1 -> donothing 1\n<==\n");
        assert_eq!(Plan::parse(&text).unwrap(), p);
        assert_eq!(Plan::parse(&format!("log line\n{text}")).unwrap(), p);
    }

    #[test]
    fn parse_errors_name_the_line() {
        let e = Plan::parse("==>\nx noop\nroot 0\n").unwrap_err();
        assert_eq!(e.line, 2);
        let e = Plan::parse("==>\n1 noop\n").unwrap_err();
        assert!(e.message.contains("root"));
        let e = Plan::parse("==>\nroot 0\n0 t ->\n").unwrap_err();
        assert_eq!(e.line, 3);
    }
}
