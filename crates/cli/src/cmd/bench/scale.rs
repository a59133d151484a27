//! `htngtp bench scale`: how cost grows with the books lent (N) and the objects on the desk
//! (M), over generated library problems ([`hybrid::scale`]).

use std::path::PathBuf;

use anyhow::Context;
use hybrid::scale::{CellSummary, ScaleOptions, ScaleRun, run_scale, summarize};

use super::plot::{Plot, Series};
use crate::cmd::demo::library_dir;
use crate::exit;

/// Arguments of `htngtp bench scale`.
#[derive(clap::Args)]
#[command(
    long_about = "How cost grows: MANAGEORDER of the library domain (domain-compound.hddl) with N \
                  books lent from the librarians' two tables, over a desk holding M other small \
                  objects, `--runs` randomized scenes per (N, M), each generated from the seed \
                  (the same seed, the same scenes). Prints per (N, M): success, median and p90 \
                  run time, GTP calls, HTN and GTP backtracks, then where the time goes (mean \
                  seconds per run by GTP task) and the failures' reasons."
)]
pub struct ScaleArgs {
    /// Books lent (N), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2, 4, 8, 16])]
    pub books: Vec<usize>,
    /// Other objects on the desk (M), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [0, 5, 10, 20])]
    pub others: Vec<usize>,
    /// Randomized scenes per (N, M).
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Seed of the scenes and of every search.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Time limit of each run, seconds.
    #[arg(long, default_value_t = 60.0, value_parser = crate::input::seconds)]
    pub time_limit: f64,
    /// Backtracking strategy.
    #[arg(long, value_enum, default_value_t = crate::cmd::plan::StrategyArg::Symbolic)]
    pub strategy: crate::cmd::plan::StrategyArg,
    /// Runs at once (default: one per core). Times are wall times: fewer runs at once than
    /// cores measure them without contention.
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Write every run as CSV here.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Draw median time against N, one line per M, into this PNG.
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,
}

