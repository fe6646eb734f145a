//! Reading a user's file with a bound on its size, so that a path to a device (`/dev/zero`) or a runaway
//! file ends in a clear error instead of exhausting memory.

use std::io::Read as _;
use std::path::Path;

/// Largest configuration file read (scenario, world, sweep, map YAML): 16 MiB.
pub const CONFIG_LIMIT: u64 = 16 << 20;

/// Largest data file read whole (images, trajectories, relations, results): 2 GiB.
pub const DATA_LIMIT: u64 = 2 << 30;

/// Reads at most `limit` bytes of `path`; a longer file (or an endless device) is an error.
pub fn read_limited(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let file = std::fs::File::open(path)?;
    let len = file.metadata().map(|m| m.len()).unwrap_or(0);
    if len > limit {
        return Err(too_large(limit));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(limit));
    }
    Ok(bytes)
}

/// [`read_limited`] as UTF-8 text.
pub fn read_text_limited(path: &Path, limit: u64) -> std::io::Result<String> {
    String::from_utf8(read_limited(path, limit)?)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}")))
}

fn too_large(limit: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::FileTooLarge,
        format!("larger than the {} MiB this file may have", limit >> 20),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_endless_device_is_refused() {
        let e = read_limited(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("larger than the 1 MiB"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f");
        std::fs::write(&p, b"abc").unwrap();
        assert_eq!(read_text_limited(&p, 3).unwrap(), "abc");
        assert!(read_limited(&p, 2).is_err());
    }
}
