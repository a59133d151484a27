//! `htngtp validate`.

/// Arguments of `htngtp validate`.
#[derive(clap::Args)]
pub struct Args {}

pub fn run(_args: Args) -> anyhow::Result<u8> {
    anyhow::bail!("`htngtp validate` is not implemented yet")
}
