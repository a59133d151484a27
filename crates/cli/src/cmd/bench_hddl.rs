//! `htngtp bench-hddl`: run the HTN planner on every problem of a benchmark directory laid out
//! like the IPC 2020 total-order track, one problem per child process, and report coverage.

use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};

use crate::exit;

/// Arguments of `htngtp bench-hddl`.
#[derive(clap::Args)]
#[command(
    after_help = "Layout: DIR holds one folder per domain; each folder holds `domain.hddl` \
                        and problem files (every other `.hddl` file whose name does not contain \
                        `domain`); a problem `X.hddl` with an `X-domain.hddl` beside it uses that \
                        domain (Monroe, Entertainment). Subfolders of a domain folder (Robot's \
                        `further-instances-not-used-in-ipc/`) are not run.\n\nEach problem runs in \
                        a child process (`htngtp plan --json`) with the limits, so a crash cannot \
                        stop the run and peak memory (VmHWM) is measured per problem. Every plan \
                        is validated again here, and with --verifier also by an external \
                        verifier (pandaPIparser: `PATH --verify DOMAIN PROBLEM PLAN`, exit 0 and \
                        `Plan verification result: true` meaning accepted). Prints per domain: \
                        solved/total, median time of the solved, peak memory, plans the external \
                        verifier accepted and rejected; a total line; writes a CSV with one row \
                        per problem (both verdicts)."
)]
pub struct Args {
    /// The benchmark directory (one folder per domain).
    pub dir: PathBuf,
    /// Seconds per problem.
    #[arg(long, default_value_t = 10.0, value_name = "S", value_parser = crate::input::seconds)]
    pub time_limit: f64,
    /// Memory limit per problem, MiB.
    #[arg(long, default_value_t = 2048, value_name = "MB")]
    pub memory_limit: u64,
    /// Run only the first N problem files of each domain (file names sorted).
    #[arg(long, value_name = "N")]
    pub first: Option<usize>,
    /// Run only domains whose folder name contains this (case-insensitive).
    #[arg(long, value_name = "TEXT")]
    pub domain: Option<String>,
    /// Write one CSV row per problem to this file.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Problems run at the same time (1 for measurements).
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
    /// Seed passed to every run.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Also check every plan with this external verifier (the competition's: pandaPIparser,
    /// run as `PATH --verify DOMAIN PROBLEM PLAN`).
    #[arg(long, value_name = "PATH")]
    pub verifier: Option<PathBuf>,
}

/// Seconds the external verifier may take on one plan.
const VERIFIER_TIMEOUT_S: u64 = 300;

struct Job {
    domain_name: String,
    domain: PathBuf,
    problem: PathBuf,
}

#[derive(Clone, Default)]
struct Row {
    domain_name: String,
    problem: String,
    status: String,
    time_s: f64,
    nodes: u64,
    peak_kb: u64,
    plan_len: usize,
    validated: bool,
    /// The external verifier's verdict: `accepted`, `rejected`, `error`, or empty (not run).
    official: String,
    message: String,
}

fn collect(args: &Args) -> anyhow::Result<Vec<Job>> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&args.dir)
        .with_context(|| format!("cannot read benchmark directory {}", args.dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    let mut jobs = Vec::new();
    for d in dirs {
        let name = d
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        if let Some(f) = &args.domain
            && !name.to_lowercase().contains(&f.to_lowercase())
        {
            continue;
        }
        let mut probs: Vec<PathBuf> = std::fs::read_dir(&d)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.is_file()
                    && p.extension().is_some_and(|e| e == "hddl")
                    && !htn::parser::is_domain_file_name(p)
            })
            .collect();
        probs.sort();
        if let Some(n) = args.first {
            probs.truncate(n);
        }
        for p in probs {
            let Some(domain) = htn::parser::domain_file_for(&p) else {
                anyhow::bail!("no domain file for {}", p.display());
            };
            jobs.push(Job {
                domain_name: name.clone(),
                domain,
                problem: p,
            });
        }
    }
    Ok(jobs)
}

