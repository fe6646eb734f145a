//! The log formats this crate reads, told by a file's name or its first bytes.

use crate::{mcap_bag, ros1_bag, sqlite_bag};
use std::path::Path;

/// The log formats this crate reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// CARMEN text lines (`.clf`, `.log`).
    Carmen,
    /// A ROS 1 bag (`.bag`).
    Ros1Bag,
    /// An MCAP file (`.mcap`: a ROS 2 bag since Iron).
    Mcap,
    /// A rosbag2 SQLite3 file (`.db3`).
    Sqlite,
    /// A ROS 2 bag folder: `metadata.yaml` and the files it names.
    Ros2Folder,
}

/// The file name's extensions each format uses (after a `.gz` is taken off).
const EXTENSIONS: &[(&str, Format)] = &[
    (".clf", Format::Carmen),
    (".log", Format::Carmen),
    (".bag", Format::Ros1Bag),
    (".mcap", Format::Mcap),
    (".db3", Format::Sqlite),
];

/// The format of `path` by its name: `.clf`, `.log`, their `.gz` variants and a bare `.gz` are CARMEN;
/// `.bag`, `.mcap` and `.db3` are bags.
pub fn format_by_extension(path: &Path) -> Option<Format> {
    let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
    let (name, gz) = match name.strip_suffix(".gz") {
        Some(stem) => (stem.to_string(), true),
        None => (name, false),
    };
    EXTENSIONS.iter().find(|(ext, _)| name.ends_with(ext)).map(|&(_, f)| f).or(gz.then_some(Format::Carmen))
}

/// The format of a (decompressed) log by its first bytes: CARMEN when it is text whose first word is a
/// comment or an upper-case record kind (`PARAM`, `FLASER`, `ODOM`, ...).
pub fn format_by_content(head: &[u8]) -> Option<Format> {
    // Binary formats are told by their magic, before the text test.
    for (magic, format) in
        [(ros1_bag::MAGIC, Format::Ros1Bag), (mcap_bag::MAGIC, Format::Mcap), (sqlite_bag::MAGIC, Format::Sqlite)]
    {
        if head.starts_with(magic) {
            return Some(format);
        }
    }
    if head.contains(&0) {
        return None;
    }
    let text = String::from_utf8_lossy(head);
    let word = text.split_whitespace().next()?;
    let carmen = word.starts_with('#')
        || (word.starts_with(|c: char| c.is_ascii_uppercase())
            && word.chars().all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_'));
    carmen.then_some(Format::Carmen)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_are_told_by_extension_or_magic_bytes() {
        assert_eq!(format_by_extension(Path::new("a.LOG.gz")), Some(Format::Carmen));
        assert_eq!(format_by_extension(Path::new("a.bag")), Some(Format::Ros1Bag));
        assert_eq!(format_by_extension(Path::new("a.db3")), Some(Format::Sqlite));
        assert_eq!(format_by_content(b"\x89MCAP0\r\n\x01"), Some(Format::Mcap));
        assert_eq!(format_by_content(b"#ROSBAG V2.0\n\x05"), Some(Format::Ros1Bag));
        assert_eq!(format_by_content(b"SQLite format 3\0"), Some(Format::Sqlite));
        assert_eq!(format_by_content(b"# CARMEN Logfile\nODOM 0"), Some(Format::Carmen));
        assert_eq!(format_by_content(b"some words\n"), None);
    }
}
