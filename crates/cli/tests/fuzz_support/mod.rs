//! The fuzz harness of the binary's inputs, shared by the bounded test
//! (`crates/cli/tests/fuzz_inputs.rs`, run by `.ci/run`) and the long run
//! (`cargo run --release -p htngtp --example fuzz_inputs -- --inputs 1000000`).
//!
//! Six kinds of input, each mutated from a corpus of real files and handed to the library entry
//! points the binary calls, in this process (fast):
//! - HDDL: domains (`parse_domain`) and problems (`parse_problem` against their parsed domain,
//!   then a short search, as `htngtp plan`, when the problem parses);
//! - scenes (TOML): `Scene::from_str`, then `World::from_scene` (URDF, initial collisions), as
//!   `htngtp facts/gtp/plan --scene` load them;
//! - plan files in the competition format: `Plan::parse`, then `validate_with`, exact and
//!   lenient, as `htngtp validate`;
//! - plan JSON: `check::parse_plan` then `check_plan` (as `htngtp check`), the viewer's loading
//!   check (`htngtp view`), and the plan JSON `htngtp validate` accepts;
//! - mesh files (STL, COLLADA, OBJ): `mesh_file::parse_mesh`, then the convex geometry a URDF
//!   link collides as (`convex::guarded_convex`), as a scene's robot loads them;
//! - SRDF files: read against their URDF's model (`AgentModel::with_srdf_str`).
//!
//! Every call runs under `catch_unwind`; a global counting allocator gives each input's peak
//! heap; a watchdog ends the run, writing the input out, when one input takes longer than
//! [`HANG_S`]. The corpus: `domains/`, `crates/*/tests` files, `viewer/fixtures`, `models/`, a
//! few meshes written here, and the shared benchmark folders, verdict corpus and robot
//! descriptions when `../shared` is present.

#![allow(dead_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use htn::model::{Domain, Problem, SourceName};

#[path = "../mesh_support/mod.rs"]
mod mesh_support;
mod mutate;
use mesh_support::{ascii_stl, binary_stl, box_triangles};
pub use mutate::mutate;

// ---------------------------------------------------------------------------------------------
// Memory: a counting allocator.

/// The system allocator, counting the bytes live and their peak since the last reset.
pub struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                let now = LIVE.fetch_add(new_size - layout.size(), Ordering::Relaxed) + new_size
                    - layout.size();
                PEAK.fetch_max(now, Ordering::Relaxed);
            } else {
                LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
        }
        p
    }
}

/// Starts measuring one input's peak heap; returns the bytes live now.
fn reset_peak() -> usize {
    let live = LIVE.load(Ordering::Relaxed);
    PEAK.store(live, Ordering::Relaxed);
    live
}

/// Peak heap above `base` since [`reset_peak`] (0 when no counting allocator is installed).
fn peak_above(base: usize) -> usize {
    PEAK.load(Ordering::Relaxed).saturating_sub(base)
}

// ---------------------------------------------------------------------------------------------
// Limits of one input.

/// An input running longer than this is a hang: the run stops and writes it out.
pub const HANG_S: u64 = 60;
/// An input slower than this is counted as over the time limit (the searches it starts have a
/// 1 s limit: this leaves the 10 % / 0.2 s of the issue and the load of a shared machine).
pub const SLOW_S: f64 = 5.0;
/// An input whose peak heap exceeds this is counted as over the memory limit (inputs are at
/// most a few MB; the searches they start have a 1 s and 2,000-node limit).
pub const HEAP_CAP: usize = 512 << 20;
/// Limits of the searches that parsed problems get.
const SEARCH_TIME: Duration = Duration::from_secs(1);
const SEARCH_NODES: u64 = 2_000;

// ---------------------------------------------------------------------------------------------
// The corpus.

/// The six input kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kind {
    Hddl,
    Scene,
    PlanText,
    PlanJson,
    Mesh,
    Srdf,
}

impl Kind {
    pub const ALL: [Kind; 6] = [
        Kind::Hddl,
        Kind::Scene,
        Kind::PlanText,
        Kind::PlanJson,
        Kind::Mesh,
        Kind::Srdf,
    ];
    pub fn name(self) -> &'static str {
        match self {
            Kind::Hddl => "hddl",
            Kind::Scene => "scene",
            Kind::PlanText => "plan-text",
            Kind::PlanJson => "plan-json",
            Kind::Mesh => "mesh",
            Kind::Srdf => "srdf",
        }
    }
}

