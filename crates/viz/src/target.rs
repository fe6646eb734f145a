//! Where a recording goes: an `.rrd` file, a viewer started now, or a viewer already running.

use crate::error::VizError;
use rerun::external::re_uri::RedapUri;
use rerun::sink::{FileSink, FileSinkOptions, GrpcSink, LogSink};
use std::net::{TcpStream, ToSocketAddrs};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The viewer's default gRPC proxy address.
pub const DEFAULT_CONNECT: &str = "127.0.0.1:9876";

/// One destination of a recording.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// An `.rrd` file, written as the run goes under [`partial_path`] and renamed to its name when the recording
    /// finishes, so that an interrupted run leaves nothing that looks complete.
    File(PathBuf),
    /// A rerun viewer started now from PATH (`rerun`), streamed to over gRPC.
    Spawn,
    /// A running viewer, by its gRPC proxy URL (`rerun+http://HOST:PORT/proxy`).
    Connect(String),
}

impl Target {
    /// A `--connect` target from HOST:PORT or a full `rerun+http://HOST:PORT/proxy` URL; `None` means the
    /// viewer's default address.
    pub fn connect(addr: Option<&str>) -> Result<Target, VizError> {
        let addr = addr.unwrap_or(DEFAULT_CONNECT).trim();
        let url = if addr.contains("://") { addr.to_string() } else { format!("rerun+http://{addr}/proxy") };
        match url.parse::<RedapUri>() {
            Ok(RedapUri::Proxy(_)) => Ok(Target::Connect(url)),
            Ok(_) => Err(VizError::BadAddress { addr: addr.to_string(), why: "not a /proxy endpoint".into() }),
            Err(e) => Err(VizError::BadAddress { addr: addr.to_string(), why: e.to_string() }),
        }
    }

    /// A short human description (`file x.rrd`, `viewer at ...`).
    pub fn describe(&self) -> String {
        match self {
            Target::File(p) => format!("file {}", p.display()),
            Target::Spawn => "a new rerun viewer".to_string(),
            Target::Connect(url) => format!("viewer at {url}"),
        }
    }

    /// Opens the destination: creates the file, starts the viewer or dials the address.
    pub(crate) fn open(&self) -> Result<Box<dyn LogSink>, VizError> {
        match self {
            Target::File(path) => open_file(path, &partial_path(path)),
            Target::Spawn => {
                if find_on_path("rerun").is_none() {
                    return Err(VizError::NoViewer);
                }
                if let Some(why) = no_display() {
                    return Err(VizError::Spawn(why));
                }
                let info = rerun::spawn(&rerun::SpawnOptions::default()).map_err(|e| VizError::Spawn(e.to_string()))?;
                let url = format!("rerun+http://127.0.0.1:{}/proxy", info.port);
                // A viewer that cannot open a window exits at once; the gRPC sink would only find out when the
                // work is done and the recording is flushed. Wait here until it listens.
                wait_for_viewer(&url).map_err(|cause| {
                    VizError::Spawn(format!(
                        "the viewer started but does not answer at {url} after {} s ({cause}); record to a file \
                         with --rrd FILE and open it with `rerun FILE`",
                        SPAWN_TIMEOUT.as_secs()
                    ))
                })?;
                grpc(&url)
            }
            Target::Connect(url) => {
                // The gRPC sink connects lazily and waits for a viewer without end: find out now.
                probe(url)?;
                grpc(url)
            }
        }
    }
}

/// How long `--connect` waits for a viewer to answer.
const PROBE_TIMEOUT: Duration = Duration::from_secs(3);
/// How long `--spawn` waits for the viewer it started to listen.
const SPAWN_TIMEOUT: Duration = Duration::from_secs(10);

/// Why no viewer window can open here, when that is plain before trying: on Linux, neither `DISPLAY` nor
/// `WAYLAND_DISPLAY` is set.
fn no_display() -> Option<String> {
    let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    (cfg!(target_os = "linux") && !set("DISPLAY") && !set("WAYLAND_DISPLAY")).then(|| {
        "no display to open a viewer window on (neither DISPLAY nor WAYLAND_DISPLAY is set); record to a file \
         with --rrd FILE and open it with `rerun FILE` where there is a display, or stream to a viewer running \
         elsewhere with --connect HOST:PORT"
            .to_string()
    })
}

