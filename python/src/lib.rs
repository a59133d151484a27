//! `htngtp._native`: the Rust half of the Python package `htngtp`.
//!
//! A thin layer over the workspace crates' public API: `geometry` (worlds, shared literals,
//! pictures), `gtp` (one geometric task call), `hybrid` (combined HTN-GTP planning and the plan
//! JSON), `htn` (HDDL parsing, symbolic planning, the validator) and `check` (the independent
//! re-check of a plan JSON). Structured results cross as JSON text (parsed by the pure-Python
//! wrapper in `htngtp/__init__.py`) and trajectories as numpy arrays; errors are raised as the
//! typed exceptions of `htngtp/errors.py`. The GIL is released while Rust plans.

use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use geometry::effort::aim_head;
use geometry::facts::{FactParams, effort_table, relations};
use geometry::render::{Camera, agent_camera, render};
use geometry::scene::AgentKind;
use gtp::planner::{CallOptions, Planner};
use htn::planner::{Limit, Limits, Outcome, PlanError, PlannerOptions, Strategy};
use hybrid::export::{TimingOptions, joint_limits, joint_positions};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::{Value, json};

/// The longest time limit accepted, seconds (a year), as the command line's.
const MAX_SECONDS: f64 = 365.0 * 24.0 * 3600.0;

/// Builds an exception of `htngtp.errors` (`name`) from `args`.
fn error<'py>(py: Python<'py>, name: &str, args: impl pyo3::call::PyCallArgs<'py>) -> PyErr {
    match py
        .import("htngtp.errors")
        .and_then(|m| m.getattr(name))
        .and_then(|cls| cls.call1(args))
    {
        Ok(e) => PyErr::from_value(e),
        Err(e) => e,
    }
}

/// An `htn` parse error as `htngtp.ParseError(message, file, line, column)`.
fn parse_error(py: Python<'_>, e: &htn::ParseError) -> PyErr {
    error(
        py,
        "ParseError",
        (e.to_string(), e.file.display().to_string(), e.line, e.col),
    )
}

/// A scene error as `htngtp.SceneError(message)`.
fn scene_error(py: Python<'_>, e: &geometry::scene::SceneError) -> PyErr {
    error(py, "SceneError", (e.to_string(),))
}

/// A seconds value as a `Duration`, refusing what the command line refuses.
fn seconds(what: &str, s: f64) -> PyResult<Duration> {
    if s > 0.0 && s <= MAX_SECONDS {
        Ok(Duration::from_secs_f64(s))
    } else {
        Err(PyValueError::new_err(format!(
            "{what} must be a number of seconds above 0 and at most {MAX_SECONDS} (a year), got {s}"
        )))
    }
}

/// A 3D world: a scene's objects and agents in their current poses.
#[pyclass(name = "World", module = "htngtp._native", frozen)]
#[derive(Clone)]
pub struct PyWorld {
    world: geometry::world::World,
}

#[pymethods]
impl PyWorld {
    /// Loads a scene file (TOML, docs/scene-format.md). Raises `htngtp.SceneError` when the
    /// scene is invalid (the message names the file and key path).
    #[staticmethod]
    #[pyo3(signature = (path, allow_initial_contact = false))]
    fn load(py: Python<'_>, path: PathBuf, allow_initial_contact: bool) -> PyResult<PyWorld> {
        let loaded = py.detach(|| {
            if allow_initial_contact {
                geometry::world::World::load_allowing_contact(&path).map(|(w, _)| w)
            } else {
                geometry::world::World::load(&path)
            }
        });
        loaded
            .map(|world| PyWorld { world })
            .map_err(|e| scene_error(py, &e))
    }

    /// The scene's objects' names, in scene order.
    fn objects(&self) -> Vec<String> {
        let w = &self.world;
        w.object_ids().map(|o| w.object(o).name.clone()).collect()
    }

    /// Whether the object `name` is movable.
    fn movable(&self, name: &str) -> PyResult<bool> {
        let o = self.object(name)?;
        Ok(self.world.object(o).movable)
    }

