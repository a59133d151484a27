//! HTN <-> GTP coupling: evaluable predicates answered by the geometric task planner, shared
//! literals as add and delete lists, interleaved backtracking.
//!
//! [`oracle::GtpOracle`] implements the `htn` crate's [`htn::oracle::GeometricOracle`] with the
//! `gtp` crate; the HTN search owns the choice points and the backtracking strategy
//! ([`htn::planner::Strategy`]), the oracle owns the stack of geometric worlds.

pub mod experiment;
pub mod export;
pub mod layout;
pub mod oracle;
pub mod random_layout;
pub mod run;
pub mod scale;
pub mod timing;

pub use oracle::{GtpOracle, OracleConfig};
pub use run::{HybridError, Run, RunOptions, plan, plan_files};
