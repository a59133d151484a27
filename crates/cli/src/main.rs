//! `htngtp`: the command-line front end. Each subcommand lives in its own module under `cmd/`;
//! this file only parses arguments and maps outcomes to exit codes.

#[macro_use]
mod out;
mod cmd;
mod input;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Exit codes shared by every subcommand.
pub mod exit {
    /// A plan was found (or the command succeeded).
    pub const OK: u8 = 0;
    /// The problem is proven unsolvable (or a checked plan is invalid).
    pub const UNSOLVABLE: u8 = 1;
    /// A time, node or memory limit stopped the search, or the symbolic strategy's cap on
    /// geometric alternatives left it incomplete.
    pub const LIMIT: u8 = 2;
    /// Bad input: unreadable or malformed files, unknown names, bad arguments.
    pub const BAD_INPUT: u8 = 3;
}

#[derive(Parser)]
#[command(
    name = "htngtp",
    version,
    about = "A combined HTN and geometric task planner for robots that work among people",
    after_help = "Exit codes: 0 plan found / success; 1 proven unsolvable (a complete search, \
                  no cap) or plan invalid; 2 stopped incomplete: a time, node or memory limit, \
                  or the strategy's cap on geometric alternatives; 3 bad input (also a failed \
                  write of the output; a closed output pipe ends quietly with 141).\n\nInputs: \
                  every input file must be a regular file of at most 256 MiB (the environment \
                  variable HTNGTP_MAX_INPUT_MIB sets another cap); devices and directories are \
                  refused."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// A folder searched for the ROS packages that `package://` names in URDFs refer to
    /// (repeatable; searched before the scene's `package_path` and ROS_PACKAGE_PATH).
    #[arg(long = "package-path", value_name = "DIR", global = true)]
    package_path: Vec<std::path::PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Run the library-receptionist scenario end to end (the paper's domain and scene).
    Demo(cmd::demo::Args),
    /// Benchmarks: `bench library` runs the paper's experiment (Table II).
    Bench(cmd::bench::Args),
    /// Plan an HDDL problem (optionally with a 3D scene for geometric tasks).
    Plan(cmd::plan::Args),
    /// Check a plan in the competition format against a domain and problem.
    Validate(cmd::validate::Args),
    /// Run every problem under a benchmark directory and report coverage.
    BenchHddl(cmd::bench_hddl::Args),
    /// Draw a scene as a PNG picture, from an agent's eyes or from above.
    Render(cmd::render::Args),
    /// Print the shared literals a scene makes true (visible, reachable, on, inside, covered-by).
    Facts(cmd::facts::Args),
    /// Run one geometric task (pick, show, give, make-accessible, put-away, ...) in a scene.
    Gtp(cmd::gtp::Args),
    /// Re-check a plan JSON's geometry independently: collisions, support, literals.
    Check(cmd::check::Args),
    /// Write a plan JSON's timed joint trajectories as ROS JointTrajectory YAML files.
    Export(cmd::export::Args),
    /// Serve the 3D web viewer and a plan JSON on 127.0.0.1, and print the URL to open.
    View(cmd::view::Args),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() {
                exit::BAD_INPUT
            } else {
                exit::OK
            };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    geometry::agent::packages::set_command_line_dirs(cli.package_path);
    let result = match cli.command {
        Command::Demo(args) => cmd::demo::run(args),
        Command::Bench(args) => cmd::bench::run(args),
        Command::Plan(args) => cmd::plan::run(args),
        Command::Validate(args) => cmd::validate::run(args),
        Command::BenchHddl(args) => cmd::bench_hddl::run(args),
        Command::Render(args) => cmd::render::run(args),
        Command::Facts(args) => cmd::facts::run(args),
        Command::Gtp(args) => cmd::gtp::run(args),
        Command::View(args) => cmd::view::run(args),
        Command::Check(args) => cmd::check::run(args),
        Command::Export(args) => cmd::export::run(args),
    };
    out::flush();
    match result {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            // Long tokens of a hostile input are cut; a message stays one readable line.
            let message = htn::text::clip(&format!("{e:#}"));
            if htn::budget::tripped().is_some() {
                // A limit passed while reading, parsing or compiling: a limit, not bad input.
                eprintln!("{message}");
                ExitCode::from(exit::LIMIT)
            } else {
                eprintln!("error: {message}");
                ExitCode::from(exit::BAD_INPUT)
            }
        }
    }
}
