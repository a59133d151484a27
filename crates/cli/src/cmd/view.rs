//! `htngtp view PLAN.json`: serves the web viewer (`viewer/dist`, built with npm) and one plan
//! JSON on 127.0.0.1, and prints the URL to open. A tiny static file server on `std::net`: GET and
//! HEAD only, loopback only, paths confined to the viewer directory. The plan is re-read on every
//! request, so re-planning and reloading the page shows the new plan. The visual mesh files the
//! plan names (`scene.agents[].links[].visuals[]`: `uri` `mesh/N.EXT` for `file`) are served at
//! `/mesh/N.EXT`, and no other file outside the viewer directory.

use std::collections::HashMap;
use std::fs;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::path::{Component, Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, SystemTime};

use anyhow::{Context, bail};

use crate::exit;

/// The environment variable naming the built viewer directory.
pub const DIST_ENV: &str = "HTNGTP_VIEWER_DIST";
/// The URL path at which the plan is served (the page loads `plan.json` beside itself).
const PLAN_PATH: &str = "/plan.json";
/// The URL folder of the plan's visual mesh files.
const MESH_PREFIX: &str = "/mesh/";
/// Longest request head accepted (request line and headers).
const MAX_HEAD: usize = 16 * 1024;

/// Arguments of `htngtp view`.
#[derive(clap::Args)]
#[command(after_help = "The viewer is a web page built with npm: \
                  `npm --prefix viewer ci && npm --prefix viewer run build` in the repository. \
                  It is looked for in --dist, then $HTNGTP_VIEWER_DIST, then viewer/dist above \
                  the executable, the current directory and the source tree.")]
pub struct Args {
    /// The plan JSON to show (`htngtp plan --json`, `htngtp demo`; format: docs/plan-json.md).
    pub plan: PathBuf,
    /// Port on 127.0.0.1 (0 picks a free one).
    #[arg(long, default_value_t = 8765)]
    pub port: u16,
    /// The built viewer directory (holding index.html).
    #[arg(long, value_name = "DIR")]
    pub dist: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    let plan = fs::canonicalize(&args.plan)
        .with_context(|| format!("cannot open the plan {}", args.plan.display()))?;
    if !plan.is_file() {
        bail!("the plan {} is not a file", plan.display());
    }
    if let Some(warning) = check_plan(&plan)? {
        eprintln!(
            "warning: {}: {warning}; the page will show this error",
            plan.display()
        );
    }
    let env_dist = std::env::var_os(DIST_ENV).map(PathBuf::from);
    let Some(dist) = find_dist(args.dist.as_deref(), env_dist.as_deref())? else {
        eprintln!(
            "error: the viewer is not built; build it with:\n  {}",
            build_command()
        );
        return Ok(exit::BAD_INPUT);
    };
    let listener = TcpListener::bind(SocketAddr::from((Ipv4Addr::LOCALHOST, args.port)))
        .with_context(|| {
            format!(
                "cannot listen on 127.0.0.1:{} (try another --port, or --port 0)",
                args.port
            )
        })?;
    let port = listener.local_addr()?.port();
    println!("htngtp view: http://127.0.0.1:{port}/");
    println!("  plan:   {}", plan.display());
    println!("  viewer: {}", dist.display());
    println!("Open the URL in a browser; Ctrl-C stops the server.");
    let site = Site::new(dist, plan);
    serve(&listener, &site, None);
    Ok(exit::OK)
}

/// Reads the plan once up front to warn about what the page would reject; `Err` if unreadable.
fn check_plan(plan: &Path) -> anyhow::Result<Option<String>> {
    crate::input::check_file(plan)?;
    let text = fs::read_to_string(plan)
        .with_context(|| format!("cannot read the plan {}", plan.display()))?;
    let value: serde_json::Value = match serde_json::from_str(&text) {
        Ok(v) => v,
        Err(e) => {
            return Ok(Some(format!(
                "not valid JSON at line {} column {}: {e}",
                e.line(),
                e.column()
            )));
        }
    };
    Ok(match value.get("format").and_then(|f| f.as_str()) {
        Some("htngtp-plan") => None,
        _ => Some("`format` is not \"htngtp-plan\": not a plan JSON (docs/plan-json.md)".into()),
    })
}

