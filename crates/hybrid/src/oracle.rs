//! [`GtpOracle`]: the `htn` crate's evaluable predicates answered by the geometric task planner.
//!
//! The oracle keeps a stack of worlds, one per geometric solution the HTN search has taken
//! (`apply` pushes, `undo` pops), and with each world its shared literals. A solution's add and
//! delete lists are the paper's `t+` and `t-`: the shared literals of the world after the
//! solution minus those before, and the other way round.
//!
//! A shared literal `visible(o, a)` or `reachable(o, a)` holds symbolically when the agent needs
//! at most [`OracleConfig::effort_threshold`] to see or reach the object (the paper's Fig. 5:
//! "Vis with E=1" counts as visible, E=3 does not). Only literals over names the HTN problem
//! knows are reported (the scene may hold furniture the domain never mentions).

use std::collections::{BTreeSet, HashMap, HashSet};
use std::hash::{Hash, Hasher};
use std::sync::Arc;
use std::time::Instant;

use geometry::facts::{FactParams, shared_literals};
use geometry::world::{Precision, World};
use gtp::planner::{CallOptions, Planner, Solution, SolutionStream};
use gtp::solution::SolutionSummary;
use gtp::stats::Stats;
use htn::oracle::{GeoSolution, GeometricOracle, GroundAtom, OracleError, SolutionId, StreamId};
use serde::Serialize;

use crate::stream_memo::{End, Known, Request, StreamMemo};

/// Settings of the oracle.
#[derive(Clone, Debug)]
pub struct OracleConfig {
    /// Seed of every GTP call (mixed with the task, its arguments and the world).
    pub seed: u64,
    /// Highest effort level at which `visible` and `reachable` hold symbolically.
    pub effort_threshold: u8,
    /// Thresholds of the fact computation (visibility fraction, resolution...).
    pub facts: FactParams,
    /// Constraint overrides passed to every GTP call (`time-limit`, `max-points`...).
    pub constraints: Vec<(String, String)>,
    /// Print every GTP request and its outcome to standard error (`HTNGTP_TRACE=1`).
    pub trace: bool,
}

impl Default for OracleConfig {
    fn default() -> Self {
        OracleConfig {
            seed: 1,
            effort_threshold: 1,
            facts: FactParams::default(),
            constraints: Vec::new(),
            trace: std::env::var_os("HTNGTP_TRACE").is_some(),
        }
    }
}

/// Table II figures of one geometric task, summed over a run (or over an experiment's runs).
#[derive(Clone, Debug, Default, Serialize)]
pub struct TaskStats {
    /// Solution requests (a first solution, or another one when backtracking).
    pub attempts: u64,
    /// Requests that produced a solution.
    pub successes: u64,
    /// The GTP's statistics of these requests, summed ([`Stats::accumulate`]).
    #[serde(flatten)]
    pub search: Stats,
    /// Time spent computing shared literals of the resulting worlds, seconds.
    pub facts_time_s: f64,
    /// Why the last failed request failed (the constraint that stopped it).
    pub last_failure: Option<String>,
}

impl TaskStats {
    /// Adds one request: its GTP statistics, whether it found a solution, and the time the
    /// shared literals of that solution took.
    pub fn record(&mut self, request: &Stats, solved: bool, facts_time_s: f64) {
        self.attempts += 1;
        self.successes += u64::from(solved);
        self.search.accumulate(request);
        self.facts_time_s += facts_time_s;
    }

    /// Adds another total of the same task (another run of an experiment).
    pub fn add(&mut self, other: &TaskStats) {
        self.attempts += other.attempts;
        self.successes += other.successes;
        self.search.accumulate(&other.search);
        self.facts_time_s += other.facts_time_s;
        if other.last_failure.is_some() {
            self.last_failure.clone_from(&other.last_failure);
        }
    }

    /// Time of GTP search and shared literals together, seconds.
    pub fn total_time_s(&self) -> f64 {
        self.search.time_s + self.facts_time_s
    }
}

/// One solution request to the GTP, timed: what `bench library --json` reports latencies of.
#[derive(Clone, Debug, Serialize)]
pub struct RequestTime {
    /// The geometric task as the domain names it, and its arguments.
    pub task: String,
    pub args: Vec<String>,
    /// Whether it produced a solution.
    pub solved: bool,
    /// The stage (constraint) that stopped the stream, for a request that found nothing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stage: Option<String>,
    /// The shared literals of its solution's world, seconds (not in `search.time_s`).
    pub facts_time_s: f64,
    /// The GTP's statistics of this request (`time_s`: its latency).
    #[serde(flatten)]
    pub search: Stats,
}