    /// The agents' names, in scene order.
    fn agents(&self) -> Vec<String> {
        let w = &self.world;
        w.agent_ids()
            .map(|a| w.agent(a).name().to_string())
            .collect()
    }

    /// The kind of agent `name`: "robot" or "human".
    fn agent_kind(&self, name: &str) -> PyResult<&'static str> {
        let a = self.agent(name)?;
        Ok(match self.world.agent(a).kind() {
            AgentKind::Robot => "robot",
            AgentKind::Human => "human",
        })
    }

    /// The pose of object `name`: `([x, y, z], [qx, qy, qz, qw])` in the world frame.
    fn object_pose(&self, name: &str) -> PyResult<([f32; 3], [f32; 4])> {
        let o = self.object(name)?;
        let p = self.world.object_pose(o);
        Ok(pose_parts(p))
    }

    /// The base pose of agent `name`: `([x, y, z], [qx, qy, qz, qw])` in the world frame.
    fn agent_pose(&self, name: &str) -> PyResult<([f32; 3], [f32; 4])> {
        let a = self.agent(name)?;
        Ok(pose_parts(self.world.agent_state(a).base))
    }

    /// Every joint value of agent `name` by joint name, the planar base's `base_x`, `base_y`
    /// and `base_yaw` included.
    fn joint_positions(&self, name: &str) -> PyResult<Vec<(String, f64)>> {
        let a = self.agent(name)?;
        Ok(joint_positions(&self.world, a).into_iter().collect())
    }

    /// The object `name` is attached to, as `(agent, link)`, when an agent holds it.
    fn holder(&self, name: &str) -> PyResult<Option<(String, String)>> {
        let o = self.object(name)?;
        let w = &self.world;
        Ok(w.attachment(o).map(|at| {
            let agent = w.agent(at.agent);
            let link = agent
                .model
                .links()
                .get(at.link)
                .map(|l| l.name.clone())
                .unwrap_or_default();
            (agent.name().to_string(), link)
        }))
    }

    /// The shared literals of the world as JSON text: a list of `{predicate, args, effort}`
    /// (visible and reachable with the least effort level, then on / inside / covered-by), as
    /// `htngtp facts --json`.
    #[pyo3(signature = (threshold = 0.5, resolution = 64))]
    fn facts_json(&self, py: Python<'_>, threshold: f32, resolution: usize) -> PyResult<String> {
        if !(threshold > 0.0 && threshold <= 1.0) {
            return Err(PyValueError::new_err(format!(
                "threshold must be in (0, 1], got {threshold}"
            )));
        }
        if !(1..=1024).contains(&resolution) {
            return Err(PyValueError::new_err(format!(
                "resolution must be between 1 and 1024, got {resolution}"
            )));
        }
        let world = &self.world;
        let out = py.detach(|| {
            let params = FactParams {
                vis_threshold: threshold,
                resolution,
                ..FactParams::default()
            };
            let mut out = Vec::new();
            for t in effort_table(world, None, &params) {
                for (o, vis, reach) in &t.objects {
                    for (predicate, e) in [("visible", vis), ("reachable", reach)] {
                        if e.is_some() {
                            out.push(
                                json!({"predicate": predicate, "args": [o, t.agent], "effort": e}),
                            );
                        }
                    }
                }
            }
            for f in relations(world, &params) {
                out.push(json!({"predicate": f.predicate, "args": f.args, "effort": null}));
            }
            Value::Array(out).to_string()
        });
        Ok(out)
    }

    /// Draws the world into a PNG at `path`, as `htngtp render`: `view` is "top", "human" (the
    /// first human's eyes), "robot" (the first robot's camera) or an agent's name; `look_at`
    /// turns that agent's head towards an object first.
    #[pyo3(signature = (view, path, width = 800, height = None, look_at = None))]
    fn render(
        &self,
        py: Python<'_>,
        view: &str,
        path: PathBuf,
        width: usize,
        height: Option<usize>,
        look_at: Option<&str>,
    ) -> PyResult<()> {
        if width == 0 || width > 4096 || height.is_some_and(|h| h == 0 || h > 4096) {
            return Err(PyValueError::new_err(
                "width and height must be between 1 and 4096",
            ));
        }
        let mut world = self.world.clone();
        let by_kind = |kind: AgentKind| world.agent_ids().find(|&a| world.agent(a).kind() == kind);
        let agent = match view {
            "top" => None,
            "human" => Some(
                by_kind(AgentKind::Human)
                    .ok_or_else(|| PyValueError::new_err("the scene has no human agent"))?,
            ),
            "robot" => Some(
                by_kind(AgentKind::Robot)
                    .ok_or_else(|| PyValueError::new_err("the scene has no robot agent"))?,
            ),
            name => Some(world.agent_id(name).ok_or_else(|| {
                PyValueError::new_err(format!(
                    "unknown view `{name}`: expected human, robot, top or an agent name ({})",
                    self.agents().join(", ")
                ))
            })?),
        };
        if let Some(name) = look_at {
            let a = agent.ok_or_else(|| {
                PyValueError::new_err("look_at needs an agent's view (human, robot or a name)")
            })?;
            let o = self.object(name)?;
            let st = world.agent_state(a).clone();
            let mut q = st.q.clone();
            aim_head(&world, a, st.base, &mut q, world.object_aabb(o).center());
            world.set_agent_config(a, st.base, &q);
        }
        let (camera, height) = match agent {
            Some(a) => {
                let fov = world.agent(a).fov;
                let aspect = (0.5 * fov[0]).tan() / (0.5 * fov[1]).tan();
                let h = height.unwrap_or(((width as f32 / aspect).round() as usize).max(1));
                (agent_camera(&world, a), h)
            }
            None => {
                let h = height.unwrap_or(width);
                (Camera::top(&world.bounds(), width as f32 / h as f32), h)
            }
        };
        py.detach(|| render(&world, &camera, width, height).save_png(&path))
            .map_err(|e| PyValueError::new_err(format!("writing {}: {e}", path.display())))
    }

    fn __repr__(&self) -> String {
        format!(
            "World(scene={:?}, {} objects, {} agents)",
            self.world.scene().name,
            self.world.object_count(),
            self.world.agent_count()
        )
    }
}

