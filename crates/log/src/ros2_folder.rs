//! A ROS 2 bag folder: `metadata.yaml` (rosbag2's) naming the storage (`mcap` or `sqlite3`) and the
//! files, read in order into one log.

use crate::bag_messages::BagMessages;
use crate::error::LogError;
use crate::{mcap_bag, sqlite_bag};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The parts of `metadata.yaml` the reader needs.
#[derive(Deserialize)]
struct Metadata {
    rosbag2_bagfile_information: Information,
}

#[derive(Deserialize)]
struct Information {
    storage_identifier: String,
    relative_file_paths: Vec<PathBuf>,
    #[serde(default)]
    compression_mode: String,
}

/// Reads the bag folder `dir` into `bag`; returns the format's name for summaries.
pub(crate) fn read(dir: &Path, bag: &mut BagMessages) -> Result<String, LogError> {
    let yaml = dir.join("metadata.yaml");
    let text = std::fs::read_to_string(&yaml).map_err(|cause| LogError::Io { path: yaml.clone(), cause })?;
    let bad = |message: String| LogError::Bag { path: yaml.clone(), message };
    let meta: Metadata = serde_norway::from_str(&text).map_err(|e| bad(format!("not rosbag2 metadata: {e}")))?;
    let info = meta.rosbag2_bagfile_information;
    if !info.compression_mode.is_empty() {
        return Err(bad(format!(
            "compression mode {}: compressed bag files are not read (decompress with `ros2 bag convert`)",
            info.compression_mode
        )));
    }
    let mut format = String::new();
    for file in &info.relative_file_paths {
        let path = dir.join(file);
        let io = |cause| LogError::Io { path: path.clone(), cause };
        // Errors name the file being read.
        bag.path = path.clone();
        format = match info.storage_identifier.as_str() {
            "mcap" => mcap_bag::read(std::io::BufReader::new(std::fs::File::open(&path).map_err(io)?), bag)?,
            "sqlite3" => sqlite_bag::read(&path, bag)?,
            other => return Err(bad(format!("storage {other} is neither mcap nor sqlite3"))),
        };
    }
    bag.path = dir.to_path_buf();
    Ok(format!("ROS 2 bag folder: {format}"))
}
