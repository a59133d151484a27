//! Subtask lists and their ordering, turned into one total order.
//!
//! HDDL spells a task network as `:ordered-subtasks` / `:ordered-tasks` (the listed order),
//! or `:subtasks` / `:tasks` with `:ordering` constraints `(< id1 id2)`. Either way htngtp
//! needs one total order: the constraints are sorted topologically, and a network whose
//! constraints leave two tasks unordered, or that has a cycle, is refused.

use std::collections::HashMap;

use crate::model::{Span, Subtask};

use super::context::{Ctx, Result, Scope, render_call};
use super::sexpr::{Sexp, shorten};

/// How the subtasks were given.
pub(crate) struct SubtaskList<'s> {
    /// The value after the keyword.
    pub value: &'s Sexp,
    /// `:ordered-subtasks` / `:ordered-tasks`.
    pub ordered: bool,
}

impl Ctx<'_> {
    /// The one subtask list among a method's or network's keyword pairs, whatever its spelling
    /// (`:subtasks`, `:tasks`, `:ordered-subtasks`, `:ordered-tasks`); a second one is an error.
    pub fn subtask_list<'s>(
        &self,
        pairs: &[(&'s str, Span, &'s Sexp)],
        owner: &str,
    ) -> Result<Option<SubtaskList<'s>>> {
        let mut lists = pairs.iter().filter(|(k, _, _)| {
            matches!(
                *k,
                ":subtasks" | ":tasks" | ":ordered-subtasks" | ":ordered-tasks"
            )
        });
        let first = lists.next();
        if let Some((key, span, _)) = lists.next() {
            return Err(self.err(*span, format!("{owner} has a second subtask list `{key}`")));
        }
        Ok(first.map(|(key, _, value)| SubtaskList {
            value,
            ordered: key.starts_with(":ordered"),
        }))
    }

    /// The subtasks of a method or of the initial task network, in their one total order.
    /// `owner` names the method or network in messages.
    pub fn task_network(
        &self,
        list: Option<SubtaskList<'_>>,
        ordering: Option<&Sexp>,
        scope: &Scope,
        owner: &str,
    ) -> Result<Vec<Subtask>> {
        let (subtasks, ordered) = match list {
            Some(l) => (self.subtask_entries(l.value, scope)?, l.ordered),
            None => (Vec::new(), false),
        };
        let mut ids: HashMap<&str, usize> = HashMap::new();
        for (i, st) in subtasks.iter().enumerate() {
            if let Some(id) = &st.id
                && let Some(&prev) = ids.get(id.as_str())
            {
                let first = subtasks.get(prev).map(|p| p.span).unwrap_or_default();
                return Err(self.err(
                    st.span,
                    format!(
                        "task id `{}` is used twice in {owner} (first at {}:{})",
                        shorten(id),
                        first.line,
                        first.col
                    ),
                ));
            }
            if let Some(id) = &st.id {
                ids.insert(id.as_str(), i);
            }
        }

        let mut edges: Vec<(usize, usize)> = Vec::new();
        if ordered {
            edges.extend((1..subtasks.len()).map(|i| (i - 1, i)));
        }
        if let Some(ordering) = ordering {
            for (a, b) in self.ordering_pairs(ordering, &ids, owner)? {
                edges.push((a, b));
            }
        }
        let order = self.total_order(&subtasks, &edges, owner)?;
        let mut slots: Vec<Option<Subtask>> = subtasks.into_iter().map(Some).collect();
        Ok(order
            .into_iter()
            .filter_map(|i| slots.get_mut(i).and_then(Option::take))
            .collect())
    }

    /// `()`, `(and entry ...)` or a single entry; an entry is `(name args)` or `(id (name args))`.
    fn subtask_entries(&self, value: &Sexp, scope: &Scope) -> Result<Vec<Subtask>> {
        let items = self.list(value, "a subtask list `(and (id (task ...)) ...)`")?;
        let entries: &[Sexp] = match value.head() {
            None if items.is_empty() => return Ok(Vec::new()),
            Some("and") => items.get(1..).unwrap_or_default(),
            _ => std::slice::from_ref(value),
        };
        entries.iter().map(|e| self.subtask(e, scope)).collect()
    }

    fn subtask(&self, entry: &Sexp, scope: &Scope) -> Result<Subtask> {
        let items = self.list(entry, "a subtask `(task ...)` or `(id (task ...))`")?;
        let (id, call) = match items {
            [id, call @ Sexp::List { .. }] => (Some(self.name(id, "a task id")?), call),
            _ => (None, entry),
        };
        let call_items = self.list(call, "a task `(name ...)`")?;
        let Some(first) = call_items.first() else {
            return Err(self.err(call.span(), "expected a task `(name ...)`, found `()`"));
        };
        let name = self.name(first, "a task or action name")?;
        let Some(info) = self.t.tasks.get(&name) else {
            let message = if self.t.predicates.contains_key(&name) {
                format!("`{}` is a predicate, not a task or action", shorten(&name))
            } else {
                format!("undeclared task or action `{}`", shorten(&name))
            };
            return Err(self.err(first.span(), message));
        };
        let kind = if info.primitive { "action" } else { "task" };
        let args = self.args(
            &info.sig,
            kind,
            first.span(),
            call_items.get(1..).unwrap_or_default(),
            scope,
        )?;
        Ok(Subtask {
            id,
            name,
            args,
            span: entry.span(),
        })
    }

    /// `()`, `(and (< a b) ...)` or a single `(< a b)`, as index pairs.
    fn ordering_pairs(
        &self,
        ordering: &Sexp,
        ids: &HashMap<&str, usize>,
        owner: &str,
    ) -> Result<Vec<(usize, usize)>> {
        let items = self.list(ordering, "an ordering `(and (< id1 id2) ...)`")?;
        let constraints: &[Sexp] = match ordering.head() {
            None if items.is_empty() => return Ok(Vec::new()),
            Some("and") => items.get(1..).unwrap_or_default(),
            _ => std::slice::from_ref(ordering),
        };
        let mut out = Vec::with_capacity(constraints.len());
        for c in constraints {
            let parts = self.list(c, "an ordering constraint `(< id1 id2)`")?;
            let [op, a, b] = parts else {
                return Err(self.err(
                    c.span(),
                    format!(
                        "expected an ordering constraint `(< id1 id2)`, found {}",
                        c.describe()
                    ),
                ));
            };
            if op.as_atom() != Some("<") {
                return Err(self.err(
                    op.span(),
                    format!(
                        "expected `<` in an ordering constraint, found {}",
                        op.describe()
                    ),
                ));
            }
            let index = |s: &Sexp| -> Result<usize> {
                let id = self.atom(s, "a task id")?;
                ids.get(id).copied().ok_or_else(|| {
                    self.err(
                        s.span(),
                        format!(
                            "unknown task id `{}` in the ordering of {owner}",
                            shorten(id)
                        ),
                    )
                })
            };
            out.push((index(a)?, index(b)?));
        }
        Ok(out)
    }

    /// The unique topological order of the constraints, or an error naming two unordered
    /// tasks or the tasks on a cycle.
    fn total_order(
        &self,
        subtasks: &[Subtask],
        edges: &[(usize, usize)],
        owner: &str,
    ) -> Result<Vec<usize>> {
        let n = subtasks.len();
        let mut succ: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut indegree = vec![0usize; n];
        for &(a, b) in edges {
            if let (Some(s), Some(d)) = (succ.get_mut(a), indegree.get_mut(b)) {
                s.push(b);
                *d += 1;
            }
        }
        let label = |i: usize| -> String {
            match subtasks.get(i) {
                Some(st) => match &st.id {
                    Some(id) => format!("{} {}", shorten(id), render_call(&st.name, &st.args)),
                    None => render_call(&st.name, &st.args),
                },
                None => String::new(),
            }
        };
        let span_of = |i: usize| subtasks.get(i).map(|s| s.span).unwrap_or_default();

        let mut ready: Vec<usize> = (0..n).filter(|&i| indegree.get(i) == Some(&0)).collect();
        let mut order = Vec::with_capacity(n);
        while let Some(&next) = ready.first() {
            if let Some(&other) = ready.get(1) {
                let (a, b) = if span_of(next) <= span_of(other) {
                    (next, other)
                } else {
                    (other, next)
                };
                return Err(self.err(
                    span_of(a),
                    format!(
                        "subtasks `{}` and `{}` of {owner} are not ordered: htngtp needs a totally ordered task network (add `(< ...)` to `:ordering` or use `:ordered-subtasks`)",
                        label(a),
                        label(b)
                    ),
                ));
            }
            ready.clear();
            order.push(next);
            for &s in succ.get(next).into_iter().flatten() {
                if let Some(d) = indegree.get_mut(s) {
                    *d -= 1;
                    if *d == 0 {
                        ready.push(s);
                    }
                }
            }
        }
        if order.len() < n {
            // Every node left has a predecessor that is left too: walking predecessors
            // must come back to a node already seen, and the walk since then is a cycle.
            let left = |i: usize| indegree.get(i).is_some_and(|d| *d > 0);
            let mut pred: Vec<Vec<usize>> = vec![Vec::new(); n];
            for &(a, b) in edges {
                if left(a)
                    && let Some(p) = pred.get_mut(b)
                {
                    p.push(a);
                }
            }
            let start = (0..n).find(|&i| left(i)).unwrap_or(0);
            let mut walk = vec![start];
            let mut at = start;
            let cycle = loop {
                let Some(&p) = pred.get(at).and_then(|p| p.first()) else {
                    break walk.clone();
                };
                if let Some(pos) = walk.iter().position(|&w| w == p) {
                    break walk.split_off(pos);
                }
                walk.push(p);
                at = p;
            };
            let mut cycle: Vec<usize> = cycle.into_iter().rev().collect();
            // Start the cycle at the task written first.
            if let Some(first) = (0..cycle.len()).min_by_key(|&k| cycle.get(k).map(|&i| span_of(i)))
            {
                cycle.rotate_left(first);
            }
            let names: Vec<String> = cycle
                .iter()
                .take(8)
                .map(|&i| format!("`{}`", label(i)))
                .collect();
            let at = cycle.first().copied().unwrap_or(0);
            return Err(self.err(
                span_of(at),
                format!(
                    "the ordering of {owner} has a cycle: {}{} (each must come before the next)",
                    names.join(" < "),
                    if cycle.len() > 8 { " < ..." } else { "" }
                ),
            ));
        }
        Ok(order)
    }
}
