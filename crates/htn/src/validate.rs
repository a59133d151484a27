//! The plan validator: checks a plan against the lifted domain and problem, independently of the
//! planner (its own name-based state and formula evaluation; nothing shared with the search).
//!
//! It checks, and names the first fault it finds:
//! - ids unique, every id used exactly once in the tree, the tree rooted at `root`;
//! - `root` matches the problem's initial task network (names, arguments, order);
//! - every decomposition line names a method of that task whose task arguments and subtasks
//!   (names, order, arguments) agree with one binding of its parameters (of the right types);
//! - the leaves of the tree, left to right, are exactly the plan's actions in order;
//! - the actions are executable in order from the initial state (numeric fluents included),
//!   with the shared literals of a GS action's geometric solution applied after its effects;
//! - each method's precondition (and `:constraints`) holds in the state before its first
//!   primitive descendant, or, for a method with none, in the state at its place in the
//!   sequence; parameters bound by neither task nor subtasks are existential;
//! - the goal, if any, holds at the end.
//!
//! Names are matched as the competition's verifier (pandaPIparser `--verify`) matches them
//! ([`Names::Exact`], the default; docs/plan-validation.md gives the rules): every action, task
//! and method name and every argument must be spelled exactly as the domain or problem file
//! declares it. [`Names::CaseInsensitive`] (`htngtp validate --lenient`) folds case first.

use std::collections::{HashMap, HashSet};
use std::hash::BuildHasherDefault;

use crate::model::{
    CompareOp, Domain, Effect, Formula, Method, NumExpr, NumericEffectOp, OBJECT_TYPE, Problem,
    Term, TypedName,
};
use crate::oracle::GroundAtom;
use crate::plan::Plan;
use crate::state::FxHasher;

type FastSet<K> = HashSet<K, BuildHasherDefault<FxHasher>>;
type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// The first fault found in a plan.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("invalid plan: {}", crate::text::clip(.0))]
pub struct Fault(pub String);

type Key = Vec<String>;

struct World<'a> {
    domain: &'a Domain,
    /// Object to its types (declared type and all ancestors, and `object`); objects of one
    /// declared type share the set.
    types: HashMap<String, std::rc::Rc<HashSet<String>>>,
    /// Type to its objects.
    objects_of: HashMap<String, Vec<String>>,
}

/// The state: facts as `[predicate, args..]` keys, indexed by predicate; fluent values.
#[derive(Clone, Default)]
struct St {
    facts: FastMap<String, FastSet<Key>>,
    values: FastMap<Key, f64>,
}

impl St {
    fn contains(&self, k: &Key) -> bool {
        self.facts.get(&k[0]).is_some_and(|s| s.contains(k))
    }
    fn insert(&mut self, k: Key) {
        self.facts.entry(k[0].clone()).or_default().insert(k);
    }
    fn remove(&mut self, k: &Key) {
        if let Some(s) = self.facts.get_mut(&k[0]) {
            s.remove(k);
        }
    }
}

type Env = FastMap<String, String>;

/// How the names of a plan are matched against the declarations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Names {
    /// Exactly as declared, as the competition's verifier matches them.
    #[default]
    Exact,
    /// Whatever their case (HDDL is case-insensitive; hand-written plans).
    CaseInsensitive,
}

/// Checks `plan` for `problem` of `domain`, names spelled exactly as declared. `shared_init`
/// are the initial facts of the shared predicates (from the geometric back end; empty for
/// plain HDDL).
pub fn validate(
    domain: &Domain,
    problem: &Problem,
    plan: &Plan,
    shared_init: &[GroundAtom],
) -> Result<(), Fault> {
    validate_with(domain, problem, plan, shared_init, Names::Exact)
}

/// Checks `plan` as [`validate`] does, matching names as `names` says.
pub fn validate_with(
    domain: &Domain,
    problem: &Problem,
    plan: &Plan,
    shared_init: &[GroundAtom],
    names: Names,
) -> Result<(), Fault> {
    let folded = match names {
        Names::Exact => exact_names(domain, problem, plan)?,
        Names::CaseInsensitive => plan.lowercased(),
    };
    check(domain, problem, &folded, shared_init)
        .map_err(|f| Fault(respell_message(domain, problem, &f.0)))
}

