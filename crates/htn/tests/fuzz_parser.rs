//! Property test: the parser never panics, and every error it gives points inside the text.
//!
//! Inputs are seeded mutations (bytes deleted, inserted, swapped; parentheses dropped or
//! doubled; tokens spliced; spans duplicated; truncation) of real HDDL files: the shared
//! benchmark folders when present (files up to 64 kB), the project's own domains and this
//! crate's malformed corpus always. `HTN_FUZZ_ITERS` sets the number of inputs (default
//! 20,000) and `HTN_FUZZ_SEED` the seed; a failing input is written to the temp folder and its
//! iteration named, so it can be replayed.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use htn::model::{Domain, SourceName};
use htn::parser::{ParseError, domain_file_for, is_domain_file_name, parse_domain, parse_problem};

/// A text to mutate, with the domain to read it against when it is a problem.
struct Seed {
    text: Vec<u8>,
    domain: Option<Arc<Domain>>,
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            collect(&path, out);
        } else if path.extension().is_some_and(|e| e == "hddl")
            && std::fs::metadata(&path).is_ok_and(|m| m.len() <= 64 * 1024)
        {
            out.push(path);
        }
    }
}

fn seeds() -> Vec<Seed> {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    let shared = manifest.join("../../../shared/benchmarks");
    if shared.is_dir() {
        collect(&shared, &mut files);
    } else {
        eprintln!(
            "note: {} is absent; fuzzing only the project's own HDDL files",
            shared.display()
        );
    }
    collect(&manifest.join("../../domains"), &mut files);
    collect(&manifest.join("tests/malformed"), &mut files);
    files.sort();

    let mut seeds = Vec::new();
    for path in files {
        let Ok(text) = std::fs::read(&path) else {
            continue;
        };
        let domain = if is_domain_file_name(&path) {
            None
        } else {
            // A problem whose domain does not parse is fuzzed as a domain: still a fine input.
            domain_file_for(&path)
                .and_then(|d| htn::parser::load_domain(d).ok())
                .map(Arc::new)
        };
        seeds.push(Seed { text, domain });
    }
    assert!(seeds.len() >= 20, "too few seed files: {}", seeds.len());
    seeds
}

const TOKENS: &[&str] = &[
    "(",
    ")",
    "()",
    " ",
    "\n",
    "-",
    "?",
    "?x",
    ":",
    "and",
    "or",
    "not",
    "imply",
    "forall",
    "exists",
    "when",
    "=",
    "<",
    ">=",
    "+",
    "-1",
    "1.5",
    "1.2.3",
    "1e9",
    "evaluable",
    "sortof",
    "either",
    ":parameters",
    ":task",
    ":subtasks",
    ":ordered-subtasks",
    ":ordering",
    ":tasks",
    ":precondition",
    ":effect",
    ":constraints",
    ":types",
    ":init",
    ":htn",
    ":objects",
    "object",
    "(< t0 t1)",
    "(< t1 t0)",
    "increase",
    "(define",
    "(domain",
    ";",
    "\u{e9}",
    "\u{1F600}",
    "\t",
];