/// What a seed is read with.
#[derive(Clone)]
pub enum Target {
    Domain,
    Problem(Arc<Domain>),
    Scene {
        base_dir: PathBuf,
        stem: String,
    },
    PlanText(Arc<Domain>, Arc<Problem>),
    PlanJson,
    /// A mesh file; its path's extension gives the format.
    Mesh,
    /// An SRDF, read against the model of the URDF `urdf`.
    Srdf {
        urdf: PathBuf,
        model: Arc<geometry::agent::AgentModel>,
    },
}

/// One corpus file.
#[derive(Clone)]
pub struct Seed {
    pub kind: Kind,
    pub path: PathBuf,
    pub text: Vec<u8>,
    pub target: Target,
}

/// A domain and a problem read.
type Pair = (Arc<Domain>, Arc<Problem>);

/// The input now running: when it started, its seed file, its bytes.
type Running = (Instant, PathBuf, Vec<u8>);

/// The repository root (this file is at `crates/cli/tests/fuzz_support/mod.rs`).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn files(dir: &Path, ext: &str, max_bytes: u64, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            if path
                .file_name()
                .is_some_and(|n| n != "target" && n != "node_modules")
            {
                files(&path, ext, max_bytes, out);
            }
        } else if path.extension().is_some_and(|e| e == ext)
            && std::fs::metadata(&path).is_ok_and(|m| m.len() <= max_bytes)
        {
            out.push(path);
        }
    }
}

fn source(path: &Path) -> SourceName {
    Arc::new(path.to_path_buf())
}

