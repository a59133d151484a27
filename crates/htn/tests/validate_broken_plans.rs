//! The validator accepts the planner's plans and rejects deliberately broken ones, naming the
//! fault. Uses the payment test domain (`tests/domains/payment-domain.hddl`).

use std::path::Path;

use htn::model::{Domain, Problem};
use htn::plan::{Plan, PlanAction};
use htn::planner::{Outcome, PlannerOptions, plan};
use htn::validate::{Names, validate, validate_with};

fn load(problem: &str) -> (Domain, Problem) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/domains");
    let d = htn::load_domain(dir.join("payment-domain.hddl")).unwrap();
    let p = htn::load_problem(dir.join(problem), &d).unwrap();
    (d, p)
}

/// The plan the planner finds for two books and credit 20 (give b1, give b2, debit).
fn good() -> (Domain, Problem, Plan) {
    let (d, p) = load("payment-credit-20.hddl");
    let r = plan(&d, &p, &PlannerOptions::default(), None).unwrap();
    let Outcome::Found { plan } = r.outcome else {
        panic!("no plan")
    };
    (d, p, plan)
}

fn fault(d: &Domain, p: &Problem, plan: &Plan) -> String {
    validate(d, p, plan, &[]).expect_err("a broken plan").0
}

/// The fault the lenient validator (names in any case, undeclared names left to later checks) finds.
fn lenient_fault(d: &Domain, p: &Problem, plan: &Plan) -> String {
    validate_with(d, p, plan, &[], Names::CaseInsensitive)
        .expect_err("a broken plan")
        .0
}

#[test]
fn the_planners_plan_is_valid() {
    let (d, p, plan) = good();
    assert_eq!(plan.actions.len(), 3);
    validate(&d, &p, &plan, &[]).unwrap();
}

#[test]
fn swapped_actions_are_rejected() {
    let (d, p, mut plan) = good();
    plan.actions.swap(0, 1);
    let f = fault(&d, &p, &plan);
    assert!(f.contains("position 1"), "{f}");
}

#[test]
fn a_missing_action_is_rejected() {
    let (d, p, mut plan) = good();
    plan.actions.remove(2);
    let f = fault(&d, &p, &plan);
    assert!(f.contains("neither an action nor a decomposed task"), "{f}");
}

#[test]
fn an_extra_action_is_rejected() {
    let (d, p, mut plan) = good();
    plan.actions.push(PlanAction {
        id: 99,
        name: "swipe-card".into(),
        args: vec!["alice".into()],
        geometric: None,
    });
    let f = fault(&d, &p, &plan);
    assert!(f.contains("action 99") && f.contains("not reached"), "{f}");
}

#[test]
fn a_method_of_another_task_is_rejected() {
    let (d, p, mut plan) = good();
    let lend = plan
        .decompositions
        .iter_mut()
        .find(|x| x.task == "lend")
        .unwrap();
    lend.method = "m6-debit-account".into();
    let f = fault(&d, &p, &plan);
    assert!(f.contains("decomposes `take-payment`, not `lend`"), "{f}");
}

#[test]
fn a_method_whose_numeric_precondition_fails_is_rejected() {
    // Credit 7 cannot pay for two books at 4: m6 is not applicable, yet the plan says m6.
    let (d, p, plan) = good();
    let (_, p7) = load("payment-credit-7.hddl");
    let f = fault(&d, &p7, &plan);
    assert!(
        f.contains("precondition of method `m6-debit-account` does not hold"),
        "{f}"
    );
    validate(&d, &p, &plan, &[]).unwrap();
}

#[test]
fn wrong_arguments_are_rejected() {
    let (d, p, mut plan) = good();
    // The member argument of the second give names a book: no binding of lend-one fits.
    plan.actions[1].args[1] = "b2".into();
    let f = fault(&d, &p, &plan);
    assert!(f.contains("subtask 1 of method `lend-one`"), "{f}");
}

#[test]
fn an_unknown_id_is_rejected() {
    let (d, p, mut plan) = good();
    plan.decompositions[0].subtasks[1] = 42;
    let f = fault(&d, &p, &plan);
    assert!(f.contains("id 42 is neither"), "{f}");
}

#[test]
fn a_wrong_root_is_rejected() {
    let (d, p, mut plan) = good();
    // The root names the lend task instead of serve, and serve's tree is left dangling.
    plan.root = vec![1];
    let f = fault(&d, &p, &plan);
    assert!(f.contains("not reached from the root"), "{f}");
    // Same tree, but the root task is not the problem's: renamed arguments.
    let (d, p, plan) = good();
    let text = plan
        .to_competition_format()
        .replace("0 serve alice", "0 serve bob");
    let broken = Plan::parse(&text).unwrap();
    let f = fault(&d, &p, &broken);
    assert!(f.contains("argument `bob` is not an object"), "{f}");
    let f = lenient_fault(&d, &p, &broken);
    assert!(f.contains("root task 0"), "{f}");
}

#[test]
fn an_unknown_action_is_rejected() {
    let (d, p, mut plan) = good();
    // Rename both the action and the method's view of it: the tree is consistent, the action is not.
    let text = plan
        .to_competition_format()
        .replace("debit alice", "steal alice");
    plan = Plan::parse(&text).unwrap();
    let f = fault(&d, &p, &plan);
    assert!(
        f.contains("task `steal` is not declared in the domain"),
        "{f}"
    );
    let f = lenient_fault(&d, &p, &plan);
    assert!(f.contains("subtask 1 of method `m6-debit-account`"), "{f}");
}

#[test]
fn an_inexecutable_action_is_rejected() {
    // Lending b1 twice: the tree matches the methods but the second give's precondition fails.
    let (d, p, plan) = good();
    let text = plan
        .to_competition_format()
        .replace("give b2 alice", "give b1 alice");
    let plan = Plan::parse(&text).unwrap();
    let f = fault(&d, &p, &plan);
    // The method binds ?b to b1 for the second lend-one, whose precondition (held b1) fails
    // before the second give.
    assert!(f.contains("does not hold"), "{f}");
}

#[test]
fn a_duplicate_id_is_rejected() {
    let (d, p, mut plan) = good();
    plan.actions[1].id = plan.actions[0].id;
    let f = fault(&d, &p, &plan);
    assert!(f.contains("used by two actions"), "{f}");
}

#[test]
fn names_must_be_spelled_as_declared_unless_lenient() {
    let (d, p, plan) = good();
    let text = plan
        .to_competition_format()
        .replace(" debit alice", " Debit alice");
    let upper = Plan::parse(&text).unwrap();
    let f = fault(&d, &p, &upper);
    assert!(
        f.contains("task `Debit` is not declared in the domain (declared as `debit`)"),
        "{f}"
    );
    validate_with(&d, &p, &upper, &[], Names::CaseInsensitive).unwrap();
    let text = plan.to_competition_format().replace(" alice", " ALICE");
    let f = fault(&d, &p, &Plan::parse(&text).unwrap());
    assert!(
        f.contains("argument `ALICE` is not an object of the problem (declared as `alice`)"),
        "{f}"
    );
}