pub fn scale(args: ScaleArgs) -> anyhow::Result<u8> {
    if args.runs == 0 {
        anyhow::bail!("--runs must be at least 1");
    }
    if let Some(&n) = args
        .books
        .iter()
        .find(|&&n| n == 0 || n > hybrid::scale::MAX_BOOKS)
    {
        anyhow::bail!(
            "--books {n}: the generated scene holds 1 to {} books",
            hybrid::scale::MAX_BOOKS
        );
    }
    let dir = library_dir()?;
    let domain = crate::input::load_domain(&dir.join("domain-compound.hddl"))?;
    let cells: Vec<(usize, usize)> = args
        .books
        .iter()
        .flat_map(|&n| args.others.iter().map(move |&m| (n, m)))
        .collect();
    let (strategy, name) = super::strategy(args.strategy, 3);
    let options = ScaleOptions {
        cells: cells.clone(),
        runs: args.runs,
        seed: args.seed,
        jobs: args.jobs.unwrap_or_else(rayon::current_num_threads),
        run: super::run_options(strategy, args.time_limit),
    };
    let bar = indicatif::ProgressBar::new((cells.len() * args.runs) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} runs {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.set_message("scale");
    let runs = run_scale(&domain, &dir, &options, &|| bar.inc(1)).map_err(anyhow::Error::msg)?;
    bar.finish_and_clear();
    let summary = summarize(&cells, &runs);
    print_table(&summary, &args, name);
    print_stages(&summary);
    print_targets(&summary);
    print_failures(&runs);
    if let Some(path) = &args.csv {
        write_csv(path, &runs)?;
    }
    if let Some(path) = &args.plot {
        plot(&summary, &args, path)?;
    }
    Ok(exit::OK)
}

fn print_table(summary: &[CellSummary], args: &ScaleArgs, strategy: &str) {
    println!(
        "\n### htngtp bench scale: {} scenes per cell, seed {}, strategy {strategy}, time limit {} s\n",
        args.runs, args.seed, args.time_limit
    );
    println!(
        "| N books | M objects | success % | median time (s) | p90 time (s) | median / book (s) | GTP calls | HTN backtracks | GTP backtracks |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for c in summary {
        println!(
            "| {} | {} | {:.0} | {:.2} | {:.2} | {:.3} | {:.1} | {:.1} | {:.1} |",
            c.books,
            c.others,
            c.success_pct,
            c.median_time_s,
            c.p90_time_s,
            c.median_time_s / c.books as f64,
            c.gtp_calls,
            c.htn_backtracks,
            c.gtp_backtracks
        );
    }
}

/// Where the time goes: mean seconds per run by GTP task, and failed requests per run.
fn print_stages(summary: &[CellSummary]) {
    println!("\nMean seconds per run by GTP task (failed requests per run in brackets):\n");
    for c in summary {
        let parts: Vec<String> = c
            .task_time_s
            .iter()
            .zip(&c.task_failures)
            .map(|((t, s), (_, f))| format!("{t} {s:.2} ({f:.1})"))
            .collect();
        println!("  N={:>2} M={:>2}: {}", c.books, c.others, parts.join(", "));
    }
}

/// The scaling targets the command reports: per M, the median time per book at N = 8 at most
/// twice that at N = 1 (cost per book does not grow with N);
/// and success at N = 8, M = 20 at least 90 %.
fn print_targets(summary: &[CellSummary]) {
    let cell = |n: usize, m: usize| summary.iter().find(|c| c.books == n && c.others == m);
    let mut ms: Vec<usize> = summary.iter().map(|c| c.others).collect();
    ms.sort_unstable();
    ms.dedup();
    println!();
    for m in ms {
        if let (Some(a), Some(b)) = (cell(1, m), cell(8, m)) {
            let ratio = (b.median_time_s / 8.0) / a.median_time_s.max(1e-9);
            println!(
                "target M={m}: median time per book at N=8 / at N=1 = {ratio:.2} ({})",
                if ratio <= 2.0 {
                    "met"
                } else {
                    "MISSED: at most 2"
                }
            );
        }
    }
    if let Some(c) = cell(8, 20) {
        println!(
            "target: success at N=8, M=20 = {:.0} % ({})",
            c.success_pct,
            if c.success_pct >= 90.0 {
                "met"
            } else {
                "MISSED: at least 90 %"
            }
        );
    }
}

fn print_failures(runs: &[ScaleRun]) {
    let failed: Vec<&ScaleRun> = runs.iter().filter(|r| !r.record.solved).collect();
    if failed.is_empty() {
        return;
    }
    println!("\nFailed runs ({}):", failed.len());
    for r in failed.iter().take(20) {
        println!(
            "  N={} M={} run {} (seed {}): {}",
            r.books, r.others, r.record.index, r.record.seed, r.record.status
        );
    }
}

fn write_csv(path: &std::path::Path, runs: &[ScaleRun]) -> anyhow::Result<()> {
    let mut csv = String::from(
        "books,others,run,seed,solved,time_s,gtp_calls,htn_backtracks,gtp_backtracks,actions,status\n",
    );
    for r in runs {
        let rec = &r.record;
        let calls: u64 = rec.tasks.values().map(|s| s.attempts).sum();
        csv.push_str(&format!(
            "{},{},{},{},{},{:.4},{},{},{},{},\"{}\"\n",
            r.books,
            r.others,
            rec.index,
            rec.seed,
            rec.solved,
            rec.time_s,
            calls,
            rec.htn_backtracks,
            rec.gtp_backtracks,
            rec.actions,
            rec.status.replace('"', "'")
        ));
    }
    std::fs::write(path, csv).with_context(|| format!("writing {}", path.display()))
}

fn plot(summary: &[CellSummary], args: &ScaleArgs, path: &std::path::Path) -> anyhow::Result<()> {
    let series = args
        .others
        .iter()
        .map(|&m| Series {
            label: format!("M = {m}"),
            points: summary
                .iter()
                .filter(|c| c.others == m)
                .map(|c| (c.books as f64, c.median_time_s))
                .collect(),
        })
        .collect();
    let plot = Plot {
        title: format!("BENCH SCALE: MEDIAN OF {} SCENES", args.runs),
        x_label: "N BOOKS LENT".into(),
        y_label: "MEDIAN TIME (S)".into(),
        x_ticks: args.books.iter().map(|&n| n as f64).collect(),
        series,
    };
    plot.save(path).map_err(anyhow::Error::msg)
}