impl PyWorld {
    fn object(&self, name: &str) -> PyResult<geometry::scene::ObjectId> {
        self.world
            .object_id(name)
            .ok_or_else(|| PyValueError::new_err(format!("no object `{name}` in the world")))
    }

    fn agent(&self, name: &str) -> PyResult<geometry::scene::AgentId> {
        self.world
            .agent_id(name)
            .ok_or_else(|| PyValueError::new_err(format!("no agent `{name}` in the world")))
    }
}

fn pose_parts(p: parry3d::math::Pose) -> ([f32; 3], [f32; 4]) {
    let (t, q) = (p.translation, p.rotation);
    ([t.x, t.y, t.z], [q.x, q.y, q.z, q.w])
}

/// The process-wide geometric task planner of `gtp` calls: it caches each scene's robot set-up
/// (grasps, arm chains), so repeated calls on one scene do not rebuild it.
fn shared_planner() -> &'static Planner {
    static PLANNER: OnceLock<Planner> = OnceLock::new();
    PLANNER.get_or_init(Planner::new)
}

/// One timed trajectory of a solution, as numpy arrays.
struct TimedTrajectory {
    agent: String,
    group: String,
    phase: String,
    holding: Option<String>,
    joint_names: Vec<String>,
    velocity_limits: Vec<f64>,
    acceleration_limits: Vec<f64>,
    waypoints: Array2<f64>,
    positions: Array2<f64>,
    velocities: Array2<f64>,
    time_from_start: Array1<f64>,
}

/// Rows of equal length as a (rows, width) array.
fn rows(rows: Vec<Vec<f64>>, width: usize) -> PyResult<Array2<f64>> {
    let n = rows.len();
    let flat: Vec<f64> = rows.into_iter().flatten().collect();
    Array2::from_shape_vec((n, width), flat)
        .map_err(|e| PyValueError::new_err(format!("ragged trajectory: {e}")))
}