/// The command that builds the viewer, with the source tree's path when it is known.
fn build_command() -> String {
    let viewer = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../viewer");
    match fs::canonicalize(&viewer) {
        Ok(v) if v.join("package.json").is_file() => {
            let v = v.display();
            format!("npm --prefix {v} ci && npm --prefix {v} run build")
        }
        _ => "npm --prefix viewer ci && npm --prefix viewer run build   (in the htngtp repository)"
            .into(),
    }
}

/// The built viewer: `flag`, else `env`, else `viewer/dist` above the executable, the current
/// directory or the source tree. `Ok(None)` when none is built; `Err` when a directory named
/// explicitly lacks index.html.
pub fn find_dist(flag: Option<&Path>, env: Option<&Path>) -> anyhow::Result<Option<PathBuf>> {
    for (what, dir) in [("--dist", flag), (DIST_ENV, env)] {
        if let Some(dir) = dir {
            if !dir.join("index.html").is_file() {
                bail!(
                    "{what} {}: no index.html there; build the viewer with:\n  {}",
                    dir.display(),
                    build_command()
                );
            }
            return Ok(Some(fs::canonicalize(dir)?));
        }
    }
    let mut starts = Vec::new();
    if let Ok(exe) = std::env::current_exe().and_then(fs::canonicalize) {
        starts.push(exe);
    }
    if let Ok(cwd) = std::env::current_dir() {
        starts.push(cwd);
    }
    starts.push(PathBuf::from(env!("CARGO_MANIFEST_DIR")));
    for start in &starts {
        for dir in start.ancestors() {
            let dist = dir.join("viewer").join("dist");
            if dist.join("index.html").is_file() {
                return Ok(Some(fs::canonicalize(dist)?));
            }
        }
    }
    Ok(None)
}

/// What is served: the viewer's files, the plan at `/plan.json`, and the visual mesh files the
/// plan names at `/mesh/N.EXT`.
pub struct Site {
    /// The built viewer directory, canonical.
    pub dist: PathBuf,
    /// The plan JSON file.
    pub plan: PathBuf,
    /// The plan's mesh files by URL path, read again when the plan file changes.
    meshes: Mutex<Option<(PlanStamp, HashMap<String, PathBuf>)>>,
}

/// When a plan file was last modified, and its size: the mesh table is read again when either
/// changes.
type PlanStamp = (Option<SystemTime>, u64);

/// An HTTP response, before it is written.
#[derive(Debug, PartialEq)]
pub struct Response {
    pub status: u16,
    pub content_type: &'static str,
    pub body: Vec<u8>,
}

impl Response {
    fn text(status: u16, body: &str) -> Self {
        Response {
            status,
            content_type: "text/plain; charset=utf-8",
            body: body.as_bytes().to_vec(),
        }
    }
}

/// The most connections served at once, each on its own thread. Beyond it, the accepting
/// thread serves the connection itself (the next waits: back-pressure, not more threads).
pub const MAX_CONNECTIONS: usize = 32;

/// Accepts connections until `max` have been handled (forever with `None`), each on a thread
/// of its own while fewer than `threads` are busy, else on the accepting thread. When no
/// thread can be started the connection is dropped with a message; the server goes on.
pub fn serve(listener: &TcpListener, site: &Site, max: Option<usize>) {
    serve_with(listener, site, max, MAX_CONNECTIONS);
}

fn serve_with(listener: &TcpListener, site: &Site, max: Option<usize>, threads: usize) {
    let busy = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for (handled, stream) in listener.incoming().enumerate() {
            match stream {
                Ok(stream) if busy.load(Ordering::SeqCst) >= threads => answer(stream, site),
                Ok(stream) => {
                    busy.fetch_add(1, Ordering::SeqCst);
                    let busy = &busy;
                    let spawned = std::thread::Builder::new().spawn_scoped(scope, move || {
                        answer(stream, site);
                        busy.fetch_sub(1, Ordering::SeqCst);
                    });
                    if let Err(e) = spawned {
                        busy.fetch_sub(1, Ordering::SeqCst);
                        eprintln!("htngtp view: cannot start a thread ({e}); connection dropped");
                    }
                }
                Err(e) => eprintln!("htngtp view: accept failed: {e}"),
            }
            if max.is_some_and(|m| handled + 1 >= m) {
                break;
            }
        }
    });
}

/// Serves one connection, reporting (not propagating) its error.
fn answer(stream: TcpStream, site: &Site) {
    if let Err(e) = handle(stream, site) {
        eprintln!("htngtp view: {e}");
    }
}