/// The corpus: every shipped and benchmark file of the four kinds (HDDL files up to
/// `max_hddl` bytes). `shared` adds `../shared/benchmarks` and the verdict corpus.
pub fn corpus(shared: bool, max_hddl: u64) -> Vec<Seed> {
    let root = root();
    let mut seeds = Vec::new();

    // HDDL: domains, and problems with their domain.
    let mut hddl = Vec::new();
    files(&root.join("domains"), "hddl", max_hddl, &mut hddl);
    files(&root.join("crates/htn/tests"), "hddl", max_hddl, &mut hddl);
    let bench = root.join("../shared/benchmarks");
    if shared {
        files(&bench, "hddl", max_hddl, &mut hddl);
    }
    let mut domains: BTreeMap<PathBuf, Option<Arc<Domain>>> = BTreeMap::new();
    let mut domain_of = |p: &Path| -> Option<Arc<Domain>> {
        domains
            .entry(p.to_path_buf())
            .or_insert_with(|| htn::load_domain(p).ok().map(Arc::new))
            .clone()
    };
    let mut problems: Vec<(PathBuf, Arc<Domain>)> = Vec::new();
    for path in hddl {
        let Ok(text) = std::fs::read(&path) else {
            continue;
        };
        let target = if htn::parser::is_domain_file_name(&path) {
            Target::Domain
        } else {
            // Problems of the project's own test domains are named `X.hddl` beside `X-domain.hddl`
            // or, in tests/domains, by a common prefix.
            let dfile = named_domain(&path, &text)
                .or_else(|| htn::parser::domain_file_for(&path))
                .or_else(|| own_domain_for(&path));
            match dfile.and_then(|d| domain_of(&d)) {
                Some(d) => {
                    problems.push((path.clone(), d.clone()));
                    Target::Problem(d)
                }
                None => Target::Domain,
            }
        };
        seeds.push(Seed {
            kind: Kind::Hddl,
            path,
            text,
            target,
        });
    }

    // Scenes.
    let mut scenes = Vec::new();
    files(&root.join("domains"), "toml", 1 << 20, &mut scenes);
    files(
        &root.join("crates/geometry/tests"),
        "toml",
        1 << 20,
        &mut scenes,
    );
    for path in scenes {
        let Ok(text) = std::fs::read(&path) else {
            continue;
        };
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        seeds.push(Seed {
            kind: Kind::Scene,
            path,
            text,
            target: Target::Scene { base_dir, stem },
        });
    }

    // Plan files: the verdict corpus (with the shared benchmarks), and plans of the project's
    // own test problems planned here.
    if shared {
        let vdir = root.join("crates/htn/tests/verdicts");
        if let Ok(tsv) = std::fs::read_to_string(vdir.join("verdicts.tsv")) {
            let mut loaded: BTreeMap<(String, String), Option<Pair>> = BTreeMap::new();
            for line in tsv.lines().filter(|l| !l.starts_with('#')) {
                let cols: Vec<&str> = line.split('\t').collect();
                let [plan, d, p, ..] = cols[..] else { continue };
                let pair = loaded
                    .entry((d.to_string(), p.to_string()))
                    .or_insert_with(|| {
                        let dom = htn::load_domain(root.join("..").join("shared").join(d)).ok()?;
                        let prob = htn::load_problem(root.join("../shared").join(p), &dom).ok()?;
                        Some((Arc::new(dom), Arc::new(prob)))
                    })
                    .clone();
                if let (Some((dom, prob)), Ok(text)) = (pair, std::fs::read(vdir.join(plan))) {
                    seeds.push(Seed {
                        kind: Kind::PlanText,
                        path: vdir.join(plan),
                        text,
                        target: Target::PlanText(dom, prob),
                    });
                }
            }
        }
    }
    for (path, domain) in problems
        .iter()
        .filter(|(p, _)| p.starts_with(root.join("crates")))
    {
        let Ok(problem) = htn::load_problem(path, domain) else {
            continue;
        };
        if !domain.geometric_tasks.is_empty() {
            continue;
        }
        let options = htn::planner::PlannerOptions {
            limits: htn::planner::Limits {
                time: Some(Duration::from_secs(5)),
                nodes: Some(100_000),
                memory_mb: Some(1024),
            },
            ..Default::default()
        };
        if let Ok(r) = htn::planner::plan(domain, &problem, &options, None)
            && let htn::planner::Outcome::Found { plan } = r.outcome
        {
            seeds.push(Seed {
                kind: Kind::PlanText,
                path: path.with_extension("plan"),
                text: plan.to_competition_format().into_bytes(),
                target: Target::PlanText(domain.clone(), Arc::new(problem.clone())),
            });
            seeds.push(Seed {
                kind: Kind::PlanText,
                path: path.with_extension("plan.json"),
                text: serde_json::to_vec(&plan).unwrap_or_default(),
                target: Target::PlanText(domain.clone(), Arc::new(problem)),
            });
        }
    }

    // Plan JSON: plans of the library problems planned here with the scene, the viewer's
    // fixtures, and plan JSON files shipped anywhere in the tests.
    let lib = root.join("domains/library");
    if let Ok(domain) = htn::load_domain(lib.join("domain-compound.hddl")) {
        for name in ["fig4", "pay-by-card"] {
            let path = lib.join(format!("{name}.hddl"));
            let (Ok(problem), Ok(world)) = (
                htn::load_problem(&path, &domain),
                geometry::world::World::load(lib.join("scene.toml")),
            ) else {
                continue;
            };
            let options = hybrid::RunOptions {
                planner: htn::planner::PlannerOptions {
                    limits: htn::planner::Limits {
                        time: Some(Duration::from_secs(60)),
                        ..Default::default()
                    },
                    ..Default::default()
                },
                ..Default::default()
            };
            let planner = Arc::new(gtp::planner::Planner::new());
            if let Ok(run) = hybrid::plan(&domain, &problem, world, planner, &options) {
                let mut v = hybrid::export::plan_json(&run, &domain.name, &problem.name);
                thin_trajectories(&mut v);
                seeds.push(Seed {
                    kind: Kind::PlanJson,
                    path: path.with_extension("json"),
                    text: serde_json::to_vec(&v).unwrap_or_default(),
                    target: Target::PlanJson,
                });
            }
        }
    }
    let mut json = Vec::new();
    files(&root.join("viewer/fixtures"), "json", 8 << 20, &mut json);
    files(&root.join("crates/check/tests"), "json", 8 << 20, &mut json);
    for path in json {
        if let Ok(text) = std::fs::read(&path) {
            seeds.push(Seed {
                kind: Kind::PlanJson,
                path,
                text,
                target: Target::PlanJson,
            });
        }
    }
    mesh_seeds(&root, shared, &mut seeds);
    srdf_seeds(&root, shared, &mut seeds);
    seeds
}