/// Times the trajectories of a GTP solution within the joints' limits, as the plan JSON's
/// `joint_trajectory` does (rest to rest, `hybrid::timing`).
fn timed(
    world: &geometry::world::World,
    summary: &gtp::solution::SolutionSummary,
    opts: &TimingOptions,
) -> PyResult<Vec<TimedTrajectory>> {
    let mut out = Vec::new();
    for t in &summary.trajectories {
        let agent = world.agent_id(&t.agent).ok_or_else(|| {
            PyValueError::new_err(format!("trajectory of unknown agent `{}`", t.agent))
        })?;
        let model = &world.agent(agent).model;
        let (velocity, acceleration): (Vec<f64>, Vec<f64>) = t
            .joints
            .iter()
            .map(|j| joint_limits(model, j, opts))
            .unzip();
        let waypoints: Vec<Vec<f64>> = t
            .waypoints
            .iter()
            .map(|w| w.iter().map(|&x| f64::from(x)).collect())
            .collect();
        let points =
            hybrid::timing::time_path(&waypoints, &velocity, &acceleration).map_err(|e| {
                PyValueError::new_err(format!("timing the {:?} trajectory: {e}", t.phase))
            })?;
        let dof = t.joints.len();
        let times = points.iter().map(|p| p.time).collect::<Vec<_>>();
        let (positions, velocities): (Vec<Vec<f64>>, Vec<Vec<f64>>) = points
            .into_iter()
            .map(|p| (p.positions, p.velocities))
            .unzip();
        let phase = serde_json::to_value(t.phase)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_else(|| format!("{:?}", t.phase));
        out.push(TimedTrajectory {
            agent: t.agent.clone(),
            group: t.arm.clone(),
            phase,
            holding: t.held.as_ref().map(|h| h.object.clone()),
            joint_names: t.joints.clone(),
            velocity_limits: velocity,
            acceleration_limits: acceleration,
            waypoints: rows(waypoints, dof)?,
            positions: rows(positions, dof)?,
            velocities: rows(velocities, dof)?,
            time_from_start: Array1::from(times),
        });
    }
    Ok(out)
}

impl TimedTrajectory {
    fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("agent", self.agent)?;
        d.set_item("group", self.group)?;
        d.set_item("phase", self.phase)?;
        d.set_item("holding", self.holding)?;
        d.set_item("joint_names", self.joint_names)?;
        d.set_item("velocity_limits", self.velocity_limits)?;
        d.set_item("acceleration_limits", self.acceleration_limits)?;
        let waypoints: Bound<'_, PyArray2<f64>> = self.waypoints.into_pyarray(py);
        let positions: Bound<'_, PyArray2<f64>> = self.positions.into_pyarray(py);
        let velocities: Bound<'_, PyArray2<f64>> = self.velocities.into_pyarray(py);
        let times: Bound<'_, PyArray1<f64>> = self.time_from_start.into_pyarray(py);
        d.set_item("waypoints", waypoints)?;
        d.set_item("positions", positions)?;
        d.set_item("velocities", velocities)?;
        d.set_item("time_from_start", times)?;
        Ok(d)
    }
}

/// The solutions of one GTP call, before they become Python objects.
struct GtpOutput {
    solutions: Vec<(
        gtp::planner::Solution,
        gtp::stats::Stats,
        Vec<TimedTrajectory>,
    )>,
    stats: gtp::stats::Stats,
    failure: Option<gtp::planner::Failure>,
}

/// Runs task `task` on `world` and pulls up to `solutions` solutions, timing their
/// trajectories. The whole call, in Rust.
fn run_gtp(
    world: &geometry::world::World,
    task: &str,
    args: &[String],
    options: &CallOptions,
    solutions: usize,
    timing: &TimingOptions,
) -> Result<PyResult<GtpOutput>, gtp::planner::GtpError> {
    let names: Vec<&str> = args.iter().map(String::as_str).collect();
    let mut stream = shared_planner().run(world, task, &names, options)?;
    let mut out = Vec::new();
    for _ in 0..solutions {
        let before = stream.stats();
        let Some(s) = stream.next() else { break };
        let stats = stream.stats().since(&before);
        let trajectories = match timed(world, &s.summary, timing) {
            Ok(t) => t,
            Err(e) => return Ok(Err(e)),
        };
        out.push((s, stats, trajectories));
    }
    let failure = if out.len() < solutions {
        stream.failure().cloned()
    } else {
        None
    };
    Ok(Ok(GtpOutput {
        solutions: out,
        stats: stream.stats(),
        failure,
    }))
}