fn handle(mut stream: TcpStream, site: &Site) -> std::io::Result<()> {
    stream.set_read_timeout(Some(Duration::from_secs(10)))?;
    stream.set_write_timeout(Some(Duration::from_secs(10)))?;
    let head = match read_head(&mut stream) {
        Ok(h) => h,
        Err(e) if e.kind() == std::io::ErrorKind::InvalidData => {
            return write_response(&mut stream, &Response::text(400, "bad request\n"), false);
        }
        Err(e) => return Err(e),
    };
    let mut parts = head.lines().next().unwrap_or("").split_whitespace();
    let (method, target) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""));
    let port = stream.local_addr()?.port();
    let response = match method {
        _ if !host_allowed(&head, port) => Response::text(
            403,
            "forbidden: the Host header must be 127.0.0.1:PORT or localhost:PORT\n",
        ),
        "GET" | "HEAD" => site.respond(target),
        _ => Response::text(405, "only GET and HEAD are served\n"),
    };
    write_response(&mut stream, &response, method != "HEAD")
}

/// Whether the request's one `Host` header names this server on loopback (`127.0.0.1:PORT` or
/// `localhost:PORT`), so that a page reaching it through DNS rebinding is refused.
fn host_allowed(head: &str, port: u16) -> bool {
    let hosts: Vec<&str> = head
        .lines()
        .skip(1)
        .filter_map(|l| l.split_once(':'))
        .filter(|(name, _)| name.trim().eq_ignore_ascii_case("host"))
        .map(|(_, value)| value.trim())
        .collect();
    let [host] = hosts[..] else {
        return false;
    };
    let host = host.to_ascii_lowercase();
    host == format!("127.0.0.1:{port}") || host == format!("localhost:{port}")
}

/// The request line and headers, up to the blank line.
fn read_head(stream: &mut TcpStream) -> std::io::Result<String> {
    let mut reader = BufReader::new(stream.take(MAX_HEAD as u64));
    let mut head = String::new();
    loop {
        let mut line = String::new();
        let n = reader.read_line(&mut line)?;
        if n == 0 || line == "\r\n" || line == "\n" {
            break;
        }
        head.push_str(&line);
        if head.len() >= MAX_HEAD {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "request head too long",
            ));
        }
    }
    Ok(head)
}

fn write_response(stream: &mut TcpStream, r: &Response, body: bool) -> std::io::Result<()> {
    let reason = match r.status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        _ => "Internal Server Error",
    };
    let head = format!(
        "HTTP/1.1 {} {reason}\r\nContent-Type: {}\r\nContent-Length: {}\r\n\
         Cache-Control: no-cache\r\nX-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n",
        r.status,
        r.content_type,
        r.body.len()
    );
    stream.write_all(head.as_bytes())?;
    if body {
        stream.write_all(&r.body)?;
    }
    stream.flush()
}

impl Site {
    /// The site of a built viewer directory (canonical) and a plan file.
    pub fn new(dist: PathBuf, plan: PathBuf) -> Site {
        Site {
            dist,
            plan,
            meshes: Mutex::new(None),
        }
    }

    /// The visual mesh file the plan names at URL path `path` (`/mesh/N.EXT`): only a file the
    /// plan's `visuals` list, and only an STL, COLLADA or OBJ file.
    fn mesh_file(&self, path: &str) -> Option<PathBuf> {
        let meta = fs::metadata(&self.plan).ok()?;
        let stamp = (meta.modified().ok(), meta.len());
        let mut cached = self.meshes.lock().unwrap_or_else(|e| e.into_inner());
        if cached.as_ref().is_none_or(|(s, _)| *s != stamp) {
            let text = fs::read(&self.plan).ok()?;
            let value: serde_json::Value = serde_json::from_slice(&text).ok()?;
            *cached = Some((stamp, plan_meshes(&value)));
        }
        let file = cached.as_ref()?.1.get(path)?.clone();
        let ext = file.extension()?.to_str()?.to_ascii_lowercase();
        (matches!(ext.as_str(), "stl" | "dae" | "obj") && file.is_file()).then_some(file)
    }

