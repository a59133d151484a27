//! What the parser builds from each language feature (texts written for these tests), and the
//! project's own library domain.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use htn::model::{
    ArithOp, CompareOp, Domain, Effect, Formula, NumExpr, NumericEffectOp, Problem, SourceName,
    Term,
};
use htn::parser::{load_domain, load_problem, parse_domain, parse_problem};

fn src(name: &str) -> SourceName {
    Arc::new(PathBuf::from(name))
}

fn domain(text: &str) -> Domain {
    parse_domain(text, src("d.hddl")).unwrap_or_else(|e| panic!("{e}"))
}

fn problem(text: &str, d: &Domain) -> Problem {
    parse_problem(text, src("p.hddl"), d).unwrap_or_else(|e| panic!("{e}"))
}

fn names(subtasks: &[htn::model::Subtask]) -> Vec<&str> {
    subtasks.iter().map(|s| s.name.as_str()).collect()
}

const ORDERINGS: &str = r#"
(define (domain Orders)
  (:requirements :hierarchy :typing)
  (:types block)
  (:predicates (clear ?b - block))
  (:task top :parameters (?b - block))
  (:method reversed
    :parameters (?b - block)
    :task (top ?b)
    :subtasks (and (task0 (a ?b)) (task1 (b)) (task2 (c)))
    :ordering (and (< task2 task0) (< task1 task2) (< task1 task0)))
  (:method single-constraint
    :parameters (?b - block)
    :task (top ?b)
    :tasks (and (x (a ?b)) (y (b)))
    :ordering (< y x))
  (:method listed
    :parameters (?b - block)
    :task (TOP ?B)
    :ordered-tasks (and (c) (B) (a ?b)))
  (:method bare-single
    :parameters (?b - block)
    :task (top ?b)
    :subtasks (a ?b))
  (:method empty
    :parameters (?b - block)
    :task (top ?b)
    :ordered-subtasks ())
  (:method empty-and
    :parameters ()
    :task (top ?b-any)
    :subtasks (and))
  (:action a :parameters (?b - block) :precondition (clear ?b))
  (:action b)
  (:action c :parameters () :effect ()))
"#;

#[test]
fn every_subtask_spelling_gives_one_total_order() {
    let text = ORDERINGS.replace(
        "(:method empty-and\n    :parameters ()\n    :task (top ?b-any)",
        "(:method empty-and\n    :parameters (?b-any - block)\n    :task (top ?b-any)",
    );
    let d = domain(&text);
    assert_eq!(d.name, "orders");
    let m = |name: &str| d.methods.iter().find(|m| m.name == name).unwrap();
    assert_eq!(names(&m("reversed").subtasks), ["b", "c", "a"]);
    assert_eq!(m("reversed").subtasks[0].id.as_deref(), Some("task1"));
    assert_eq!(names(&m("single-constraint").subtasks), ["b", "a"]);
    assert_eq!(names(&m("listed").subtasks), ["c", "b", "a"]);
    assert_eq!(m("listed").task, "top");
    assert_eq!(m("listed").task_args, [Term::Var("?b".into())]);
    assert_eq!(names(&m("bare-single").subtasks), ["a"]);
    assert!(m("empty").subtasks.is_empty());
    assert!(m("empty-and").subtasks.is_empty());
    let a = d.actions.iter().find(|a| a.name == "b").unwrap();
    assert_eq!(a.precondition, Formula::True);
    assert!(a.effects.is_empty());
}

#[test]
fn an_unbound_task_argument_is_refused() {
    let e = parse_domain(ORDERINGS, src("d.hddl")).unwrap_err();
    assert!(e.message.contains("unbound variable `?b-any`"), "{e}");
}