fn run_one(exe: &Path, args: &Args, job: &Job) -> Row {
    let mut row = Row {
        domain_name: job.domain_name.clone(),
        problem: job
            .problem
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default(),
        ..Row::default()
    };
    let start = Instant::now();
    let child = Command::new(exe)
        .arg("plan")
        .arg(&job.domain)
        .arg(&job.problem)
        .arg("--json")
        .arg("--time-limit")
        .arg(args.time_limit.to_string())
        .arg("--memory-limit")
        .arg(args.memory_limit.to_string())
        .arg("--seed")
        .arg(args.seed.to_string())
        .arg("--exit-with-stdin")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => {
            row.status = "error".into();
            row.message = format!("cannot start the planner: {e}");
            return row;
        }
    };
    // Read the pipes on threads so a large plan cannot block the child.
    let mut out = child.stdout.take().expect("piped stdout");
    let mut err = child.stderr.take().expect("piped stderr");
    let out_t = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let err_t = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    // The child stops itself at the limit; a hard stop a little later catches a hang.
    let hard = crate::input::duration(args.time_limit + 10.0);
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break Some(s),
            Ok(None) if start.elapsed() > hard => {
                let _ = child.kill();
                let _ = child.wait();
                break None;
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(5)),
            Err(_) => break None,
        }
    };
    // The child's stdin: open while this process lives; its end stops the child.
    drop(child.stdin.take());
    let wall = start.elapsed().as_secs_f64();
    let stdout = out_t.join().unwrap_or_default();
    let stderr = err_t.join().unwrap_or_default();
    row.time_s = wall;
    let Some(status) = status else {
        row.status = "killed".into();
        row.message = "did not stop at its time limit; killed".into();
        return row;
    };
    let v: serde_json::Value = match serde_json::from_str(stdout.trim()) {
        Ok(v) => v,
        Err(_) => {
            row.status = match status.code().and_then(|c| u8::try_from(c).ok()) {
                Some(exit::BAD_INPUT) => "bad-input".into(),
                // A limit passed while reading, parsing or compiling: no JSON.
                Some(exit::LIMIT) => "limit-reached".into(),
                _ => "crash".into(),
            };
            row.message = stderr
                .lines()
                .last()
                .unwrap_or(&format!("exit status {status}"))
                .to_string();
            return row;
        }
    };
    row.status = v["status"].as_str().unwrap_or("?").to_string();
    if let Some(l) = v["limit"].as_str() {
        row.message = format!("{l} limit");
    }
    // Wall-clock time of the whole run: parsing, search and validation.
    row.time_s = wall;
    row.nodes = v["stats"]["nodes"].as_u64().unwrap_or(0);
    row.peak_kb = v["peak_memory_kb"].as_u64().unwrap_or(0);
    if row.status == "found" {
        row.plan_len = v["plan"]["actions"].as_array().map_or(0, Vec::len);
        let text = v["plan_text"].as_str().unwrap_or("");
        match revalidate(job, text) {
            Ok(()) => row.validated = true,
            Err(e) => {
                row.status = "invalid".into();
                row.message = e.to_string();
            }
        }
        if let Some(verifier) = &args.verifier {
            let (verdict, why) = official_verdict(verifier, job, text);
            row.official = verdict.into();
            if !why.is_empty() {
                row.message = format!("{} official: {why}", row.message)
                    .trim()
                    .to_string();
            }
        }
    }
    row
}

/// The external verifier's verdict on `text` (`accepted`, `rejected` or `error`) and, unless
/// accepted, the first of its checks that failed (or why it could not run).
fn official_verdict(verifier: &Path, job: &Job, text: &str) -> (&'static str, String) {
    let file = std::env::temp_dir().join(format!(
        "htngtp-bench-{}-{}-{}.plan",
        std::process::id(),
        job.domain_name,
        job.problem
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
    ));
    if let Err(e) = std::fs::write(&file, text) {
        return ("error", format!("cannot write {}: {e}", file.display()));
    }
    let mut cmd = Command::new(verifier);
    cmd.arg("--verify")
        .arg(&job.domain)
        .arg(&job.problem)
        .arg(&file);
    let result = run_bounded(cmd, Duration::from_secs(VERIFIER_TIMEOUT_S));
    let _ = std::fs::remove_file(&file);
    match result {
        Err(e) => ("error", e),
        Ok((code, out)) => {
            let out = strip_ansi(&out);
            if code == Some(0) && out.contains("Plan verification result: true") {
                ("accepted", String::new())
            } else {
                let failed = out
                    .lines()
                    .find(|l| l.ends_with(": false") && !l.contains("result"))
                    .unwrap_or("verification result: false");
                ("rejected", failed.to_string())
            }
        }
    }
}

