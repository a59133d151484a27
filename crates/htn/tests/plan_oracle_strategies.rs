//! The evaluable-predicate interface and the three backtracking strategies, with a fake
//! geometric world: a desk with two slots, front (`p1`) and back (`p2`). A book can go on a free
//! slot, but a book in the front slot blocks the arm's path: while it is there nothing else can
//! be placed. Putting the first book at the back keeps the front free for the second.
//!
//! With two light books (`desk-light`), Symbolic and Chronological both give the second book by
//! hand (the newest choice point is its method), while GeometricFirst moves the first book to
//! the back and puts both on the desk. With the second book heavy (`desk-heavy`), Symbolic must
//! change HTN choices (second book first on the desk, first by hand), while Chronological and
//! GeometricFirst re-place the first book.

use std::collections::HashMap;
use std::path::Path;

use htn::model::{Domain, Problem};
use htn::oracle::{GeoSolution, GeometricOracle, GroundAtom, OracleError, SolutionId, StreamId};
use htn::plan::Plan;
use htn::planner::{
    Limit, Limits, Outcome, PlanError, PlannerOptions, SearchStats, Strategy, plan,
};
use htn::validate::validate;

const SLOTS: [&str; 2] = ["p1", "p2"];
/// The desk with a line of sight (`hiding`): three slots; a book on `p1` hides one on `p2`.
const SIGHT_SLOTS: [&str; 3] = ["p1", "p2", "p3"];

/// A book placed on a slot.
type Placement = (String, String);

#[derive(Default)]
struct Desk {
    /// (book, slot) placed so far.
    world: Vec<(String, String)>,
    saved: Vec<Vec<(String, String)>>,
    /// Per stream: the book, the world it was opened in, the next slot to try.
    streams: HashMap<u64, (String, Vec<Placement>, usize)>,
    next_id: u64,
    /// Every solution given out, by its id: (book, slot).
    solutions: Vec<Placement>,
    /// A crowded desk: any book on it blocks every further placement.
    crowded: bool,
    /// Nothing blocks, but a book on `p1` hides a book on `p2` (shared literal `visible`).
    hiding: bool,
    /// How long each solution takes to compute, as a real GTP's do.
    delay: std::time::Duration,
}

impl GeometricOracle for Desk {
    fn initial_facts(&mut self) -> Result<Vec<GroundAtom>, OracleError> {
        Ok(Vec::new())
    }
    fn open(&mut self, task: &str, args: &[String]) -> Result<StreamId, OracleError> {
        assert_eq!(task, "make-accessible");
        self.next_id += 1;
        self.streams
            .insert(self.next_id, (args[0].clone(), self.world.clone(), 0));
        Ok(StreamId(self.next_id))
    }
    fn next_solution(&mut self, s: StreamId) -> Result<Option<GeoSolution>, OracleError> {
        std::thread::sleep(self.delay);
        let (book, opened_in, pos) = self.streams.get_mut(&s.0).expect("an open stream");
        // Stack discipline: a stream is asked only in the world it was opened in.
        assert_eq!(*opened_in, self.world, "stream asked in another world");
        let blocked = if self.hiding {
            false
        } else if self.crowded {
            !self.world.is_empty()
        } else {
            self.world.iter().any(|(_, slot)| slot == "p1")
        };
        let slots: &[&str] = if self.hiding { &SIGHT_SLOTS } else { &SLOTS };
        let at = |slot: &str| self.world.iter().find(|(_, s)| s == slot).map(|(b, _)| b);
        while *pos < slots.len() {
            let slot = slots[*pos];
            *pos += 1;
            if !blocked && at(slot).is_none() {
                let mut add = vec![GroundAtom::new("on-desk", &[book])];
                let mut delete = vec![];
                if self.hiding {
                    if slot != "p2" || at("p1").is_none() {
                        add.push(GroundAtom::new("visible", &[book]));
                    }
                    if let (Some(other), "p1") = (at("p2"), slot) {
                        delete.push(GroundAtom::new("visible", &[other]));
                    }
                }
                self.solutions.push((book.clone(), slot.to_string()));
                return Ok(Some(GeoSolution {
                    add,
                    delete,
                    id: SolutionId(self.solutions.len() as u64 - 1),
                }));
            }
        }
        Ok(None)
    }
    fn close(&mut self, s: StreamId) {
        self.streams.remove(&s.0);
    }
    fn apply(&mut self, id: SolutionId) -> Result<(), OracleError> {
        let placed = self.solutions[id.0 as usize].clone();
        self.saved.push(self.world.clone());
        self.world.push(placed);
        Ok(())
    }
    fn undo(&mut self) {
        self.world = self.saved.pop().expect("an apply to undo");
    }
    fn world_fingerprint(&self) -> u64 {
        let mut h = 0u64;
        for (b, s) in &self.world {
            for c in b.bytes().chain(s.bytes()) {
                h = h.wrapping_mul(31).wrapping_add(c as u64);
            }
        }
        h
    }
}

