//! ROS 1 bags (format 2.0: `#ROSBAG V2.0`), read front to back one record at a time: the bag header,
//! then chunks (uncompressed, `bz2` or `lz4`) of connection and message records, then the index (skipped).
//!
//! Each record is a `uint32` header length, the header's `name=value` fields (each prefixed by its `uint32`
//! length; `op` says the record's kind), a `uint32` data length and the data. A chunk's data is records
//! again, compressed as its `compression` field says; `size` is their uncompressed length.
//!
//! Why a reader of our own: the `rosbag` crate (0.6) memory-maps the file (unsafe, and undefined if the
//! file changes while read), slices it at the index position its header claims (a panic on a truncated
//! bag) and sizes a chunk's buffer from its header unchecked. The format is a few record kinds; the
//! decompression is the `bzip2` and `lz4_flex` crates'.

use crate::bag_messages::{BagMessages, MAX_RECORD_BYTES, Wire};
use crate::error::LogError;
use std::collections::{BTreeMap, BTreeSet};
use std::io::Read;

/// The first bytes of a ROS 1 bag.
pub(crate) const MAGIC: &[u8] = b"#ROSBAG V2.0\n";

const OP_MESSAGE: u8 = 0x02;
const OP_BAG_HEADER: u8 = 0x03;
const OP_CHUNK: u8 = 0x05;
const OP_CONNECTION: u8 = 0x07;

/// A record: its header fields and its data.
struct Record {
    fields: BTreeMap<String, Vec<u8>>,
    data: Vec<u8>,
}

impl Record {
    fn op(&self) -> Option<u8> {
        self.fields.get("op").and_then(|v| v.first().copied())
    }

    fn field(&self, name: &str) -> Result<&[u8], String> {
        self.fields.get(name).map(Vec::as_slice).ok_or_else(|| format!("a record without its `{name}` field"))
    }

    fn u32(&self, name: &str) -> Result<u32, String> {
        let v = self.field(name)?;
        Ok(u32::from_le_bytes(v.try_into().map_err(|_| format!("field `{name}` is not 4 bytes"))?))
    }

    fn string(&self, name: &str) -> Result<String, String> {
        String::from_utf8(self.field(name)?.to_vec()).map_err(|_| format!("field `{name}` is not UTF-8"))
    }
}

/// Parses a header's `name=value` fields.
fn fields(mut header: &[u8]) -> Result<BTreeMap<String, Vec<u8>>, String> {
    let mut fields = BTreeMap::new();
    while !header.is_empty() {
        let (len, rest) = header.split_at_checked(4).ok_or("a header field's length is cut off")?;
        let len = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
        let (field, rest) = rest.split_at_checked(len).ok_or("a header field runs past its header")?;
        let eq = field.iter().position(|&b| b == b'=').ok_or("a header field without `=`")?;
        fields.insert(String::from_utf8_lossy(&field[..eq]).into_owned(), field[eq + 1..].to_vec());
        header = rest;
    }
    Ok(fields)
}

/// Reads one length-prefixed block: `None` at a clean end of the input (`eof_ok`), an error naming the
/// offset when the input ends inside it.
fn block(r: &mut impl Read, offset: &mut u64, eof_ok: bool) -> Result<Option<Vec<u8>>, String> {
    let mut len = [0u8; 4];
    let got = read_full(r, &mut len).map_err(|e| format!("byte {offset}: {e}"))?;
    if got == 0 && eof_ok {
        return Ok(None);
    }
    if got < 4 {
        return Err(format!(
            "cut off at byte {}: the file ends inside a record (a truncated download or copy?)",
            *offset + got as u64
        ));
    }
    let len = u32::from_le_bytes(len) as usize;
    if len > MAX_RECORD_BYTES {
        return Err(format!(
            "the record at byte {offset} claims {len} bytes, more than the {MAX_RECORD_BYTES} a record may have"
        ));
    }
    let mut bytes = Vec::new();
    r.take(len as u64).read_to_end(&mut bytes).map_err(|e| format!("byte {offset}: {e}"))?;
    if bytes.len() < len {
        return Err(format!(
            "cut off at byte {}: the file ends inside a record of {len} bytes (a truncated download or copy?)",
            *offset + 4 + bytes.len() as u64
        ));
    }
    *offset += 4 + len as u64;
    Ok(Some(bytes))
}

/// Reads as many bytes as `buf` holds or the input has.
fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// Reads a record at `offset`; `None` at the end of the input.
fn record(r: &mut impl Read, offset: &mut u64) -> Result<Option<Record>, String> {
    let start = *offset;
    let Some(header) = block(r, offset, true)? else { return Ok(None) };
    let fields = fields(&header).map_err(|e| format!("the record at byte {start}: {e}"))?;
    let data = block(r, offset, false)?.unwrap_or_default();
    Ok(Some(Record { fields, data }))
}

/// The messages of a connection: its topic and type.
type Connections = BTreeMap<u32, (String, String)>;

