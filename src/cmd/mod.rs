//! One module per subcommand.

pub mod eval;
pub mod features;
pub mod log;
pub mod map;
pub mod merge;
pub mod run;
pub mod slam;
pub mod study;
pub mod viz;

use anyhow::{Result, bail};
use std::path::Path;

/// Fails unless a file can be written at `path` (its folder exists, no folder in the way): checked before
/// long work, so that a typo in an output path costs nothing and no result is computed only to be lost.
pub fn check_output(path: &Path) -> Result<()> {
    if path.is_dir() {
        bail!("{}: cannot write there: it is a folder", path.display());
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        bail!("{}: cannot write there: folder {} does not exist", path.display(), dir.display());
    }
    Ok(())
}

/// Fails when `output` names the same file as one of `inputs`: an output never overwrites an input.
pub fn check_not_input(output: &Path, inputs: &[&Path]) -> Result<()> {
    let resolve = |p: &Path| -> Option<std::path::PathBuf> {
        if let Ok(c) = p.canonicalize() {
            return Some(c);
        }
        let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        Some(dir.canonicalize().ok()?.join(p.file_name()?))
    };
    let Some(out) = resolve(output) else { return Ok(()) };
    for input in inputs {
        if resolve(input).as_deref() == Some(out.as_path()) {
            bail!("{}: refusing to write an output over the input {}", output.display(), input.display());
        }
    }
    Ok(())
}

/// The process's peak resident memory, bytes (Linux: VmHWM of /proc/self/status; `None` elsewhere).
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}