fn load(problem: &str) -> (Domain, Problem) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/domains");
    let domain = if problem.starts_with("desk-visible") {
        "desk-visible-domain.hddl"
    } else {
        "desk-domain.hddl"
    };
    let d = htn::load_domain(dir.join(domain)).unwrap();
    let p = htn::load_problem(dir.join(problem), &d).unwrap();
    (d, p)
}

/// Plans with a fresh desk; returns the plan's steps as text (`makebkacc b1@p2`, `givebk b2`)
/// and the statistics. Checks the plan with the validator and the desk's final world.
fn run(problem: &str, strategy: Strategy) -> (Vec<String>, SearchStats) {
    run_on(problem, strategy, false)
}

fn run_on(problem: &str, strategy: Strategy, crowded: bool) -> (Vec<String>, SearchStats) {
    let opts = PlannerOptions {
        strategy,
        ..PlannerOptions::default()
    };
    run_with(problem, &opts, crowded)
}

fn run_with(problem: &str, opts: &PlannerOptions, crowded: bool) -> (Vec<String>, SearchStats) {
    let strategy = opts.strategy;
    let (d, p) = load(problem);
    let mut desk = Desk {
        crowded,
        hiding: problem.starts_with("desk-visible"),
        ..Desk::default()
    };
    let r = plan(&d, &p, opts, Some(&mut desk)).unwrap();
    let Outcome::Found { plan } = r.outcome else {
        panic!("{problem} {strategy:?}: no plan: {:?}", r.outcome)
    };
    validate(&d, &p, &plan, &[]).unwrap();
    // The world the desk is left in is the plan's: one placement per GS step, in order.
    let placed: Vec<Placement> = plan
        .actions
        .iter()
        .filter_map(|a| a.geometric.as_ref())
        .map(|g| desk.solutions[g.solution.0 as usize].clone())
        .collect();
    assert_eq!(desk.world, placed);
    (steps(&plan, &desk), r.stats)
}

fn steps(plan: &Plan, desk: &Desk) -> Vec<String> {
    plan.actions
        .iter()
        .map(|a| match &a.geometric {
            Some(g) => {
                let slot = &desk.solutions[g.solution.0 as usize].1;
                format!("{} {}@{slot}", a.name, a.args[0])
            }
            None => format!("{} {}", a.name, a.args[0]),
        })
        .collect()
}

#[test]
fn light_books_symbolic_hands_the_second_over() {
    let (s, st) = run("desk-light.hddl", Strategy::Symbolic);
    assert_eq!(s, ["makebkacc b1@p1", "givebk b2"]);
    assert_eq!(st.geo_backtracks, 0);
    assert_eq!(st.htn_backtracks, 1);
}

#[test]
fn light_books_chronological_revisits_the_newest_choice_an_htn_one() {
    let (s, st) = run("desk-light.hddl", Strategy::Chronological);
    assert_eq!(s, ["makebkacc b1@p1", "givebk b2"]);
    assert_eq!(st.geo_backtracks, 0);
}

#[test]
fn light_books_geometric_first_moves_the_first_book_to_the_back() {
    let (s, st) = run("desk-light.hddl", Strategy::GeometricFirst { k: 1 });
    assert_eq!(s, ["makebkacc b1@p2", "makebkacc b2@p1"]);
    assert_eq!(st.geo_backtracks, 1);
    assert_eq!(st.htn_backtracks, 0);
    assert_eq!((st.geo_repairs, st.geo_repairs_succeeded), (1, 1));
}

#[test]
fn geometric_first_with_no_budget_behaves_like_symbolic() {
    let (s, _) = run("desk-light.hddl", Strategy::GeometricFirst { k: 0 });
    assert_eq!(s, ["makebkacc b1@p1", "givebk b2"]);
}

#[test]
fn heavy_book_symbolic_changes_the_htn_choices() {
    let (s, st) = run("desk-heavy.hddl", Strategy::Symbolic);
    assert_eq!(s, ["makebkacc b2@p1", "givebk b1"]);
    assert_eq!(st.geo_backtracks, 0);
    assert!(st.htn_backtracks >= 2);
}

