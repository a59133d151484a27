//! A generator of hostile HDDL problems: inputs whose search space, joins or grounding explode
//! (many objects of few types, methods with many free parameters, long static chains,
//! recursion over resources, many wide actions). None has a plan; each would run for hours
//! or exhaust memory without limits, so a run must stop at `--time-limit` or `--memory-limit`.

/// One generated problem.
pub struct Hostile {
    /// What it stresses, for messages.
    pub name: String,
    pub domain: String,
    pub problem: String,
}

fn objects(prefix: &str, n: usize) -> Vec<String> {
    (0..n).map(|i| format!("{prefix}{i}")).collect()
}

fn define(name: &str, types: &str, predicates: &str, body: &str) -> String {
    format!(
        "(define (domain {name})\n (:requirements :typing :hierarchy :negative-preconditions \
         :equality)\n (:types {types})\n (:predicates {predicates})\n{body})\n"
    )
}

fn problem(name: &str, objects: &str, htn: &str, init: &str) -> String {
    format!(
        "(define (problem {name}-1) (:domain {name})\n (:objects {objects})\n (:htn \
         :ordered-subtasks (and {htn}))\n (:init {init}))\n"
    )
}

/// A method with `params` free parameters over `n` objects (`n^params` bindings), each of
/// which fails only after a first step.
pub fn wide(n: usize, params: usize) -> Hostile {
    let ps: Vec<String> = (0..params).map(|i| format!("?v{i}")).collect();
    let pre: Vec<String> = ps.iter().map(|p| format!("(p {p})")).collect();
    let body = format!(
        " (:task t :parameters ())\n (:method m :parameters ({} - obj) :task (t)\n  \
         :precondition (and {})\n  :ordered-subtasks (and (mark ?v0) (finish ?v0 {})))\n \
         (:action mark :parameters (?x - obj) :effect (done))\n (:action finish :parameters \
         (?x ?y - obj) :precondition (and (not (done)) (p ?y)))\n",
        ps.join(" "),
        pre.join(" "),
        ps[params - 1]
    );
    let os = objects("o", n);
    let init: Vec<String> = os.iter().map(|o| format!("(p {o})")).collect();
    Hostile {
        name: format!("wide: {params} free parameters over {n} objects"),
        domain: define("wide", "obj", "(p ?x - obj) (done)", &body),
        problem: problem(
            "wide",
            &format!("{} - obj", os.join(" ")),
            "(t)",
            &init.join(" "),
        ),
    }
}

/// Recursion along a static chain of `n` objects, each step's method joining `hops` links
/// of the chain ahead, toward a goal no step reaches.
pub fn chain(n: usize, hops: usize) -> Hostile {
    let vs: Vec<String> = (0..=hops).map(|i| format!("?x{i}")).collect();
    let links: Vec<String> = vs
        .windows(2)
        .map(|w| format!("(next {} {})", w[0], w[1]))
        .collect();
    let body = format!(
        " (:task walk :parameters (?x - node))\n (:method step :parameters ({} - node) :task \
         (walk ?x0)\n  :precondition (and {})\n  :ordered-subtasks (and (go ?x0 ?x1) (walk \
         ?x1)))\n (:method arrive :parameters (?x - node) :task (walk ?x)\n  :precondition \
         (goal ?x)\n  :ordered-subtasks (and (stop ?x)))\n (:action go :parameters (?x ?y - \
         node) :precondition (at ?x) :effect (and (not (at ?x)) (at ?y)))\n (:action stop \
         :parameters (?x - node) :precondition (and (at ?x) (goal ?x)))\n",
        vs.join(" "),
        links.join(" ")
    );
    let os = objects("n", n);
    let mut init: Vec<String> = os
        .windows(2)
        .map(|w| format!("(next {} {})", w[0], w[1]))
        .collect();
    // A cycle back to the start: the chain never ends, and no node is a goal.
    init.push(format!("(next {} {})", os[n - 1], os[0]));
    init.push(format!("(at {})", os[0]));
    Hostile {
        name: format!("chain: {n} nodes in a cycle, {hops} links per step"),
        domain: define(
            "chain",
            "node",
            "(next ?x ?y - node) (at ?x - node) (goal ?x - node)",
            &body,
        ),
        problem: problem(
            "chain",
            &format!("{} - node", os.join(" ")),
            &format!("(walk {})", os[0]),
            &init.join(" "),
        ),
    }
}

/// Tours of a complete graph of `n` places, never visiting one twice, ending in a step that
/// needs to be back at the start after visiting the second place (possible in the relaxed
/// problem, never in the real one): `n 2^n` states (where, and the set visited).
pub fn tours(n: usize) -> Hostile {
    let body = " (:task tour :parameters ())\n (:method move :parameters (?x ?y - place) :task \
         (tour)\n  :precondition (and (at ?x) (link ?x ?y) (not (visited ?y)))\n  \
         :ordered-subtasks (and (goto ?x ?y) (tour)))\n (:method finish :parameters (?x ?y - \
         place) :task (tour)\n  :ordered-subtasks (and (close ?x ?y)))\n (:action goto \
         :parameters (?x ?y - place) :precondition (at ?x) :effect (and (not (at ?x)) (at ?y) \
         (visited ?y)))\n (:action close :parameters (?x ?y - place) :precondition (and (home \
         ?x) (at ?x) (second ?y) (visited ?y)))\n";
    let os = objects("c", n);
    let mut init = vec![
        format!("(at {})", os[0]),
        format!("(visited {})", os[0]),
        format!("(home {})", os[0]),
        format!("(second {})", os[1]),
    ];
    for a in &os {
        for b in &os {
            if a != b {
                init.push(format!("(link {a} {b})"));
            }
        }
    }
    Hostile {
        name: format!("tours: a complete graph of {n} places"),
        domain: define(
            "tours",
            "place",
            "(at ?x - place) (link ?x ?y - place) (visited ?x - place) (home ?x - place) \
             (second ?x - place)",
            body,
        ),
        problem: problem(
            "tours",
            &format!("{} - place", os.join(" ")),
            "(tour)",
            &init.join(" "),
        ),
    }
}

