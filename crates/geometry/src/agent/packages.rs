//! Where the files a URDF names are: `package://NAME/PATH`, `file://PATH` and plain paths.
//!
//! A `package://NAME/PATH` URI names the folder whose `package.xml` declares
//! `<name>NAME</name>`, found as ROS finds it: each folder of the package path is searched,
//! recursively, for `package.xml` files (a folder holding one is a package, and the search does
//! not go below it); the first folder of the path that holds the package wins. The package path
//! is, in this order: the folders given on the command line (`--package-path DIR`,
//! [`set_command_line_dirs`]), the scene's `package_path`, then `ROS_PACKAGE_PATH` (folders
//! separated by `:`). `file://PATH` is an absolute path; any other name is a path relative to
//! the URDF file's folder.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock, RwLock};

/// How deep below a folder of the package path `package.xml` files are looked for.
const MAX_SEARCH_DEPTH: usize = 8;

static COMMAND_LINE_DIRS: RwLock<Vec<PathBuf>> = RwLock::new(Vec::new());

/// Sets the folders given on the command line (`--package-path DIR`, repeatable); they are
/// searched before the scene's and `ROS_PACKAGE_PATH`'s.
pub fn set_command_line_dirs(dirs: Vec<PathBuf>) {
    *COMMAND_LINE_DIRS.write().unwrap_or_else(|e| e.into_inner()) = dirs;
}

/// Where a URDF's file names are resolved: the URDF's folder and the package path.
#[derive(Clone, Debug, Default)]
pub struct PackagePath {
    /// The folder of the URDF file (relative names are resolved against it).
    pub urdf_dir: PathBuf,
    /// The scene's `package_path` folders (already resolved against the scene's folder).
    pub scene_dirs: Vec<PathBuf>,
}

/// A file name of a URDF that names no file: what was tried.
#[derive(Debug, Clone, PartialEq)]
pub struct NotFound {
    /// What is wrong, with every place searched.
    pub message: String,
}

impl PackagePath {
    /// The package path's folders in search order (command line, scene, `ROS_PACKAGE_PATH`).
    pub fn dirs(&self) -> Vec<PathBuf> {
        let mut dirs: Vec<PathBuf> = COMMAND_LINE_DIRS
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .clone();
        dirs.extend(self.scene_dirs.iter().cloned());
        if let Some(env) = std::env::var_os("ROS_PACKAGE_PATH") {
            dirs.extend(std::env::split_paths(&env).filter(|p| !p.as_os_str().is_empty()));
        }
        dirs
    }

    /// The file `uri` names (`package://`, `file://` or a path relative to the URDF); the file
    /// need not exist, but a package that cannot be found is an error naming every folder
    /// searched.
    pub fn resolve(&self, uri: &str) -> Result<PathBuf, NotFound> {
        if let Some(rest) = uri.strip_prefix("package://") {
            let (name, path) = rest.split_once('/').unwrap_or((rest, ""));
            if name.is_empty() || path.is_empty() {
                return Err(NotFound {
                    message: "not of the form package://NAME/PATH".to_string(),
                });
            }
            let dirs = self.dirs();
            for dir in &dirs {
                if let Some(root) = packages_under(dir).get(name) {
                    return Ok(root.join(path));
                }
            }
            let searched = if dirs.is_empty() {
                "the package path is empty (give --package-path DIR, the scene's \
                 `package_path`, or ROS_PACKAGE_PATH)"
                    .to_string()
            } else {
                let list: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
                format!(
                    "no package.xml declaring <name>{name}</name> in {}",
                    list.join(", ")
                )
            };
            return Err(NotFound {
                message: format!("package `{name}` not found: {searched}"),
            });
        }
        if let Some(path) = uri.strip_prefix("file://") {
            return Ok(PathBuf::from(path));
        }
        Ok(self.urdf_dir.join(uri))
    }
}

/// The packages below `dir`: name to folder, crawled once per folder and process.
fn packages_under(dir: &Path) -> HashMap<String, PathBuf> {
    static CRAWLED: OnceLock<Mutex<HashMap<PathBuf, HashMap<String, PathBuf>>>> = OnceLock::new();
    let cache = CRAWLED.get_or_init(Default::default);
    let key = dir.to_path_buf();
    if let Some(found) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return found.clone();
    }
    let mut found = HashMap::new();
    crawl(dir, 0, &mut found);
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(key, found.clone());
    found
}

fn crawl(dir: &Path, depth: usize, found: &mut HashMap<String, PathBuf>) {
    let manifest = dir.join("package.xml");
    if manifest.is_file() {
        if let Some(name) = std::fs::read_to_string(&manifest)
            .ok()
            .and_then(|t| package_name(&t))
        {
            found.entry(name).or_insert_with(|| dir.to_path_buf());
        }
        return;
    }
    if depth >= MAX_SEARCH_DEPTH {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut subdirs: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
        .map(|e| e.path())
        .filter(|p| {
            !p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        })
        .collect();
    subdirs.sort();
    for sub in subdirs {
        crawl(&sub, depth + 1, found);
    }
}

/// The text of the first `<name>` element of a `package.xml`.
fn package_name(text: &str) -> Option<String> {
    let start = text.find("<name>")? + "<name>".len();
    let end = start + text[start..].find("</name>")?;
    let name = text[start..end].trim();
    (!name.is_empty()).then(|| name.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_name_is_read() {
        let xml = "<?xml version=\"1.0\"?>\n<package format=\"2\">\n  <name> my_robot </name>\n";
        assert_eq!(package_name(xml).as_deref(), Some("my_robot"));
        assert_eq!(package_name("<package/>"), None);
    }

    #[test]
    fn relative_and_file_uris() {
        let p = PackagePath {
            urdf_dir: PathBuf::from("/robots/x/urdf"),
            scene_dirs: Vec::new(),
        };
        assert_eq!(
            p.resolve("meshes/a.stl").unwrap(),
            PathBuf::from("/robots/x/urdf/meshes/a.stl")
        );
        assert_eq!(
            p.resolve("file:///m/b.stl").unwrap(),
            PathBuf::from("/m/b.stl")
        );
        assert!(p.resolve("package://only").is_err());
    }

    #[test]
    fn packages_are_found_below_a_folder() {
        let root = std::env::temp_dir().join(format!("htngtp-pkg-{}", std::process::id()));
        let pkg = root.join("src").join("arm_description");
        std::fs::create_dir_all(&pkg).unwrap();
        std::fs::write(
            pkg.join("package.xml"),
            "<package><name>arm</name></package>",
        )
        .unwrap();
        let p = PackagePath {
            urdf_dir: PathBuf::new(),
            scene_dirs: vec![root.clone()],
        };
        assert_eq!(
            p.resolve("package://arm/m/l.stl").unwrap(),
            pkg.join("m/l.stl")
        );
        let e = p.resolve("package://other/m/l.stl").unwrap_err();
        assert!(e.message.contains("package `other`"), "{}", e.message);
        assert!(
            e.message.contains(&root.display().to_string()),
            "{}",
            e.message
        );
        std::fs::remove_dir_all(&root).unwrap();
    }
}