#[test]
fn heavy_book_chronological_replaces_the_first_book() {
    // The second book fails at once: trying the first book's next placement is a local retry,
    // which every round of limited discrepancy allows.
    let (s, st) = run("desk-heavy.hddl", Strategy::Chronological);
    assert_eq!(s, ["makebkacc b1@p2", "makebkacc b2@p1"]);
    assert_eq!((st.geo_backtracks, st.discrepancy_round), (1, 0));
}

#[test]
fn heavy_book_plain_chronological_replaces_the_first_book() {
    let opts = PlannerOptions {
        strategy: Strategy::Chronological,
        discrepancy_rounds: false,
        ..PlannerOptions::default()
    };
    let (s, st) = run_with("desk-heavy.hddl", &opts, false);
    assert_eq!(s, ["makebkacc b1@p2", "makebkacc b2@p1"]);
    assert_eq!(st.geo_backtracks, 1);
}

/// Three books on the desk where a book in front hides the one behind: one must be handed
/// over. Plain chronological backtracking revises the second book's placement, which the
/// third book's was built on, before any HTN choice of the second book (it ends up lending the
/// third book second and handing the second over); the first round of limited discrepancy
/// does not revise it: it lends the third book second, by hand, and retries the second book's
/// placement, which nothing was built on.
#[test]
fn chronological_rounds_try_htn_choices_before_revising_a_placement() {
    let p = "desk-visible-three.hddl";
    let (s, st) = run(p, Strategy::Chronological);
    assert_eq!(
        s,
        ["makebkacc b1@p1", "givebk b3", "makebkacc b2@p3", "tick m"]
    );
    assert_eq!(st.discrepancy_round, 0);
    let plain = PlannerOptions {
        discrepancy_rounds: false,
        ..PlannerOptions::default()
    };
    let (s, _) = run_with(p, &plain, false);
    assert_eq!(
        s,
        ["makebkacc b1@p1", "makebkacc b3@p3", "givebk b2", "tick m"]
    );
}

#[test]
fn heavy_book_geometric_first_replaces_the_first_book() {
    let (s, st) = run("desk-heavy.hddl", Strategy::GeometricFirst { k: 2 });
    assert_eq!(s, ["makebkacc b1@p2", "makebkacc b2@p1"]);
    assert_eq!(st.geo_repairs_succeeded, 1);
}

#[test]
fn geometric_first_falls_back_to_htn_choices_when_no_repair_works() {
    // On a crowded desk no placement of the first book leaves room for the second: the repair
    // tries b1 at the back, replays, fails again, restores b1 at the front and only then hands
    // the second book over (the HTN alternative at the failure point).
    let (s, st) = run_on("desk-light.hddl", Strategy::GeometricFirst { k: 3 }, true);
    assert_eq!(s, ["makebkacc b1@p1", "givebk b2"]);
    assert_eq!((st.geo_repairs, st.geo_repairs_succeeded), (1, 0));
    assert_eq!(st.geo_backtracks, 1);
    assert_eq!(st.htn_backtracks, 1);
}

/// A method whose precondition reads shared literals fails because of a placement (the second
/// book hidden behind the first, as in the paper's Fig. 4): geometric-first places the second
/// book elsewhere, with no HTN backtrack; symbolic changes method (hands it over).
#[test]
fn a_shared_literal_precondition_failure_is_repaired_geometrically_first() {
    let (s, st) = run("desk-visible.hddl", Strategy::GeometricFirst { k: 2 });
    assert_eq!(s, ["makebkacc b1@p1", "makebkacc b2@p3", "tick m"]);
    assert_eq!((st.htn_backtracks, st.geo_backtracks), (0, 1));
    assert_eq!(st.geo_repairs_succeeded, 1);
    let (s, st) = run("desk-visible.hddl", Strategy::Symbolic);
    assert_eq!(s, ["makebkacc b1@p1", "givebk b2", "tick m"]);
    assert_eq!(st.geo_backtracks, 0);
    assert!(st.htn_backtracks > 0);
}

#[test]
fn without_a_geometric_back_end_planning_names_the_first_gs_action() {
    let (d, p) = load("desk-light.hddl");
    let e = plan(&d, &p, &PlannerOptions::default(), None).unwrap_err();
    assert!(matches!(&e, PlanError::NoOracle { action, .. } if action == "makebkacc"));
    assert!(e.to_string().contains("make-accessible"), "{e}");
}

/// The outcome alone, with a fresh desk.
fn outcome(problem: &str, strategy: Strategy, crowded: bool) -> Outcome {
    let (d, p) = load(problem);
    let mut desk = Desk {
        crowded,
        ..Desk::default()
    };
    let opts = PlannerOptions {
        strategy,
        ..PlannerOptions::default()
    };
    plan(&d, &p, &opts, Some(&mut desk)).unwrap().outcome
}

