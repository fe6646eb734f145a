//! A study's folder while the study runs: `study.json` says what the study is, and `results.csv` gets each
//! finished trial's rows appended and flushed at once, so an interrupted study loses no finished trial and
//! `--resume` continues it. `collect` compares the shards' `study.json` and refuses shards of other studies.

use super::StudyError;
use super::csv_row::{CsvRow, parse_rows, rows_text};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write as _;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Name of the parameters file in a study folder.
pub const PARAMS_FILE: &str = "study.json";

/// Name of the results file in a study folder.
pub const RESULTS_FILE: &str = "results.csv";

/// What a study is, by parameter name (the shard aside): two folders hold results of one study exactly when
/// their parameters are equal.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct StudyParams(pub BTreeMap<String, String>);

/// A 64-bit FNV-1a fingerprint of some bytes (a map, a sweep file), stable across machines and versions.
pub fn fingerprint(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

impl StudyParams {
    /// Sets parameter `name`.
    pub fn set(&mut self, name: &str, value: impl ToString) -> &mut Self {
        self.0.insert(name.to_string(), value.to_string());
        self
    }

    /// Reads `dir/study.json`; `None` when the folder has none.
    pub fn read(dir: &Path) -> Result<Option<StudyParams>, StudyError> {
        let path = dir.join(PARAMS_FILE);
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(StudyError::file(&path, e)),
        };
        serde_json::from_str(&text).map(Some).map_err(|e| StudyError::Results {
            path,
            line: e.line(),
            message: format!("not a study's parameters: {e}"),
        })
    }

    /// Writes `dir/study.json` (through a temporary file).
    pub fn write(&self, dir: &Path) -> Result<(), StudyError> {
        let path = dir.join(PARAMS_FILE);
        let text = serde_json::to_string_pretty(self).map_err(|e| StudyError::file(&path, e))? + "\n";
        mrslam_core::output::write_file_atomic(&path, text.as_bytes()).map_err(|e| StudyError::file(&path, e))
    }

    /// Fails, naming the first parameter that differs, unless `other` (read from `path`) is the same study.
    pub fn check_same(&self, other: &StudyParams, path: &Path, what: &str) -> Result<(), StudyError> {
        let keys: BTreeSet<&String> =
            self.0.keys().chain(other.0.keys()).filter(|k| k.as_str() != SHARD_TRIALS_PARAM).collect();
        for k in keys {
            let (mine, theirs) = (self.0.get(k), other.0.get(k));
            if mine != theirs {
                let show = |v: Option<&String>| v.map_or("(none)".to_string(), |v| format!("`{v}`"));
                return Err(StudyError::Results {
                    path: path.to_path_buf(),
                    line: 0,
                    message: format!(
                        "{what}: `{k}` is {} there but {} here: results of different studies do not mix",
                        show(theirs),
                        show(mine)
                    ),
                });
            }
        }
        Ok(())
    }
}

/// The parameter naming a shard of a study split across processes (`K/N`, 0-based): set only for N > 1, and
/// the one parameter in which the shards of one study differ.
pub const SHARD_PARAM: &str = "shard";

/// The parameter holding how many trials a shard runs (set with [`SHARD_PARAM`]): what `collect` checks the
/// shard's `results.csv` against. Not part of what the study is: [`StudyParams::check_same`] passes over it, so
/// the shards of one study, and a shard started before it existed, still compare equal.
pub const SHARD_TRIALS_PARAM: &str = "shard_trials";

/// The shards among `dirs` whose `results.csv` holds fewer trials than their `study.json` says they run (an
/// interrupted shard), one line each: `DIR: M of N trials`. Folders without the count are not judged.
pub fn incomplete_shards(dirs: &[PathBuf]) -> Result<Vec<String>, StudyError> {
    let mut incomplete = Vec::new();
    for d in dirs {
        let Some(params) = StudyParams::read(d)? else { continue };
        let Some(want) = params.0.get(SHARD_TRIALS_PARAM).and_then(|v| v.parse::<usize>().ok()) else { continue };
        let path = d.join(RESULTS_FILE);
        let text = mrslam_core::input::read_text_limited(&path, mrslam_core::input::DATA_LIMIT)
            .map_err(|e| StudyError::file(&path, e))?;
        // The trial is every results file's first column.
        let trials: BTreeSet<&str> =
            text.lines().skip(1).filter(|l| !l.trim().is_empty()).filter_map(|l| l.split(',').next()).collect();
        if trials.len() < want {
            incomplete.push(format!("{}: {} of {want} trials", d.display(), trials.len()));
        }
    }
    Ok(incomplete)
}