/// A world of the stack with its shared literals.
#[derive(Clone)]
struct Frame {
    world: World,
    facts: Arc<BTreeSet<GroundAtom>>,
    fingerprint: u64,
    /// Every bit of the world, for the memo of requests.
    exact: u64,
}

/// A solution given out to the HTN search: the world after it, with its literals, and what
/// the GTP did (grasp, placement, trajectories).
struct Given {
    frame: Frame,
    summary: SolutionSummary,
}

/// An open solution stream of the HTN search: its request, and how many of the request's
/// solutions it has read.
struct Stream {
    request: Request,
    pos: usize,
}

/// One solution request's outcome: the solution if any, the statistics of that request, and
/// why the stream ended when it did.
struct Pulled {
    solution: Option<Solution>,
    delta: Stats,
    end: End,
}

/// A geometric task that found no (further) solution.
#[derive(Clone, Debug)]
pub struct TaskFailure {
    /// The task as the domain names it, and its arguments.
    pub task: String,
    pub args: Vec<String>,
    /// The GTP's reason in words.
    pub why: String,
    /// The stage of the GTP's search (the constraint) that stopped it, when it named one.
    pub stage: Option<gtp::planner::Stage>,
}

/// The GTP as an HTN oracle. See the module docs.
pub struct GtpOracle {
    planner: Arc<Planner>,
    config: OracleConfig,
    /// Names the HTN problem knows (objects and constants); literals over others are dropped.
    known: HashSet<String>,
    stack: Vec<Frame>,
    /// Every solution given out, indexed by its [`SolutionId`]; `apply` pushes its frame.
    solutions: Vec<Given>,
    streams: HashMap<u64, Stream>,
    next_stream: u64,
    /// Every request's solutions, read back when it is asked again (`stream_memo.rs`).
    memo: StreamMemo,
    stats: HashMap<String, TaskStats>,
    /// Every solution request, in order.
    requests: Vec<RequestTime>,
    /// The last request that found no solution.
    last_failure: Option<TaskFailure>,
    /// The HTN search's deadline, passed to every GTP call.
    deadline: Option<std::time::Instant>,
}

impl GtpOracle {
    /// An oracle over `world`. `known` lists the names of the HTN problem's objects and the
    /// domain's constants.
    pub fn new(
        planner: Arc<Planner>,
        world: World,
        known: impl IntoIterator<Item = String>,
        config: OracleConfig,
    ) -> GtpOracle {
        let known: HashSet<String> = known.into_iter().map(|s| s.to_ascii_lowercase()).collect();
        // Levels above the threshold never hold symbolically: don't examine them.
        let mut config = config;
        config.facts.max_effort = config.facts.max_effort.min(config.effort_threshold);
        let mut oracle = GtpOracle {
            planner,
            config,
            known,
            stack: Vec::new(),
            solutions: Vec::new(),
            streams: HashMap::new(),
            next_stream: 0,
            memo: StreamMemo::default(),
            stats: HashMap::new(),
            requests: Vec::new(),
            last_failure: None,
            deadline: None,
        };
        let frame = oracle.frame(world);
        oracle.stack.push(frame);
        oracle
    }

    /// The current world (after every applied solution).
    pub fn world(&self) -> &World {
        &self.stack[self.stack.len() - 1].world
    }

    /// The world solution `id` led to (`None` for an id this oracle did not give out).
    pub fn solution_world(&self, id: SolutionId) -> Option<&World> {
        self.given(id).map(|g| &g.frame.world)
    }

    /// What the GTP did in solution `id`: grasp, placement, visibility, trajectories.
    pub fn solution_summary(&self, id: SolutionId) -> Option<&SolutionSummary> {
        self.given(id).map(|g| &g.summary)
    }

    fn given(&self, id: SolutionId) -> Option<&Given> {
        self.solutions.get(usize::try_from(id.0).ok()?)
    }

    /// The geometric task planner answering the predicates.
    pub fn planner(&self) -> &Planner {
        &self.planner
    }

    /// The last geometric task that found no (further) solution: its arguments, why, and the
    /// constraint that stopped it.
    pub fn last_failure(&self) -> Option<&TaskFailure> {
        self.last_failure.as_ref()
    }

    /// The shared literals of the initial world.
    pub fn initial_literals(&self) -> Vec<GroundAtom> {
        self.stack[0].facts.iter().cloned().collect()
    }

    /// The shared literals of the current world.
    pub fn current_facts(&self) -> &BTreeSet<GroundAtom> {
        &self.stack[self.stack.len() - 1].facts
    }

