//! ROS 2 bags in SQLite3 (`.db3`, rosbag2's storage before Iron), read through `rusqlite` (SQLite
//! itself, bundled): the `topics` table, then the `messages` rows in the order they were written, one row
//! in memory at a time.

use crate::bag_messages::{BagMessages, MAX_RECORD_BYTES, Wire};
use crate::error::LogError;
use rusqlite::{Connection, OpenFlags};
use std::collections::BTreeMap;
use std::path::Path;

/// The first bytes of an SQLite3 database.
pub(crate) const MAGIC: &[u8] = b"SQLite format 3\0";

/// Reads the rosbag2 SQLite3 file at `path` into `bag`; returns the format's name for summaries.
pub(crate) fn read(path: &Path, bag: &mut BagMessages) -> Result<String, LogError> {
    let err = |e: rusqlite::Error| LogError::Bag {
        path: path.to_path_buf(),
        message: format!("not a readable rosbag2 SQLite3 file: {e}"),
    };
    let db = Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX)
        .map_err(err)?;
    let mut topics: BTreeMap<i64, (String, String, String)> = BTreeMap::new();
    let mut query = db.prepare("SELECT id, name, type, serialization_format FROM topics").map_err(err)?;
    let mut rows = query.query([]).map_err(err)?;
    while let Some(row) = rows.next().map_err(err)? {
        topics.insert(
            row.get(0).map_err(err)?,
            (row.get(1).map_err(err)?, row.get(2).map_err(err)?, row.get(3).map_err(err)?),
        );
    }
    let mut query = db.prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY id").map_err(err)?;
    let mut rows = query.query([]).map_err(err)?;
    while let Some(row) = rows.next().map_err(err)? {
        let topic_id: i64 = row.get(0).map_err(err)?;
        let stamp: i64 = row.get(1).map_err(err)?;
        let data = row.get_ref(2).map_err(err)?.as_blob().map_err(|e| err(e.into()))?;
        let Some((topic, type_name, format)) = topics.get(&topic_id) else {
            return Err(bag.error(format!("a message of topic id {topic_id}, which the topics table lacks")));
        };
        if data.len() > MAX_RECORD_BYTES {
            return Err(
                bag.error(format!("a message of {topic} has {} bytes, more than a record may have", data.len()))
            );
        }
        let wire = if format == "ros1" { Wire::Ros1 } else { Wire::Cdr };
        bag.add(topic, type_name, wire, u64::try_from(stamp).unwrap_or(0), data)?;
    }
    Ok("rosbag2 SQLite3".to_string())
}
