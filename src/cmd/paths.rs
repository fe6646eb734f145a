//! Output paths checked before any work: the folder exists, the extension says what is written, and no
//! output lands on an input or on another output (a map YAML counts with the image beside it).

use anyhow::{Result, bail};
use mrslam_core::map_io;
use std::path::{Path, PathBuf};

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

/// [`check_output`] and [`check_extension`] at once.
pub fn check_output_kind(path: &Path, what: &str, allowed: &[&str]) -> Result<()> {
    check_extension(path, what, allowed)?;
    check_output(path)
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
fn resolve(p: &Path) -> Option<PathBuf> {
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

/// Fails when two of `outputs` would write the same file (a map YAML counts with its PGM).
pub fn check_distinct(outputs: &[&Path]) -> Result<()> {
    for (i, a) in outputs.iter().enumerate() {
        for b in &outputs[i + 1..] {
            for fa in written_files(a) {
                for fb in written_files(b) {
                    if resolve(&fa).is_some() && resolve(&fa) == resolve(&fb) {
                        bail!("{} and {}: both would write {}", a.display(), b.display(), fa.display());
                    }
                }
            }
        }
    }
    Ok(())
}

/// Checks a command's outputs before any work: each can be written, none is an input, no two collide.
pub fn check_outputs(outputs: &[&Path], inputs: &[&Path]) -> Result<()> {
    for out in outputs {
        check_output(out)?;
        check_not_input(out, inputs)?;
    }
    check_distinct(outputs)
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
        assert!(check_distinct(&[&dir.path().join("a.yaml"), &dir.path().join("a.yml")]).is_err());
        assert!(check_extension(Path::new("willow"), "OUT", &["yaml"]).is_err());
        Ok(())
    }
}