#[test]
fn types_with_several_parents_constants_and_type_checks() {
    let d = domain(
        r#"(define (domain t)
  (:types truck - vehicle  car - vehicle  truck - container  place)
  (:constants depot - place)
  (:predicates (at ?v - vehicle ?p - place) (full ?c - container))
  (:task go :parameters (?t - truck))
  (:method m :parameters (?t - truck) :task (go ?t)
    :precondition (and (at ?t depot) (full ?t) (not (= ?t depot)))
    :ordered-subtasks (drive ?t depot))
  (:action drive :parameters (?v - vehicle ?p - place)
    :effect (and (at ?v ?p) (forall (?q - place) (when (not (= ?q ?p)) (not (at ?v ?q)))))))"#,
    );
    let truck = d.types.iter().find(|t| t.name == "truck").unwrap();
    assert_eq!(truck.parents, ["vehicle", "container"]);
    assert!(
        d.types
            .iter()
            .any(|t| t.name == "vehicle" && t.parents == ["object"])
    );
    assert_eq!(d.constants[0].name, "depot");
    let drive = &d.actions[0];
    match &drive.effects[1] {
        Effect::Forall(vars, inner) => {
            assert_eq!(vars[0].name, "?q");
            assert!(
                matches!(&inner[0], Effect::When(Formula::Not(_), e) if matches!(e[0], Effect::Delete(_)))
            );
        }
        other => panic!("expected forall, got {other:?}"),
    }

    // A car is no container: passing one where a container is expected cannot be right.
    let e = parse_domain(
        r#"(define (domain t)
  (:types truck - vehicle  car - vehicle  truck - container)
  (:predicates (full ?c - container))
  (:action a :parameters (?c - car) :precondition (full ?c)))"#,
        src("d.hddl"),
    )
    .unwrap_err();
    assert_eq!((e.line, e.col), (4, 57));
    assert!(
        e.message
            .contains("does not fit parameter `?c - container`"),
        "{e}"
    );
}

#[test]
fn connectives_quantifiers_and_sortof() {
    let d = domain(
        r#"(define (domain c)
  (:types a - b)
  (:predicates (p ?x - b) (q ?x - b))
  (:task t :parameters ())
  (:method m :parameters (?x - b) :task (t)
    :constraints (and (sortof ?x - a))
    :subtasks (and (act ?x)))
  (:action act :parameters (?x - b)
    :precondition (and (or (p ?x) (q ?x)) (imply (p ?x) (q ?x))
                       (exists (?y - a) (p ?y)) (forall (?y - b) (not (q ?y))))))"#,
    );
    match &d.methods[0].constraints {
        Formula::And(parts) => match &parts[0] {
            Formula::Exists(vars, body) => {
                assert_eq!(vars[0].ty, "a");
                assert!(
                    matches!(&**body, Formula::Equal(Term::Var(w), Term::Var(x), _) if *w == vars[0].name && x == "?x")
                );
            }
            other => panic!("{other:?}"),
        },
        other => panic!("{other:?}"),
    }
    match &d.actions[0].precondition {
        Formula::And(parts) => {
            assert!(matches!(parts[0], Formula::Or(_)));
            assert!(matches!(parts[1], Formula::Imply(..)));
            assert!(matches!(parts[2], Formula::Exists(..)));
            assert!(matches!(parts[3], Formula::Forall(..)));
        }
        other => panic!("{other:?}"),
    }
}

const NUMERIC: &str = r#"(define (domain shop)
  (:requirements :hierarchy :typing :numeric-fluents)
  (:types member)
  (:predicates (paid ?m - member))
  (:functions (credit ?m - member) (cost) - number)
  (:task pay :parameters (?m - member))
  (:method by-credit :parameters (?m - member) :task (pay ?m)
    :precondition (>= (credit ?m) (* (cost) 2))
    :ordered-subtasks (debit ?m))
  (:action debit :parameters (?m - member)
    :precondition (and (> (credit ?m) 0) (= (credit ?m) (+ (cost) 1 -2.5)) (< (- (cost)) 10))
    :effect (and (decrease (credit ?m) (cost)) (paid ?m) (assign (cost) (/ (cost) 2)))))"#;

