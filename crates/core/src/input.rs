//! Reading a user's file with a bound on its size, so that a path to a device (`/dev/zero`) or a runaway
//! file ends in a clear error instead of exhausting memory.

use std::io::Read as _;
use std::path::Path;

/// Largest configuration file read (scenario, world, sweep, map YAML): 16 MiB.
pub const CONFIG_LIMIT: u64 = 16 << 20;

/// Largest data file read whole (images, trajectories, relations, results): 2 GiB.
pub const DATA_LIMIT: u64 = 2 << 30;

/// The bytes a text file's start is checked by before the rest is read.
const TEXT_SNIFF: u64 = 4096;

/// Reads at most `limit` bytes of `path`; a longer file (or an endless device) is an error.
pub fn read_limited(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    read_checked(path, limit, |_| Ok(()))
}

/// Reads at most `limit` bytes of `path`, calling `check_start` on its first [`TEXT_SNIFF`] bytes before the
/// rest is read.
fn read_checked(
    path: &Path,
    limit: u64,
    check_start: impl Fn(&[u8]) -> std::io::Result<()>,
) -> std::io::Result<Vec<u8>> {
    let mut file = std::fs::File::open(path)?;
    let len = file.metadata().map(|m| m.len()).unwrap_or(0);
    if len > limit {
        return Err(too_large(limit));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    (&mut file).take(TEXT_SNIFF.min(limit + 1)).read_to_end(&mut bytes)?;
    check_start(&bytes)?;
    let rest = (limit + 1).saturating_sub(bytes.len() as u64);
    file.take(rest).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(limit));
    }
    Ok(bytes)
}

/// [`read_limited`] as UTF-8 text; a file whose first bytes are not text (a binary file, a device such as
/// `/dev/zero`) is refused having read them, not the whole bound.
pub fn read_text_limited(path: &Path, limit: u64) -> std::io::Result<String> {
    String::from_utf8(read_checked(path, limit, check_text_start)?)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not UTF-8 text: {e}")))
}

/// Fails unless `head`, a file's first bytes, may start a text file: no NUL byte, UTF-8 (a character cut at its
/// end aside).
fn check_text_start(head: &[u8]) -> std::io::Result<()> {
    let invalid = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidData, m);
    if let Some(i) = head.iter().position(|&b| b == 0) {
        return Err(invalid(format!("not a text file: byte {} is NUL (a binary file, or a device?)", i + 1)));
    }
    match std::str::from_utf8(head) {
        Err(e) if e.error_len().is_some() => Err(invalid(format!("not UTF-8 text: {e}"))),
        _ => Ok(()),
    }
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

    #[test]
    fn a_device_or_binary_file_read_as_text_is_refused_at_its_first_bytes() {
        // /dev/zero would fill the whole bound before the UTF-8 check; its first bytes are enough.
        let e = read_text_limited(Path::new("/dev/zero"), DATA_LIMIT).unwrap_err();
        assert!(e.to_string().contains("byte 1 is NUL"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f");
        // A multi-byte character cut by the first read is fine.
        let text = format!("{}ü rest", "a".repeat(TEXT_SNIFF as usize - 1));
        std::fs::write(&p, &text).unwrap();
        assert_eq!(read_text_limited(&p, DATA_LIMIT).unwrap(), text);
        std::fs::write(&p, b"ok\xff\xfe").unwrap();
        assert!(read_text_limited(&p, DATA_LIMIT).unwrap_err().to_string().contains("not UTF-8"));
    }
}
