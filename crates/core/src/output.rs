//! Writing output files so that a reader never sees a half-written one.

use std::io::Write as _;
use std::path::{Path, PathBuf};

/// A file could not be written; names the file.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {cause}")]
pub struct WriteError {
    /// File at fault.
    pub path: PathBuf,
    /// Underlying error.
    pub cause: std::io::Error,
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename.
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    let tmp = temporary_name(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(cause) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(WriteError { path: path.to_path_buf(), cause });
    }
    Ok(())
}

/// A file written as a stream that appears under its name only when [`AtomicFile::commit`] is called: until
/// then the bytes go to a hidden temporary file beside it, removed if the writer is dropped uncommitted.
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    writer: Option<std::io::BufWriter<std::fs::File>>,
}

impl AtomicFile {
    /// Starts writing `path` (through a temporary file in the same folder).
    pub fn create(path: &Path) -> Result<Self, WriteError> {
        let tmp = temporary_name(path);
        let file = std::fs::File::create(&tmp).map_err(|cause| WriteError { path: path.to_path_buf(), cause })?;
        Ok(Self { path: path.to_path_buf(), tmp, writer: Some(std::io::BufWriter::new(file)) })
    }

    /// The file's final name.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The hidden temporary file the bytes go to until [`AtomicFile::commit`] (left behind only if the process is
    /// killed before it commits or drops the writer).
    pub fn temporary_path(&self) -> &Path {
        &self.tmp
    }

    /// Flushes, syncs and renames the temporary file to the final name.
    pub fn commit(mut self) -> Result<(), WriteError> {
        let result = (|| {
            let writer = self.writer.take().ok_or_else(|| std::io::Error::other("already committed"))?;
            let file = writer.into_inner().map_err(|e| e.into_error())?;
            file.sync_all()?;
            std::fs::rename(&self.tmp, &self.path)
        })();
        result.map_err(|cause| WriteError { path: self.path.clone(), cause })
    }

    fn writer(&mut self) -> std::io::Result<&mut std::io::BufWriter<std::fs::File>> {
        self.writer.as_mut().ok_or_else(|| std::io::Error::other("already committed"))
    }
}

impl std::io::Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer()?.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.writer()?.flush()
    }
}

/// Seeking flushes the buffer first (as `BufWriter` does): a writer that goes back to fill in an index (MCAP's)
/// can write through an [`AtomicFile`].
impl std::io::Seek for AtomicFile {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        self.writer()?.seek(pos)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// The hidden temporary name `path` is written under before its rename.
fn temporary_name(path: &Path) -> PathBuf {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    dir.join(format!(".{name}.tmp{}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_streamed_file_appears_only_when_committed() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("log.clf");
        let mut f = AtomicFile::create(&p).unwrap();
        f.write_all(b"ODOM 0 0 0\n").unwrap();
        assert!(!p.exists(), "visible before commit");
        drop(f);
        assert!(!p.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "the temporary file is left behind");
        let mut f = AtomicFile::create(&p).unwrap();
        f.write_all(b"ODOM 1 0 0\n").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "ODOM 1 0 0\n");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_file_is_written_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        write_file_atomic(&p, b"one").unwrap();
        write_file_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        // No temporary file is left behind, even when the rename fails (a folder in the way).
        let e = write_file_atomic(dir.path(), b"x").unwrap_err();
        assert!(e.to_string().starts_with(&dir.path().display().to_string()), "{e}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