#[test]
fn numeric_fluents_in_conditions_effects_and_init() {
    let d = domain(NUMERIC);
    assert_eq!(d.functions.len(), 2);
    match &d.methods[0].precondition {
        Formula::Compare(
            CompareOp::Ge,
            NumExpr::Fluent(f),
            NumExpr::Binary(ArithOp::Mul, _, two),
            _,
        ) => {
            assert_eq!(f.function, "credit");
            assert_eq!(**two, NumExpr::Number(2.0));
        }
        other => panic!("{other:?}"),
    }
    let debit = &d.actions[0];
    match &debit.precondition {
        Formula::And(parts) => {
            assert!(
                matches!(&parts[1], Formula::Compare(CompareOp::Eq, _, NumExpr::Binary(ArithOp::Add, _, x), _) if **x == NumExpr::Number(-2.5))
            );
            assert!(matches!(
                &parts[2],
                Formula::Compare(CompareOp::Lt, NumExpr::Neg(_), _, _)
            ));
        }
        other => panic!("{other:?}"),
    }
    assert!(
        matches!(&debit.effects[0], Effect::Numeric(NumericEffectOp::Decrease, f, NumExpr::Fluent(_)) if f.function == "credit")
    );
    assert!(matches!(
        &debit.effects[2],
        Effect::Numeric(
            NumericEffectOp::Assign,
            _,
            NumExpr::Binary(ArithOp::Div, ..)
        )
    ));

    let p = problem(
        r#"(define (problem p1) (:domain SHOP)
  (:objects alice - member)
  (:htn :parameters () :subtasks (and (task0 (pay alice))))
  (:init (= (credit alice) 20) (= (cost) 4.5))
  (:goal (paid alice)))"#,
        &d,
    );
    assert_eq!(p.init_values.len(), 2);
    assert_eq!(p.init_values[1].value, 4.5);
    assert_eq!(p.init_values[0].args, ["alice"]);
    assert_eq!(names(&p.htn.subtasks), ["pay"]);
    assert!(matches!(&p.goal, Formula::Atom(a) if a.predicate == "paid"));
}

const GEOMETRIC: &str = r#"(define (domain lib)
  (:types book agent - object member - agent)
  (:predicates (held ?b - book ?m - member) (lent ?b - book ?m - member))
  (:shared-predicates (visible ?o - object ?a - agent))
  (:geometric-tasks (make-accessible ?o - object ?h - agent) (pick ?o - object))
  (:task lend :parameters (?b - book ?m - member))
  (:method m :parameters (?b - book ?m - member) :task (lend ?b ?m)
    :precondition (visible ?b ?m)
    :ordered-subtasks (and (makebkacc ?b ?m) (pick ?b)))
  (:action makebkacc :parameters (?b - book ?m - member)
    :precondition (and (held ?b ?m) (evaluable (make-accessible ?b ?m)))
    :effect (and (not (held ?b ?m)) (lent ?b ?m)))
  (:action pick :parameters (?b - book)
    :precondition (evaluable (pick ?b))))"#;

#[test]
fn the_geometric_extension() {
    let d = domain(GEOMETRIC);
    assert_eq!(d.shared_predicates[0].name, "visible");
    assert_eq!(d.geometric_tasks.len(), 2);
    match &d.actions[0].precondition {
        Formula::And(parts) => assert!(
            matches!(&parts[1], Formula::Evaluable { task, args, .. } if task == "make-accessible" && args.len() == 2)
        ),
        other => panic!("{other:?}"),
    }
    // An action may bear its geometric task's name (separate namespaces).
    assert!(
        matches!(&d.actions[1].precondition, Formula::Evaluable { task, .. } if task == "pick")
    );

    let e = parse_problem(
        r#"(define (problem p) (:domain lib) (:objects b - book m - member)
  (:init (held b m) (visible b m)))"#,
        src("p.hddl"),
        &d,
    )
    .unwrap_err();
    assert_eq!((e.line, e.col), (2, 22));
    assert!(
        e.message.contains("shared predicate `visible` in `:init`"),
        "{e}"
    );
}

#[test]
fn problems_know_constants_htn_parameters_and_refuse_another_domain() {
    let d = domain(
        r#"(define (domain k) (:types a) (:constants c - a) (:predicates (foo ?x - a))
  (:task t :parameters (?x - a))
  (:method m :parameters (?x - a) :task (t ?x) :subtasks (and (noop ?x)))
  (:action noop :parameters (?x - a) :precondition (foo ?x)))"#,
    );
    let p = problem(
        r#"(define (problem q) (:domain k) (:objects c - a o - a)
  (:htn :parameters (?v - a) :subtasks (and (t0 (t ?v)) (t1 (t c))) :ordering (and (< t1 t0)))
  (:init (foo c)))"#,
        &d,
    );
    assert_eq!(
        p.objects.len(),
        1,
        "the repeated constant is not an extra object"
    );
    assert_eq!(p.htn.params[0].name, "?v");
    assert_eq!(p.htn.subtasks[0].args, [Term::Const("c".into())]);
    let e = parse_problem("(define (problem q) (:domain other))", src("p.hddl"), &d).unwrap_err();
    assert!(e.message.contains("for domain `other`"), "{e}");
    assert_eq!((e.line, e.col), (1, 30));
}

