//! Symbolic half of htngtp: HDDL in, totally-ordered HTN plans out.
//!
//! [`model`] is the lifted domain and problem as written in HDDL (with numeric fluents and the
//! geometric extension of `docs/hddl-extension.md`); [`parser`] turns text into it with
//! `FILE:LINE:COL` errors ([`load_domain`], [`load_problem`] for files). [`planner::plan`]
//! searches for a plan (depth-first decomposition with a best-first fallback), and
//! [`validate::validate`] checks a plan as the competition's verifier does. This crate knows
//! nothing of geometry: evaluable predicates reach the world through the
//! [`oracle::GeometricOracle`] trait, which the `hybrid` crate implements with the geometric
//! task planner; without an oracle the planner solves purely symbolic problems.
//!
//! # Example
//!
//! Parse a small domain and problem, plan, print the plan in the competition format and check
//! it with the validator:
//!
//! ```
//! use std::path::PathBuf;
//! use std::sync::Arc;
//! use htn::planner::{Outcome, PlannerOptions, plan};
//!
//! let domain = htn::parse_domain(
//!     "(define (domain lamp)
//!        (:requirements :hierarchy :negative-preconditions)
//!        (:predicates (on))
//!        (:task light :parameters ())
//!        (:method switch-on :parameters () :task (light)
//!          :precondition (not (on)) :ordered-subtasks (and (press)))
//!        (:method already-on :parameters () :task (light)
//!          :precondition (on) :ordered-subtasks (and))
//!        (:action press :parameters () :precondition (not (on)) :effect (on)))",
//!     Arc::new(PathBuf::from("lamp-domain.hddl")),
//! )?;
//! let problem = htn::parse_problem(
//!     "(define (problem dark) (:domain lamp)
//!        (:htn :parameters () :ordered-subtasks (and (light)))
//!        (:init))",
//!     Arc::new(PathBuf::from("dark.hddl")),
//!     &domain,
//! )?;
//!
//! let result = plan(&domain, &problem, &PlannerOptions::default(), None)?;
//! let Outcome::Found { plan } = &result.outcome else {
//!     panic!("no plan: {:?}", result.outcome);
//! };
//! assert_eq!(plan.actions.len(), 1);
//! assert_eq!(plan.actions[0].name, "press");
//! htn::validate::validate(&domain, &problem, plan, &[]).expect("the plan is valid");
//! println!("{}", plan.to_competition_format());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

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