    /// The response to a GET of `target` (a request target such as `/assets/viewer.js?v=1`).
    pub fn respond(&self, target: &str) -> Response {
        let path = target.split(['?', '#']).next().unwrap_or("");
        let Some(path) = percent_decode(path) else {
            return Response::text(400, "bad percent-encoding in the path\n");
        };
        if path == PLAN_PATH {
            return match fs::read(&self.plan) {
                Ok(body) => Response {
                    status: 200,
                    content_type: "application/json",
                    body,
                },
                Err(e) => Response::text(500, &format!("cannot read the plan: {e}\n")),
            };
        }
        if path.starts_with(MESH_PREFIX) {
            let Some(file) = self.mesh_file(&path) else {
                return Response::text(404, "no such mesh in the plan\n");
            };
            return match fs::read(&file) {
                Ok(body) => Response {
                    status: 200,
                    content_type: content_type(&file),
                    body,
                },
                Err(_) => Response::text(404, "not found\n"),
            };
        }
        let Some(file) = self.resolve(&path) else {
            return Response::text(403, "forbidden path\n");
        };
        match fs::read(&file) {
            Ok(body) => Response {
                status: 200,
                content_type: content_type(&file),
                body,
            },
            Err(_) => Response::text(404, "not found\n"),
        }
    }

    /// The file under `dist` for a decoded URL path, or `None` when the path would leave `dist`
    /// (`..`, absolute components, backslashes, hidden names, or a symlink pointing out).
    pub fn resolve(&self, path: &str) -> Option<PathBuf> {
        let rel = path.strip_prefix('/')?;
        let rel = if rel.is_empty() || rel.ends_with('/') {
            format!("{rel}index.html")
        } else {
            rel.into()
        };
        if rel.contains('\\') || rel.contains('\0') {
            return None;
        }
        let mut file = self.dist.clone();
        for segment in rel.split('/') {
            if segment.is_empty() {
                continue;
            }
            if segment.starts_with('.') || segment.contains(':') {
                return None;
            }
            let mut comps = Path::new(segment).components();
            match (comps.next(), comps.next()) {
                (Some(Component::Normal(c)), None) => file.push(c),
                _ => return None,
            }
        }
        // A symlink inside dist must not lead out of it.
        match fs::canonicalize(&file) {
            Ok(real) if real.starts_with(&self.dist) => Some(real),
            Ok(_) => None,
            Err(_) => Some(file), // does not exist: a 404, not a 403
        }
    }
}

/// The visual mesh files a plan names: URL path (`/` + `uri`) to `file`, for URIs of the form
/// `mesh/NAME` (one segment, no hidden name).
fn plan_meshes(plan: &serde_json::Value) -> HashMap<String, PathBuf> {
    let mut out = HashMap::new();
    let list = |v: &serde_json::Value, key: &str| -> Vec<serde_json::Value> {
        v.get(key)
            .and_then(|a| a.as_array())
            .cloned()
            .unwrap_or_default()
    };
    let Some(scene) = plan.get("scene") else {
        return out;
    };
    for agent in list(scene, "agents") {
        for link in list(&agent, "links") {
            for v in list(&link, "visuals") {
                let (Some(uri), Some(file)) = (
                    v.get("uri").and_then(|u| u.as_str()),
                    v.get("file").and_then(|f| f.as_str()),
                ) else {
                    continue;
                };
                let ok = uri.strip_prefix("mesh/").is_some_and(|name| {
                    !name.is_empty()
                        && !name.starts_with('.')
                        && !name.contains(['/', '\\', ':', '\0'])
                });
                if ok && Path::new(file).is_absolute() {
                    out.insert(format!("/{uri}"), PathBuf::from(file));
                }
            }
        }
    }
    out
}

fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = s.get(i + 1..i + 3)?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