/// `message` with every name between backticks, double quotes or parentheses spelled as
/// declared (the checks run on case-folded names; messages should show the files' spelling).
/// A name right after the word `method` is looked up among the methods first.
fn respell_message(domain: &Domain, problem: &Problem, message: &str) -> String {
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
fn exact_names(domain: &Domain, problem: &Problem, plan: &Plan) -> Result<Plan, Fault> {
    let sp = &domain.spelling;
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
    for (id, name, args, method) in lines {
        if sp.tasks.declared(name) != Some(name.as_str()) {
            return Err(Fault(format!(
                "id {id}: task `{name}` is not declared in the domain{}",
                spelled_as(sp.tasks.declared(name))
            )));
        }
        let params = declared_params(domain, name);
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
        a.args.truncate(declared_params(domain, &a.name));
    }
    for d in &mut folded.decompositions {
        d.args.truncate(declared_params(domain, &d.task));
    }
    Ok(folded)
}

/// How many parameters the task or action `name` (any case) declares; `usize::MAX` if none is
/// declared.
fn declared_params(domain: &Domain, name: &str) -> usize {
    let name = name.to_ascii_lowercase();
    let task = domain.tasks.iter().find(|t| t.name == name);
    let action = domain.actions.iter().find(|a| a.name == name);
    task.map(|t| t.params.len())
        .or(action.map(|a| a.params.len()))
        .unwrap_or(usize::MAX)
}

/// ` (declared as `X`)` when a declaration differs only in case.
fn spelled_as(declared: Option<&str>) -> String {
    declared.map_or_else(String::new, |d| format!(" (declared as `{d}`)"))
}

/// The checks of [`validate`] on a plan whose names are case-folded.
fn check(
    domain: &Domain,
    problem: &Problem,
    plan: &Plan,
    shared_init: &[GroundAtom],
) -> Result<(), Fault> {
    let w = World::new(domain, problem);
    let fault = |m: String| Err(Fault(m));
    // The process's budget (set by the binary) covers validating the plan it found.
    let within_budget = || match crate::budget::check() {
        Some(limit) => Err(Fault(crate::budget::message(limit, "validating the plan"))),
        None => Ok(()),
    };
    within_budget()?;

    // Ids.
    let mut action_at: HashMap<u32, usize> = HashMap::new();
    for (i, a) in plan.actions.iter().enumerate() {
        if action_at.insert(a.id, i).is_some() {
            return fault(format!("id {} is used by two actions", a.id));
        }
    }
    let mut dec_of: HashMap<u32, usize> = HashMap::new();
    for (i, d) in plan.decompositions.iter().enumerate() {
        if action_at.contains_key(&d.id) {
            return fault(format!(
                "id {} is both an action and a decomposed task",
                d.id
            ));
        }
        if dec_of.insert(d.id, i).is_some() {
            return fault(format!("task id {} is decomposed twice", d.id));
        }
    }

    // The tree: every id used exactly once, leaves in order.
    let mut used: HashSet<u32> = HashSet::new();
    let mut leaves: Vec<u32> = Vec::new();
    // (decomposition index, leaf position) in depth-first order.
    let mut dec_pos: Vec<(usize, usize)> = Vec::new();
    // Depth first, left to right, with an explicit stack (trees can be very deep).
    let mut todo: Vec<u32> = plan.root.iter().rev().copied().collect();
    while let Some(id) = todo.pop() {
        if !used.insert(id) {
            return fault(format!("id {id} occurs twice in the decomposition tree"));
        }
        if action_at.contains_key(&id) {
            leaves.push(id);
            continue;
        }
        let Some(&d) = dec_of.get(&id) else {
            return fault(format!(
                "id {id} is neither an action nor a decomposed task"
            ));
        };
        dec_pos.push((d, leaves.len()));
        todo.extend(plan.decompositions[d].subtasks.iter().rev());
    }
    for a in &plan.actions {
        if !used.contains(&a.id) {
            return fault(format!(
                "action {} ({}) is not reached from the root",
                a.id, a.name
            ));
        }
    }
    for d in &plan.decompositions {
        if !used.contains(&d.id) {
            return fault(format!(
                "decomposed task {} ({}) is not reached from the root",
                d.id, d.task
            ));
        }
    }
    for (i, (&leaf, a)) in leaves.iter().zip(&plan.actions).enumerate() {
        if leaf != a.id {
            return fault(format!(
                "the tree puts action {leaf} at position {} of the plan, but the plan lists action {} there",
                i + 1,
                a.id
            ));
        }
    }

    // The name and arguments of an id.
    let name_args = |id: u32| -> (&str, &[String]) {
        if let Some(&i) = action_at.get(&id) {
            (&plan.actions[i].name, &plan.actions[i].args)
        } else {
            let d = &plan.decompositions[dec_of[&id]];
            (&d.task, &d.args)
        }
    };

    // Root against the initial task network.
    let net = &problem.htn.subtasks;
    if net.len() != plan.root.len() {
        return fault(format!(
            "the root has {} tasks, the problem's initial task network {}",
            plan.root.len(),
            net.len()
        ));
    }
    let mut root_env: Env = Env::default();
    for (k, (st, &id)) in net.iter().zip(&plan.root).enumerate() {
        let (name, args) = name_args(id);
        if st.name != name || !unify(&w, &mut root_env, &st.args, args, &problem.htn.params) {
            return fault(format!(
                "root task {} is `{name}` with arguments {args:?}, but task {} of the initial network is ({} {})",
                id,
                k + 1,
                st.name,
                show_terms(&st.args)
            ));
        }
    }

    // Decomposition lines against methods; remember each one's binding.
    let mut bindings: Vec<Env> = vec![Env::default(); plan.decompositions.len()];
    for (i, d) in plan.decompositions.iter().enumerate() {
        let Some(task) = domain.tasks.iter().find(|t| t.name == d.task) else {
            return fault(format!(
                "task {} `{}` is not an abstract task of the domain",
                d.id, d.task
            ));
        };
        if task.params.len() != d.args.len() {
            return fault(format!(
                "task {} `{}` has {} arguments, the domain declares {}",
                d.id,
                d.task,
                d.args.len(),
                task.params.len()
            ));
        }
        for (p, a) in task.params.iter().zip(&d.args) {
            if !w.is_of(a, &p.ty) {
                return fault(format!(
                    "task {} `{}`: `{a}` is not an object of type `{}`",
                    d.id, d.task, p.ty
                ));
            }
        }
        let Some(m) = domain.methods.iter().find(|m| m.name == d.method) else {
            return fault(format!(
                "task {}: `{}` is not a method of the domain",
                d.id, d.method
            ));
        };
        if m.task != d.task {
            return fault(format!(
                "task {}: method `{}` decomposes `{}`, not `{}`",
                d.id, m.name, m.task, d.task
            ));
        }
        let mut env = Env::default();
        if !unify(&w, &mut env, &m.task_args, &d.args, &m.params) {
            return fault(format!(
                "task {} ({} {}): the arguments do not match method `{}`'s task ({} {})",
                d.id,
                d.task,
                d.args.join(" "),
                m.name,
                m.task,
                show_terms(&m.task_args)
            ));
        }
        if m.subtasks.len() != d.subtasks.len() {
            return fault(format!(
                "task {}: method `{}` has {} subtasks, the plan gives {}",
                d.id,
                m.name,
                m.subtasks.len(),
                d.subtasks.len()
            ));
        }
        for (k, (st, &c)) in m.subtasks.iter().zip(&d.subtasks).enumerate() {
            let (name, args) = name_args(c);
            if st.name != name || !unify(&w, &mut env, &st.args, args, &m.params) {
                return fault(format!(
                    "task {}: subtask {} of method `{}` is ({} {}), but id {c} is ({name} {})",
                    d.id,
                    k + 1,
                    m.name,
                    st.name,
                    show_terms(&st.args),
                    args.join(" ")
                ));
            }
        }
        bindings[i] = env;
    }

    // Execute, checking method preconditions at their places.
    let mut st = St::default();
    for f in &problem.init {
        st.insert(key(&f.predicate, &f.args));
    }
    for a in shared_init {
        st.insert(key(&a.predicate, &a.args));
    }
    for v in &problem.init_values {
        st.values.insert(key(&v.function, &v.args), v.value);
    }
    within_budget()?;
    let mut next_dec = 0;
    for pos in 0..=plan.actions.len() {
        if pos % 256 == 255 {
            within_budget()?;
        }
        while next_dec < dec_pos.len() && dec_pos[next_dec].1 == pos {
            let di = dec_pos[next_dec].0;
            let d = &plan.decompositions[di];
            let m = domain
                .methods
                .iter()
                .find(|m| m.name == d.method)
                .expect("checked above");
            if !w.method_pre_holds(&st, m, &bindings[di]) {
                let when = if pos < plan.actions.len() {
                    format!("before action {}", plan.actions[pos].id)
                } else {
                    "at the end of the plan".to_string()
                };
                return fault(format!(
                    "task {} ({} {}): the precondition of method `{}` does not hold {when}",
                    d.id,
                    d.task,
                    d.args.join(" "),
                    m.name
                ));
            }
            next_dec += 1;
        }
        if pos == plan.actions.len() {
            break;
        }
        let a = &plan.actions[pos];
        w.execute(&mut st, a).map_err(|m| {
            Fault(format!(
                "action {} ({} {}): {m}",
                a.id,
                a.name,
                a.args.join(" ")
            ))
        })?;
    }
    let mut env = Env::default();
    if !w.holds(&st, &problem.goal, &mut env) {
        return fault("the goal does not hold at the end of the plan".to_string());
    }
    if !w.holds(&st, &problem.htn.constraints, &mut root_env) {
        return fault("the initial task network's constraints do not hold".to_string());
    }
    Ok(())
}

fn key(head: &str, args: &[String]) -> Key {
    let mut k = Vec::with_capacity(args.len() + 1);
    k.push(head.to_string());
    k.extend(args.iter().cloned());
    k
}

fn show_terms(ts: &[Term]) -> String {
    ts.iter()
        .map(|t| match t {
            Term::Var(v) | Term::Const(v) => v.as_str(),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Extends `env` so that `terms` denote `args`; variables must be among `params` and the
/// objects of their types.
fn unify(w: &World, env: &mut Env, terms: &[Term], args: &[String], params: &[TypedName]) -> bool {
    if terms.len() != args.len() {
        return false;
    }
    for (t, a) in terms.iter().zip(args) {
        match t {
            Term::Const(c) => {
                if c != a {
                    return false;
                }
            }
            Term::Var(v) => match env.get(v) {
                Some(b) => {
                    if b != a {
                        return false;
                    }
                }
                None => {
                    let Some(p) = params.iter().find(|p| &p.name == v) else {
                        return false;
                    };
                    if !w.is_of(a, &p.ty) {
                        return false;
                    }
                    env.insert(v.clone(), a.clone());
                }
            },
        }
    }
    true
}

impl<'a> World<'a> {
    fn new(domain: &'a Domain, problem: &Problem) -> World<'a> {
        let mut parents: HashMap<&str, Vec<&str>> = HashMap::new();
        for t in &domain.types {
            parents
                .entry(t.name.as_str())
                .or_default()
                .extend(t.parents.iter().map(String::as_str));
        }
        // Each declared type's ancestor set, computed once.
        let mut ancestors: HashMap<&str, std::rc::Rc<HashSet<String>>> = HashMap::new();
        let mut types: HashMap<String, std::rc::Rc<HashSet<String>>> = HashMap::new();
        for o in domain.constants.iter().chain(&problem.objects) {
            let set = ancestors.entry(o.ty.as_str()).or_insert_with(|| {
                let mut set = HashSet::new();
                let mut todo = vec![o.ty.as_str(), OBJECT_TYPE];
                while let Some(t) = todo.pop() {
                    if set.insert(t.to_string())
                        && let Some(ps) = parents.get(t)
                    {
                        todo.extend(ps.iter().copied());
                    }
                }
                std::rc::Rc::new(set)
            });
            // A name declared twice (a constant and an object) has the types of both.
            match types.get_mut(&o.name) {
                Some(had) => {
                    let mut both: HashSet<String> = (**had).clone();
                    both.extend(set.iter().cloned());
                    *had = std::rc::Rc::new(both);
                }
                None => {
                    types.insert(o.name.clone(), set.clone());
                }
            }
        }
        let mut objects_of: HashMap<String, Vec<String>> = HashMap::new();
        let mut names: Vec<&String> = types.keys().collect();
        names.sort();
        for o in names {
            for t in types[o].iter() {
                objects_of.entry(t.clone()).or_default().push(o.clone());
            }
        }
        World {
            domain,
            types,
            objects_of,
        }
    }

    fn is_of(&self, o: &str, ty: &str) -> bool {
        self.types.get(o).is_some_and(|ts| ts.contains(ty))
    }

    fn objects(&self, ty: &str) -> &[String] {
        self.objects_of.get(ty).map_or(&[], Vec::as_slice)
    }

    fn term<'e>(&self, t: &'e Term, env: &'e Env) -> Option<&'e str> {
        match t {
            Term::Const(c) => Some(c),
            Term::Var(v) => env.get(v).map(String::as_str),
        }
    }

    fn ground(&self, head: &str, args: &[Term], env: &Env) -> Option<Key> {
        let mut k = vec![head.to_string()];
        for a in args {
            k.push(self.term(a, env)?.to_string());
        }
        Some(k)
    }

    fn num(&self, st: &St, e: &NumExpr, env: &Env) -> Option<f64> {
        Some(match e {
            NumExpr::Number(x) => *x,
            NumExpr::Fluent(f) => *st.values.get(&self.ground(&f.function, &f.args, env)?)?,
            NumExpr::Binary(op, a, b) => {
                let (a, b) = (self.num(st, a, env)?, self.num(st, b, env)?);
                op.apply(a, b)?
            }
            NumExpr::Neg(a) => -self.num(st, a, env)?,
        })
    }

    /// Whether `f` holds; variables not in `env` are unbound (an error of the model: false).
    fn holds(&self, st: &St, f: &Formula, env: &mut Env) -> bool {
        match f {
            Formula::True => true,
            Formula::Atom(a) => self
                .ground(&a.predicate, &a.args, env)
                .is_some_and(|k| st.contains(&k)),
            Formula::Equal(a, b, _) => match (self.term(a, env), self.term(b, env)) {
                (Some(x), Some(y)) => x == y,
                _ => false,
            },
            Formula::Not(x) => !self.holds(st, x, env),
            Formula::And(xs) => xs.iter().all(|x| self.holds(st, x, env)),
            Formula::Or(xs) => xs.iter().any(|x| self.holds(st, x, env)),
            Formula::Imply(a, b) => !self.holds(st, a, env) || self.holds(st, b, env),
            Formula::Exists(vars, body) => self.quantify(st, vars, body, env, true),
            Formula::Forall(vars, body) => !self.quantify_not(st, vars, body, env),
            Formula::Compare(op, a, b, _) => match (self.num(st, a, env), self.num(st, b, env)) {
                (Some(x), Some(y)) => match op {
                    CompareOp::Lt => x < y,
                    CompareOp::Le => x <= y,
                    CompareOp::Eq => x == y,
                    CompareOp::Ge => x >= y,
                    CompareOp::Gt => x > y,
                },
                _ => false,
            },
            // Geometric truth is not checked here: the plan's geometric solution attests it.
            Formula::Evaluable { .. } => true,
        }
    }

    /// Whether some binding of `vars` makes `body` hold.
    fn quantify(
        &self,
        st: &St,
        vars: &[TypedName],
        body: &Formula,
        env: &mut Env,
        want: bool,
    ) -> bool {
        let Some((v, rest)) = vars.split_first() else {
            return self.holds(st, body, env) == want;
        };
        let saved = env.get(&v.name).cloned();
        let mut found = false;
        for o in self.objects(&v.ty) {
            env.insert(v.name.clone(), o.clone());
            if self.quantify(st, rest, body, env, want) {
                found = true;
                break;
            }
        }
        match saved {
            Some(s) => env.insert(v.name.clone(), s),
            None => env.remove(&v.name),
        };
        found
    }

    /// Whether some binding of `vars` makes every formula of `body` hold. Variables are bound
    /// through the facts of a positive atom that mentions them when there is one (the same
    /// answer as trying every object of their types, much faster), else by their types.
    fn quantify_all(&self, st: &St, vars: &[TypedName], body: &[&Formula], env: &mut Env) -> bool {
        let mut conj: Vec<&Formula> = Vec::new();
        fn flatten<'f>(f: &'f Formula, out: &mut Vec<&'f Formula>) {
            match f {
                Formula::And(xs) => xs.iter().for_each(|x| flatten(x, out)),
                Formula::True => {}
                f => out.push(f),
            }
        }
        body.iter().for_each(|f| flatten(f, &mut conj));
        self.bind(st, vars, &conj, env)
    }

    fn bind(&self, st: &St, vars: &[TypedName], conj: &[&Formula], env: &mut Env) -> bool {
        let unbound: Vec<&TypedName> = vars.iter().filter(|v| !env.contains_key(&v.name)).collect();
        if unbound.is_empty() {
            return conj.iter().all(|f| self.holds(st, f, env));
        }
        let is_unbound = |t: &Term, env: &Env| matches!(t, Term::Var(v) if !env.contains_key(v) && unbound.iter().any(|u| &u.name == v));
        // A positive atom over some unbound variable binds them from the facts.
        let atom = conj.iter().find_map(|f| match f {
            Formula::Atom(a) if a.args.iter().any(|t| is_unbound(t, env)) => Some(a),
            _ => None,
        });
        if let Some(a) = atom {
            let Some(facts) = st.facts.get(&a.predicate) else {
                return false;
            };
            for fact in facts {
                if fact.len() != a.args.len() + 1 {
                    continue;
                }
                let mut newly: Vec<String> = Vec::new();
                let mut ok = true;
                for (t, val) in a.args.iter().zip(&fact[1..]) {
                    match t {
                        Term::Const(c) => ok = c == val,
                        Term::Var(v) => match env.get(v) {
                            Some(b) => ok = b == val,
                            None => {
                                let ty =
                                    unbound.iter().find(|u| &u.name == v).map(|u| u.ty.as_str());
                                ok = ty.is_some_and(|ty| self.is_of(val, ty));
                                if ok {
                                    env.insert(v.clone(), val.clone());
                                    newly.push(v.clone());
                                }
                            }
                        },
                    }
                    if !ok {
                        break;
                    }
                }
                let found = ok && self.bind(st, vars, conj, env);
                for v in newly {
                    env.remove(&v);
                }
                if found {
                    return true;
                }
            }
            return false;
        }
        let v = unbound[0];
        for o in self.objects(&v.ty) {
            env.insert(v.name.clone(), o.clone());
            if self.bind(st, vars, conj, env) {
                env.remove(&v.name);
                return true;
            }
        }
        env.remove(&v.name);
        false
    }

    /// Whether some binding of `vars` makes `body` false.
    fn quantify_not(&self, st: &St, vars: &[TypedName], body: &Formula, env: &mut Env) -> bool {
        self.quantify(st, vars, body, env, false)
    }

    fn method_pre_holds(&self, st: &St, m: &Method, env: &Env) -> bool {
        let free: Vec<TypedName> = m
            .params
            .iter()
            .filter(|p| !env.contains_key(&p.name))
            .cloned()
            .collect();
        let mut env = env.clone();
        self.quantify_all(st, &free, &[&m.precondition, &m.constraints], &mut env)
    }

    fn execute(&self, st: &mut St, a: &crate::plan::PlanAction) -> Result<(), String> {
        let Some(act) = self.domain.actions.iter().find(|x| x.name == a.name) else {
            return Err("not an action of the domain".into());
        };
        if act.params.len() != a.args.len() {
            return Err(format!(
                "has {} arguments, the domain declares {}",
                a.args.len(),
                act.params.len()
            ));
        }
        let mut env = Env::default();
        for (p, x) in act.params.iter().zip(&a.args) {
            if !self.is_of(x, &p.ty) {
                return Err(format!("`{x}` is not an object of type `{}`", p.ty));
            }
            env.insert(p.name.clone(), x.clone());
        }
        if !self.holds(st, &act.precondition, &mut env) {
            return Err("its precondition does not hold".into());
        }
        let gs = has_evaluable(&act.precondition);
        if gs && a.geometric.is_none() {
            return Err(
                "a GS action without its geometric solution (the competition format does not carry shared literals; check the JSON plan)".into(),
            );
        }
        let mut adds = Vec::new();
        let mut dels = Vec::new();
        let mut values = Vec::new();
        self.effects(
            st,
            &act.effects,
            &mut env,
            &mut adds,
            &mut dels,
            &mut values,
        )?;
        for (k, v) in values {
            st.values.insert(k, v);
        }
        for k in &dels {
            st.remove(k);
        }
        for k in adds {
            st.insert(k);
        }
        if let Some(g) = &a.geometric {
            for x in &g.delete {
                st.remove(&key(&x.predicate, &x.args));
            }
            for x in &g.add {
                st.insert(key(&x.predicate, &x.args));
            }
        }
        Ok(())
    }

    fn effects(
        &self,
        st: &St,
        effs: &[Effect],
        env: &mut Env,
        adds: &mut Vec<Key>,
        dels: &mut Vec<Key>,
        values: &mut Vec<(Key, f64)>,
    ) -> Result<(), String> {
        for e in effs {
            match e {
                Effect::Add(x) => adds.extend(self.ground(&x.predicate, &x.args, env)),
                Effect::Delete(x) => dels.extend(self.ground(&x.predicate, &x.args, env)),
                Effect::Forall(vars, inner) => {
                    self.forall_effects(st, vars, inner, env, adds, dels, values)?
                }
                Effect::When(c, inner) => {
                    if self.holds(st, c, env) {
                        self.effects(st, inner, env, adds, dels, values)?;
                    }
                }
                Effect::Numeric(op, f, e) => {
                    let k = self
                        .ground(&f.function, &f.args, env)
                        .ok_or("an effect on an unbound fluent")?;
                    let x = self.num(st, e, env).ok_or_else(|| {
                        format!(
                            "effect on ({}): the value reads an undefined fluent",
                            k.join(" ")
                        )
                    })?;
                    let cur = st.values.get(&k).copied();
                    let v = match (op, cur) {
                        (NumericEffectOp::Assign, _) => x,
                        (_, None) => {
                            return Err(format!("effect on undefined fluent ({})", k.join(" ")));
                        }
                        (_, Some(c)) => op.apply(c, x).ok_or("scale-down by zero")?,
                    };
                    values.push((k, v));
                }
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn forall_effects(
        &self,
        st: &St,
        vars: &[TypedName],
        inner: &[Effect],
        env: &mut Env,
        adds: &mut Vec<Key>,
        dels: &mut Vec<Key>,
        values: &mut Vec<(Key, f64)>,
    ) -> Result<(), String> {
        let Some((v, rest)) = vars.split_first() else {
            return self.effects(st, inner, env, adds, dels, values);
        };
        for o in self.objects(&v.ty) {
            env.insert(v.name.clone(), o.clone());
            self.forall_effects(st, rest, inner, env, adds, dels, values)?;
        }
        env.remove(&v.name);
        Ok(())
    }
}

fn has_evaluable(f: &Formula) -> bool {
    match f {
        Formula::Evaluable { .. } => true,
        Formula::And(xs) => xs.iter().any(has_evaluable),
        _ => false,
    }
}