fn repo() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

#[test]
fn the_library_domains_and_problems_parse() {
    let dir = repo().join("domains/library");
    let d = load_domain(dir.join("domain.hddl")).unwrap_or_else(|e| panic!("{e}"));
    assert!(!d.geometric_tasks.is_empty() && !d.functions.is_empty());
    let compound = load_domain(dir.join("domain-compound.hddl")).unwrap_or_else(|e| panic!("{e}"));
    let mut problems = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if path.extension().is_some_and(|e| e == "hddl") && !name.starts_with("domain") {
            load_problem(&path, &d).unwrap_or_else(|e| panic!("{e}"));
            load_problem(&path, &compound).unwrap_or_else(|e| panic!("{e}"));
            problems += 1;
        }
    }
    assert!(problems >= 1);
}

#[test]
fn deep_but_legal_nesting_parses_and_deeper_is_refused() {
    // 240 nested `not` inside an action inside the define: 243 levels, under the limit.
    let depth = 240;
    let body = format!("{}(p){}", "(not ".repeat(depth), ")".repeat(depth));
    let text = format!("(define (domain n) (:predicates (p)) (:action a :precondition {body}))");
    let d = domain(&text);
    let mut f = &d.actions[0].precondition;
    let mut nots = 0;
    while let Formula::Not(inner) = f {
        nots += 1;
        f = inner;
    }
    assert_eq!(nots, depth);

    let depth = htn::parser::MAX_DEPTH;
    let body = format!("{}(p){}", "(not ".repeat(depth), ")".repeat(depth));
    let text = format!("(define (domain n) (:predicates (p)) (:action a :precondition {body}))");
    let e = parse_domain(&text, src("d.hddl")).unwrap_err();
    assert!(e.message.contains("nested deeper"), "{e}");
}

#[test]
fn empty_text_and_files_that_are_not_utf8_or_missing() {
    let e = parse_domain("", src("d.hddl")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "d.hddl:1:1: empty file: expected `(define (domain NAME) ...)`"
    );

    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htn-parse-features-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("latin1.hddl");
    std::fs::write(&bad, b"(define (domain d)\n  (:predicates (caf\xe9)))").unwrap();
    let e = load_domain(&bad).unwrap_err();
    assert_eq!((e.line, e.col), (2, 20));
    assert!(e.message.contains("not valid UTF-8"), "{e}");

    let missing = dir.join("missing.hddl");
    let e = load_domain(&missing).unwrap_err();
    assert_eq!(e.line, 0);
    assert!(
        e.to_string()
            .starts_with(&format!("{}: cannot read the file", missing.display())),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_quantified_variable_shadows_a_parameter_only_inside_its_quantifier() {
    let d = domain(
        r#"(define (domain s) (:types a b) (:predicates (p ?x - a) (q ?x - b))
  (:action act :parameters (?x - a)
    :precondition (and (forall (?x - b) (q ?x)) (p ?x))
    :effect (forall (?x - b) (not (q ?x)))))"#,
    );
    assert_eq!(d.actions[0].params[0].ty, "a");
    // Outside the quantifier `?x` is an `a` again: passing it to `q` is a type error.
    let e = parse_domain(
        r#"(define (domain s) (:types a b) (:predicates (p ?x - a) (q ?x - b))
  (:action act :parameters (?x - a)
    :precondition (and (exists (?x - b) (q ?x)) (q ?x))))"#,
        src("d.hddl"),
    )
    .unwrap_err();
    assert_eq!((e.line, e.col), (3, 52));
    assert!(e.message.contains("does not fit"), "{e}");
}

/// A parent type named nowhere else is taken as a subtype of `object`, with a warning at the
/// place; a declared one gives none.
#[test]
fn an_undeclared_parent_type_is_read_with_a_warning() {
    let d = domain("(define (domain d) (:types truck - vehicle) (:predicates (at ?t - truck)))");
    assert_eq!(d.warnings.len(), 1);
    let w = &d.warnings[0];
    assert_eq!((w.line, w.col), (1, 28));
    assert!(
        w.message.contains(
            "the parent type `vehicle` of `truck` is not declared; taken as a subtype of `object`"
        ),
        "{w}"
    );
    let d = domain("(define (domain d) (:types truck - vehicle vehicle - object))");
    assert!(d.warnings.is_empty());
}