fn connection(rec: &Record, connections: &mut Connections) -> Result<(), String> {
    let id = rec.u32("conn")?;
    let topic = rec.string("topic")?;
    let own = fields(&rec.data)?;
    let type_name = own.get("type").map(|v| String::from_utf8_lossy(v).into_owned()).unwrap_or_default();
    connections.insert(id, (topic, type_name));
    Ok(())
}

fn message(rec: &Record, connections: &Connections, bag: &mut BagMessages) -> Result<Result<(), LogError>, String> {
    let id = rec.u32("conn")?;
    let time = rec.field("time")?;
    let time: [u8; 8] = time.try_into().map_err(|_| "field `time` is not 8 bytes")?;
    let sec = u64::from(u32::from_le_bytes([time[0], time[1], time[2], time[3]]));
    let nsec = u64::from(u32::from_le_bytes([time[4], time[5], time[6], time[7]]));
    let (topic, type_name) =
        connections.get(&id).ok_or_else(|| format!("a message of connection {id}, which no record defines"))?;
    Ok(bag.add(topic, type_name, Wire::Ros1, sec * 1_000_000_000 + nsec, &rec.data))
}

/// Decompresses a chunk's data as its `compression` field says, to its `size`.
fn decompress(rec: &Record) -> Result<(String, Vec<u8>), String> {
    let compression = rec.string("compression")?;
    let size = rec.u32("size")? as usize;
    if size > MAX_RECORD_BYTES {
        return Err(format!("claims {size} bytes uncompressed, more than a record may have"));
    }
    let data = &rec.data[..];
    let mut out = Vec::new();
    let limit = size as u64 + 1;
    let read = match compression.as_str() {
        "none" => {
            out = data.to_vec();
            Ok(out.len())
        }
        "bz2" => bzip2::read::BzDecoder::new(data).take(limit).read_to_end(&mut out),
        "lz4" => lz4_flex::frame::FrameDecoder::new(data).take(limit).read_to_end(&mut out),
        other => return Err(format!("compression `{other}` is none of none, bz2, lz4")),
    };
    read.map_err(|e| format!("does not decompress ({compression}): {e}"))?;
    if out.len() != size {
        return Err(format!("decompresses ({compression}) to {} bytes, not the {size} its header says", out.len()));
    }
    Ok((compression, out))
}

/// Reads a ROS 1 bag from `r` (from its first byte) into `bag`; returns the format's name for summaries.
pub(crate) fn read(mut r: impl Read, bag: &mut BagMessages) -> Result<String, LogError> {
    let path = bag.path.clone();
    let error = |message: String| LogError::Bag { path: path.clone(), message };
    let mut magic = [0u8; MAGIC.len()];
    let got = read_full(&mut r, &mut magic).map_err(|e| bag.error(e.to_string()))?;
    if got < MAGIC.len() || magic != MAGIC {
        return Err(bag.error("not a ROS 1 bag of format 2.0 (no `#ROSBAG V2.0` line)".into()));
    }
    let mut offset = MAGIC.len() as u64;
    let mut connections = Connections::new();
    let mut compressions = BTreeSet::new();
    let mut index_pos = 0;
    loop {
        let start = offset;
        let rec = match record(&mut r, &mut offset) {
            Ok(Some(rec)) => rec,
            Ok(None) => break,
            Err(e) => return Err(error(e)),
        };
        let at = |e: String| error(format!("the record at byte {start}: {e}"));
        match rec.op() {
            Some(OP_BAG_HEADER) => {
                let v = rec.field("index_pos").map_err(at)?;
                index_pos =
                    u64::from_le_bytes(v.try_into().map_err(|_| at("field `index_pos` is not 8 bytes".into()))?);
            }
            Some(OP_CONNECTION) => connection(&rec, &mut connections).map_err(at)?,
            Some(OP_MESSAGE) => message(&rec, &connections, bag).map_err(at)??,
            Some(OP_CHUNK) => {
                let (compression, data) =
                    decompress(&rec).map_err(|e| error(format!("the chunk at byte {start} {e}")))?;
                compressions.insert(compression);
                let (mut inner, mut inner_offset) = (&data[..], 0);
                let chunk_err = |e: String| error(format!("the chunk at byte {start}: {e}"));
                while let Some(rec) = record(&mut inner, &mut inner_offset).map_err(chunk_err)? {
                    match rec.op() {
                        Some(OP_CONNECTION) => connection(&rec, &mut connections).map_err(chunk_err)?,
                        Some(OP_MESSAGE) => message(&rec, &connections, bag).map_err(chunk_err)??,
                        _ => {}
                    }
                }
            }
            // Index records, chunk information: the reader goes through the chunks themselves.
            _ => {}
        }
    }
    if index_pos > offset {
        return Err(bag.error(format!(
            "cut off at byte {offset}: the bag's header puts its index at byte {index_pos} (a truncated download or copy?)"
        )));
    }
    let kinds: Vec<String> =
        compressions.into_iter().map(|c| if c == "none" { "uncompressed".into() } else { c }).collect();
    Ok(format!("ROS 1 bag ({} chunks)", kinds.join(" and ")))
}
