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
//!
//! By concern: `names.rs` (names as declared, and messages respelled), `structure.rs` (ids,
//! the tree, the root and the decomposition lines), `world.rs` (the validator's own state,
//! formulas and action execution); this file runs them in order and executes the plan.

use std::collections::{HashMap, HashSet};
use std::hash::BuildHasherDefault;

use crate::model::{Domain, Problem};
use crate::oracle::GroundAtom;
use crate::plan::Plan;
use crate::state::FxHasher;

mod names;
mod structure;
mod world;

use names::{exact_names, respell_message};
use structure::Tree;
use world::{St, World, key};

type FastSet<K> = HashSet<K, BuildHasherDefault<FxHasher>>;
type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// The first fault found in a plan.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("invalid plan: {}", crate::text::clip(.0))]
pub struct Fault(pub String);

type Key = Vec<String>;

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

/// The checks of [`validate`] on a plan whose names are case-folded.
fn check(
    domain: &Domain,
    problem: &Problem,
    plan: &Plan,
    shared_init: &[GroundAtom],
) -> Result<(), Fault> {
    let w = World::new(domain, problem);
    within_budget()?;
    let tree = Tree::new(plan)?;
    let mut root_env = tree.check_root(&w, problem)?;
    let bindings = tree.check_decompositions(&w, domain)?;
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
        while next_dec < tree.dec_pos.len() && tree.dec_pos[next_dec].1 == pos {
            let di = tree.dec_pos[next_dec].0;
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

/// A fault with message `m`.
fn fault<T>(m: String) -> Result<T, Fault> {
    Err(Fault(m))
}

/// The process's budget (set by the binary) covers validating the plan it found.
fn within_budget() -> Result<(), Fault> {
    match crate::budget::check() {
        Some(limit) => Err(Fault(crate::budget::message(limit, "validating the plan"))),
        None => Ok(()),
    }
}
