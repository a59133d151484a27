//! Combined HTN and geometric planning through the `hybrid` crate's API: one library problem
//! planned in its scene with geometric-first backtracking, then each action of the plan with the
//! shared literals its geometric solution added and deleted, and the search statistics.
//!
//! ```sh
//! cargo run --release -p hybrid --example plan_library                       # lend-and-debit
//! cargo run --release -p hybrid --example plan_library -- fig4 scene.toml domain-compound.hddl
//! cargo run --release -p hybrid --example plan_library -- fig4 scene-fetch.toml domain.hddl
//! ```
//!
//! Arguments, all optional: `PROBLEM` (a problem of `domains/library/` without `.hddl`, default
//! `lend-and-debit`), `SCENE` (default `scene.toml`), `DOMAIN` (default `domain.hddl`).
//! `htngtp plan` is the full command-line tool for the same call.

use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

use htn::planner::{Limits, Outcome, PlannerOptions, Strategy};
use hybrid::RunOptions;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../domains/library");
    let problem = args.first().map_or("lend-and-debit", String::as_str);
    let scene = args.get(1).map_or("scene.toml", String::as_str);
    let domain = args.get(2).map_or("domain.hddl", String::as_str);
    let options = RunOptions {
        planner: PlannerOptions {
            strategy: Strategy::GeometricFirst { k: 3 },
            limits: Limits {
                time: Some(Duration::from_secs(120)),
                ..Limits::default()
            },
            ..PlannerOptions::default()
        },
        ..RunOptions::default()
    };
    let run = match hybrid::plan_files(
        &dir.join(domain),
        &dir.join(format!("{problem}.hddl")),
        &dir.join(scene),
        &options,
    ) {
        Ok(run) => run,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(3);
        }
    };
    let code = match &run.result.outcome {
        Outcome::Found { plan } => {
            for (i, a) in plan.actions.iter().enumerate() {
                println!("{i:>2}. {} {}", a.name, a.args.join(" "));
                if let Some(g) = &a.geometric {
                    println!("    GTP {}({})", g.task, g.args.join(", "));
                    for (sign, atoms) in [("+", &g.add), ("-", &g.delete)] {
                        if !atoms.is_empty() {
                            let atoms: Vec<String> = atoms.iter().map(|a| a.to_string()).collect();
                            println!("      {sign} {}", atoms.join(" "));
                        }
                    }
                }
            }
            0
        }
        Outcome::Unsolvable => {
            println!("no plan: {}", run.failure_message());
            1
        }
        Outcome::LimitReached { limit } => {
            println!("stopped by the {limit}; {}", run.failure_message());
            2
        }
    };
    let s = &run.result.stats;
    println!(
        "{} nodes, {} HTN backtracks, {} GTP backtracks, {:.3} s",
        s.nodes, s.htn_backtracks, s.geo_backtracks, s.time_s
    );
    ExitCode::from(code)
}
