//! `htngtp validate`: check a plan in the competition format against a domain and problem.

use std::path::PathBuf;

use anyhow::Context;

use crate::exit;

/// Arguments of `htngtp validate`.
#[derive(clap::Args)]
#[command(
    after_help = "Checks, independently of the planner, that the plan's actions are \
                        executable in order from the initial state (numeric fluents included) \
                        and that its decomposition lines are a valid decomposition of the \
                        initial task network into exactly those actions (methods match their \
                        tasks, subtasks in order with consistent arguments, method preconditions \
                        hold before each method's first action). The plan may be in the \
                        competition format (text between `==>` and `<==`) or the JSON that \
                        `htngtp plan --json` prints. Names must be spelled exactly as the domain \
                        and problem files declare them, as the competition's verifier \
                        (pandaPIparser --verify) requires; --lenient matches them in any case.\n\nExit codes: 0 valid, 1 invalid (the first \
                        fault is printed), 3 bad input."
)]
pub struct Args {
    /// The HDDL domain file.
    pub domain: PathBuf,
    /// The HDDL problem file.
    pub problem: PathBuf,
    /// The plan file.
    pub plan: PathBuf,
    /// Match names whatever their case (HDDL is case-insensitive), for hand-written plans; the
    /// competition's verifier would refuse a plan that needs this.
    #[arg(long)]
    pub lenient: bool,
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    crate::input::check_files([&*args.domain, &*args.problem, &*args.plan])?;
    let domain = crate::input::load_domain(&args.domain)?;
    let problem = htn::load_problem(&args.problem, &domain)?;
    let text = std::fs::read_to_string(&args.plan)
        .with_context(|| format!("cannot read plan file {}", args.plan.display()))?;
    let plan = if text.trim_start().starts_with('{') {
        let v: serde_json::Value = serde_json::from_str(&text)
            .with_context(|| format!("{}: not valid JSON", args.plan.display()))?;
        let p = if v.get("plan").is_some() {
            &v["plan"]
        } else {
            &v
        };
        serde_json::from_value::<htn::plan::Plan>(p.clone())
            .with_context(|| format!("{}: not a plan in JSON", args.plan.display()))?
    } else {
        htn::plan::Plan::parse(&text).map_err(|e| {
            // `FILE:LINE:COL: message`, or `FILE: message` for the plan as a whole.
            let sep = if e.line > 0 { ":" } else { ": " };
            anyhow::anyhow!("{}{sep}{e}", args.plan.display())
        })?
    };
    let names = if args.lenient {
        htn::validate::Names::CaseInsensitive
    } else {
        htn::validate::Names::Exact
    };
    match htn::validate::validate_with(&domain, &problem, &plan, &[], names) {
        Ok(()) => {
            println!(
                "valid: {} actions, {} decompositions",
                plan.actions.len(),
                plan.decompositions.len()
            );
            Ok(exit::OK)
        }
        Err(fault) => {
            println!("{fault}");
            Ok(exit::UNSOLVABLE)
        }
    }
}
