//! One entry point for every log: the format chosen by magic bytes or extension, then its reader.

use crate::error::LogError;
use crate::format::{Format, format_by_content, format_by_extension};
use crate::options::ReadOptions;
use crate::sensor_log::SensorLog;
use crate::{bag_read, carmen};
use std::io::{BufRead, BufReader};
use std::path::Path;

/// The gzip magic bytes: a compressed log is decompressed before its format is told.
const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// Reads the log at `path` with `options`: gunzipped when it starts with the gzip magic bytes, the reader
/// chosen by the file's extension, else by its first bytes; a format no reader knows is refused, naming the
/// file. A folder is a ROS 2 bag (its `metadata.yaml` names the files).
pub fn read_log(path: &Path, options: &ReadOptions) -> Result<SensorLog, LogError> {
    if path.is_dir() {
        return bag_read::read_bag(path, Format::Ros2Folder, options);
    }
    let io = |cause| LogError::Io { path: path.to_path_buf(), cause };
    let mut file = BufReader::new(std::fs::File::open(path).map_err(io)?);
    // The magic is peeked at, not consumed: the file is opened once.
    let gzipped = file.fill_buf().map_err(io)?.starts_with(&GZIP_MAGIC);
    let mut reader: Box<dyn BufRead> =
        if gzipped { Box::new(BufReader::new(flate2::read::MultiGzDecoder::new(file))) } else { Box::new(file) };
    let format = match format_by_extension(path) {
        Some(format) => format,
        None => {
            let head = reader.fill_buf().map_err(|cause| match cause.kind() {
                std::io::ErrorKind::UnexpectedEof => LogError::Truncated { path: path.to_path_buf(), line: 0 },
                _ => LogError::Io { path: path.to_path_buf(), cause },
            })?;
            format_by_content(head).ok_or_else(|| LogError::UnknownFormat { path: path.to_path_buf() })?
        }
    };
    let parsed = match format {
        Format::Carmen => carmen::parse(reader, path, options),
        bag => bag_read::read_bag(path, bag, options),
    };
    // The readers see bytes, not the file: the bound was passed once decompressed when the file is gzipped.
    parsed.map_err(|e| match e {
        LogError::TooLarge { path, limit, .. } => LogError::TooLarge { path, limit, compressed: gzipped },
        e => e,
    })
}

/// The log's name for displays and recordings: its file name without `.gz`, `.clf` and `.log`.
pub fn log_name(path: &Path) -> String {
    let name = path.file_name().map_or_else(|| "log".to_string(), |n| n.to_string_lossy().into_owned());
    name.trim_end_matches(".gz").trim_end_matches(".clf").trim_end_matches(".log").to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    const LOG: &str = "# CARMEN Logfile\nODOM 0 0 0 0 0 0 1.0 h 1\nFLASER 2 1.0 2.0 0 0 0 0 0 0 1.5 h 1\n";

    #[test]
    fn the_reader_is_chosen_by_magic_bytes_or_extension() {
        let dir = tempfile::tempdir().unwrap();
        // A gzipped CARMEN log named .txt: gunzipped by its magic, told CARMEN by its first line.
        let p = dir.path().join("log.txt");
        let mut enc = flate2::write::GzEncoder::new(std::fs::File::create(&p).unwrap(), flate2::Compression::fast());
        enc.write_all(LOG.as_bytes()).unwrap();
        enc.finish().unwrap();
        let log = read_log(&p, &ReadOptions::default()).unwrap();
        assert_eq!((log.scans.len(), log.odometry.len()), (1, 1));
        // Named .clf, a log is CARMEN whatever its first line.
        let p = dir.path().join("empty.clf");
        std::fs::write(&p, "").unwrap();
        assert_eq!(read_log(&p, &ReadOptions::default()).unwrap().scans.len(), 0);
    }

    #[test]
    fn an_unknown_format_is_refused_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        for (name, bytes) in [("map.png", &b"\x89PNG\r\n\x1a\n\0\0"[..]), ("notes.txt", b"some words\n"), ("e", b"")] {
            let p = dir.path().join(name);
            std::fs::write(&p, bytes).unwrap();
            let e = read_log(&p, &ReadOptions::default()).unwrap_err();
            assert!(matches!(e, LogError::UnknownFormat { .. }), "{name}: {e}");
            assert!(e.to_string().starts_with(&format!("{}: not a log format", p.display())), "{e}");
        }
    }

    /// `text` gzipped into `path`.
    fn gzip(path: &Path, text: &[u8]) {
        let mut enc = flate2::write::GzEncoder::new(std::fs::File::create(path).unwrap(), flate2::Compression::best());
        enc.write_all(text).unwrap();
        enc.finish().unwrap();
    }

    #[test]
    fn a_gzip_bomb_is_refused_by_its_decompressed_bytes() {
        let dir = tempfile::tempdir().unwrap();
        // 4 MiB of comment lines in about 20 KB (they hold nothing once read, so only the bytes count): refused
        // past 1 MiB decompressed, not read whole.
        let p = dir.path().join("bomb.clf.gz");
        let comments = "# a CARMEN comment line\n";
        gzip(&p, &comments.as_bytes().repeat((4 << 20) / comments.len()));
        assert!(std::fs::metadata(&p).unwrap().len() < 100_000);
        let small = ReadOptions { max_bytes: 1 << 20, ..ReadOptions::default() };
        let e = read_log(&p, &small).unwrap_err();
        assert!(matches!(e, LogError::TooLarge { limit: 1048576, compressed: true, .. }), "{e}");
        assert!(e.to_string().contains("more than 1 MiB once decompressed"), "{e}");
        // One endless line of zeros, gzipped: refused at the line bound.
        let p = dir.path().join("zeros.clf.gz");
        gzip(&p, &vec![b'0'; 4 << 20]);
        let short = ReadOptions { max_line_bytes: 4096, ..ReadOptions::default() };
        let e = read_log(&p, &short).unwrap_err();
        assert!(matches!(e, LogError::LineTooLong { line: 1, limit: 4096, .. }), "{e}");
    }

    #[test]
    fn an_endless_device_named_as_a_log_is_refused_at_its_first_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("zero.clf");
        std::os::unix::fs::symlink("/dev/zero", &p).unwrap();
        let e = read_log(&p, &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, LogError::LineTooLong { line: 1, .. }), "{e}");
        assert!(e.to_string().contains("zero.clf:1: line longer than 1048576 bytes"), "{e}");
    }

    #[test]
    fn a_log_is_named_by_its_file_without_log_extensions() {
        assert_eq!(log_name(Path::new("data/aces.clf.gz")), "aces");
        assert_eq!(log_name(Path::new("fr079-corrected.log")), "fr079-corrected");
        assert_eq!(log_name(Path::new("run.txt")), "run.txt");
        assert_eq!(log_name(Path::new("/")), "log");
    }
}
