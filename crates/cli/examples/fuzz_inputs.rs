//! The long fuzz run of the binary's inputs (HDDL, scenes, plan files, plan JSON, mesh files,
//! SRDF files), in process.
//!
//! ```sh
//! cargo run --release -p htngtp --example fuzz_inputs -- --inputs 1000000 --seed 1
//! ```
//! `--inputs N` is the total, split among the kinds by `--shares H,S,T,J,M,R` (default
//! 45,13,27,5,5,5 percent); `--out DIR` is where failing inputs go (default
//! `target/fuzz-inputs`); `--no-shared` leaves out `../shared` (benchmarks, verdict corpus, robots).
//! Exit 0 when no input panicked, hung, ran over the time or the memory bound; 1 otherwise.
//! See `crates/cli/tests/fuzz_support/mod.rs`.

#[path = "../tests/fuzz_support/mod.rs"]
mod fuzz_support;

use std::collections::BTreeMap;
use std::path::PathBuf;

use fuzz_support::{Counting, Kind};

#[global_allocator]
static ALLOC: Counting = Counting;

fn main() {
    let mut inputs: u64 = 10_000;
    let mut seed: u64 = 1;
    let mut shares = [45u64, 13, 27, 5, 5, 5];
    let mut out = fuzz_support::root().join("target/fuzz-inputs");
    let mut shared = true;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || {
            args.next()
                .unwrap_or_else(|| usage(&format!("{a} needs a value")))
        };
        match a.as_str() {
            "--inputs" => inputs = value().parse().unwrap_or_else(|_| usage("--inputs N")),
            "--seed" => seed = value().parse().unwrap_or_else(|_| usage("--seed N")),
            "--out" => out = PathBuf::from(value()),
            "--no-shared" => shared = false,
            "--shares" => {
                let v: Vec<u64> = value().split(',').filter_map(|x| x.parse().ok()).collect();
                shares = v
                    .try_into()
                    .unwrap_or_else(|_| usage("--shares H,S,T,J,M,R"));
            }
            _ => usage(&format!("unknown argument {a}")),
        }
    }
    let seeds = fuzz_support::corpus(shared, 256 * 1024);
    let total_share: u64 = shares.iter().sum::<u64>().max(1);
    let per_kind: BTreeMap<Kind, u64> = Kind::ALL
        .iter()
        .zip(shares)
        .map(|(&k, s)| (k, inputs * s / total_share))
        .collect();
    for k in Kind::ALL {
        eprintln!(
            "{}: {} seed files, {} inputs",
            k.name(),
            seeds.iter().filter(|s| s.kind == k).count(),
            per_kind[&k]
        );
    }
    let report = fuzz_support::run(
        &seeds,
        &fuzz_support::Options {
            seed,
            per_kind,
            out_dir: out,
            progress: 10_000,
        },
    );
    println!("{}", report.summary());
    std::process::exit(if report.bad() == 0 { 0 } else { 1 });
}

fn usage(msg: &str) -> ! {
    eprintln!(
        "fuzz_inputs: {msg}\nusage: fuzz_inputs [--inputs N] [--seed N] [--shares H,S,T,J,M,R] [--out DIR] [--no-shared]"
    );
    std::process::exit(2);
}
