//! MCAP files (ROS 2's bag format since Iron; uncompressed, zstd or lz4 chunks), read front to back
//! through the `mcap` crate's streaming reader (Foxglove's reference implementation): a chunk at a time
//! in memory, records no larger than [`MAX_RECORD_BYTES`], each chunk's CRC checked before its messages are
//! read. Messages encoded `cdr`
//! (ROS 2) or `ros1` are decoded by their schema's name.

use crate::bag_messages::{BagMessages, MAX_RECORD_BYTES, Wire};
use crate::error::LogError;
use mcap::records::Record;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Read;

/// The first bytes of an MCAP file.
pub(crate) const MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// A channel: its topic, its schema's name and its message encoding.
struct Channel {
    topic: String,
    type_name: String,
    encoding: String,
}

/// Reads an MCAP file from `r` into `bag`; returns the format's name for summaries.
pub(crate) fn read(mut r: impl Read, bag: &mut BagMessages) -> Result<String, LogError> {
    let options =
        LinearReaderOptions::default().with_prevalidate_chunk_crcs(true).with_record_length_limit(MAX_RECORD_BYTES);
    let mut reader = LinearReader::new_with_options(options);
    let mut schemas: BTreeMap<u16, String> = BTreeMap::new();
    let mut channels: BTreeMap<u16, Channel> = BTreeMap::new();
    let mut compressions = BTreeSet::new();
    let mut fed: u64 = 0;
    let path = bag.path.clone();
    let mcap_err = |fed: u64, e: mcap::McapError| {
        let cut = matches!(e, mcap::McapError::UnexpectedEof | mcap::McapError::UnexpectedEoc);
        let hint = if cut { " (cut off: a truncated download or copy?)" } else { "" };
        LogError::Bag { path: path.clone(), message: format!("MCAP, within the first {fed} bytes: {e}{hint}") }
    };
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| mcap_err(fed, e))? {
            LinearReadEvent::ReadRequest(need) => {
                let n = r.read(reader.insert(need)).map_err(|e| LogError::Io { path: path.clone(), cause: e })?;
                reader.notify_read(n);
                fed += n as u64;
            }
            LinearReadEvent::Record { opcode, data } => {
                let record = mcap::parse_record(opcode, data).map_err(|e| mcap_err(fed, e))?;
                match record {
                    Record::Schema { header, .. } => {
                        schemas.insert(header.id, header.name);
                    }
                    Record::Channel(c) => {
                        let type_name = schemas.get(&c.schema_id).cloned().unwrap_or_default();
                        channels.insert(c.id, Channel { topic: c.topic, type_name, encoding: c.message_encoding });
                    }
                    Record::ChunkIndex(index) => {
                        compressions.insert(index.compression);
                    }
                    Record::Message { header, data } => {
                        let Some(c) = channels.get(&header.channel_id) else {
                            return Err(bag.error(format!(
                                "MCAP, within the first {fed} bytes: a message on channel {}, which no record defines",
                                header.channel_id
                            )));
                        };
                        match c.encoding.as_str() {
                            "cdr" => bag.add(&c.topic, &c.type_name, Wire::Cdr, header.log_time, &data)?,
                            "ros1" => bag.add(&c.topic, &c.type_name, Wire::Ros1, header.log_time, &data)?,
                            // Counted, not decoded: an encoding (json, protobuf) no ROS bag uses.
                            other => {
                                let type_name = format!("{} ({other})", c.type_name);
                                bag.add(&c.topic, &type_name, Wire::Cdr, header.log_time, &[])?
                            }
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    let kinds: Vec<String> =
        compressions.into_iter().map(|c| if c.is_empty() { "uncompressed".to_string() } else { c }).collect();
    Ok(if kinds.is_empty() { "MCAP".to_string() } else { format!("MCAP ({} chunks)", kinds.join(" and ")) })
}
