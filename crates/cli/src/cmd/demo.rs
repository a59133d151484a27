//! `htngtp demo`: the library receptionist of the paper end to end, from the bundled files.

use std::path::{Path, PathBuf};

use htn::planner::{PlannerOptions, Strategy};
use hybrid::OracleConfig;

use crate::cmd::geo::{Outputs, run_plan};

/// Arguments of `htngtp demo`.
#[derive(clap::Args)]
#[command(
    about = "Run the library-receptionist scenario end to end from the bundled files",
    long_about = "Plans MANAGEORDER for a member who reserved two books and lacks the credit to pay \
                  from their account (the paper's methods m1, m3 and m7: the robot picks each book and \
                  makes it accessible to the member on the reception desk, brings the POS machine \
                  and puts it away afterwards), in the library scene of the paper's Fig. 4, with \
                  the variant of the domain used in the paper's experiment (PICK grouped with the \
                  GTP task that follows it) and geometric-first backtracking (other solutions of \
                  earlier GTP tasks before HTN alternatives, the paper's Fig. 3). As in Fig. 4, the \
                  POS machine comes only when every lent book is in the member's view, and the \
                  white book's first placement hides the grey one: the GTP places it again. Prints \
                  the decomposition tree, the plan with each GS action's geometric solution and the \
                  statistics; writes the plan JSON (for `htngtp view`) and pictures of the world \
                  after each GS action into the output folder."
)]
pub struct Args {
    /// Folder for the plan JSON and the pictures.
    #[arg(long, default_value = "htngtp-demo")]
    pub out: PathBuf,
    /// Seed of the geometric searches.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Acceleration limit of the plan JSON's timed joint trajectories for every arm joint whose
    /// URDF declares none (rad/s^2, or m/s^2 for sliding joints; the shipped models declare
    /// none). The planar base keeps its own limits (docs/plan-json.md).
    #[arg(long, value_name = "A", default_value_t = hybrid::timing::DEFAULT_JOINT_ACCELERATION,
          value_parser = crate::input::acceleration)]
    pub max_acceleration: f64,
}

/// The bundled `domains/library` folder: beside the working directory, beside the executable's
/// checkout (`target/*/htngtp`), or where this crate was built from.
pub fn library_dir() -> anyhow::Result<PathBuf> {
    let mut candidates = vec![PathBuf::from("domains/library")];
    if let Ok(exe) = std::env::current_exe() {
        for up in exe.ancestors().skip(1).take(4) {
            candidates.push(up.join("domains/library"));
        }
    }
    candidates.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../domains/library"));
    candidates
        .into_iter()
        .find(|d| d.join("domain.hddl").is_file())
        .ok_or_else(|| {
            anyhow::anyhow!(
                "cannot find the bundled domains/library folder; run from the repository root"
            )
        })
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    let dir = library_dir()?;
    std::fs::create_dir_all(&args.out)?;
    println!(
        "htngtp demo: {} + {} in {}\n",
        dir.join("domain-compound.hddl").display(),
        dir.join("fig4.hddl").display(),
        dir.join("scene.toml").display()
    );
    let json_file = args.out.join("plan.json");
    let began = std::time::Instant::now();
    let domain = crate::input::load_domain(&dir.join("domain-compound.hddl"))?;
    let problem = htn::load_problem(dir.join("fig4.hddl"), &domain)?;
    let code = run_plan(
        &domain,
        &problem,
        began,
        crate::cmd::geo::SceneInput {
            path: &dir.join("scene.toml"),
            allow_initial_contact: false,
        },
        PlannerOptions {
            seed: args.seed,
            strategy: Strategy::GeometricFirst { k: 3 },
            ..PlannerOptions::default()
        },
        OracleConfig {
            seed: args.seed,
            ..OracleConfig::default()
        },
        &Outputs {
            json: false,
            json_file: Some(json_file.clone()),
            png_dir: Some(args.out.join("pictures")),
            timing: hybrid::export::TimingOptions {
                joint_acceleration: args.max_acceleration,
            },
        },
    )?;
    println!(
        "\nSee it in 3D: htngtp view {} (build the viewer once: npm --prefix viewer ci && npm --prefix viewer run build)",
        json_file.display()
    );
    Ok(code)
}
