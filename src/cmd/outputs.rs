//! The one rule every command that writes files keeps, checked before any work: each output's extension says
//! the kind of file written there, its folder exists, it lands on no input (nor on the image a map YAML input
//! names) and on no other output (a map YAML counts with the PGM and the PNG preview written beside it).

use super::paths::{check_extension, check_not_input, check_output, written_files};
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};

/// The extensions of each kind of file a command writes (lower case, no dot).
pub mod kind {
    /// A map_server map: the YAML (the PGM and the PNG preview are written beside it).
    pub const MAP: &[&str] = &["yaml", "yml"];
    /// A map in any format `map convert` writes.
    pub const ANY_MAP: &[&str] = &["yaml", "yml", "pgm", "png"];
    /// A JSON document (reports, summaries, features).
    pub const JSON: &[&str] = &["json"];
    /// A PNG picture.
    pub const PNG: &[&str] = &["png"];
    /// A rerun recording.
    pub const RRD: &[&str] = &["rrd"];
    /// A ROS 2 bag in one MCAP file.
    pub const MCAP: &[&str] = &["mcap"];
    /// A text table of poses, `stamp x y theta` per line.
    pub const TRAJECTORY: &[&str] = &["txt", "dat"];
    /// A TOML file (worlds).
    pub const TOML: &[&str] = &["toml"];
    /// A CSV table.
    pub const CSV: &[&str] = &["csv"];
    /// Any file a command names itself (its extension is the command's, not the user's).
    pub const ANY: &[&str] = &[];
}

/// The files a command reads and writes, checked by one rule ([`Outputs::check`]) before any work.
#[derive(Default)]
pub struct Outputs {
    inputs: Vec<PathBuf>,
    outputs: Vec<(String, PathBuf, &'static [&'static str])>,
}

impl Outputs {
    /// A command reading `inputs` (a map YAML counts with the image it names).
    pub fn reading<'p>(inputs: impl IntoIterator<Item = &'p Path>) -> Self {
        Outputs { inputs: inputs.into_iter().map(Path::to_path_buf).collect(), outputs: Vec::new() }
    }

    /// An output given to `what` (a flag, e.g. `--summary`), of the kind whose extensions are `kind`.
    pub fn file(mut self, what: &str, path: &Path, kind: &'static [&'static str]) -> Self {
        self.outputs.push((what.to_string(), path.to_path_buf(), kind));
        self
    }

    /// [`Outputs::file`] when the output was asked for.
    pub fn maybe(self, what: &str, path: Option<&Path>, kind: &'static [&'static str]) -> Self {
        match path {
            Some(p) => self.file(what, p, kind),
            None => self,
        }
    }

    /// Fails, naming the flag and the file, unless every output has an extension of its kind, can be written
    /// (its folder exists, no folder in its place), lands on no input and on no other output.
    pub fn check(&self) -> Result<()> {
        let inputs: Vec<&Path> = self.inputs.iter().map(PathBuf::as_path).collect();
        for (what, path, kind) in &self.outputs {
            check_output(path).map_err(|e| anyhow::anyhow!("{what} {e}"))?;
            if !kind.is_empty() {
                check_extension(path, what, kind)?;
            }
            check_not_input(path, &inputs).map_err(|e| anyhow::anyhow!("{what} {e}"))?;
        }
        for (i, (what_a, a, _)) in self.outputs.iter().enumerate() {
            for (what_b, b, _) in &self.outputs[i + 1..] {
                if let Some(file) = first_shared(a, b) {
                    bail!(
                        "{what_a} {} and {what_b} {}: both would write {}; give each output its own name",
                        a.display(),
                        b.display(),
                        file.display()
                    );
                }
            }
        }
        Ok(())
    }
}

/// The first file that writing `a` and writing `b` would both write.
fn first_shared(a: &Path, b: &Path) -> Option<PathBuf> {
    let wb: Vec<PathBuf> = written_files(b).iter().filter_map(|f| super::paths::resolve(f)).collect();
    written_files(a).into_iter().find(|f| super::paths::resolve(f).is_some_and(|r| wb.contains(&r)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_are_checked_against_inputs_each_other_and_their_kind() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let d = dir.path();
        let yaml = d.join("m.yaml");
        std::fs::write(&yaml, "image: pic.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n")?;
        let log = d.join("a.clf");
        let rule = |out: &Path, traj: &Path| {
            Outputs::reading([log.as_path(), yaml.as_path()])
                .file("-o", out, kind::MAP)
                .file("--trajectory", traj, kind::TRAJECTORY)
                .check()
                .map_err(|e| e.to_string())
        };
        assert!(rule(&d.join("s.yaml"), &d.join("t.txt")).is_ok());
        // Two outputs on one file, by name or through the PGM or the preview beside a map.
        let e = rule(&d.join("s.yaml"), &d.join("s.yaml")).unwrap_err();
        assert!(e.contains("--trajectory") && e.contains("s.yaml"), "{e}");
        let e = rule(&d.join("s.yaml"), &d.join("s.pgm")).unwrap_err();
        assert!(e.contains("`.pgm` is not a format written here; expected .txt or .dat"), "{e}");
        let both =
            Outputs::default().file("--summary", &d.join("s.png"), kind::PNG).file("-o", &d.join("s.yml"), kind::MAP);
        let e = both.check().unwrap_err().to_string();
        assert!(e.contains("both would write") && e.contains("s.png"), "{e}");
        // An input, or the image an input map names.
        let e = rule(&yaml, &d.join("t.txt")).unwrap_err();
        assert!(e.contains("-o") && e.contains("refusing to write an output over the input"), "{e}");
        let e = rule(&d.join("pic.yaml"), &d.join("t.txt")).unwrap_err();
        assert!(e.contains("pic.pgm, the image of the input"), "{e}");
        Ok(())
    }
}
