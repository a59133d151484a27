//! Names as declared: the plan's names checked against the files' spelling (as the
//! competition's verifier does), and fault messages respelled as the files spell them.

use crate::model::{Domain, Problem};
use crate::plan::Plan;

use super::{FastMap, Fault, within_budget};

/// `message` with every name between backticks, double quotes or parentheses spelled as
/// declared (the checks run on case-folded names; messages should show the files' spelling).
/// A name right after the word `method` is looked up among the methods first.
pub(super) fn respell_message(domain: &Domain, problem: &Problem, message: &str) -> String {
    let sp = &domain.spelling;
    let tables = [
        &problem.spelling.objects,
        &sp.objects,
        &sp.tasks,
        &sp.methods,
        &sp.predicates,
        &sp.types,
    ];
    let spell = |w: &str, after_method: bool| -> Option<String> {
        let first = after_method.then_some(&sp.methods);
        first
            .into_iter()
            .chain(tables)
            .find_map(|t| t.declared(w))
            .map(str::to_string)
    };
    let is_name_char = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '_';
    let (mut out, mut word, mut prev) = (String::new(), String::new(), String::new());
    let (mut quoted, mut depth) = (false, 0usize);
    for c in message.chars().chain(std::iter::once('\0')) {
        if is_name_char(c) {
            word.push(c);
            continue;
        }
        let inside = quoted || depth > 0;
        match spell(&word, prev == "method").filter(|_| inside) {
            Some(d) => out.push_str(&d),
            None => out.push_str(&word),
        }
        if !word.is_empty() {
            prev = std::mem::take(&mut word);
        }
        match c {
            '`' | '"' => quoted = !quoted,
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            '\0' => continue,
            _ => {}
        }
        out.push(c);
    }
    out
}

/// Refuses a name not spelled as declared, as pandaPIparser's verifier does: an action or task
/// name must be a declared one, exactly; a method name a method of its task, exactly; an
/// argument an object or constant, exactly. Arguments beyond the task's parameters are dropped,
/// as that verifier drops them (with a warning). Returns the plan case-folded for the checks.
pub(super) fn exact_names(domain: &Domain, problem: &Problem, plan: &Plan) -> Result<Plan, Fault> {
    let sp = &domain.spelling;
    let counts = param_counts(domain);
    let object = |a: &str| {
        problem
            .spelling
            .objects
            .declared(a)
            .or_else(|| sp.objects.declared(a))
            == Some(a)
    };
    let lines = plan
        .actions
        .iter()
        .map(|a| (a.id, &a.name, &a.args, None))
        .chain(
            plan.decompositions
                .iter()
                .map(|d| (d.id, &d.task, &d.args, Some(&d.method))),
        );
    for (k, (id, name, args, method)) in lines.enumerate() {
        if k % 1024 == 1023 {
            within_budget()?;
        }
        if sp.tasks.declared(name) != Some(name.as_str()) {
            return Err(Fault(format!(
                "id {id}: task `{name}` is not declared in the domain{}",
                spelled_as(sp.tasks.declared(name))
            )));
        }
        let params = declared_params(&counts, name);
        if let Some(a) = args.iter().take(params).find(|a| !object(a)) {
            let declared = problem
                .spelling
                .objects
                .declared(a)
                .or_else(|| sp.objects.declared(a));
            return Err(Fault(format!(
                "id {id} ({name}): argument `{a}` is not an object of the problem{}",
                spelled_as(declared)
            )));
        }
        if let Some(m) = method
            && sp.methods.declared(m) != Some(m.as_str())
        {
            return Err(Fault(format!(
                "id {id} ({name}): there is no method `{m}`{}",
                spelled_as(sp.methods.declared(m))
            )));
        }
    }
    let mut folded = plan.lowercased();
    for a in &mut folded.actions {
        a.args.truncate(declared_params(&counts, &a.name));
    }
    for d in &mut folded.decompositions {
        d.args.truncate(declared_params(&counts, &d.task));
    }
    Ok(folded)
}

/// Per task and action name (lower case, as the domain keeps them), how many parameters it
/// declares (a task's count if a task and an action share the name).
fn param_counts(domain: &Domain) -> FastMap<&str, usize> {
    let mut counts = FastMap::default();
    for a in &domain.actions {
        counts.insert(a.name.as_str(), a.params.len());
    }
    for t in &domain.tasks {
        counts.insert(t.name.as_str(), t.params.len());
    }
    counts
}

/// How many parameters the task or action `name` (any case) declares; `usize::MAX` if none is
/// declared.
fn declared_params(counts: &FastMap<&str, usize>, name: &str) -> usize {
    let found = match counts.get(name) {
        Some(&n) => Some(n),
        None => counts.get(name.to_ascii_lowercase().as_str()).copied(),
    };
    found.unwrap_or(usize::MAX)
}

/// ` (declared as `X`)` when a declaration differs only in case.
fn spelled_as(declared: Option<&str>) -> String {
    declared.map_or_else(String::new, |d| format!(" (declared as `{d}`)"))
}