/// Runs `cmd` to its end or `limit` (then kills it); its exit code and stdout.
fn run_bounded(mut cmd: Command, limit: Duration) -> Result<(Option<i32>, String), String> {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot start {:?}: {e}", cmd.get_program()))?;
    let mut out = child.stdout.take().expect("piped stdout");
    let out_t = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break Ok(s.code()),
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                break Err(format!("no verdict within {} s", limit.as_secs()));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(5)),
            Err(e) => break Err(e.to_string()),
        }
    };
    let stdout = out_t.join().unwrap_or_default();
    status.map(|code| (code, stdout))
}

/// `text` without terminal colour codes (`ESC [ ... m`).
fn strip_ansi(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            for c in chars.by_ref() {
                if c == 'm' {
                    break;
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// Validates a plan here, apart from the child that found it.
fn revalidate(job: &Job, text: &str) -> anyhow::Result<()> {
    let domain = htn::load_domain(&job.domain)?;
    let problem = htn::load_problem(&job.problem, &domain)?;
    let plan = htn::plan::Plan::parse(text)?;
    htn::validate::validate(&domain, &problem, &plan, &[])?;
    Ok(())
}

fn median(mut xs: Vec<f64>) -> Option<f64> {
    if xs.is_empty() {
        return None;
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    Some(if n % 2 == 1 {
        xs[n / 2]
    } else {
        (xs[n / 2 - 1] + xs[n / 2]) / 2.0
    })
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    let jobs = collect(&args)?;
    if jobs.is_empty() {
        anyhow::bail!("no problems found under {}", args.dir.display());
    }
    let exe = std::env::current_exe().context("cannot find the htngtp executable")?;
    let bar = ProgressBar::new(jobs.len() as u64).with_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} [{elapsed_precise}] {msg}")
            .expect("a valid template"),
    );
    let csv = args.csv.as_deref().map(CsvFile::create).transpose()?;
    let csv = Mutex::new(csv);
    let rows: Mutex<Vec<Option<Row>>> = Mutex::new(vec![None; jobs.len()]);
    let next = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..args.jobs.max(1) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some(job) = jobs.get(i) else { break };
                    bar.set_message(format!(
                        "{}/{}",
                        job.domain_name,
                        job.problem
                            .file_name()
                            .unwrap_or_default()
                            .to_string_lossy()
                    ));
                    let row = run_one(&exe, &args, job);
                    if row.status == "invalid"
                        || row.status == "crash"
                        || row.official == "rejected"
                    {
                        bar.println(format!(
                            "{} {}: {} {}",
                            row.domain_name, row.problem, row.status, row.message
                        ));
                    }
                    if let Some(f) = csv.lock().expect("csv").as_mut() {
                        f.append(&row);
                    }
                    rows.lock().expect("rows")[i] = Some(row);
                    bar.inc(1);
                }
            });
        }
    });
    bar.finish_and_clear();
    let rows: Vec<Row> = rows
        .into_inner()
        .expect("rows")
        .into_iter()
        .flatten()
        .collect();

    let mut by_domain: BTreeMap<&str, Vec<&Row>> = BTreeMap::new();
    for r in &rows {
        by_domain.entry(&r.domain_name).or_default().push(r);
    }
    println!(
        "{:<34} {:>8} {:>10} {:>12} {:>9} {:>9} {:>9} {:>9}",
        "domain", "solved", "median s", "peak MiB", "limit", "invalid", "accepted", "rejected"
    );
    let official = |rs: &[&Row], v: &str| -> String {
        if args.verifier.is_none() {
            return "-".into();
        }
        rs.iter().filter(|r| r.official == v).count().to_string()
    };
    let (mut solved_all, mut total_all, mut invalid_all) = (0, 0, 0);
    let mut peak_all = 0u64;
    let mut times_all = Vec::new();
    for (d, rs) in &by_domain {
        let solved: Vec<&&Row> = rs.iter().filter(|r| r.status == "found").collect();
        let times: Vec<f64> = solved.iter().map(|r| r.time_s).collect();
        let peak = rs.iter().map(|r| r.peak_kb).max().unwrap_or(0);
        let limit = rs.iter().filter(|r| r.status == "limit-reached").count();
        let invalid = rs.iter().filter(|r| r.status == "invalid").count();
        times_all.extend(&times);
        solved_all += solved.len();
        total_all += rs.len();
        invalid_all += invalid;
        peak_all = peak_all.max(peak);
        println!(
            "{:<34} {:>8} {:>10} {:>12.1} {:>9} {:>9} {:>9} {:>9}",
            d,
            format!("{}/{}", solved.len(), rs.len()),
            median(times).map_or("-".into(), |m| format!("{m:.3}")),
            peak as f64 / 1024.0,
            limit,
            invalid,
            official(rs, "accepted"),
            official(rs, "rejected")
        );
    }
    let all: Vec<&Row> = rows.iter().collect();
    println!(
        "{:<34} {:>8} {:>10} {:>12.1} {:>9} {:>9} {:>9} {:>9}",
        "TOTAL",
        format!("{solved_all}/{total_all}"),
        median(times_all).map_or("-".into(), |m| format!("{m:.3}")),
        peak_all as f64 / 1024.0,
        rows.iter().filter(|r| r.status == "limit-reached").count(),
        invalid_all,
        official(&all, "accepted"),
        official(&all, "rejected")
    );
    let refused = rows
        .iter()
        .filter(|r| r.official == "rejected" || r.official == "error")
        .count();
    if let Some(f) = csv.into_inner().expect("csv") {
        f.finish()?;
    }
    Ok(if invalid_all > 0 || refused > 0 {
        exit::UNSOLVABLE
    } else {
        exit::OK
    })
}