fn content_type(file: &Path) -> &'static str {
    match file.extension().and_then(|e| e.to_str()).unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "json" | "map" => "application/json",
        "png" => "image/png",
        "svg" => "image/svg+xml",
        "ico" => "image/x-icon",
        "wasm" => "application/wasm",
        "txt" => "text/plain; charset=utf-8",
        _ => "application/octet-stream",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh directory with a fake built viewer and a plan beside it.
    fn fixture(name: &str) -> (PathBuf, Site) {
        let root = std::env::temp_dir().join(format!("htngtp-view-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&root);
        fs::create_dir_all(root.join("dist/assets")).unwrap();
        fs::write(
            root.join("dist/index.html"),
            "<!doctype html><title>viewer</title>",
        )
        .unwrap();
        fs::write(root.join("dist/assets/viewer.js"), "console.log(1)").unwrap();
        fs::write(root.join("secret.txt"), "outside").unwrap();
        fs::write(
            root.join("plan.json"),
            r#"{"format":"htngtp-plan","version":1}"#,
        )
        .unwrap();
        let site = Site::new(
            fs::canonicalize(root.join("dist")).unwrap(),
            root.join("plan.json"),
        );
        (root, site)
    }

    #[test]
    fn serves_index_assets_and_the_plan() {
        let (root, site) = fixture("serve");
        let index = site.respond("/");
        assert_eq!(
            (index.status, index.content_type),
            (200, "text/html; charset=utf-8")
        );
        assert!(String::from_utf8_lossy(&index.body).contains("<title>viewer</title>"));
        let js = site.respond("/assets/viewer.js?x=1");
        assert_eq!(
            (js.status, js.content_type),
            (200, "text/javascript; charset=utf-8")
        );
        let plan = site.respond("/plan.json");
        assert_eq!((plan.status, plan.content_type), (200, "application/json"));
        assert_eq!(plan.body, fs::read(root.join("plan.json")).unwrap());
        // Re-read on every request.
        fs::write(root.join("plan.json"), "{}").unwrap();
        assert_eq!(site.respond("/plan.json").body, b"{}");
        assert_eq!(site.respond("/missing.js").status, 404);
        fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn refuses_paths_that_leave_the_viewer_directory() {
        let (root, site) = fixture("traversal");
        for bad in [
            "/../secret.txt",
            "/assets/../../secret.txt",
            "/%2e%2e/secret.txt",
            "/assets/%2E%2E/%2e%2e/secret.txt",
            "/..%2fsecret.txt",
            "/assets\\..\\..\\secret.txt",
            "/.hidden",
            "/C:/Windows",
            "/%00",
        ] {
            let r = site.respond(bad);
            assert!(r.status == 403 || r.status == 400, "{bad} -> {}", r.status);
            assert_ne!(r.body, b"outside", "{bad} leaked a file");
        }
        assert_eq!(site.respond("/%zz").status, 400);
        fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn serves_the_mesh_files_the_plan_names_and_no_other() {
        let (root, site) = fixture("meshes");
        let mesh = root.join("arm.stl");
        fs::write(&mesh, "solid arm\nendsolid arm\n").unwrap();
        let plan = serde_json::json!({
            "format": "htngtp-plan", "version": 1,
            "scene": { "agents": [ { "links": [ { "name": "a", "visuals": [
                { "uri": "mesh/0.stl", "file": fs::canonicalize(&mesh).unwrap() },
                { "uri": "mesh/1.txt", "file": fs::canonicalize(root.join("secret.txt")).unwrap() },
                { "uri": "mesh/../2.stl", "file": fs::canonicalize(&mesh).unwrap() },
            ] } ] } ] }
        });
        fs::write(&site.plan, plan.to_string()).unwrap();
        let r = site.respond("/mesh/0.stl");
        assert_eq!(r.status, 200);
        assert_eq!(r.body, fs::read(&mesh).unwrap());
        // Not a mesh file type, not a name the plan gives, or a name leaving mesh/: refused.
        for bad in [
            "/mesh/1.txt",
            "/mesh/2.stl",
            "/mesh/../2.stl",
            "/mesh/%2e%2e/2.stl",
        ] {
            let r = site.respond(bad);
            assert_eq!(r.status, 404, "{bad}");
            assert_ne!(r.body, b"outside", "{bad} leaked a file");
        }
        // The plan is read again when it changes.
        fs::write(
            &site.plan,
            r#"{"format":"htngtp-plan","version":1,"scene":{}}"#,
        )
        .unwrap();
        assert_eq!(site.respond("/mesh/0.stl").status, 404);
        fs::remove_dir_all(root).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn refuses_symlinks_out_of_the_viewer_directory() {
        let (root, site) = fixture("symlink");
        std::os::unix::fs::symlink(root.join("secret.txt"), root.join("dist/link.txt")).unwrap();
        assert_eq!(site.respond("/link.txt").status, 403);
        fs::remove_dir_all(root).unwrap();
    }

    /// With a pool of one thread, clients that arrive together are all answered (the
    /// accepting thread serves those beyond the pool).
    #[test]
    fn a_full_pool_still_answers_every_client() {
        let (root, site) = fixture("pool");
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        let n = 6;
        let replies = std::thread::scope(|s| {
            s.spawn(|| serve_with(&listener, &site, Some(n), 1));
            let clients: Vec<_> = (0..n)
                .map(|_| {
                    s.spawn(move || {
                        let mut c = TcpStream::connect(addr).unwrap();
                        c.write_all(
                            format!("GET /plan.json HTTP/1.1\r\nHost: {addr}\r\n\r\n").as_bytes(),
                        )
                        .unwrap();
                        let mut out = String::new();
                        c.read_to_string(&mut out).unwrap();
                        out
                    })
                })
                .collect();
            clients
                .into_iter()
                .map(|c| c.join().unwrap())
                .collect::<Vec<_>>()
        });
        assert!(replies.iter().all(|r| r.starts_with("HTTP/1.1 200 OK\r\n")));
        fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn answers_over_tcp_on_loopback() {
        let (root, site) = fixture("tcp");
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        let port = addr.port();
        let requests = [
            format!("GET /plan.json HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n"),
            format!("HEAD / HTTP/1.1\r\nHost: localhost:{port}\r\n\r\n"),
            format!("POST / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nContent-Length: 0\r\n\r\n"),
            format!("GET /../secret.txt HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n"),
            // DNS rebinding: a page of evil.example resolved to 127.0.0.1.
            format!("GET /plan.json HTTP/1.1\r\nHost: evil.example:{port}\r\n\r\n"),
            "GET /plan.json HTTP/1.1\r\n\r\n".to_string(),
            format!(
                "GET /plan.json HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n\r\n",
                port ^ 1
            ),
            format!(
                "GET /plan.json HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nHost: evil.example\r\n\r\n"
            ),
        ];
        let replies = std::thread::scope(|s| {
            s.spawn(|| serve(&listener, &site, Some(requests.len())));
            requests
                .iter()
                .map(|req| {
                    let mut c = TcpStream::connect(addr).unwrap();
                    c.write_all(req.as_bytes()).unwrap();
                    let mut out = String::new();
                    c.read_to_string(&mut out).unwrap();
                    out
                })
                .collect::<Vec<_>>()
        });
        assert!(
            replies[0].starts_with("HTTP/1.1 200 OK\r\n"),
            "{}",
            replies[0]
        );
        assert!(replies[0].contains("Content-Type: application/json\r\n"));
        assert!(replies[0].ends_with(r#"{"format":"htngtp-plan","version":1}"#));
        assert!(replies[1].starts_with("HTTP/1.1 200 OK\r\n"));
        assert!(
            replies[1].ends_with("\r\n\r\n"),
            "HEAD has no body: {}",
            replies[1]
        );
        assert!(replies[2].starts_with("HTTP/1.1 405 "));
        assert!(replies[3].starts_with("HTTP/1.1 403 "));
        for r in &replies[4..] {
            assert!(r.starts_with("HTTP/1.1 403 "), "{r}");
            assert!(r.contains("Host header"), "{r}");
            assert!(!r.contains("htngtp-plan"), "{r}");
        }
        fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn finds_the_viewer_from_the_flag_and_says_what_is_missing() {
        let (root, site) = fixture("find");
        let found = find_dist(Some(&root.join("dist")), None).unwrap();
        assert_eq!(found, Some(site.dist.clone()));
        let err = find_dist(Some(&root), None).unwrap_err().to_string();
        assert!(
            err.contains("no index.html") && err.contains("npm --prefix"),
            "{err}"
        );
        // The flag wins over the environment variable.
        assert_eq!(
            find_dist(Some(&root.join("dist")), Some(&root)).unwrap(),
            Some(site.dist)
        );
        fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn warns_about_plans_the_page_would_reject() {
        let (root, site) = fixture("check");
        assert_eq!(check_plan(&site.plan).unwrap(), None);
        fs::write(&site.plan, "{\n  \"format\": ").unwrap();
        let w = check_plan(&site.plan).unwrap().unwrap();
        assert!(w.contains("line 2"), "{w}");
        fs::write(&site.plan, "[]").unwrap();
        assert!(check_plan(&site.plan).unwrap().unwrap().contains("format"));
        assert!(check_plan(&root.join("nope.json")).is_err());
        fs::remove_dir_all(root).unwrap();
    }
}