/// The shards of `count` that `found` (their 0-based indices) lacks.
fn missing_shards(found: &BTreeSet<usize>, count: usize) -> Vec<usize> {
    (0..count).filter(|k| !found.contains(k)).collect()
}

/// The parameters of the study whose shards `dirs` hold (the shard aside): refuses shards of different
/// studies, a mix of shards with and without `study.json`, and, unless `partial`, an incomplete set of shards
/// (each names its shard in `study.json`). Returns the parameters (`None` when no shard has a `study.json`:
/// folders of an older mrslam) and the missing shards' names (`K/N`, empty when all are there).
pub fn collect_params(dirs: &[PathBuf], partial: bool) -> Result<(Option<StudyParams>, Vec<String>), StudyError> {
    let mut first: Option<(&PathBuf, Option<StudyParams>)> = None;
    let mut shards: BTreeMap<usize, BTreeSet<usize>> = BTreeMap::new();
    for d in dirs {
        let mut p = StudyParams::read(d)?;
        if let Some(p) = p.as_mut() {
            p.0.remove(SHARD_TRIALS_PARAM);
        }
        if let Some(shard) = p.as_mut().and_then(|p| p.0.remove(SHARD_PARAM)) {
            let s = crate::Shard::parse(&shard).map_err(|e| StudyError::File {
                path: d.join(PARAMS_FILE),
                message: format!("`{SHARD_PARAM}`: {e}"),
            })?;
            shards.entry(s.count).or_default().insert(s.index);
        }
        match &first {
            None => first = Some((d, p)),
            Some((d0, p0)) => match (p0, &p) {
                (Some(a), Some(b)) => {
                    a.check_same(b, &d.join(PARAMS_FILE), &format!("not a shard of the study in {}", d0.display()))?
                }
                (None, None) => {}
                _ => {
                    let (with, without) = if p0.is_some() { (*d0, d) } else { (d, *d0) };
                    return Err(StudyError::File {
                        path: without.join(PARAMS_FILE),
                        message: format!(
                            "missing, while {} has one: cannot tell whether they are one study",
                            with.display()
                        ),
                    });
                }
            },
        }
    }
    if shards.len() > 1 {
        let counts: Vec<String> = shards.keys().map(usize::to_string).collect();
        return Err(StudyError::Invalid(format!(
            "collect: the folders are shards of studies split {} ways: not one study",
            counts.join(" and ")
        )));
    }
    let missing: Vec<String> = shards
        .iter()
        .flat_map(|(&n, found)| missing_shards(found, n).into_iter().map(move |k| format!("{k}/{n}")))
        .collect();
    if !missing.is_empty() && !partial {
        return Err(StudyError::Invalid(format!(
            "collect: shard{} {} of the study {} missing (not among the folders given); give every shard's \
             folder, or --partial to collect these anyway",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", "),
            if missing.len() > 1 { "are" } else { "is" }
        )));
    }
    Ok((first.and_then(|(_, p)| p), missing))
}

/// The `results.csv` of a running study, appended to trial by trial with rows of type `R`.
pub struct Journal<R> {
    path: PathBuf,
    file: Mutex<std::fs::File>,
    rows: PhantomData<fn(&R)>,
    /// Opened fresh (not resumed): its `study.json` and `results.csv` were made by this run.
    fresh: bool,
    /// Whether any rows were appended.
    appended: std::sync::atomic::AtomicBool,
}