/// The call options of a `gtp` call: seed, threshold overrides, time limit.
fn call_options(
    seed: u64,
    settings: Vec<(String, String)>,
    time_limit: Option<f64>,
) -> PyResult<CallOptions> {
    let mut options = CallOptions::seeded(seed);
    for (k, v) in &settings {
        options = options.with(k.trim(), v.trim());
    }
    if let Some(s) = time_limit {
        options.deadline = Some(Instant::now() + seconds("time_limit", s)?);
    }
    Ok(options)
}

/// One geometric task call: returns a dict with `solutions` (each `summary` and `stats` as
/// JSON text, `world` after it, `trajectories` with numpy arrays), `stats` (JSON text, the
/// whole call) and `failure` (JSON text or None: why the stream ended before `solutions`).
/// Raises ValueError for an unknown task, wrong arguments or a bad setting.
#[pyfunction]
#[pyo3(signature = (world, task, args, seed = 1, solutions = 1, settings = Vec::new(), time_limit = None, max_acceleration = hybrid::timing::DEFAULT_JOINT_ACCELERATION))]
#[pyo3(name = "gtp")]
#[allow(clippy::too_many_arguments)]
fn gtp_call<'py>(
    py: Python<'py>,
    world: &PyWorld,
    task: &str,
    args: Vec<String>,
    seed: u64,
    solutions: usize,
    settings: Vec<(String, String)>,
    time_limit: Option<f64>,
    max_acceleration: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let options = call_options(seed, settings, time_limit)?;
    let timing = timing_options(max_acceleration)?;
    let w = &world.world;
    let out = py
        .detach(|| run_gtp(w, task, &args, &options, solutions, &timing))
        .map_err(|e| PyValueError::new_err(e.to_string()))??;
    let d = PyDict::new(py);
    let list = PyList::empty(py);
    for (s, stats, trajectories) in out.solutions {
        let sd = PyDict::new(py);
        sd.set_item("summary", summary_json(&s.summary)?)?;
        sd.set_item("stats", to_json(&stats)?)?;
        sd.set_item("world", PyWorld { world: s.world })?;
        let ts = PyList::empty(py);
        for t in trajectories {
            ts.append(t.into_dict(py)?)?;
        }
        sd.set_item("trajectories", ts)?;
        list.append(sd)?;
    }
    d.set_item("solutions", list)?;
    d.set_item("stats", to_json(&out.stats)?)?;
    d.set_item("failure", out.failure.as_ref().map(to_json).transpose()?)?;
    Ok(d)
}

/// The same call as [`gtp_call`] entirely in Rust, timed: the seconds from the request to the last
/// solution's timed trajectories, with no Python object made. `python/bench/overhead.py`
/// compares it with the Python call.
#[pyfunction]
#[pyo3(signature = (world, task, args, seed = 1, solutions = 1, settings = Vec::new()))]
fn gtp_rust_seconds(
    py: Python<'_>,
    world: &PyWorld,
    task: &str,
    args: Vec<String>,
    seed: u64,
    solutions: usize,
    settings: Vec<(String, String)>,
) -> PyResult<(f64, usize)> {
    let options = call_options(seed, settings, None)?;
    let timing = TimingOptions::default();
    let w = &world.world;
    py.detach(|| {
        let began = Instant::now();
        let out = run_gtp(w, task, &args, &options, solutions, &timing)
            .map_err(|e| PyValueError::new_err(e.to_string()))??;
        Ok((began.elapsed().as_secs_f64(), out.solutions.len()))
    })
}