/// Mesh files: the tests' own, three written here (a binary and an ASCII STL cube, a COLLADA
/// cube with a unit and a node transform), and the shared robots' up to 256 kB.
fn mesh_seeds(root: &Path, shared: bool, seeds: &mut Vec<Seed>) {
    let mut paths = Vec::new();
    let robots = root.join("../shared/robots");
    for ext in ["stl", "dae", "obj"] {
        files(
            &root.join("crates/geometry/tests"),
            ext,
            1 << 20,
            &mut paths,
        );
        if shared {
            files(&robots, ext, 256 << 10, &mut paths);
        }
    }
    for path in paths {
        if let Ok(text) = std::fs::read(&path) {
            seeds.push(Seed {
                kind: Kind::Mesh,
                path,
                text,
                target: Target::Mesh,
            });
        }
    }
    let cube = box_triangles([0.0; 3], [1.0; 3]);
    let binary = binary_stl(&cube, cube.len() as u32);
    let ascii = ascii_stl(&cube);
    let corners: Vec<String> = (0..8)
        .map(|i| format!("{} {} {}", i & 1, (i >> 1) & 1, (i >> 2) & 1))
        .collect();
    let dae = format!(
        "<?xml version=\"1.0\"?>\n<COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">\n<asset><unit meter=\"0.01\"/><up_axis>Z_UP</up_axis></asset>\n<library_geometries><geometry id=\"g\"><mesh>\n<source id=\"p\"><float_array id=\"pa\" count=\"24\">{}</float_array><technique_common><accessor source=\"#pa\" count=\"8\" stride=\"3\"><param name=\"X\" type=\"float\"/><param name=\"Y\" type=\"float\"/><param name=\"Z\" type=\"float\"/></accessor></technique_common></source>\n<vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices>\n<triangles count=\"12\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/><p>0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5</p></triangles>\n</mesh></geometry></library_geometries>\n<library_visual_scenes><visual_scene id=\"s\"><node id=\"n\"><matrix>1 0 0 0.5 0 1 0 0 0 0 1 0 0 0 0 1</matrix><instance_geometry url=\"#g\"/></node></visual_scene></library_visual_scenes>\n<scene><instance_visual_scene url=\"#s\"/></scene>\n</COLLADA>\n",
        corners.join(" ")
    );
    for (name, text) in [
        ("written-binary.stl", binary),
        ("written-ascii.stl", ascii.into_bytes()),
        ("written-cube.dae", dae.into_bytes()),
    ] {
        seeds.push(Seed {
            kind: Kind::Mesh,
            path: PathBuf::from(name),
            text,
            target: Target::Mesh,
        });
    }
}

/// The model of the URDF at `path`, its `package://` names searched in `packages`.
fn urdf_model(path: &Path, packages: &Path) -> Result<geometry::agent::AgentModel, String> {
    use geometry::agent::{AgentModel, MeshOptions, PackagePath};
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let options = MeshOptions {
        packages: PackagePath {
            urdf_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            scene_dirs: vec![packages.to_path_buf()],
        },
        modes: Default::default(),
    };
    AgentModel::from_urdf_str_with(&text, &path.display().to_string(), &options)
        .map_err(|e| e.to_string())
}

/// SRDF files with the URDF each describes: the project's models, and the shared robots'
/// MoveIt SRDFs when present.
fn srdf_seeds(root: &Path, shared: bool, seeds: &mut Vec<Seed>) {
    let models = root.join("models");
    let mut pairs: Vec<(PathBuf, PathBuf)> = ["pr2", "fetch", "human"]
        .iter()
        .map(|m| {
            (
                models.join(format!("{m}.srdf")),
                models.join(format!("{m}.urdf")),
            )
        })
        .collect();
    if shared {
        let robots = root.join("../shared/robots");
        pairs.push((
            robots.join("pr2_description/srdf/robot.xml"),
            robots.join("pr2_description/urdf/robot.xml"),
        ));
        pairs.push((
            robots.join("panda_moveit_config/config/panda.srdf"),
            robots.join("panda_description/urdf/panda.urdf"),
        ));
    }
    let robots = root.join("../shared/robots");
    for (srdf, urdf) in pairs {
        let (Ok(text), Ok(model)) = (std::fs::read(&srdf), urdf_model(&urdf, &robots)) else {
            continue;
        };
        seeds.push(Seed {
            kind: Kind::Srdf,
            path: srdf,
            text,
            target: Target::Srdf {
                urdf,
                model: Arc::new(model),
            },
        });
    }
}

