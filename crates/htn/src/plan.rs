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
///
/// Displayed as `LINE:COL: message`, or `message` alone for the text as a whole (no `root`
/// line, an empty file); the caller puts the file name in front. Long tokens are cut.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlanParseError {
    /// 1-based line in the plan text (0: the text as a whole).
    pub line: usize,
    /// 1-based column (in characters) of the word at fault (0: the text as a whole).
    pub col: usize,
    pub message: String,
}

impl std::fmt::Display for PlanParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let message = crate::text::clip(&self.message);
        if self.line == 0 {
            write!(f, "{message}")
        } else {
            write!(f, "{}:{}: {message}", self.line, self.col)
        }
    }
}

impl std::error::Error for PlanParseError {}

/// What a plan in the competition format looks like, for messages.
const FORMAT: &str = "expected the competition format: `==>`, one `ID action args...` line per \
                      action, `root IDs`, one `ID task args -> method IDs` line per \
                      decomposition, `<==`";

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
        let mut root_line: Option<usize> = None;
        let mut last_line = 0;
        for (i, raw) in lines.iter().enumerate().skip(start) {
            let n = i + 1;
            let content = raw.split(';').next().unwrap_or("");
            if content.trim().is_empty() {
                continue;
            }
            if content.trim() == "<==" {
                break;
            }
            last_line = n;
            // Each word with its 1-based column in characters.
            let words = words_with_columns(content);
            let err = |k: usize, message: String| PlanParseError {
                line: n,
                col: words.get(k).map_or(1, |w| w.0),
                message,
            };
            let word = |k: usize| words.get(k).map_or("", |w| w.1);
            if word(0) == "root" {
                if let Some(first) = root_line {
                    return Err(err(
                        0,
                        format!("a second `root` line (the first is line {first})"),
                    ));
                }
                root_line = Some(n);
                for k in 1..words.len() {
                    plan.root.push(parse_id(word(k)).map_err(|m| err(k, m))?);
                }
                continue;
            }
            let id = parse_id(word(0)).map_err(|m| {
                err(
                    0,
                    format!("{m} (expected `ID name args...`, `root IDs` or `ID task args -> method IDs`)"),
                )
            })?;
            if words.len() < 2 {
                return Err(err(0, format!("id {id} has no action or task name")));
            }
            let names = |from: usize, to: usize| -> Vec<String> {
                words
                    .get(from..to)
                    .unwrap_or_default()
                    .iter()
                    .map(|w| w.1.to_string())
                    .collect()
            };
            if let Some(arrow) = words.iter().position(|w| w.1 == "->") {
                if root_line.is_none() {
                    return Err(err(0, "a decomposition line before the `root` line".into()));
                }
                if words.len() <= arrow + 1 {
                    return Err(err(arrow, "expected a method name after `->`".into()));
                }
                if arrow < 2 {
                    return Err(err(arrow, "expected a task name before `->`".into()));
                }
                let subtasks = (arrow + 2..words.len())
                    .map(|k| parse_id(word(k)).map_err(|m| err(k, m)))
                    .collect::<Result<Vec<_>, _>>()?;
                plan.decompositions.push(Decomposition {
                    id,
                    task: word(1).to_string(),
                    args: names(2, arrow),
                    method: word(arrow + 1).to_string(),
                    subtasks,
                });
            } else {
                if root_line.is_some() {
                    return Err(err(
                        0,
                        "an action line after the `root` line (expected `ID task args -> method IDs`)"
                            .into(),
                    ));
                }
                plan.actions.push(PlanAction {
                    id,
                    name: word(1).to_string(),
                    args: names(2, words.len()),
                    geometric: None,
                });
            }
        }
        if root_line.is_none() {
            let message = if last_line == 0 {
                format!("the plan is empty ({FORMAT})")
            } else {
                format!("no `root` line ({FORMAT})")
            };
            return Err(PlanParseError {
                line: 0,
                col: 0,
                message,
            });
        }
        Ok(plan)
    }
}

/// The words of `line` with the 1-based column (in characters) each starts at.
fn words_with_columns(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start: Option<(usize, usize)> = None; // (byte, column) of the word being read
    let mut col = 0;
    for (i, c) in line.char_indices() {
        col += 1;
        if c.is_whitespace() {
            if let Some((b, k)) = start.take() {
                out.push((k, &line[b..i]));
            }
        } else if start.is_none() {
            start = Some((i, col));
        }
    }
    if let Some((b, k)) = start {
        out.push((k, &line[b..]));
    }
    out
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
    w.parse::<u32>().map_err(|_| {
        format!(
            "`{}` is not an id (a non-negative integer)",
            crate::text::cut(w, crate::text::MAX_WORD)
        )
    })
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
        assert_eq!((e.line, e.col), (2, 1));
        let e = Plan::parse("==>\n1 noop\n").unwrap_err();
        assert!(e.message.starts_with("no `root` line"), "{e}");
        assert_eq!(e.to_string(), e.message);
        let e = Plan::parse("==>\nroot 0\n0 t ->\n").unwrap_err();
        assert_eq!((e.line, e.col), (3, 5));
        let e = Plan::parse("==>\nroot 0 \t x\n").unwrap_err();
        assert_eq!((e.line, e.col), (2, 10));
        assert!(e.to_string().starts_with("2:10: `x` is not an id"), "{e}");
    }

    #[test]
    fn an_empty_plan_is_called_empty_and_long_tokens_are_cut() {
        for empty in ["", "\n\n", "==>\n<==\n", "; only a comment\n"] {
            let e = Plan::parse(empty).unwrap_err();
            assert_eq!(e.line, 0);
            assert!(e.to_string().starts_with("the plan is empty"), "{e}");
        }
        let long = "x".repeat(300_000);
        let e = Plan::parse(&format!("==>\n{long} a\nroot 0\n")).unwrap_err();
        let len = e.to_string().len();
        assert!(len < crate::text::MAX_WORD + 150, "{len}: {e}");
    }
}
