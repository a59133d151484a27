//! HDDL text to the [`crate::model`], with file:line:column errors.
//!
//! Reads what the total-order track of the International Planning Competition 2020 uses
//! (`:ordered-subtasks`, `:ordered-tasks`, `:subtasks`/`:tasks` with `:ordering`, method
//! preconditions, `:constraints`, negative preconditions, `=`, `forall`/`exists`/`or`/`imply`,
//! `forall`/`when` effects, constants, types with several parents, `sortof`), numeric fluents
//! in the PDDL 2.1 style, and the geometric extension (`:shared-predicates`,
//! `:geometric-tasks`, `(evaluable (t ...))`); see `docs/hddl-extension.md`.
//!
//! Everything is checked as it is read: declared names, arities, argument types (a variable
//! must have a type compatible with the parameter's, a constant or object a subtype of it),
//! bound variables, duplicate declarations, a totally ordered task network without cycles,
//! shared predicates kept out of `:init` and effects, and evaluable predicates only as
//! conjuncts of an action's top-level precondition (at most one per action), and a problem
//! whose `(:domain NAME)` is not the domain it is read with (an error, not a warning: its
//! names would be checked against the wrong declarations). The first
//! problem found is returned as a [`ParseError`]; no input makes the parser panic (nesting is
//! limited to [`MAX_DEPTH`] levels, so no input can exhaust the stack either).

mod context;
mod domain;
mod error;
mod formula;
mod problem;
mod sexpr;
mod tasknet;
mod types;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::model::{Domain, Problem, SourceName, Span};

pub use domain::parse_domain;
pub use error::ParseError;
pub use problem::parse_problem;
pub use sexpr::MAX_DEPTH;
pub use types::{MAX_TYPES, TypeTable, TypeTableError};

/// Reads and parses a domain file.
pub fn load_domain(path: impl AsRef<Path>) -> Result<Domain, ParseError> {
    let path = path.as_ref();
    let source: SourceName = Arc::new(path.to_path_buf());
    let text = read_text(path, &source)?;
    parse_domain(&text, source)
}

/// Reads and parses a problem file of `domain`.
pub fn load_problem(path: impl AsRef<Path>, domain: &Domain) -> Result<Problem, ParseError> {
    let path = path.as_ref();
    let source: SourceName = Arc::new(path.to_path_buf());
    let text = read_text(path, &source)?;
    parse_problem(&text, source, domain)
}

/// The text of a file; a file that is not UTF-8 is an error at the first bad byte.
fn read_text(path: &Path, source: &SourceName) -> Result<String, ParseError> {
    // The text is held whole: it must fit in the memory budget, with the tree read from it
    // (checked as it is read).
    let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    if !crate::budget::fits(len) {
        return Err(ParseError::whole_file(
            source,
            crate::budget::message(
                crate::planner::Limit::Memory,
                &format!("reading this file of {} MiB", len >> 20),
            ),
        ));
    }
    let bytes = std::fs::read(path)
        .map_err(|e| ParseError::whole_file(source, format!("cannot read the file: {e}")))?;
    String::from_utf8(bytes).map_err(|e| {
        let good = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let before = String::from_utf8_lossy(bytes.get(..good).unwrap_or_default());
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        ParseError::new(
            source,
            Span {
                line: u32::try_from(line).unwrap_or(u32::MAX),
                col: u32::try_from(col).unwrap_or(u32::MAX),
            },
            "the file is not valid UTF-8 text",
        )
    })
}

/// The domain file that goes with a problem file, by the conventions of the IPC benchmark
/// folders: `X-domain.hddl` beside `X.hddl` (Monroe, Entertainment, the feature tests), else
/// `domain.hddl` in the problem's folder or in its parent folder. `None` if none exists.
pub fn domain_file_for(problem: &Path) -> Option<PathBuf> {
    let dir = problem.parent().unwrap_or(Path::new(""));
    let mut candidates = Vec::new();
    if let (Some(stem), Some(ext)) = (problem.file_stem(), problem.extension()) {
        let mut name = stem.to_os_string();
        name.push("-domain.");
        name.push(ext);
        candidates.push(dir.join(name));
    }
    candidates.push(dir.join("domain.hddl"));
    if let Some(up) = dir.parent() {
        candidates.push(up.join("domain.hddl"));
    }
    candidates.into_iter().find(|c| c.is_file())
}

/// Whether a file name looks like a domain file (`domain.hddl`, `X-domain.hddl`,
/// `X_domain.hddl`, `domain-X.hddl`); everything else with the `.hddl` extension is a problem.
pub fn is_domain_file_name(path: &Path) -> bool {
    path.file_stem()
        .and_then(|s| s.to_str())
        .is_some_and(|s| s.to_ascii_lowercase().contains("domain"))
}
