//! `htngtp plan`.

/// Arguments of `htngtp plan`.
#[derive(clap::Args)]
pub struct Args {}

pub fn run(_args: Args) -> anyhow::Result<u8> {
    anyhow::bail!("`htngtp plan` is not implemented yet")
}
