//! Checks on the command line's values and input files, before anything is read: limits that
//! are numbers a clock can hold, and files that are files of a sensible size.

use std::path::Path;
use std::time::Duration;

/// The longest time limit accepted (a year): longer is a typing error, and `inf`, `nan` or
/// `1e20` cannot be a `Duration`.
const MAX_SECONDS: f64 = 365.0 * 24.0 * 3600.0;

/// The default cap on an input file, in MiB (HDDL, scene, plan, plan JSON); the environment
/// variable `HTNGTP_MAX_INPUT_MIB` sets another.
pub const DEFAULT_MAX_INPUT_MIB: u64 = 256;

/// The clap value parser of a time limit in seconds: a finite number above 0, at most a year.
pub fn seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v <= MAX_SECONDS => Ok(v),
        _ => Err(format!(
            "expected seconds, a number above 0 and at most {MAX_SECONDS} (a year), found `{s}`"
        )),
    }
}

/// An acceleration limit (`--max-acceleration`): a finite number above 0, at most 1000.
pub fn acceleration(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v <= 1000.0 => Ok(v),
        _ => Err(format!(
            "expected an acceleration in rad/s^2 (or m/s^2), a number above 0 and at most 1000, found `{s}`"
        )),
    }
}

/// A GTP threshold override `KEY=VALUE` (`plan --gtp-set`), checked as `htngtp gtp --set`
/// would apply it, so that a typo is refused before any search.
pub fn gtp_setting(s: &str) -> Result<(String, String), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected KEY=VALUE, found `{s}`"))?;
    let (k, v) = (k.trim().to_string(), v.trim().to_string());
    gtp::task::Constraints::defaults(gtp::task::TaskKind::Pick).set(&k, &v)?;
    Ok((k, v))
}

/// A time limit as a `Duration` (the value passed [`seconds`]; clamped to be safe).
pub fn duration(s: f64) -> Duration {
    Duration::from_secs_f64(s.clamp(0.0, MAX_SECONDS))
}

/// The input cap in bytes: `HTNGTP_MAX_INPUT_MIB` if set to a number, else the default.
pub fn max_input_bytes() -> u64 {
    std::env::var("HTNGTP_MAX_INPUT_MIB")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .unwrap_or(DEFAULT_MAX_INPUT_MIB)
        .saturating_mul(1 << 20)
}

/// Refuses an input that is not a regular file of at most [`max_input_bytes`]: a directory, a
/// device (`/dev/zero`, `/dev/urandom`: endless), or a file too large to read whole. Pipes and
/// FIFOs pass (their size is unknown until read).
pub fn check_file(path: &Path) -> anyhow::Result<()> {
    use std::os::unix::fs::FileTypeExt;
    let meta = std::fs::metadata(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot read: {e}", path.display()))?;
    let kind = meta.file_type();
    let cap = max_input_bytes();
    if kind.is_dir() {
        anyhow::bail!("{}: is a directory, not a file", path.display());
    }
    if kind.is_char_device() || kind.is_block_device() || kind.is_socket() {
        anyhow::bail!("{}: is a device, not a file", path.display());
    }
    if meta.len() > cap {
        anyhow::bail!(
            "{}: the file is {} MiB, more than the {} MiB input cap (HTNGTP_MAX_INPUT_MIB sets it)",
            path.display(),
            meta.len() >> 20,
            cap >> 20
        );
    }
    Ok(())
}

/// Reads and parses an HDDL domain, printing its warnings (`warning: FILE:LINE:COL: ...`).
pub fn load_domain(path: &Path) -> anyhow::Result<htn::model::Domain> {
    let domain = htn::load_domain(path)?;
    for w in &domain.warnings {
        eprintln!("warning: {w}");
    }
    Ok(domain)
}

/// Sets the budget of reading, parsing and compiling: the time limit from `began`, the memory
/// limit (see `htn::budget`).
pub fn set_budget(began: std::time::Instant, time_limit_s: f64, memory_mb: u64) {
    htn::budget::set(began.checked_add(duration(time_limit_s)), Some(memory_mb));
}

/// [`check_file`] for each path.
pub fn check_files<'a>(paths: impl IntoIterator<Item = &'a Path>) -> anyhow::Result<()> {
    paths.into_iter().try_for_each(check_file)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_limits_must_be_finite_positive_and_at_most_a_year() {
        for bad in ["inf", "nan", "1e20", "-1", "0", "", "x"] {
            let e = seconds(bad).unwrap_err();
            assert!(e.contains(&format!("`{bad}`")), "{e}");
        }
        assert_eq!(seconds("2.5"), Ok(2.5));
    }

    #[test]
    fn devices_and_directories_are_refused() {
        let e = check_file(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.contains("is a device"), "{e}");
        let e = check_file(Path::new("/")).unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
    }
}
