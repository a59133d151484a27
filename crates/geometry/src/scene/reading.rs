//! Reading a scene file: bounded reads, and TOML errors located by line, column and key path.

use std::path::Path;

use super::SceneError;

/// Reads a text file of at most `cap` bytes; directories, larger files and endless devices are
/// refused with a reason (reading stops at the cap, whatever the file claims its size is).
pub fn read_capped(path: &Path, cap: u64) -> Result<String, String> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read the scene file: {e}"))?;
    let meta = file
        .metadata()
        .map_err(|e| format!("cannot read the scene file: {e}"))?;
    if meta.is_dir() {
        return Err("is a directory, not a file".into());
    }
    if meta.len() > cap {
        return Err(format!(
            "the file is {} bytes, more than the {} MiB allowed",
            meta.len(),
            cap >> 20
        ));
    }
    let mut bytes = Vec::new();
    file.take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read the scene file: {e}"))?;
    if bytes.len() as u64 > cap {
        return Err(format!(
            "more than the {} MiB allowed (is it a device or an endless stream?)",
            cap >> 20
        ));
    }
    String::from_utf8(bytes).map_err(|e| format!("not UTF-8 text: {e}"))
}

/// Turns a TOML/serde error into a [`SceneError`] with line:column and the key path at its span.
pub(super) fn toml_error(text: &str, source: &str, e: &toml::de::Error) -> SceneError {
    let (line_col, key_path) = match e.span() {
        Some(span) => {
            let (l, c) = line_col_of(text, span.start);
            let path = toml::de::DeTable::parse(text)
                .ok()
                .map(|t| key_path_at(t.get_ref(), span.start))
                .unwrap_or_default();
            (Some((l, c)), path)
        }
        None => (None, String::new()),
    };
    SceneError {
        file: source.to_string(),
        line_col,
        key_path,
        reason: e.message().trim().to_string(),
    }
}

fn line_col_of(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |s| s.chars().count()) + 1;
    (line, col)
}

/// The deepest key path whose key or value span contains `offset`.
fn key_path_at(table: &toml::de::DeTable<'_>, offset: usize) -> String {
    let mut path = String::new();
    walk_table(table, offset, &mut path);
    path
}

fn walk_table(table: &toml::de::DeTable<'_>, offset: usize, path: &mut String) -> bool {
    // A key or value whose span contains the offset.
    for (k, v) in table.iter() {
        if v.span().contains(&offset) || k.span().contains(&offset) {
            push_key(path, k.get_ref());
            walk_value(v.get_ref(), offset, path);
            return true;
        }
    }
    // Tables and arrays of tables written with headers (`[a]`, `[[a]]`) span only their
    // header: look for the offset among their keys.
    for (k, v) in table.iter() {
        let mut sub = String::new();
        let nested = matches!(
            v.get_ref(),
            toml::de::DeValue::Table(_) | toml::de::DeValue::Array(_)
        );
        if nested && walk_value(v.get_ref(), offset, &mut sub) {
            push_key(path, k.get_ref());
            path.push_str(&sub);
            return true;
        }
    }
    false
}

/// Appends the path below `v` (`.key` or `[i]` steps); true if the offset was found inside.
fn walk_value(v: &toml::de::DeValue<'_>, offset: usize, path: &mut String) -> bool {
    match v {
        toml::de::DeValue::Table(t) => {
            let mut sub = String::new();
            if walk_table(t, offset, &mut sub) {
                path.push('.');
                path.push_str(&sub);
                return true;
            }
            false
        }
        toml::de::DeValue::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                if item.span().contains(&offset) {
                    path.push_str(&format!("[{i}]"));
                    walk_value(item.get_ref(), offset, path);
                    return true;
                }
            }
            for (i, item) in a.iter().enumerate() {
                let mut sub = String::new();
                if walk_value(item.get_ref(), offset, &mut sub) {
                    path.push_str(&format!("[{i}]"));
                    path.push_str(&sub);
                    return true;
                }
            }
            false
        }
        _ => false,
    }
}

fn push_key(path: &mut String, k: &str) {
    if !path.is_empty() {
        path.push('.');
    }
    path.push_str(k);
}
