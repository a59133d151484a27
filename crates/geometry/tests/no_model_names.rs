//! No link or joint name of a shipped model (`models/*.urdf`) is written in the code: arms,
//! hands, shoulders, the head and the postures come from each model's SRDF, and the plan JSON
//! carries what the checker needs. This test extracts every link and joint name from the URDFs
//! and searches every `crates/*/src` file for it as a whole identifier, leaving out
//! `#[cfg(test)]` items (tests may name the models they load).

use std::fs;
use std::path::{Path, PathBuf};

/// Names that are also ordinary words or format vocabulary, not a model's own naming: the
/// human model's `eye` link (the concept every agent has), and `base_link` (also the SRDF's
/// `<chain base_link=..>` attribute).
const WORDS: &[&str] = &["eye", "base_link"];

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every `name` of a `<link>` or `<joint>` element in URDF `text`.
fn element_names(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for tag in ["<link", "<joint"] {
        for (i, _) in text.match_indices(tag) {
            let rest = &text[i + tag.len()..];
            if !rest.starts_with(char::is_whitespace) {
                continue;
            }
            let head = &rest[..rest.find('>').unwrap_or(rest.len())];
            if let Some(j) = head.find("name=\"") {
                let v = &head[j + 6..];
                out.push(v[..v.find('"').unwrap_or(v.len())].to_string());
            }
        }
    }
    out
}

/// `text` without its `#[cfg(test)]` items: the attribute, any attributes after it, and the
/// item up to its closing brace (or semicolon).
fn without_tests(text: &str) -> String {
    let mut out = String::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        if line.trim() != "#[cfg(test)]" {
            out.push_str(line);
            out.push('\n');
            continue;
        }
        let mut depth = 0i64;
        let mut opened = false;
        for l in lines.by_ref() {
            depth += l.matches('{').count() as i64 - l.matches('}').count() as i64;
            opened |= l.contains('{');
            let done = if opened {
                depth <= 0
            } else {
                l.trim_end().ends_with(';')
            };
            if done {
                break;
            }
        }
    }
    out
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Lines of `text` where `name` occurs as a whole identifier.
fn occurrences(text: &str, name: &str) -> Vec<String> {
    text.lines()
        .filter(|line| {
            line.match_indices(name).any(|(i, _)| {
                let before = line[..i].chars().next_back();
                let after = line[i + name.len()..].chars().next();
                !before.is_some_and(is_ident) && !after.is_some_and(is_ident)
            })
        })
        .map(|l| l.trim().to_string())
        .collect()
}

fn model_names() -> Vec<String> {
    let mut names = Vec::new();
    let models = fs::read_dir(workspace().join("models")).expect("models/");
    for e in models.flatten() {
        if e.path().extension().is_some_and(|x| x == "urdf") {
            names.extend(element_names(
                &fs::read_to_string(e.path()).expect("a URDF"),
            ));
        }
    }
    names.sort();
    names.dedup();
    names.retain(|n| !WORDS.contains(&n.as_str()));
    names
}

#[test]
fn the_extraction_and_the_test_filter_work() {
    let urdf = "<robot><link name=\"a_link\"/><joint\n name=\"j\" type=\"fixed\"/><linkx name=\"no\"/></robot>";
    assert_eq!(element_names(urdf), ["a_link", "j"]);
    let code = "fn f() { g(\"a_link\") }\n#[cfg(test)]\nmod tests {\n    fn t() {\n        h(\"b\");\n    }\n}\nfn k() {}\n";
    assert_eq!(without_tests(code), "fn f() { g(\"a_link\") }\nfn k() {}\n");
    assert_eq!(
        occurrences("x(\"a_link\"); a_link2; xa_link", "a_link").len(),
        1
    );
    assert!(occurrences("r_a_link", "a_link").is_empty());
}

#[test]
fn no_model_link_or_joint_name_in_the_crates_sources() {
    let names = model_names();
    assert!(names.len() > 50, "names found in models/*.urdf: {names:?}");
    let mut files = Vec::new();
    for e in fs::read_dir(workspace().join("crates"))
        .expect("crates/")
        .flatten()
    {
        rust_files(&e.path().join("src"), &mut files);
    }
    files.sort();
    assert!(files.len() > 50, "sources found: {}", files.len());
    let mut hits = Vec::new();
    for f in &files {
        let text = without_tests(&fs::read_to_string(f).expect("a source file"));
        for n in &names {
            for line in occurrences(&text, n) {
                hits.push(format!("{}: `{n}` in: {line}", f.display()));
            }
        }
    }
    assert!(
        hits.is_empty(),
        "model names in the code:\n{}",
        hits.join("\n")
    );
}