/// The CSV file, one row appended and flushed per problem as soon as it is known: an
/// interrupted run keeps the rows of the problems it finished. Rows come in the order the
/// problems finish (the run order with `--jobs 1`).
struct CsvFile {
    path: PathBuf,
    file: std::fs::File,
    /// The first failed write, reported when the run ends.
    error: Option<std::io::Error>,
}

impl CsvFile {
    const HEADER: &str = "domain,problem,status,time_s,nodes,peak_memory_kb,plan_length,validated,official,message\n";

    /// Creates (truncates) the file and writes the header.
    fn create(path: &Path) -> anyhow::Result<CsvFile> {
        let mut file = std::fs::File::create(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        file.write_all(Self::HEADER.as_bytes())
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(CsvFile {
            path: path.to_path_buf(),
            file,
            error: None,
        })
    }

    /// Appends one row (unbuffered: the row is in the file when this returns).
    fn append(&mut self, r: &Row) {
        if self.error.is_some() {
            return;
        }
        let fields = [
            csv_field(&r.domain_name),
            csv_field(&r.problem),
            csv_field(&r.status),
            format!("{:.3}", r.time_s),
            r.nodes.to_string(),
            r.peak_kb.to_string(),
            r.plan_len.to_string(),
            r.validated.to_string(),
            csv_field(&r.official),
            csv_field(&r.message),
        ];
        let line = fields.join(",") + "\n";
        if let Err(e) = self.file.write_all(line.as_bytes()) {
            self.error = Some(e);
        }
    }

    /// The first write error, if any.
    fn finish(self) -> anyhow::Result<()> {
        match self.error {
            Some(e) => Err(e).with_context(|| format!("cannot write {}", self.path.display())),
            None => Ok(()),
        }
    }
}

/// A CSV field as RFC 4180 writes it: quoted when it holds a comma, a quote or a line break,
/// with quotes doubled.
pub(crate) fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::csv_field;

    #[test]
    fn csv_fields_are_quoted_as_rfc_4180_says() {
        assert_eq!(csv_field("plain"), "plain");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(csv_field("two\nlines"), "\"two\nlines\"");
    }
}