/// Keeps the first two and the last frame of every trajectory of a plan JSON: a seed of a few
/// hundred kB instead of 13 MB, still a plan `htngtp check` reads (fast enough to fuzz).
fn thin_trajectories(plan: &mut serde_json::Value) {
    let Some(steps) = plan.get_mut("steps").and_then(|s| s.as_array_mut()) else {
        return;
    };
    for step in steps {
        let Some(trajs) = step
            .pointer_mut("/gtp/trajectories")
            .and_then(|t| t.as_array_mut())
        else {
            continue;
        };
        for t in trajs {
            if let Some(frames) = t.get_mut("frames").and_then(|f| f.as_array_mut())
                && frames.len() > 3
            {
                let last = frames.pop();
                frames.truncate(2);
                frames.extend(last);
            }
        }
    }
}

/// The domain a malformed-corpus problem names on its second line (`; domain: FILE`).
fn named_domain(problem: &Path, text: &[u8]) -> Option<PathBuf> {
    let text = std::str::from_utf8(text.get(..text.len().min(400))?).ok()?;
    let name = text.lines().find_map(|l| l.strip_prefix("; domain: "))?;
    Some(problem.with_file_name(name.trim()))
}

/// The domain of a problem in `crates/htn/tests/domains` (`desk-heavy.hddl` with
/// `desk-domain.hddl`), by the longest common prefix before a `-`.
fn own_domain_for(problem: &Path) -> Option<PathBuf> {
    let dir = problem.parent()?;
    let stem = problem.file_stem()?.to_str()?;
    let prefix = stem.split('-').next()?;
    let d = dir.join(format!("{prefix}-domain.hddl"));
    d.is_file().then_some(d)
}

// ---------------------------------------------------------------------------------------------
// Running one input.

/// What one input did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Read (and checked, planned or validated) without error.
    Accepted,
    /// Refused with an error message.
    Refused,
    /// A panic, with its message.
    Panic(String),
}

thread_local! {
    static LAST_PANIC: std::cell::RefCell<String> = const { std::cell::RefCell::new(String::new()) };
}

/// Installs a panic hook that records the message (printed by the run's summary, not here).
pub fn quiet_panics() {
    std::panic::set_hook(Box::new(|info| {
        let msg = format!("{info}");
        LAST_PANIC.with(|p| *p.borrow_mut() = msg);
    }));
}

fn guarded(f: impl FnOnce() -> bool) -> Verdict {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(true) => Verdict::Accepted,
        Ok(false) => Verdict::Refused,
        Err(_) => Verdict::Panic(LAST_PANIC.with(|p| p.borrow().clone())),
    }
}