fn mutate(rng: &mut fastrand::Rng, text: &mut Vec<u8>) {
    let n = text.len();
    let pos = |rng: &mut fastrand::Rng| if n == 0 { 0 } else { rng.usize(0..=n) };
    match rng.u8(0..10) {
        // Delete a short range.
        0 => {
            let a = pos(rng).min(n);
            let b = (a + rng.usize(1..=8)).min(n);
            text.drain(a..b);
        }
        // Insert random bytes (possibly invalid UTF-8).
        1 => {
            let at = pos(rng).min(n);
            let bytes: Vec<u8> = (0..rng.usize(1..=4)).map(|_| rng.u8(..)).collect();
            text.splice(at..at, bytes);
        }
        // Swap two bytes.
        2 if n >= 2 => {
            let (a, b) = (rng.usize(0..n), rng.usize(0..n));
            text.swap(a, b);
        }
        // Drop a parenthesis.
        3 => {
            let parens: Vec<usize> = (0..n)
                .filter(|&i| matches!(text.get(i), Some(b'(' | b')')))
                .collect();
            if !parens.is_empty() {
                let i = parens[rng.usize(0..parens.len())];
                text.remove(i);
            }
        }
        // Duplicate a parenthesis.
        4 => {
            let parens: Vec<usize> = (0..n)
                .filter(|&i| matches!(text.get(i), Some(b'(' | b')')))
                .collect();
            if !parens.is_empty() {
                let i = parens[rng.usize(0..parens.len())];
                let c = text[i];
                text.insert(i, c);
            }
        }
        // Insert a token of the language.
        5 => {
            let at = pos(rng).min(n);
            let t = TOKENS[rng.usize(0..TOKENS.len())];
            text.splice(at..at, t.bytes().chain(std::iter::once(b' ')));
        }
        // Replace a word with another word of the same text (splice tokens).
        6 if n > 0 => {
            let word = |rng: &mut fastrand::Rng| -> (usize, usize) {
                let mut a = rng.usize(0..n);
                while a > 0 && !text[a - 1].is_ascii_whitespace() && !b"()".contains(&text[a - 1]) {
                    a -= 1;
                }
                let mut b = a;
                while b < n && !text[b].is_ascii_whitespace() && !b"()".contains(&text[b]) {
                    b += 1;
                }
                (a, b)
            };
            let (sa, sb) = word(rng);
            let (da, db) = word(rng);
            let w: Vec<u8> = text[sa..sb].to_vec();
            text.splice(da..db, w);
        }
        // Duplicate a span (e.g. a whole declaration or half of one).
        7 if n > 0 => {
            let a = rng.usize(0..n);
            let b = (a + rng.usize(1..=200)).min(n);
            let chunk: Vec<u8> = text[a..b].to_vec();
            let at = pos(rng).min(n);
            text.splice(at..at, chunk);
        }
        // Truncate.
        8 => {
            let at = pos(rng).min(n);
            text.truncate(at);
        }
        // Change the case of a byte or replace it by a delimiter.
        _ if n > 0 => {
            let i = rng.usize(0..n);
            text[i] = match rng.u8(0..4) {
                0 => text[i].to_ascii_uppercase(),
                1 => b'(',
                2 => b')',
                _ => b' ',
            };
        }
        _ => {}
    }
}

/// Checks that an error names the given file and a line:column inside `text`.
fn check_position(e: &ParseError, text: &str, file: &SourceName) -> Result<(), String> {
    if &e.file != file {
        return Err(format!(
            "error names file {} instead of {}",
            e.file.display(),
            file.display()
        ));
    }
    let line = usize::try_from(e.line).unwrap_or(usize::MAX);
    let Some(l) = text.split('\n').nth(line.wrapping_sub(1)) else {
        return Err(format!("line {} is outside the text: {e}", e.line));
    };
    let col = usize::try_from(e.col).unwrap_or(usize::MAX);
    if col == 0 || col > l.chars().count() + 1 {
        return Err(format!(
            "column {} is outside line {} ({} chars): {e}",
            e.col,
            e.line,
            l.chars().count()
        ));
    }
    let shown = e.to_string();
    if shown.contains('\n') {
        return Err(format!("message spans several lines: {shown:?}"));
    }
    Ok(())
}

#[test]
fn mutated_hddl_never_panics_and_errors_point_into_the_text() {
    let iterations: u64 = std::env::var("HTN_FUZZ_ITERS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000);
    let seed: u64 = std::env::var("HTN_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x5eed_4d31);
    let seeds = seeds();
    let file: SourceName = Arc::new(PathBuf::from("fuzz.hddl"));
    let (mut ok, mut errors) = (0u64, 0u64);
    for i in 0..iterations {
        let mut rng = fastrand::Rng::with_seed(seed ^ i.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let s = &seeds[rng.usize(0..seeds.len())];
        let mut bytes = s.text.clone();
        // Often a single mutation, so that many inputs get past the reader into the checks.
        let mutations = if rng.bool() { 1 } else { rng.usize(2..=4) };
        for _ in 0..mutations {
            mutate(&mut rng, &mut bytes);
        }
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let result = catch_unwind(AssertUnwindSafe(|| match &s.domain {
            Some(d) => parse_problem(&text, file.clone(), d).map(|_| ()),
            None => parse_domain(&text, file.clone()).map(|_| ()),
        }));
        let failure = match result {
            Err(_) => Some("the parser panicked".to_string()),
            Ok(Ok(())) => {
                ok += 1;
                None
            }
            Ok(Err(e)) => {
                errors += 1;
                check_position(&e, &text, &file).err()
            }
        };
        if let Some(why) = failure {
            let dump = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
                .join(format!("htn-fuzz-failure-{seed}-{i}.hddl"));
            let _ = std::fs::write(&dump, &bytes);
            panic!(
                "iteration {i} (HTN_FUZZ_SEED={seed}): {why}; input written to {}",
                dump.display()
            );
        }
    }
    eprintln!("fuzzed {iterations} inputs: {ok} parsed, {errors} refused with a located error");
    assert_eq!(ok + errors, iterations);
    assert!(errors > 0, "mutations should break some inputs");
}