/// A solution's summary as JSON text, without the trajectories' waypoints: they come as numpy
/// arrays beside it (parsing them from JSON was most of the Python layer's cost).
fn summary_json(summary: &gtp::solution::SolutionSummary) -> PyResult<String> {
    let mut v = serde_json::to_value(summary).map_err(|e| PyValueError::new_err(e.to_string()))?;
    if let Some(ts) = v.get_mut("trajectories").and_then(Value::as_array_mut) {
        for t in ts.iter_mut().filter_map(Value::as_object_mut) {
            t.remove("waypoints");
        }
    }
    Ok(v.to_string())
}

fn to_json(v: &impl serde::Serialize) -> PyResult<String> {
    serde_json::to_string(v).map_err(|e| PyValueError::new_err(e.to_string()))
}

fn timing_options(max_acceleration: f64) -> PyResult<TimingOptions> {
    if !(max_acceleration > 0.0 && max_acceleration <= 1000.0) {
        return Err(PyValueError::new_err(format!(
            "max_acceleration must be above 0 and at most 1000, got {max_acceleration}"
        )));
    }
    Ok(TimingOptions {
        joint_acceleration: max_acceleration,
    })
}

/// What stopped a plan call, for the Python exceptions.
enum Stopped {
    Parse(htn::ParseError),
    Scene(geometry::scene::SceneError),
    Limit(Limit, String, Value),
    Unsolvable(String, Value),
    Other(String),
}

impl Stopped {
    fn into_py(self, py: Python<'_>) -> PyErr {
        match self {
            Stopped::Parse(e) => parse_error(py, &e),
            Stopped::Scene(e) => scene_error(py, &e),
            Stopped::Limit(limit, message, stats) => error(
                py,
                "LimitReached",
                (
                    message,
                    serde_json::to_value(limit)
                        .ok()
                        .and_then(|v| v.as_str().map(str::to_string))
                        .unwrap_or_default(),
                    stats.to_string(),
                ),
            ),
            Stopped::Unsolvable(message, stats) => {
                error(py, "Unsolvable", (message, stats.to_string()))
            }
            Stopped::Other(m) => PyValueError::new_err(m),
        }
    }
}

/// A plan error of the HTN planner as what stopped the call.
fn plan_error(e: PlanError) -> Stopped {
    match e {
        PlanError::Stopped(limit) => Stopped::Limit(limit, e.to_string(), Value::Null),
        e => Stopped::Other(e.to_string()),
    }
}

/// Everything `plan` needs, read from Python's arguments.
struct PlanRequest {
    domain: PathBuf,
    problem: PathBuf,
    scene: Option<PathBuf>,
    allow_initial_contact: bool,
    options: PlannerOptions,
    time_limit: Duration,
    memory_mb: u64,
    timing: TimingOptions,
}

/// Stats of a symbolic run as the plan JSON's `stats`.
fn search_stats(s: &htn::planner::SearchStats) -> Value {
    json!({
        "nodes": s.nodes,
        "htn_backtracks": s.htn_backtracks,
        "gtp_backtracks": s.geo_backtracks,
        "time_ms": s.time_s * 1e3,
        "peak_memory_kb": s.peak_memory_kb,
    })
}

/// The plan JSON of a symbolic plan (no scene): the layout of docs/plan-json.md with `scene`
/// null, no `gtp` parts, and the plan in the competition format as `plan_text`.
fn symbolic_json(domain: &str, problem: &str, plan: &htn::plan::Plan, stats: Value) -> Value {
    let mut tree = Vec::new();
    for d in &plan.decompositions {
        tree.push(json!({ "id": d.id, "task": d.task, "args": d.args, "method": d.method, "children": d.subtasks }));
    }
    let mut steps = Vec::new();
    for (i, a) in plan.actions.iter().enumerate() {
        tree.push(json!({ "id": a.id, "action": a.name, "args": a.args, "step": i }));
        steps.push(json!({
            "index": i, "id": a.id, "action": a.name, "args": a.args,
            "added": [], "deleted": [], "gtp": null, "object_poses": {},
        }));
    }
    json!({
        "format": "htngtp-plan",
        "version": 1,
        "domain": domain,
        "problem": problem,
        "status": "solved",
        "message": null,
        "scene": null,
        "initial_literals": [],
        "tree": tree,
        "root": plan.root,
        "steps": steps,
        "stats": stats,
        "plan_text": plan.to_competition_format(),
    })
}