/// Hands `bytes` to the entry points for `seed`'s kind, as the binary would (its text read as
/// UTF-8 first, as the binary reads its inputs).
pub fn run_input(seed: &Seed, bytes: &[u8]) -> Verdict {
    if let Target::Mesh = &seed.target {
        // Binary STL is not text.
        return guarded(|| {
            use geometry::agent::{ConvexMode, convex};
            geometry::mesh_file::parse_mesh(bytes, &seed.path)
                .and_then(|m| convex::guarded_convex(&m, [1.0; 3], ConvexMode::Auto))
                .is_ok()
        });
    }
    let Ok(text) = std::str::from_utf8(bytes) else {
        // The binary refuses text that is not UTF-8 before parsing it.
        return Verdict::Refused;
    };
    match &seed.target {
        Target::Domain => guarded(|| htn::parse_domain(text, source(&seed.path)).is_ok()),
        Target::Problem(domain) => guarded(|| {
            let Ok(problem) = htn::parse_problem(text, source(&seed.path), domain) else {
                return false;
            };
            let options = htn::planner::PlannerOptions {
                limits: htn::planner::Limits {
                    time: Some(SEARCH_TIME),
                    nodes: Some(SEARCH_NODES),
                    memory_mb: None,
                },
                ..Default::default()
            };
            if !domain.geometric_tasks.is_empty() {
                return true;
            }
            match htn::planner::plan(domain, &problem, &options, None) {
                Ok(r) => {
                    if let htn::planner::Outcome::Found { plan } = &r.outcome {
                        // Every plan the planner returns must pass the validator.
                        assert!(
                            htn::validate::validate(domain, &problem, plan, &[]).is_ok(),
                            "a found plan fails validation"
                        );
                    }
                    true
                }
                Err(_) => false,
            }
        }),
        Target::Scene { base_dir, stem } => {
            guarded(
                || match geometry::scene::Scene::from_str(text, "fuzz.toml", base_dir, stem) {
                    Ok(scene) => geometry::world::World::from_scene(scene).is_ok(),
                    Err(e) => {
                        let _ = e.to_string();
                        false
                    }
                },
            )
        }
        Target::PlanText(domain, problem) => guarded(|| {
            let plan = if text.trim_start().starts_with('{') {
                match serde_json::from_str::<htn::plan::Plan>(text) {
                    Ok(p) => p,
                    Err(_) => return false,
                }
            } else {
                match htn::plan::Plan::parse(text) {
                    Ok(p) => p,
                    Err(e) => {
                        let _ = e.to_string();
                        return false;
                    }
                }
            };
            let exact = htn::validate::validate_with(
                domain,
                problem,
                &plan,
                &[],
                htn::validate::Names::Exact,
            );
            let lenient = htn::validate::validate_with(
                domain,
                problem,
                &plan,
                &[],
                htn::validate::Names::CaseInsensitive,
            );
            if let Err(f) = &exact {
                let _ = f.to_string();
            }
            exact.is_ok() || lenient.is_ok()
        }),
        Target::Mesh => unreachable!("read above"),
        Target::Srdf { model, .. } => {
            guarded(
                || match (**model).clone().with_srdf_str(text, "fuzz.srdf") {
                    Ok(_) => true,
                    Err(e) => {
                        let _ = e.to_string();
                        false
                    }
                },
            )
        }
        Target::PlanJson => guarded(|| {
            // `htngtp view`'s loading check.
            let view_ok = serde_json::from_str::<serde_json::Value>(text)
                .is_ok_and(|v| v.get("format").and_then(|f| f.as_str()) == Some("htngtp-plan"));
            // `htngtp validate` reading a plan JSON (in the fuzz's plan-text kind, against the
            // right problems; here only read).
            let _ = serde_json::from_str::<htn::plan::Plan>(text).is_ok();
            // `htngtp check`.
            match check::parse_plan(text, "fuzz.json") {
                Ok(plan) => {
                    let report = check::check_plan(&plan, &check::Options::default());
                    let _ = report;
                    view_ok
                }
                Err(e) => {
                    let _ = e.to_string();
                    false
                }
            }
        }),
    }
}

// ---------------------------------------------------------------------------------------------
// A run.

/// Counts of one kind.
#[derive(Clone, Debug, Default)]
pub struct Tally {
    pub inputs: u64,
    pub accepted: u64,
    pub refused: u64,
    pub panics: u64,
    /// Inputs slower than [`SLOW_S`].
    pub slow: u64,
    /// Inputs whose peak heap exceeded [`HEAP_CAP`].
    pub over_memory: u64,
    pub max_ms: f64,
    pub max_heap: usize,
}

/// The outcome of a run: tallies per kind and the first few failures (input files written).
#[derive(Debug, Default)]
pub struct Report {
    pub tallies: BTreeMap<Kind, Tally>,
    pub failures: Vec<String>,
    pub seconds: f64,
}

impl Report {
    pub fn total(&self) -> u64 {
        self.tallies.values().map(|t| t.inputs).sum()
    }
    pub fn bad(&self) -> u64 {
        self.tallies
            .values()
            .map(|t| t.panics + t.slow + t.over_memory)
            .sum()
    }
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{} inputs in {:.0} s\n{:<10} {:>9} {:>9} {:>9} {:>6} {:>6} {:>8} {:>9} {:>10}\n",
            self.total(),
            self.seconds,
            "kind",
            "inputs",
            "accepted",
            "refused",
            "panics",
            "slow",
            "over-mem",
            "max ms",
            "max heap"
        );
        for (k, t) in &self.tallies {
            s += &format!(
                "{:<10} {:>9} {:>9} {:>9} {:>6} {:>6} {:>8} {:>9.0} {:>7} MiB\n",
                k.name(),
                t.inputs,
                t.accepted,
                t.refused,
                t.panics,
                t.slow,
                t.over_memory,
                t.max_ms,
                t.max_heap >> 20
            );
        }
        for f in &self.failures {
            s += &format!("FAILURE: {f}\n");
        }
        s
    }
}

