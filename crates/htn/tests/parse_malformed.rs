//! The malformed-input corpus: every file in `tests/malformed/` is broken on purpose and must
//! give one one-line error `FILE:LINE:COL: message` at the expected place, saying the expected
//! thing, without panicking.
//!
//! Each file starts with `; expect: LINE:COL phrase` (the phrase must occur in the message).
//! A problem file has a second line `; domain: FILE` naming the (valid) domain, in the same
//! folder, that it is read against. Files whose name starts with `_` are those valid domains.

use std::path::{Path, PathBuf};

use htn::parser::{ParseError, load_domain, load_problem};

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed")
}

struct Case {
    path: PathBuf,
    line: u32,
    col: u32,
    phrase: String,
    domain: Option<PathBuf>,
}

fn case(path: &Path) -> Case {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let expect = lines
        .next()
        .and_then(|l| l.strip_prefix("; expect: "))
        .unwrap_or_else(|| {
            panic!(
                "{}: first line must be `; expect: L:C phrase`",
                path.display()
            )
        });
    let (pos, phrase) = expect.split_once(' ').unwrap_or((expect, ""));
    let (line, col) = pos
        .split_once(':')
        .unwrap_or_else(|| panic!("{}: bad position", path.display()));
    let domain = lines
        .next()
        .and_then(|l| l.strip_prefix("; domain: "))
        .map(|d| path.with_file_name(d.trim()));
    Case {
        path: path.to_path_buf(),
        line: line.parse().unwrap(),
        col: col.parse().unwrap(),
        phrase: phrase.trim().to_string(),
        domain,
    }
}

fn run(c: &Case) -> Result<(), ParseError> {
    match &c.domain {
        None => load_domain(&c.path).map(|_| ()),
        Some(d) => {
            let domain =
                load_domain(d).unwrap_or_else(|e| panic!("the corpus domain is broken: {e}"));
            load_problem(&c.path, &domain).map(|_| ())
        }
    }
}

#[test]
fn the_corpus_domains_are_valid() {
    for entry in std::fs::read_dir(corpus()).unwrap() {
        let path = entry.unwrap().path();
        if path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('_'))
        {
            load_domain(&path).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

#[test]
fn every_malformed_file_gives_the_expected_one_line_error() {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(corpus())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "hddl"))
        .filter(|p| {
            !p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('_'))
        })
        .collect();
    paths.sort();
    assert!(paths.len() >= 25, "only {} malformed files", paths.len());
    let mut wrong = Vec::new();
    for path in &paths {
        let c = case(path);
        let outcome = std::panic::catch_unwind(|| run(&c));
        let message = match outcome {
            Err(_) => format!("{}: PANICKED", path.display()),
            Ok(Ok(())) => format!("{}: parsed without error", path.display()),
            Ok(Err(e)) => {
                let shown = e.to_string();
                let prefix = format!("{}:{}:{}: ", path.display(), c.line, c.col);
                if shown.starts_with(&prefix)
                    && e.message.contains(&c.phrase)
                    && !shown.contains('\n')
                {
                    continue;
                }
                format!(
                    "expected {}:{} `{}`, got\n    {shown}",
                    c.line, c.col, c.phrase
                )
            }
        };
        wrong.push(message);
    }
    assert!(
        wrong.is_empty(),
        "{} of {} cases wrong:\n{}",
        wrong.len(),
        paths.len(),
        wrong.join("\n")
    );
}