impl<R: CsvRow> Journal<R> {
    /// Opens `dir` for the study `params` whose trials write `rows_per_trial` rows each.
    ///
    /// Fresh (`resume` false): refuses a folder that already holds a `results.csv`, so no result is lost to
    /// a rerun. Resumed: the folder's `study.json` must match; the complete trials of its `results.csv` come
    /// back (a trial cut off by the interruption is dropped and runs again).
    pub fn open(
        dir: &Path,
        params: &StudyParams,
        rows_per_trial: usize,
        resume: bool,
    ) -> Result<(Journal<R>, Vec<R>), StudyError> {
        std::fs::create_dir_all(dir).map_err(|e| StudyError::file(dir, e))?;
        let path = dir.join(RESULTS_FILE);
        let done = if resume {
            let found = StudyParams::read(dir)?.ok_or_else(|| StudyError::File {
                path: dir.join(PARAMS_FILE),
                message: "nothing to resume: no study was started in this folder".into(),
            })?;
            params.check_same(&found, &dir.join(PARAMS_FILE), "cannot resume")?;
            let text = match std::fs::read_to_string(&path) {
                Ok(t) => t,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
                Err(e) => return Err(StudyError::file(&path, e)),
            };
            complete_trials(&text, &path, rows_per_trial)?
        } else {
            if path.exists() {
                return Err(StudyError::File {
                    path,
                    message: "already holds the results of a study: --resume continues it, or choose another --out"
                        .into(),
                });
            }
            params.write(dir)?;
            Vec::new()
        };
        // Start the file anew with the header and the complete trials, then append.
        let text = rows_text(&done);
        mrslam_core::output::write_file_atomic(&path, text.as_bytes()).map_err(|e| StudyError::file(&path, e))?;
        let file = std::fs::OpenOptions::new().append(true).open(&path).map_err(|e| StudyError::file(&path, e))?;
        let appended = std::sync::atomic::AtomicBool::new(false);
        Ok((Journal { path, file: Mutex::new(file), rows: PhantomData, fresh: !resume, appended }, done))
    }

    /// Undoes a fresh start that produced nothing (it failed before its first trial finished): removes the
    /// `results.csv` and `study.json` it wrote, so that the corrected retry starts as if it were the first.
    /// A resumed study, or one with rows, is left as it is.
    pub fn abandon(self) {
        if self.fresh && !self.appended.load(std::sync::atomic::Ordering::SeqCst) {
            drop(self.file);
            let _ = std::fs::remove_file(&self.path);
            if let Some(dir) = self.path.parent() {
                let _ = std::fs::remove_file(dir.join(PARAMS_FILE));
            }
        }
    }

    /// Appends the rows of one or more finished trials in one write and flushes them to the file.
    pub fn append(&self, rows: &[R]) -> Result<(), StudyError> {
        let mut text = String::new();
        for r in rows {
            text += &r.to_csv();
            text.push('\n');
        }
        let mut file = self.file.lock().map_err(|_| StudyError::file(&self.path, "a writer panicked"))?;
        self.appended.store(true, std::sync::atomic::Ordering::SeqCst);
        file.write_all(text.as_bytes()).and_then(|()| file.flush()).map_err(|e| StudyError::file(&self.path, e))
    }
}

