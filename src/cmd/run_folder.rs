//! A run's output folder. The files a run will write there are checked by the one output rule before the run;
//! they are written into a staging folder inside it and moved into place at the end, so an interrupted run
//! leaves the folder as it was. The files an earlier run wrote there and this one does not are then removed:
//! only those, as listed in the folder's [`MANIFEST`] or named as this run's outputs, and only names a run writes
//! (maps with their images and previews, pictures, `report.json`, recordings and bags): a run removes nothing it
//! did not make. A file of this run's output names already in the folder that no manifest lists (the user's own,
//! or a run's from before manifests) is not overwritten unless asked (`--force`).

use super::paths::written_files;
use super::{Outputs, kind};
use anyhow::{Context, Result, bail};
use mrslam_core::output::write_file_atomic;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The file naming, one per line, the files of the run whose report sits beside it.
pub const MANIFEST: &str = "run-files.txt";

/// A run's output folder, its outputs checked.
pub struct RunFolder {
    dir: PathBuf,
    files: Vec<PathBuf>,
    /// The run's own files given by their own flags (`--rrd`, `--mcap`), written in place, not staged.
    own: Vec<PathBuf>,
    /// The files the scenario reads: never removed, whatever a manifest says.
    inputs: Vec<PathBuf>,
}

/// The extensions of the files a run writes into its folder (maps, their images and previews, overlay pictures,
/// recordings, bags); with `report.json`, the only names a manifest may make a run remove.
const RUN_EXTENSIONS: &[&str] = &["yaml", "pgm", "png", "rrd", "mcap"];

/// Whether a run could have written a file called `name` into its folder.
fn a_runs_name(name: &str) -> bool {
    name == "report.json" || RUN_EXTENSIONS.contains(&super::paths::extension(Path::new(name)).as_str())
}

