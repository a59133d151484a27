//! `htngtp bench-hddl`.

/// Arguments of `htngtp bench-hddl`.
#[derive(clap::Args)]
pub struct Args {}

pub fn run(_args: Args) -> anyhow::Result<u8> {
    anyhow::bail!("`htngtp bench-hddl` is not implemented yet")
}