/// Options of a run.
pub struct Options {
    pub seed: u64,
    /// Inputs per kind.
    pub per_kind: BTreeMap<Kind, u64>,
    /// Where failing inputs are written.
    pub out_dir: PathBuf,
    /// Print progress every this many inputs (0: never).
    pub progress: u64,
}

/// Runs the harness: for each kind in turn, `per_kind` mutated inputs, round-robin over that
/// kind's seeds.
pub fn run(seeds: &[Seed], opts: &Options) -> Report {
    quiet_panics();
    let began = Instant::now();
    // The watchdog: the input now running and when it started.
    let current: Arc<std::sync::Mutex<Option<Running>>> = Arc::new(std::sync::Mutex::new(None));
    let done = Arc::new(AtomicBool::new(false));
    {
        let (current, done, dir) = (current.clone(), done.clone(), opts.out_dir.clone());
        std::thread::spawn(move || {
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(500));
                let guard = current.lock().unwrap_or_else(|e| e.into_inner());
                if let Some((t, path, bytes)) = &*guard
                    && t.elapsed() > Duration::from_secs(HANG_S)
                {
                    let _ = std::fs::create_dir_all(&dir);
                    let f = dir.join("hang.input");
                    let _ = std::fs::write(&f, bytes);
                    eprintln!(
                        "HANG: an input mutated from {} ran over {HANG_S} s; written to {}",
                        path.display(),
                        f.display()
                    );
                    std::process::exit(70);
                }
            }
        });
    }
    let counter = AtomicU64::new(0);
    let mut report = Report::default();
    for kind in Kind::ALL {
        let of_kind: Vec<&Seed> = seeds.iter().filter(|s| s.kind == kind).collect();
        let n = opts.per_kind.get(&kind).copied().unwrap_or(0);
        if of_kind.is_empty() || n == 0 {
            continue;
        }
        let mut rng = fastrand::Rng::with_seed(opts.seed ^ ((kind as u64 + 1) * 0x9E37_79B9));
        let tally = report.tallies.entry(kind).or_default();
        for i in 0..n {
            let seed = of_kind[(i as usize) % of_kind.len()];
            let other = of_kind[rng.usize(0..of_kind.len())];
            let mut bytes = seed.text.clone();
            mutate(&mut rng, kind, &mut bytes, &other.text);
            if let Ok(mut g) = current.lock() {
                *g = Some((Instant::now(), seed.path.clone(), bytes.clone()));
            }
            let base = reset_peak();
            let t = Instant::now();
            let verdict = run_input(seed, &bytes);
            let ms = t.elapsed().as_secs_f64() * 1000.0;
            let heap = peak_above(base);
            tally.inputs += 1;
            tally.max_ms = tally.max_ms.max(ms);
            tally.max_heap = tally.max_heap.max(heap);
            let mut failure = None;
            match &verdict {
                Verdict::Accepted => tally.accepted += 1,
                Verdict::Refused => tally.refused += 1,
                Verdict::Panic(m) => {
                    tally.panics += 1;
                    failure = Some(format!("panic: {m}"));
                }
            }
            if ms > SLOW_S * 1000.0 {
                tally.slow += 1;
                failure.get_or_insert(format!("slow: {ms:.0} ms"));
            }
            if heap > HEAP_CAP {
                tally.over_memory += 1;
                failure.get_or_insert(format!("heap: {} MiB", heap >> 20));
            }
            if let Some(what) = failure
                && report.failures.len() < 50
            {
                let _ = std::fs::create_dir_all(&opts.out_dir);
                let f = opts.out_dir.join(format!(
                    "{}-{}-{i}.input",
                    kind.name(),
                    report.failures.len()
                ));
                let _ = std::fs::write(&f, &bytes);
                report.failures.push(format!(
                    "{} input {i} (mutated from {}; written to {}): {what}",
                    kind.name(),
                    seed.path.display(),
                    f.display()
                ));
            }
            let c = counter.fetch_add(1, Ordering::Relaxed) + 1;
            if opts.progress > 0 && c % opts.progress == 0 {
                eprintln!(
                    "{c} inputs, {:.0} s, {} failures",
                    began.elapsed().as_secs_f64(),
                    report.failures.len()
                );
            }
        }
    }
    done.store(true, Ordering::Relaxed);
    report.seconds = began.elapsed().as_secs_f64();
    report
}