/// Recursion over `n` resources: each level takes any free resource (in any order), and the
/// end needs the first one both held and free (each alone is reachable, never both): `2^n`
/// states, `n!` orders.
pub fn resources(n: usize) -> Hostile {
    let body = " (:task use :parameters ())\n (:method take :parameters (?r - res) :task (use)\n  \
         :precondition (free ?r)\n  :ordered-subtasks (and (grab ?r) (use)))\n (:method more \
         :parameters (?r ?s - res) :task (use)\n  :precondition (and (free ?r) (free ?s) (not \
         (= ?r ?s)))\n  :ordered-subtasks (and (grab ?r) (release ?s) (use)))\n (:method end \
         :parameters (?r - res) :task (use)\n  :ordered-subtasks (and (exhausted ?r)))\n (:action grab \
         :parameters (?r - res) :precondition (free ?r) :effect (and (not (free ?r)) (held \
         ?r)))\n (:action release :parameters (?r - res) :precondition (free ?r) :effect (and \
         (free ?r)))\n (:action exhausted :parameters (?r - res) :precondition (and (first ?r) (held ?r) (free \
         ?r)))\n";
    let os = objects("r", n);
    let mut init: Vec<String> = os.iter().map(|o| format!("(free {o})")).collect();
    init.push(format!("(first {})", os[0]));
    Hostile {
        name: format!("resources: {n} free resources"),
        domain: define(
            "resources",
            "res",
            "(free ?r - res) (held ?r - res) (first ?r - res)",
            body,
        ),
        problem: problem(
            "resources",
            &format!("{} - res", os.join(" ")),
            "(use)",
            &init.join(" "),
        ),
    }
}

/// `k` actions of four parameters over `n` objects joined through a dense static relation
/// (a grounding of `k * n^4`), used by a recursive task that never reaches its goal.
pub fn wide_actions(n: usize, k: usize) -> Hostile {
    let mut body = String::from(
        " (:task work :parameters ())\n (:method done :parameters () :task (work)\n  \
         :ordered-subtasks (and (finish)))\n (:action finish :parameters () :precondition \
         (finished))\n",
    );
    for i in 0..k {
        body += &format!(
            " (:method via{i} :parameters (?a ?b ?c ?d - obj) :task (work)\n  :precondition \
             (and (rel ?a ?b) (rel ?b ?c) (rel ?c ?d))\n  :ordered-subtasks (and (act{i} ?a ?b \
             ?c ?d) (work)))\n (:action act{i} :parameters (?a ?b ?c ?d - obj)\n  \
             :precondition (and (rel ?a ?b) (rel ?b ?c) (rel ?c ?d) (not (used{i} ?a)))\n  \
             :effect (and (used{i} ?a) (mark ?d)))\n"
        );
    }
    let used: Vec<String> = (0..k).map(|i| format!("(used{i} ?x - obj)")).collect();
    let os = objects("o", n);
    let mut init = Vec::new();
    for (i, a) in os.iter().enumerate() {
        for (j, b) in os.iter().enumerate() {
            if (i + j) % 3 != 0 {
                init.push(format!("(rel {a} {b})"));
            }
        }
    }
    Hostile {
        name: format!("wide actions: {k} of four parameters over {n} objects"),
        domain: define(
            "wideacts",
            "obj",
            &format!(
                "(rel ?x ?y - obj) (mark ?x - obj) (finished) {}",
                used.join(" ")
            ),
            &body,
        ),
        problem: problem(
            "wideacts",
            &format!("{} - obj", os.join(" ")),
            "(work)",
            &init.join(" "),
        ),
    }
}

/// Every family, at sizes that explode.
pub fn all() -> Vec<Hostile> {
    vec![
        wide(60, 6),
        chain(3000, 4),
        tours(24),
        resources(40),
        wide_actions(40, 12),
    ]
}

/// `count` problems of the families at sizes drawn from `seed`: from ones solved or refuted
/// at once to ones that explode.
pub fn random(seed: u64, count: usize) -> Vec<Hostile> {
    let mut rng = fastrand::Rng::with_seed(seed);
    (0..count)
        .map(|_| match rng.usize(0..5) {
            0 => wide(rng.usize(2..80), rng.usize(1..9)),
            1 => chain(rng.usize(2..5000), rng.usize(1..7)),
            2 => tours(rng.usize(2..30)),
            3 => resources(rng.usize(1..60)),
            _ => wide_actions(rng.usize(2..50), rng.usize(1..20)),
        })
        .collect()
}