/// Polls the viewer at `url` until it accepts connections or [`SPAWN_TIMEOUT`] passes.
fn wait_for_viewer(url: &str) -> Result<(), String> {
    let start = std::time::Instant::now();
    loop {
        match probe(url) {
            Ok(()) => return Ok(()),
            Err(VizError::NoViewerAt { cause, .. }) if start.elapsed() >= SPAWN_TIMEOUT => return Err(cause),
            Err(e) if start.elapsed() >= SPAWN_TIMEOUT => return Err(e.to_string()),
            Err(_) => std::thread::sleep(Duration::from_millis(200)),
        }
    }
}

/// Fails unless something accepts TCP connections at the host and port of `url`.
fn probe(url: &str) -> Result<(), VizError> {
    let bad = |why: String| VizError::BadAddress { addr: url.to_string(), why };
    let authority = url.split("://").nth(1).and_then(|rest| rest.split('/').next()).unwrap_or(url);
    let addrs: Vec<_> =
        authority.to_socket_addrs().map_err(|e| bad(format!("cannot resolve {authority}: {e}")))?.collect();
    let mut last = None;
    for a in &addrs {
        match TcpStream::connect_timeout(a, PROBE_TIMEOUT) {
            Ok(_) => return Ok(()),
            Err(e) => last = Some(e),
        }
    }
    Err(VizError::NoViewerAt {
        addr: url.to_string(),
        cause: last.map_or_else(|| "no address".to_string(), |e| e.to_string()),
    })
}

/// Where the recording for `path` is written until it finishes: `NAME.partial.rrd` beside it (an interrupted run's
/// recording stays there, readable by the viewer up to where the run stopped).
pub fn partial_path(path: &Path) -> PathBuf {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!("{stem}.partial.rrd"))
}

fn open_file(path: &Path, partial: &Path) -> Result<Box<dyn LogSink>, VizError> {
    let err = |cause: String| VizError::CreateFile { path: path.to_path_buf(), cause };
    if path.is_dir() {
        return Err(err("it is a folder".into()));
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        return Err(err(format!("folder {} does not exist", dir.display())));
    }
    // FileSink creates the file now, so a path that cannot be written fails here, before any work is done. The
    // footer (one manifest per store, for random access and for `rerun rrd verify`) is written when the sink is
    // dropped; its manifests come out in hash-map order, so two runs' files hold the same messages but not always
    // the same bytes (`inspect::first_difference` compares the content).
    let options = FileSinkOptions::default();
    let sink = FileSink::with_options(partial, options).map_err(|e| match e {
        rerun::sink::FileSinkError::CreateFile { source, .. } => err(source.to_string()),
        other => err(other.to_string()),
    })?;
    Ok(Box::new(sink))
}

fn grpc(url: &str) -> Result<Box<dyn LogSink>, VizError> {
    match url.parse::<RedapUri>() {
        Ok(RedapUri::Proxy(uri)) => Ok(Box::new(GrpcSink::new(uri))),
        Ok(_) => Err(VizError::BadAddress { addr: url.to_string(), why: "not a /proxy endpoint".into() }),
        Err(e) => Err(VizError::BadAddress { addr: url.to_string(), why: e.to_string() }),
    }
}

/// The first executable called `name` on PATH.
pub fn find_on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(name)).find(|p| is_executable(p))
}

#[cfg(unix)]
fn is_executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    p.metadata().is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

#[cfg(not(unix))]
fn is_executable(p: &Path) -> bool {
    p.is_file() || p.with_extension("exe").is_file()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn connect_addresses() {
        assert_eq!(Target::connect(None).unwrap(), Target::Connect("rerun+http://127.0.0.1:9876/proxy".into()));
        assert_eq!(
            Target::connect(Some("10.0.0.5:9000")).unwrap(),
            Target::Connect("rerun+http://10.0.0.5:9000/proxy".into())
        );
        assert!(Target::connect(Some("rerun+http://127.0.0.1:9876/proxy")).is_ok());
        let e = Target::connect(Some("not an address at all")).unwrap_err().to_string();
        assert!(e.contains("not an address at all"), "{e}");
    }

    #[test]
    fn unwritable_files_are_refused_with_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let e = Target::File(dir.path().to_path_buf()).open().err().unwrap().to_string();
        assert!(e.contains("it is a folder"), "{e}");
        let missing = dir.path().join("no/such/dir/run.rrd");
        let e = Target::File(missing.clone()).open().err().unwrap().to_string();
        assert!(e.contains(&missing.display().to_string()) && e.contains("does not exist"), "{e}");
    }
}
