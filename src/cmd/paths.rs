//! The facts about paths the output rule ([`super::outputs::Outputs`]) is made of: whether a file can be
//! written, its extension, the files writing or reading a path touches.

use anyhow::{Result, bail};
use mrslam_core::map_io;
use std::path::{Path, PathBuf};

/// Fails unless a file can be written at `path` (its folder exists, no folder in the way): checked before
/// long work, so that a typo in an output path costs nothing and no result is computed only to be lost.
pub fn check_output(path: &Path) -> Result<()> {
    // A map YAML names its image by text; a name that is not text cannot be written into it, nor shown.
    if path.file_name().is_some_and(|n| n.to_str().is_none()) {
        bail!("{}: cannot write there: the file name is not UTF-8 text; rename it", path.display());
    }
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

/// Makes the output folder `dir` (given to `--out`) when it is not there: its parent must exist, as every
/// output's folder must ([`check_output`]), so a typo in `--out` makes no chain of folders.
pub fn create_out_folder(dir: &Path) -> Result<()> {
    if dir.is_dir() {
        return Ok(());
    }
    check_output(dir).map_err(|e| anyhow::anyhow!("--out {e}"))?;
    std::fs::create_dir(dir).map_err(|e| anyhow::anyhow!("--out {}: cannot create output folder: {e}", dir.display()))
}

/// The lower-case extension of `path` (empty when it has none).
pub fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}

/// Fails unless `path` (given to `what`, e.g. `--png`) ends in one of `allowed` (lower case, no dot).
pub fn check_extension(path: &Path, what: &str, allowed: &[&str]) -> Result<()> {
    let ext = extension(path);
    if allowed.contains(&ext.as_str()) {
        return Ok(());
    }
    let list = allowed.iter().map(|e| format!(".{e}")).collect::<Vec<_>>().join(" or ");
    if ext.is_empty() {
        bail!("{what} {}: no file extension; expected {list}", path.display());
    }
    bail!("{what} {}: `.{ext}` is not a format written here; expected {list}", path.display());
}

fn is_map_yaml(path: &Path) -> bool {
    matches!(extension(path).as_str(), "yaml" | "yml")
}

/// The files that writing `path` creates: itself, and for a map YAML the PGM and the PNG preview beside it.
pub fn written_files(path: &Path) -> Vec<PathBuf> {
    let mut files = vec![path.to_path_buf()];
    if is_map_yaml(path) {
        files.push(path.with_extension("pgm"));
        files.push(map_io::preview_path(path));
    }
    files
}

/// The files that reading `path` reads: itself, and for a map YAML the image it names (when it can be read).
pub fn read_files(path: &Path) -> Vec<PathBuf> {
    let mut files = vec![path.to_path_buf()];
    if is_map_yaml(path)
        && let Ok(text) = std::fs::read_to_string(path)
        && let Ok(meta) = map_io::parse_map_yaml(&text, path)
    {
        files.push(map_io::resolve_image_path(path, &meta.image));
    }
    files
}

/// `path` made absolute with symbolic links resolved; for a file not yet there, its folder's.
pub(super) fn resolve(p: &Path) -> Option<PathBuf> {
    if let Ok(c) = p.canonicalize() {
        return Some(c);
    }
    let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    Some(dir.canonicalize().ok()?.join(p.file_name()?))
}

/// Fails when writing `output` would overwrite one of `inputs` (or the image a map YAML input names).
pub fn check_not_input(output: &Path, inputs: &[&Path]) -> Result<()> {
    for out in written_files(output) {
        let Some(o) = resolve(&out) else { continue };
        for input in inputs {
            for read in read_files(input) {
                if resolve(&read).as_deref() == Some(o.as_path()) {
                    let what = if read == *input {
                        format!("the input {}", input.display())
                    } else {
                        format!("{}, the image of the input {}", read.display(), input.display())
                    };
                    bail!("{}: refusing to write an output over {what}", output.display());
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_yaml_counts_with_its_image() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let yaml = dir.path().join("m.yaml");
        std::fs::write(&yaml, "image: pic.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n")?;
        assert!(check_not_input(&dir.path().join("pic.pgm"), &[&yaml]).is_err());
        assert!(check_not_input(&dir.path().join("other.yaml"), &[&yaml]).is_ok());
        assert!(check_extension(Path::new("willow"), "OUT", &["yaml"]).is_err());
        Ok(())
    }

    #[cfg(unix)]
    #[test]
    fn an_output_name_that_is_not_text_is_refused() {
        use std::os::unix::ffi::OsStrExt;
        let name = std::ffi::OsStr::from_bytes(b"y\xff.yaml");
        let e = check_output(Path::new(name)).unwrap_err().to_string();
        assert!(e.contains("not UTF-8"), "{e}");
    }
}