/// The symbolic strategy, which stops once it used up its geometric alternatives, has proven
/// nothing, so it reports a limit (exit 2), never "no plan exists". Here a plan exists (the
/// first book at the back), which chronological backtracking finds, and geometric-first too:
/// with no repair budget, through the chronological pass that follows its repairs.
#[test]
fn a_capped_strategy_that_fails_reports_a_limit_not_unsolvability() {
    let capped = Outcome::LimitReached {
        limit: Limit::GeometricAlternatives,
    };
    let p = "desk-both-heavy.hddl";
    assert_eq!(outcome(p, Strategy::Symbolic, false), capped);
    for s in [Strategy::Chronological, Strategy::GeometricFirst { k: 0 }] {
        assert!(
            matches!(outcome(p, s, false), Outcome::Found { .. }),
            "{s:?}"
        );
    }
    let (_, st) = run(p, Strategy::GeometricFirst { k: 0 });
    assert!(st.chronological_after_repairs);
}

/// Whatever the repair budget, geometric-first finds the plan of `desk-both-heavy`: by its
/// repairs when they reach it, else by the chronological pass after them.
#[test]
fn geometric_first_is_as_complete_as_chronological() {
    let p = "desk-both-heavy.hddl";
    for k in [0, 1, 2, 3] {
        let (s, st) = run(p, Strategy::GeometricFirst { k });
        assert!(!s.is_empty(), "k = {k}");
        assert_eq!(st.chronological_after_repairs, k == 0, "k = {k}");
    }
}

/// With a time limit, geometric-first's repairs hand over to the chronological pass after
/// their share of it: with a share of 1 for the pass, at once, so the plan is chronological's.
#[test]
fn geometric_first_hands_over_after_its_share_of_the_time() {
    let p = "desk-heavy.hddl";
    let (chrono, _) = run(p, Strategy::Chronological);
    let opts = PlannerOptions {
        strategy: Strategy::GeometricFirst { k: 2 },
        limits: Limits {
            time: Some(std::time::Duration::from_secs(60)),
            ..Limits::default()
        },
        chronological_share: 1.0,
        ..PlannerOptions::default()
    };
    let (s, st) = run_with(p, &opts, false);
    assert_eq!(s, chrono);
    assert!(st.chronological_after_repairs);
    assert_eq!(st.geo_repairs, 0);
    // With the default share the repairs have time to find it themselves.
    let (_, st) = run_with(
        p,
        &PlannerOptions {
            chronological_share: 0.5,
            ..opts
        },
        false,
    );
    assert!(!st.chronological_after_repairs);
    assert_eq!(st.geo_repairs_succeeded, 1);
}

/// The handover to the chronological pass may fall due in the middle of a repair (here, on a
/// crowded desk, the repair that moves the first book back, with solutions that take 15 ms):
/// it waits for the repair to end, and the plan is found whenever it comes.
#[test]
fn the_handover_during_a_repair_waits_for_it() {
    for share in [0.94, 0.95, 0.96, 0.97, 0.98] {
        let (d, p) = load("desk-light.hddl");
        let mut desk = Desk {
            crowded: true,
            delay: std::time::Duration::from_millis(15),
            ..Desk::default()
        };
        let opts = PlannerOptions {
            strategy: Strategy::GeometricFirst { k: 3 },
            limits: Limits {
                time: Some(std::time::Duration::from_secs(1)),
                ..Limits::default()
            },
            chronological_share: share,
            ..PlannerOptions::default()
        };
        let r = plan(&d, &p, &opts, Some(&mut desk)).unwrap();
        let Outcome::Found { plan } = r.outcome else {
            panic!("share {share}: {:?}", r.outcome)
        };
        validate(&d, &p, &plan, &[]).unwrap();
    }
}

/// Only a complete search, which tried every geometric solution, may say no plan exists:
/// chronological backtracking, or geometric-first once its chronological pass is done.
#[test]
fn only_the_complete_search_proves_unsolvability() {
    let p = "desk-both-heavy.hddl";
    for s in [Strategy::Chronological, Strategy::GeometricFirst { k: 3 }] {
        assert_eq!(outcome(p, s, true), Outcome::Unsolvable, "{s:?}");
    }
    assert_eq!(
        outcome(p, Strategy::Symbolic, true),
        Outcome::LimitReached {
            limit: Limit::GeometricAlternatives
        }
    );
}