/// Runs a plan request (without the GIL): the plan JSON text of the plan found, or why none.
fn run_plan(req: PlanRequest) -> Result<String, Stopped> {
    // The budget of reading and parsing is process-wide (`htn::budget`): one plan call at a
    // time, so that calls from several Python threads do not overwrite each other's limits.
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _turn = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let began = Instant::now();
    // The limits cover reading and parsing, as on the command line.
    htn::budget::set(began.checked_add(req.time_limit), Some(req.memory_mb));
    let result = plan_within_budget(&req, began);
    htn::budget::set(None, None);
    result
}

fn plan_within_budget(req: &PlanRequest, began: Instant) -> Result<String, Stopped> {
    let domain = htn::load_domain(&req.domain).map_err(Stopped::Parse)?;
    let problem = htn::load_problem(&req.problem, &domain).map_err(Stopped::Parse)?;
    let mut options = req.options;
    options.limits.time = Some(req.time_limit.saturating_sub(began.elapsed()));
    let Some(scene) = &req.scene else {
        let result = htn::planner::plan(&domain, &problem, &options, None).map_err(plan_error)?;
        let stats = search_stats(&result.stats);
        return match &result.outcome {
            Outcome::Found { plan } => {
                htn::validate::validate(&domain, &problem, plan, &[]).map_err(|e| {
                    Stopped::Other(format!("the plan found does not validate: {}", e.0))
                })?;
                Ok(symbolic_json(&domain.name, &problem.name, plan, stats).to_string())
            }
            Outcome::Unsolvable => Err(Stopped::Unsolvable(
                "no plan exists (the whole search space was explored)".into(),
                stats,
            )),
            Outcome::LimitReached { limit } => Err(Stopped::Limit(
                *limit,
                format!("stopped: {limit} reached"),
                stats,
            )),
        };
    };
    let world = if req.allow_initial_contact {
        geometry::world::World::load_allowing_contact(scene).map(|(w, _)| w)
    } else {
        geometry::world::World::load(scene)
    }
    .map_err(Stopped::Scene)?;
    options.limits.time = Some(req.time_limit.saturating_sub(began.elapsed()));
    let run_options = hybrid::RunOptions {
        planner: options,
        oracle: hybrid::OracleConfig {
            seed: options.seed,
            ..hybrid::OracleConfig::default()
        },
    };
    let run = hybrid::plan(
        &domain,
        &problem,
        world,
        std::sync::Arc::new(Planner::new()),
        &run_options,
    )
    .map_err(|e| match e {
        hybrid::HybridError::Parse(e) => Stopped::Parse(e),
        hybrid::HybridError::Scene(e) => Stopped::Scene(e),
        hybrid::HybridError::Plan(e) => plan_error(e),
        e => Stopped::Other(e.to_string()),
    })?;
    let mut json = hybrid::export::plan_json_with(&run, &domain.name, &problem.name, &req.timing);
    match &run.result.outcome {
        Outcome::Found { plan } => {
            json["plan_text"] = json!(plan.to_competition_format());
            Ok(json.to_string())
        }
        Outcome::Unsolvable => Err(Stopped::Unsolvable(
            run.failure_message(),
            json["stats"].clone(),
        )),
        Outcome::LimitReached { limit } => Err(Stopped::Limit(
            *limit,
            format!("stopped by the {limit}; {}", run.failure_message()),
            json["stats"].clone(),
        )),
    }
}

