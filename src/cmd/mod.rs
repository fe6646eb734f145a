//! One module per subcommand.

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