    /// Table II figures per geometric task.
    pub fn task_stats(&self) -> &HashMap<String, TaskStats> {
        &self.stats
    }

    /// Every solution request so far, in order, with its time.
    pub fn requests(&self) -> &[RequestTime] {
        &self.requests
    }

    /// Requests answered from the memo, without a GTP call: a solution given out before in
    /// the same world, or the end of its stream (`stream_memo.rs`).
    pub fn replays(&self) -> u64 {
        self.memo.replays
    }

    /// The symbolic shared literals of `world`.
    pub fn literals(&self, world: &World) -> BTreeSet<GroundAtom> {
        shared_literals(world, &self.config.facts)
            .into_iter()
            .filter(|f| match (f.predicate.as_str(), f.effort) {
                ("visible" | "reachable", Some(e)) => e <= self.config.effort_threshold,
                ("visible" | "reachable", None) => false,
                _ => true,
            })
            .filter(|f| f.args.iter().all(|a| self.known.contains(a)))
            .map(|f| GroundAtom {
                predicate: f.predicate,
                args: f.args,
            })
            .collect()
    }

    fn frame(&self, world: World) -> Frame {
        let facts = Arc::new(self.literals(&world));
        // Two worlds that differ in geometry only are told apart by the HTN search.
        let fingerprint = world.fingerprint(Precision::Millimetre);
        let exact = world.fingerprint(Precision::Exact);
        Frame {
            world,
            facts,
            fingerprint,
            exact,
        }
    }

    fn call_options(&self, task: &str, args: &[String]) -> CallOptions {
        // Seeded by the task the GTP runs: a compound task of the paper (`pick-and-put-away`)
        // and the task that answers it (`put-away`) are the same call.
        let task = gtp::task::TaskKind::from_name(task).map_or(task, |k| k.name());
        let mut h = std::collections::hash_map::DefaultHasher::new();
        (task, args, self.stack[self.stack.len() - 1].fingerprint).hash(&mut h);
        CallOptions {
            seed: self.config.seed ^ h.finish(),
            constraints: self.config.constraints.clone(),
            deadline: self.deadline,
        }
    }

    fn run(
        &self,
        world: &World,
        task: &str,
        args: &[String],
    ) -> Result<SolutionStream, OracleError> {
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let options = self.call_options(task, args);
        self.planner
            .run(world, task, &refs, &options)
            .map_err(|e| OracleError(format!("{task}({}): {e}", args.join(", "))))
    }

    /// The GTP's stream of `request`, past the solutions the memo holds: the parked one, or
    /// the request asked again from its start (its first solutions, given before, dropped).
    fn live_stream(&mut self, request: &Request) -> Result<SolutionStream, OracleError> {
        if let Some(s) = self.memo.unpark(request) {
            return Ok(s);
        }
        let world = self.world().clone();
        let mut s = self.run(&world, &request.task, &request.args)?;
        for _ in 0..self.memo.given(request) {
            s.next();
        }
        Ok(s)
    }

    /// Asks the GTP for the next solution of `request`, with the statistics of that request;
    /// the memo records it.
    fn pull(&mut self, request: &Request) -> Result<Pulled, OracleError> {
        let mut gtp = self.live_stream(request)?;
        let before = gtp.stats();
        let solution = gtp.next();
        let delta = gtp.stats().since(&before);
        let end = End {
            failure: gtp.failure().map(|f| f.to_string()),
            stage: gtp.failure().map(|f| f.stage),
        };
        if solution.is_some() {
            self.memo.park(request, gtp);
        } else {
            self.memo.end(request, end.clone());
        }
        Ok(Pulled {
            solution,
            delta,
            end,
        })
    }

    /// Records a request that found no (further) solution as the last failure.
    fn note_failure(&mut self, request: &Request, end: End) {
        let why = end.failure.unwrap_or_else(|| "no further solution".into());
        let s = self.stats.entry(request.task.clone()).or_default();
        s.last_failure = Some(why.clone());
        self.last_failure = Some(TaskFailure {
            task: request.task.clone(),
            args: request.args.clone(),
            why,
            stage: end.stage,
        });
    }

    /// The next solution of `request` as the memo gives it back, when it has it.
    fn replay(&mut self, request: &Request, pos: usize) -> Option<Option<GeoSolution>> {
        let known = match self.memo.known(request, pos) {
            Known::Solution(s) => Some(s),
            Known::End(end) => {
                self.note_failure(request, end);
                None
            }
            Known::Unknown => return None,
        };
        if self.config.trace {
            eprintln!(
                "[gtp] {}({}) -> {} (read back: asked before in this world)",
                request.task,
                request.args.join(", "),
                if known.is_some() { "solution" } else { "none" },
            );
        }
        Some(known)
    }