/// The rows of the trials `text` holds completely: lines cut off, and trials with fewer than
/// `rows_per_trial` rows, are dropped.
fn complete_trials<R: CsvRow>(text: &str, path: &Path, rows_per_trial: usize) -> Result<Vec<R>, StudyError> {
    // Only lines that end in a newline were written completely.
    let whole = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
    if whole.trim().is_empty() {
        return Ok(Vec::new());
    }
    let mut rows: Vec<R> = parse_rows(whole, path)?.into_iter().map(|(_, r)| r).collect();
    let mut count: BTreeMap<usize, usize> = BTreeMap::new();
    for r in &rows {
        *count.entry(r.trial()).or_default() += 1;
    }
    rows.retain(|r| count[&r.trial()] == rows_per_trial);
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::TrialRow;

    #[test]
    fn collecting_some_shards_of_a_study_is_refused_naming_the_missing_ones() {
        let dir = tempfile::tempdir().unwrap();
        let shard = |k: usize, n: usize| {
            let d = dir.path().join(format!("s{k}of{n}"));
            std::fs::create_dir_all(&d).unwrap();
            let mut p = StudyParams::default();
            p.set("kind", "overlap").set(SHARD_PARAM, format!("{k}/{n}"));
            p.write(&d).unwrap();
            d
        };
        let (a, c) = (shard(0, 3), shard(2, 3));
        let e = collect_params(&[a.clone(), c.clone()], false).unwrap_err().to_string();
        assert!(e.contains("shard 1/3 of the study is missing") && e.contains("--partial"), "{e}");
        let (params, missing) = collect_params(&[a.clone(), c.clone()], true).unwrap();
        assert_eq!(missing, vec!["1/3".to_string()]);
        // The collected study is the whole one: no shard named.
        assert_eq!(params.unwrap().0.get(SHARD_PARAM), None);
        let (_, missing) = collect_params(&[a.clone(), shard(1, 3), c], false).unwrap();
        assert!(missing.is_empty());
        let e = collect_params(&[a, shard(1, 2)], true).unwrap_err().to_string();
        assert!(e.contains("split 2 and 3 ways"), "{e}");
    }

    #[test]
    fn a_shard_with_fewer_trials_than_it_runs_is_incomplete_and_its_count_is_not_what_the_study_is() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path().join("s0");
        std::fs::create_dir_all(&d).unwrap();
        let mut p = StudyParams::default();
        p.set("kind", "overlap").set(SHARD_PARAM, "0/2").set(SHARD_TRIALS_PARAM, 3);
        p.write(&d).unwrap();
        let header = crate::results::HEADER;
        std::fs::write(d.join(RESULTS_FILE), format!("{header}\n0,a\n0,b\n2,a\n")).unwrap();
        assert_eq!(
            incomplete_shards(std::slice::from_ref(&d)).unwrap(),
            vec![format!("{}: 2 of 3 trials", d.display())]
        );
        std::fs::write(d.join(RESULTS_FILE), format!("{header}\n0,a\n2,a\n4,a\n")).unwrap();
        assert!(incomplete_shards(std::slice::from_ref(&d)).unwrap().is_empty());
        // A shard folder from before the count resumes as the same study.
        let mut old = p.clone();
        old.0.remove(SHARD_TRIALS_PARAM);
        assert!(p.check_same(&old, &d, "cannot resume").is_ok());
    }

    fn row(trial: usize, alg: &str) -> TrialRow {
        TrialRow {
            trial,
            overlap_target: Some(0.2),
            overlap: 0.2,
            seed: 1,
            algorithm: alg.into(),
            accepted: true,
            success: true,
            false_merge: false,
            rotation_error_deg: Some(0.1),
            translation_error_m: Some(0.01),
            time_ms: 1.0,
            rotation_error_at_end_deg: None,
            translation_error_at_end_m: None,
            stage: String::new(),
        }
    }

    #[test]
    fn a_fresh_start_that_produced_nothing_is_undone_and_no_other() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let mut params = StudyParams::default();
        params.set("seed", 5);
        let (j, _) = Journal::<TrialRow>::open(d, &params, 1, false).unwrap();
        j.abandon();
        assert!(!d.join(RESULTS_FILE).exists() && !d.join(PARAMS_FILE).exists());
        // Rows written: kept.
        let (j, _) = Journal::<TrialRow>::open(d, &params, 1, false).unwrap();
        j.append(&[row(0, "sift")]).unwrap();
        j.abandon();
        assert!(d.join(RESULTS_FILE).exists() && d.join(PARAMS_FILE).exists());
        // A resumed study: kept, although this run added nothing.
        let (j, _) = Journal::<TrialRow>::open(d, &params, 1, true).unwrap();
        j.abandon();
        assert!(d.join(RESULTS_FILE).exists() && d.join(PARAMS_FILE).exists());
    }

    #[test]
    fn an_interrupted_study_resumes_with_its_complete_trials() {
        let dir = tempfile::tempdir().unwrap();
        let mut params = StudyParams::default();
        params.set("seed", 5);
        let (j, done) = Journal::<TrialRow>::open(dir.path(), &params, 2, false).unwrap();
        assert!(done.is_empty());
        j.append(&[row(0, "sift"), row(0, "rmap")]).unwrap();
        j.append(&[row(3, "sift")]).unwrap(); // a trial cut off after its first row
        drop(j);
        // A line cut off in the middle.
        let path = dir.path().join(RESULTS_FILE);
        let mut f = std::fs::OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(b"4,0.2,0.2").unwrap();
        drop(f);
        // A fresh start in the folder is refused; a resume of another study too.
        assert!(Journal::<TrialRow>::open(dir.path(), &params, 2, false).is_err());
        let mut other = params.clone();
        other.set("seed", 6);
        let e = Journal::<TrialRow>::open(dir.path(), &other, 2, true).err().unwrap().to_string();
        assert!(e.contains("`seed` is `5` there but `6` here"), "{e}");
        let (_, done) = Journal::<TrialRow>::open(dir.path(), &params, 2, true).unwrap();
        assert_eq!(done, vec![row(0, "sift"), row(0, "rmap")]);
        assert_eq!(std::fs::read_to_string(&path).unwrap().lines().count(), 3, "the file holds what was kept");
    }
}