/// Plans `problem` of `domain` (HDDL files), with the geometric tasks answered in `scene` when
/// given; returns the plan JSON text (docs/plan-json.md; without a scene, `scene` is null), with
/// the plan in the competition format as `plan_text`. The plan has passed the validator. Raises
/// `htngtp.ParseError`, `htngtp.SceneError`, `htngtp.LimitReached` or `htngtp.Unsolvable`.
#[pyfunction]
#[pyo3(signature = (domain, problem, scene = None, strategy = "chronological", geo_k = 3, seed = 0, time_limit = 300.0, node_limit = None, memory_limit = 8192, max_acceleration = hybrid::timing::DEFAULT_JOINT_ACCELERATION, allow_initial_contact = false))]
#[pyo3(name = "plan")]
#[allow(clippy::too_many_arguments)]
fn plan_call(
    py: Python<'_>,
    domain: PathBuf,
    problem: PathBuf,
    scene: Option<PathBuf>,
    strategy: &str,
    geo_k: usize,
    seed: u64,
    time_limit: f64,
    node_limit: Option<u64>,
    memory_limit: u64,
    max_acceleration: f64,
    allow_initial_contact: bool,
) -> PyResult<String> {
    let (strategy, discrepancy_rounds) = match strategy {
        "symbolic" => (Strategy::Symbolic, true),
        "chronological" => (Strategy::Chronological, true),
        "plain-chronological" | "plain_chronological" => (Strategy::Chronological, false),
        "geometric-first" | "geometric_first" => (Strategy::GeometricFirst { k: geo_k }, true),
        other => {
            return Err(PyValueError::new_err(format!(
                "unknown strategy `{other}`: expected symbolic, chronological, \
                 plain-chronological or geometric-first"
            )));
        }
    };
    if memory_limit == 0 {
        return Err(PyValueError::new_err("memory_limit must be at least 1 MiB"));
    }
    let time_limit = seconds("time_limit", time_limit)?;
    let req = PlanRequest {
        domain,
        problem,
        scene,
        allow_initial_contact,
        options: PlannerOptions {
            limits: Limits {
                time: Some(time_limit),
                nodes: node_limit,
                memory_mb: Some(memory_limit),
            },
            seed,
            strategy,
            discrepancy_rounds,
            ..PlannerOptions::default()
        },
        time_limit,
        memory_mb: memory_limit,
        timing: timing_options(max_acceleration)?,
    };
    py.detach(|| run_plan(req)).map_err(|s| s.into_py(py))
}

/// The independent re-check of a plan JSON (`htngtp check`): returns the report as JSON text
/// (`faults`, counts, the largest forward-kinematics error). Raises ValueError when the text is
/// not a plan JSON.
#[pyfunction]
#[pyo3(signature = (text, file = "<plan>"))]
fn check_plan_json(py: Python<'_>, text: &str, file: &str) -> PyResult<String> {
    py.detach(|| {
        let plan = check::parse_plan(text, file).map_err(|e| e.to_string())?;
        let report = check::check_plan(&plan, &check::Options::default());
        serde_json::to_string(&report).map_err(|e| e.to_string())
    })
    .map_err(PyValueError::new_err)
}

/// Validates a plan in the competition format against `domain` and `problem` (the `htn`
/// validator, names spelled as declared). Returns None when valid, else the first fault.
#[pyfunction]
fn validate_plan_text(
    py: Python<'_>,
    domain: PathBuf,
    problem: PathBuf,
    text: &str,
) -> PyResult<Option<String>> {
    let d = htn::load_domain(&domain).map_err(|e| parse_error(py, &e))?;
    let p = htn::load_problem(&problem, &d).map_err(|e| parse_error(py, &e))?;
    let plan = htn::plan::Plan::parse(text).map_err(|e| {
        PyValueError::new_err(format!("plan text:{}:{}: {}", e.line, e.col, e.message))
    })?;
    Ok(htn::validate::validate(&d, &p, &plan, &[])
        .err()
        .map(|f| f.0))
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyWorld>()?;
    m.add_function(wrap_pyfunction!(gtp_call, m)?)?;
    m.add_function(wrap_pyfunction!(gtp_rust_seconds, m)?)?;
    m.add_function(wrap_pyfunction!(plan_call, m)?)?;
    m.add_function(wrap_pyfunction!(check_plan_json, m)?)?;
    m.add_function(wrap_pyfunction!(validate_plan_text, m)?)?;
    m.add(
        "DEFAULT_JOINT_ACCELERATION",
        hybrid::timing::DEFAULT_JOINT_ACCELERATION,
    )?;
    Ok(())
}