    /// Asks the GTP for the next solution of `request`: the solution with its add and delete
    /// lists, timed and traced, or `None` with the reason recorded as the last failure.
    fn ask(&mut self, request: &Request) -> Result<Option<GeoSolution>, OracleError> {
        let Pulled {
            solution,
            delta,
            end,
        } = self.pull(request)?;
        let (task, args) = (request.task.clone(), request.args.clone());
        let t0 = Instant::now();
        let result = match solution {
            None => None,
            Some(sol) => {
                let frame = self.frame(sol.world);
                let before = self.current_facts();
                let add = frame.facts.difference(before).cloned().collect();
                let delete = before.difference(&frame.facts).cloned().collect();
                let id = SolutionId(self.solutions.len() as u64);
                self.solutions.push(Given {
                    frame,
                    summary: sol.summary,
                });
                let given = GeoSolution { add, delete, id };
                self.memo.push(request, given.clone());
                Some(given)
            }
        };
        let facts_time_s = t0.elapsed().as_secs_f64();
        self.requests.push(RequestTime {
            task: task.clone(),
            args: args.clone(),
            solved: result.is_some(),
            stage: end
                .stage
                .filter(|_| result.is_none())
                .map(|s| s.name().to_string()),
            facts_time_s,
            search: delta,
        });
        let s = self.stats.entry(task.clone()).or_default();
        s.record(&delta, result.is_some(), facts_time_s);
        if self.config.trace {
            let lists = result
                .as_ref()
                .map(|r| {
                    let show = |sign: char, atoms: &[GroundAtom]| -> String {
                        atoms.iter().map(|a| format!(" {sign}{a}")).collect()
                    };
                    format!("{}{}", show('+', &r.add), show('-', &r.delete))
                })
                .unwrap_or_default();
            eprintln!(
                "[gtp] {task}({}) -> {} in {:.1} ms (+{:.1} ms facts){}{lists}",
                args.join(", "),
                if result.is_some() { "solution" } else { "none" },
                delta.time_s * 1e3,
                t0.elapsed().as_secs_f64() * 1e3,
                end.failure
                    .as_ref()
                    .map(|f| format!(": {f}"))
                    .unwrap_or_default()
            );
        }
        if result.is_none() {
            self.note_failure(request, end);
        }
        Ok(result)
    }
}

impl GeometricOracle for GtpOracle {
    fn initial_facts(&mut self) -> Result<Vec<GroundAtom>, OracleError> {
        Ok(self.initial_literals())
    }

    fn open(&mut self, task: &str, args: &[String]) -> Result<StreamId, OracleError> {
        let request = Request {
            task: task.to_string(),
            args: args.to_vec(),
            world: self.stack[self.stack.len() - 1].exact,
        };
        if !self.memo.contains(&request) {
            let world = self.world().clone();
            let gtp = self.run(&world, task, args)?;
            self.memo.park(&request, gtp);
        }
        let id = self.next_stream;
        self.next_stream += 1;
        self.streams.insert(id, Stream { request, pos: 0 });
        Ok(StreamId(id))
    }

    fn next_solution(&mut self, stream: StreamId) -> Result<Option<GeoSolution>, OracleError> {
        let (request, pos) = self
            .streams
            .get(&stream.0)
            .map(|s| (s.request.clone(), s.pos))
            .ok_or_else(|| OracleError(format!("unknown stream {}", stream.0)))?;
        let result = match self.replay(&request, pos) {
            Some(known) => known,
            None => self.ask(&request)?,
        };
        if result.is_some()
            && let Some(s) = self.streams.get_mut(&stream.0)
        {
            s.pos += 1;
        }
        Ok(result)
    }

    fn close(&mut self, stream: StreamId) {
        self.streams.remove(&stream.0);
    }

    fn apply(&mut self, id: SolutionId) -> Result<(), OracleError> {
        let frame = self
            .given(id)
            .map(|g| g.frame.clone())
            .ok_or_else(|| OracleError(format!("solution {} was not given out here", id.0)))?;
        self.stack.push(frame);
        Ok(())
    }

    fn undo(&mut self) {
        if self.stack.len() > 1 {
            self.stack.pop();
        }
    }

    fn set_deadline(&mut self, deadline: Option<std::time::Instant>) {
        self.deadline = deadline;
    }

    fn world_fingerprint(&self) -> u64 {
        self.stack[self.stack.len() - 1].fingerprint
    }
}
