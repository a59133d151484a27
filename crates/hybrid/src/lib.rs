//! HTN <-> GTP coupling: evaluable predicates answered by the geometric task planner, shared
//! literals as add and delete lists, interleaved backtracking.
//!
//! [`oracle::GtpOracle`] implements the `htn` crate's [`htn::oracle::GeometricOracle`] with the
//! `gtp` crate; the HTN search owns the choice points and the backtracking strategy
//! ([`htn::planner::Strategy`]), the oracle owns the stack of geometric worlds. [`plan`] and
//! [`plan_files`] run a whole request, [`export::plan_json`] writes the plan JSON
//! (`docs/plan-json.md`) with timed trajectories ([`timing`]); [`experiment`], [`scale`],
//! [`layout`], [`random_layout`] and [`room_layout`] are the benchmarks of `htngtp bench`.
//!
//! # Example
//!
//! Plan the library's lend-and-debit problem in its scene with geometric-first backtracking,
//! then write the plan JSON:
//!
//! ```
//! use std::path::Path;
//! use htn::planner::{Outcome, PlannerOptions, Strategy};
//! use hybrid::RunOptions;
//!
//! let library = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../domains/library");
//! let options = RunOptions {
//!     planner: PlannerOptions {
//!         strategy: Strategy::GeometricFirst { k: 3 },
//!         ..PlannerOptions::default()
//!     },
//!     ..RunOptions::default()
//! };
//! let run = hybrid::plan_files(
//!     &library.join("domain-compound.hddl"),
//!     &library.join("lend-and-debit.hddl"),
//!     &library.join("scene.toml"),
//!     &options,
//! )?;
//! let Outcome::Found { plan } = &run.result.outcome else {
//!     panic!("{}", run.failure_message());
//! };
//! // A GS action carries the shared literals its geometric solution changed.
//! let step = plan.actions.iter().find_map(|a| a.geometric.as_ref()).expect("a GS action");
//! println!("{}({}): + {:?}", step.task, step.args.join(", "), step.add);
//! assert!(!step.add.is_empty());
//!
//! let json = hybrid::export::plan_json(&run, "library", "lend-and-debit");
//! assert_eq!(json["status"], "solved");
//! assert_eq!(json["steps"].as_array().map(Vec::len), Some(plan.actions.len()));
//! # Ok::<(), hybrid::HybridError>(())
//! ```

pub mod experiment;
pub mod export;
pub mod layout;
pub mod oracle;
pub mod random_layout;
pub mod room_layout;
pub mod run;
pub mod scale;
mod stream_memo;
pub mod timing;

pub use oracle::{GtpOracle, OracleConfig};
pub use run::{HybridError, Run, RunOptions, plan, plan_files};
