//! A bounded fuzz run over the binary's six input kinds (HDDL, scenes, plan files, plan JSON,
//! mesh files, SRDF files),
//! run by `cargo test` and so by `.ci/run`: mutated corpus files through the library entry
//! points in process (no panic, no input over [`fuzz_support::SLOW_S`] or the heap cap), then a
//! small sample through the built binary (exit 0, 1, 2 or 3 only: never a panic's 101 or a
//! signal, never more than 10 % (at least 0.2 s) over its time limit). The long run is the `fuzz_inputs` example (see
//! `fuzz_support`). `HTNGTP_FUZZ_INPUTS` sets the inputs per kind of the in-process part.

mod fuzz_support;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use fuzz_support::{Counting, Kind, Seed, Target};

#[global_allocator]
static ALLOC: Counting = Counting;

fn shared_present() -> bool {
    let present = fuzz_support::root().join("../shared/benchmarks").is_dir();
    if !present {
        eprintln!("note: ../shared/benchmarks is absent; the corpus is the project's own files");
    }
    present
}

#[test]
fn mutated_inputs_never_panic_hang_or_exhaust_memory_in_process() {
    let per: u64 = std::env::var("HTNGTP_FUZZ_INPUTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1500);
    // Small HDDL files keep the bounded run short (big benchmark files are in the long run).
    let seeds = fuzz_support::corpus(shared_present(), 24 * 1024);
    for k in Kind::ALL {
        assert!(
            seeds.iter().any(|s| s.kind == k),
            "no corpus file of kind {}",
            k.name()
        );
    }
    let per_kind: BTreeMap<Kind, u64> = Kind::ALL
        .iter()
        .map(|&k| {
            let n = match k {
                Kind::Scene | Kind::Mesh | Kind::Srdf => per / 5,
                _ => per,
            };
            (k, n)
        })
        .collect();
    let report = fuzz_support::run(
        &seeds,
        &fuzz_support::Options {
            seed: 13,
            per_kind,
            out_dir: std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
                .join(format!("htngtp-fuzz-{}", std::process::id())),
            progress: 0,
        },
    );
    eprintln!("{}", report.summary());
    assert_eq!(report.bad(), 0, "{}", report.summary());
}

/// A mutated input written where the binary can read it, under the seed's own file name (so a
/// problem finds its domain by the benchmark conventions) in a scratch copy of its folder.
fn through_binary(seed: &Seed, bytes: &[u8], dir: &Path, k: usize) -> Vec<Vec<String>> {
    let exe = env!("CARGO_BIN_EXE_htngtp");
    let _ = exe;
    let file = dir.join(format!(
        "{k}-{}",
        seed.path.file_name().unwrap().to_string_lossy()
    ));
    std::fs::write(&file, bytes).unwrap();
    let f = file.display().to_string();
    let root = fuzz_support::root();
    match &seed.target {
        Target::Domain => vec![vec!["validate".into(), f.clone(), f.clone(), f]],
        Target::Problem(d) => {
            let d = d.source.display().to_string();
            vec![vec![
                "plan".into(),
                d,
                f,
                "--time-limit".into(),
                "2".into(),
                "--memory-limit".into(),
                "1024".into(),
            ]]
        }
        Target::Scene { base_dir, .. } => {
            // Next to the seed, so that its relative URDF and mesh paths resolve.
            let beside = base_dir.join(format!(".fuzz-{}-{k}.toml", std::process::id()));
            std::fs::write(&beside, bytes).unwrap();
            let b = beside.display().to_string();
            let _ = std::fs::remove_file(&file);
            vec![vec!["facts".into(), b, "--resolution".into(), "16".into()]]
        }
        Target::PlanText(d, p) => vec![vec![
            "validate".into(),
            d.source.display().to_string(),
            p.source.display().to_string(),
            f,
        ]],
        Target::Mesh => {
            // A robot whose one link collides as the mesh.
            let urdf = dir.join(format!("{k}-mesh.urdf"));
            std::fs::write(
                &urdf,
                format!(
                    "<robot name=\"m\"><link name=\"base\"/><link name=\"body\"><collision><geometry><mesh filename=\"{f}\"/></geometry></collision></link><joint name=\"j\" type=\"fixed\"><parent link=\"base\"/><child link=\"body\"/></joint></robot>"
                ),
            )
            .unwrap();
            let scene = robot_scene(dir, k, &urdf, None, "eye = \"body\"\nhands = [\"body\"]\n");
            vec![vec![
                "facts".into(),
                scene,
                "--resolution".into(),
                "16".into(),
            ]]
        }
        Target::Srdf { urdf, .. } => {
            let scene = robot_scene(dir, k, urdf, Some(&file), "");
            vec![vec![
                "facts".into(),
                scene,
                "--resolution".into(),
                "16".into(),
            ]]
        }
        Target::PlanJson => vec![
            vec!["check".into(), f.clone()],
            vec![
                "validate".into(),
                root.join("domains/library/domain.hddl")
                    .display()
                    .to_string(),
                root.join("domains/library/fig4.hddl").display().to_string(),
                f,
            ],
        ],
    }
}

/// A scene in `dir` with one robot from `urdf` (and `srdf`), its extra keys `extra`; returns
/// its path.
fn robot_scene(dir: &Path, k: usize, urdf: &Path, srdf: Option<&Path>, extra: &str) -> String {
    let robots = fuzz_support::root().join("../shared/robots");
    let srdf = srdf.map_or(String::new(), |s| {
        format!("srdf = {:?}\n", s.display().to_string())
    });
    let scene = dir.join(format!("{k}-robot.toml"));
    std::fs::write(
        &scene,
        format!(
            "[scene]\nname = \"fuzz\"\npackage_path = [{:?}]\n\n[[agents]]\nname = \"bot\"\nkind = \"robot\"\nurdf = {:?}\n{srdf}{extra}",
            robots.display().to_string(),
            urdf.display().to_string()
        ),
    )
    .unwrap();
    scene.display().to_string()
}

/// The `--time-limit` of a command line, seconds.
fn time_limit(args: &[String]) -> Option<f64> {
    let i = args.iter().position(|a| a == "--time-limit")?;
    args.get(i + 1)?.parse().ok()
}

#[test]
fn a_sample_of_mutated_inputs_through_the_binary_exits_cleanly() {
    let exe = env!("CARGO_BIN_EXE_htngtp");
    let seeds = fuzz_support::corpus(shared_present(), 24 * 1024);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("htngtp-fuzz-bin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut rng = fastrand::Rng::with_seed(7);
    let mut runs = 0;
    let mut failures = Vec::new();
    for kind in Kind::ALL {
        let of_kind: Vec<&Seed> = seeds.iter().filter(|s| s.kind == kind).collect();
        let n = match kind {
            Kind::Scene | Kind::Mesh | Kind::Srdf => 8,
            _ => 25,
        };
        for k in 0..n {
            let seed = of_kind[rng.usize(0..of_kind.len())];
            let other = of_kind[rng.usize(0..of_kind.len())];
            let mut bytes = seed.text.clone();
            fuzz_support::mutate(&mut rng, kind, &mut bytes, &other.text);
            for args in through_binary(seed, &bytes, &dir, k) {
                let began = Instant::now();
                let mut child = Command::new(exe)
                    .args(&args)
                    .stdin(Stdio::null())
                    .stdout(Stdio::null())
                    .stderr(Stdio::piped())
                    .spawn()
                    .unwrap();
                // Drained while the child runs: an error quoting a long mutated input can be
                // bigger than the pipe's buffer, and a child blocked writing it never exits.
                let mut stderr = child.stderr.take().expect("piped stderr");
                let drain = std::thread::spawn(move || {
                    use std::io::Read;
                    let mut err = String::new();
                    let _ = stderr.read_to_string(&mut err);
                    err
                });
                // A liveness bound, far above the 2 s limits given: a hung child is killed.
                let status = loop {
                    if let Some(s) = child.try_wait().unwrap() {
                        break Some(s);
                    }
                    if began.elapsed() > Duration::from_secs(120) {
                        let _ = child.kill();
                        let _ = child.wait();
                        break None;
                    }
                    std::thread::sleep(Duration::from_millis(10));
                };
                let err = drain.join().unwrap_or_default();
                runs += 1;
                let wall = began.elapsed().as_secs_f64();
                // A run with a time limit stops within 10 % (at least 0.2 s) of it.
                let over_limit = time_limit(&args).is_some_and(|t| wall > t + (t * 0.1).max(0.2));
                let ok = status
                    .and_then(|s| s.code())
                    .is_some_and(|c| (0..=3).contains(&c))
                    && !err.contains("panicked")
                    && !over_limit;
                if !ok {
                    let kept = dir.join(format!("failed-{}-{k}.input", kind.name()));
                    let _ = std::fs::write(&kept, &bytes);
                    failures.push(format!(
                        "{args:?}: {status:?} after {wall:.2} s (input kept as {}): {}",
                        kept.display(),
                        err.chars().take(500).collect::<String>()
                    ));
                }
                if let Target::Scene { base_dir, .. } = &seed.target {
                    let _ = std::fs::remove_file(
                        base_dir.join(format!(".fuzz-{}-{k}.toml", std::process::id())),
                    );
                }
            }
        }
    }
    eprintln!("{runs} runs of the binary, {} failures", failures.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
