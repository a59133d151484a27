//! Symbolic half of htngtp: HDDL in, totally-ordered HTN plans out.
//!
//! `model` is the lifted domain and problem as written in HDDL (with numeric fluents and the
//! geometric extension); `parser` turns text into it with file:line:column errors. The planner and
//! the validator work on that model. This crate knows nothing of geometry: evaluable predicates
//! reach the world through a trait that the `hybrid` crate implements.

pub mod budget;
pub mod model;
pub mod oracle;
pub mod parser;
pub mod plan;
pub mod planner;
pub mod state;
pub mod text;
pub mod validate;

pub use parser::{ParseError, load_domain, load_problem, parse_domain, parse_problem};