/// A file of a run given by its own flag: the flag, the file, the kind of file it must be.
pub type OwnOutput<'p> = (&'static str, &'p Path, &'static [&'static str]);

impl RunFolder {
    /// Makes `dir` when it is not there (its parent must exist unless `make_parents`: a typo in `--out` makes
    /// no chain of folders), then checks `files` (the run's outputs in `dir`) and the files given by their own
    /// flags (`own`: a recording, a bag) by the one output rule against `inputs`. A folder made here is removed
    /// again when the check fails. Unless `force`, a file of `files` already in `dir` that no manifest lists is
    /// refused: a run replaces only what a run wrote.
    pub fn prepare(
        dir: &Path,
        make_parents: bool,
        files: Vec<PathBuf>,
        own: &[OwnOutput<'_>],
        inputs: &[PathBuf],
        force: bool,
    ) -> Result<RunFolder> {
        let made = !dir.exists();
        if dir.exists() && !dir.is_dir() {
            bail!("--out {}: is a file, expected a folder", dir.display());
        }
        if made {
            let parent = dir.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
            if !make_parents && !parent.is_dir() {
                bail!("--out {}: cannot create it: folder {} does not exist", dir.display(), parent.display());
            }
            let created = if make_parents { std::fs::create_dir_all(dir) } else { std::fs::create_dir(dir) };
            created.with_context(|| format!("--out {}: cannot create output folder", dir.display()))?;
        }
        let manifest = dir.join(MANIFEST);
        let mut rule = Outputs::reading(inputs.iter().map(PathBuf::as_path));
        // A map's PGM and preview are checked with its YAML.
        let beside_a_map = |f: &PathBuf| files.iter().any(|g| g != f && written_files(g).contains(f));
        for f in files.iter().filter(|f| !beside_a_map(f)).chain([&manifest]) {
            rule = rule.file("--out", f, kind::ANY);
        }
        for (flag, path, kind) in own {
            rule = rule.file(flag, path, kind);
        }
        if let Err(e) = rule.check() {
            if made {
                let _ = std::fs::remove_dir(dir);
            }
            return Err(e);
        }
        if !force {
            refuse_unlisted(dir, &files)?;
        }
        let own = own.iter().map(|(_, p, _)| p.to_path_buf()).collect();
        Ok(RunFolder { dir: dir.to_path_buf(), files, own, inputs: inputs.to_vec() })
    }

    /// Calls `write` on a staging folder inside the run's folder, moves what it wrote into place, removes the
    /// files of an earlier run this one did not rewrite, and writes the [`MANIFEST`]. Returns the removed files.
    pub fn commit(&self, write: impl FnOnce(&Path) -> Result<()>) -> Result<Vec<PathBuf>> {
        let staging = self.dir.join(format!(".mrslam-run-{}.staging", std::process::id()));
        let _ = std::fs::remove_dir_all(&staging);
        std::fs::create_dir(&staging).with_context(|| format!("{}: cannot create", staging.display()))?;
        let moved = write(&staging).and_then(|()| self.move_into_place(&staging));
        let _ = std::fs::remove_dir_all(&staging);
        let mut written = moved?;
        // The earlier run's files: its manifest's, and any of this run's names it left (a refused merge's map).
        let mut earlier = self.manifest();
        earlier.extend(self.files.iter().filter_map(|f| plain_name(f)));
        for r in self.own.iter().filter(|r| r.parent() == Some(self.dir.as_path())) {
            written.extend(plain_name(r));
        }
        let mut removed = Vec::new();
        let resolved_inputs: Vec<PathBuf> = self.inputs.iter().filter_map(|i| i.canonicalize().ok()).collect();
        let ours: BTreeSet<String> = self.files.iter().filter_map(|f| plain_name(f)).collect();
        for name in earlier.difference(&written).filter(|n| ours.contains(*n) || a_runs_name(n)) {
            let path = self.dir.join(name);
            let an_input = path.canonicalize().is_ok_and(|c| resolved_inputs.contains(&c));
            if path.is_file() && !an_input {
                std::fs::remove_file(&path).with_context(|| format!("{}: cannot remove", path.display()))?;
                removed.push(path);
            }
        }
        let mut text = String::from(
            "# The files `mrslam run` wrote here for the report.json beside them; a later run\n\
             # into this folder replaces or removes these and no others.\n",
        );
        for name in &written {
            text.push_str(name);
            text.push('\n');
        }
        write_file_atomic(&self.dir.join(MANIFEST), text.as_bytes())?;
        Ok(removed)
    }

    /// Moves every file of `staging` into the run's folder; returns their names.
    fn move_into_place(&self, staging: &Path) -> Result<BTreeSet<String>> {
        let mut names = BTreeSet::new();
        let mut entries: Vec<PathBuf> = std::fs::read_dir(staging)
            .with_context(|| format!("{}: cannot list", staging.display()))?
            .map(|e| e.map(|e| e.path()))
            .collect::<std::io::Result<_>>()?;
        // report.json last: a folder with a report holds the maps beside it.
        entries.sort_by_key(|p| (p.file_name().is_some_and(|f| f == "report.json"), p.clone()));
        for from in entries {
            let Some(name) = plain_name(&from) else { continue };
            let to = self.dir.join(&name);
            std::fs::rename(&from, &to).with_context(|| format!("{}: cannot move into place", to.display()))?;
            names.insert(name);
        }
        Ok(names)
    }

    /// The names in the folder's [`MANIFEST`].
    fn manifest(&self) -> BTreeSet<String> {
        listed(&self.dir)
    }
}

/// The names in `dir`'s [`MANIFEST`] (none when there is none): plain file names only, so that an edited
/// manifest cannot point outside the folder.
fn listed(dir: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(dir.join(MANIFEST)).unwrap_or_default();
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .filter(|l| Path::new(l).file_name().is_some_and(|f| f == *l) && *l != MANIFEST)
        .map(str::to_string)
        .collect()
}

/// Fails, naming the first, when a file of `files` is already in `dir` and no manifest there lists it.
fn refuse_unlisted(dir: &Path, files: &[PathBuf]) -> Result<()> {
    let listed = listed(dir);
    let unlisted = files.iter().filter(|f| f.is_file()).find(|f| plain_name(f).is_none_or(|n| !listed.contains(&n)));
    if let Some(f) = unlisted {
        bail!(
            "--out {}: {} is there and no earlier run lists it in {MANIFEST} (a file of your own, or a run's from \
             before {MANIFEST} existed): refusing to overwrite it; move it away, or --force to replace it",
            dir.display(),
            f.display()
        );
    }
    Ok(())
}

/// The file name of `path` as text, when it has one.
fn plain_name(path: &Path) -> Option<String> {
    path.file_name().and_then(|f| f.to_str()).map(str::to_string)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_replaces_or_removes_its_own_files_and_no_others() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let d = dir.path();
        let files = vec![d.join("a.json"), d.join("b.json")];
        let folder = RunFolder::prepare(d, false, files.clone(), &[], &[], false)?;
        folder.commit(|s| {
            std::fs::write(s.join("a.json"), "1")?;
            std::fs::write(s.join("b.json"), "1")?;
            Ok(())
        })?;
        std::fs::write(d.join("mine.rrd"), "a user's")?;
        // The second run writes only a.json: b.json (the first run's) goes, the user's file stays.
        let removed = folder.commit(|s| Ok(std::fs::write(s.join("a.json"), "2")?))?;
        assert_eq!(removed, vec![d.join("b.json")]);
        assert_eq!(std::fs::read_to_string(d.join("a.json"))?, "2");
        assert!(d.join("mine.rrd").exists());
        // A manifest naming a file outside the folder removes nothing there.
        std::fs::write(d.join(MANIFEST), "../outside\nmine.rrd/..\n")?;
        assert!(folder.commit(|_| Ok(()))?.iter().all(|p| p.parent() == Some(d)));
        // A failed write leaves the folder as it was, and no staging folder.
        let before = std::fs::read_dir(d)?.count();
        assert!(folder.commit(|_| bail!("interrupted")).is_err());
        assert_eq!(std::fs::read_dir(d)?.count(), before);
        Ok(())
    }

    #[test]
    fn a_run_overwrites_no_unlisted_file_and_removes_only_names_a_run_writes() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let d = dir.path();
        std::fs::write(d.join("experia.yaml"), "the user's own")?;
        std::fs::write(d.join("report.json"), "the user's own")?;
        let files = vec![d.join("experia.yaml"), d.join("report.json")];
        let e = RunFolder::prepare(d, false, files.clone(), &[], &[], false).err().map(|e| e.to_string());
        let e = e.unwrap_or_default();
        assert!(e.contains("experia.yaml is there") && e.contains("run-files.txt") && e.contains("--force"), "{e}");
        assert_eq!(std::fs::read_to_string(d.join("experia.yaml"))?, "the user's own");
        // With --force the run replaces them and lists them; then a manifest with a hand-added name removes only
        // what a run could have written.
        let folder = RunFolder::prepare(d, false, files.clone(), &[], &[], true)?;
        folder.commit(|s| {
            std::fs::write(s.join("experia.yaml"), "1")?;
            Ok(std::fs::write(s.join("report.json"), "1")?)
        })?;
        let manifest = std::fs::read_to_string(d.join(MANIFEST))?;
        std::fs::write(d.join(MANIFEST), format!("{manifest}notes.txt\nold.rrd\n"))?;
        std::fs::write(d.join("notes.txt"), "the user's notes")?;
        std::fs::write(d.join("old.rrd"), "an earlier run's recording")?;
        let folder = RunFolder::prepare(d, false, files, &[], &[], false)?;
        let removed = folder.commit(|s| {
            std::fs::write(s.join("experia.yaml"), "2")?;
            Ok(std::fs::write(s.join("report.json"), "2")?)
        })?;
        assert_eq!(removed, vec![d.join("old.rrd")]);
        assert_eq!(std::fs::read_to_string(d.join("notes.txt"))?, "the user's notes");
        Ok(())
    }

    #[test]
    fn a_missing_parent_is_refused_and_an_output_over_an_input_removes_the_folder_it_made() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let deep = dir.path().join("missing/deep");
        let e =
            RunFolder::prepare(&deep, false, vec![], &[], &[], false).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("does not exist"), "{e}");
        assert!(!dir.path().join("missing").exists());
        let input = dir.path().join("in.rrd");
        std::fs::write(&input, "an input")?;
        let fresh = dir.path().join("fresh");
        let e = RunFolder::prepare(
            &fresh,
            false,
            vec![fresh.join("x.json")],
            &[("--rrd", &input, kind::RRD)],
            std::slice::from_ref(&input),
            false,
        )
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
        assert!(e.contains("--rrd") && e.contains("refusing to write an output over the input"), "{e}");
        assert!(!fresh.exists());
        Ok(())
    }
}
