//! One module per subcommand; each exposes `Args` (clap) and `run(Args) -> anyhow::Result<u8>`.

pub mod bench;
pub mod bench_hddl;
pub mod check;
pub mod demo;
pub mod export;
pub mod facts;
pub mod geo;
pub mod gtp;
pub mod plan;
pub mod render;
pub mod validate;
pub mod view;
