//! MCAP files (ROS 2's bag format since Iron; uncompressed, zstd or lz4 chunks), read front to back
//! through the `mcap` crate's streaming reader (Foxglove's reference implementation): a chunk at a time
//! in memory, records no larger than [`MAX_RECORD_BYTES`], each chunk's CRC checked before its messages are
//! read. Messages encoded `cdr`
//! (ROS 2) or `ros1` are decoded by their schema's name.
//!
//! Two guards keep a small file from claiming large allocations (both found by fuzzing): the reader's read
//! requests are served [`READ_BYTES`] at a time (it asks for as many bytes as a record's header claims,
//! 4 GiB for a chunk whose compression name claims it), and only the records the log needs (schemas,
//! channels, messages, chunk indexes) are parsed, once their length prefixes are checked against the
//! record ([`prefixes_fit`]): `mcap::parse_record` reserves what a string's prefix claims before reading it.
//! A third keeps the crate from walking past an uncompressed chunk: `mcap_frames` checks its records' framing.
//! A fourth keeps it from spinning forever on, or underflowing in, a compressed chunk that holds less or more
//! than it declares: each chunk is decompressed here into at most its declared size (`mcap_chunk`) and read as
//! an uncompressed chunk by a reader of its own that sees nothing past it ([`read_chunk`]). A fifth keeps a
//! compressed chunk from claiming memory its bytes cannot fill: the crate reserves (and zeroes) a chunk's
//! declared uncompressed size, and a record's claimed length within it, before it decompresses; a chunk that
//! declares more than its compressed bytes can expand to ([`max_expansion`]) or more than the log may hold
//! ([`ReadOptions::max_bytes`](crate::ReadOptions::max_bytes)) is refused first, and no record in it may claim
//! more than the chunk declares.

use crate::bag_messages::{BagMessages, MAX_RECORD_BYTES, Wire};
use crate::error::LogError;
use crate::mcap_chunk;
use crate::mcap_frames::McapFrames;
use mcap::records::{Record, op};
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::io::Read;
use std::path::Path;

/// The first bytes of an MCAP file.
pub(crate) const MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// The most bytes handed to the reader at a time.
const READ_BYTES: usize = 1 << 20;

/// A record's opcode and length: one byte and a little-endian u64.
const RECORD_HEADER: usize = 9;

/// A channel: its topic, its schema's name and its message encoding.
struct Channel {
    topic: String,
    type_name: String,
    encoding: String,
}

/// Where a record lies, for errors.
#[derive(Clone, Copy)]
enum Place {
    /// Outside chunks, within the first this many bytes of the file (those handed to the reader).
    Within(u64),
    /// In the chunk record at this byte.
    Chunk(u64),
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::Within(fed) => write!(f, "within the first {fed} bytes"),
            Place::Chunk(at) => write!(f, "the chunk at byte {at}"),
        }
    }
}

/// An error of the `mcap` crate's reader at `place` of the file at `path`.
fn mcap_err(path: &Path, place: Place, e: mcap::McapError) -> LogError {
    let cut = matches!(place, Place::Within(_))
        && matches!(e, mcap::McapError::UnexpectedEof | mcap::McapError::UnexpectedEoc);
    let hint = if cut { " (cut off: a truncated download or copy?)" } else { "" };
    LogError::Bag { path: path.to_path_buf(), message: format!("MCAP, {place}: {e}{hint}") }
}

/// What the records read so far define, and the bag their messages go to.
struct Records<'a> {
    bag: &'a mut BagMessages,
    schemas: BTreeMap<u16, String>,
    channels: BTreeMap<u16, Channel>,
    compressions: BTreeSet<String>,
}

impl Records<'_> {
    /// Takes the record `opcode` with body `data`, at `place`.
    fn take(&mut self, opcode: u8, data: &[u8], place: Place) -> Result<(), LogError> {
        if !matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE | op::CHUNK_INDEX) {
            return Ok(());
        }
        if !prefixes_fit(opcode, data) {
            return Err(self
                .bag
                .error(format!("MCAP, {place}: a record (opcode {opcode:#04x}) whose fields run past its end")));
        }
        let record = mcap::parse_record(opcode, data).map_err(|e| mcap_err(&self.bag.path, place, e))?;
        match record {
            Record::Schema { header, .. } => {
                self.schemas.insert(header.id, header.name);
            }
            Record::Channel(c) => {
                let type_name = self.schemas.get(&c.schema_id).cloned().unwrap_or_default();
                self.channels.insert(c.id, Channel { topic: c.topic, type_name, encoding: c.message_encoding });
            }
            Record::ChunkIndex(index) => {
                self.compressions.insert(index.compression);
            }
            Record::Message { header, data } => {
                let Some(c) = self.channels.get(&header.channel_id) else {
                    return Err(self.bag.error(format!(
                        "MCAP, {place}: a message on channel {}, which no record defines",
                        header.channel_id
                    )));
                };
                let bag = &mut *self.bag;
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
        Ok(())
    }
}

/// Reads an MCAP file from `r` into `bag`; returns the format's name for summaries.
pub(crate) fn read(r: impl Read, bag: &mut BagMessages) -> Result<String, LogError> {
    // The framing of uncompressed chunks checked before the crate walks them (see `mcap_frames`).
    let mut r = McapFrames::new(r);
    // Chunks are yielded whole, each read by a reader of its own (see `read_chunk`).
    let options = LinearReaderOptions::default().with_emit_chunks(true).with_record_length_limit(MAX_RECORD_BYTES);
    let mut reader = LinearReader::new_with_options(options);
    let path = bag.path.clone();
    let mut records =
        Records { bag, schemas: BTreeMap::new(), channels: BTreeMap::new(), compressions: BTreeSet::new() };
    let mut fed: u64 = 0;
    // Where the next record starts: the reader yields every record of the file (chunks whole), in order.
    let mut next_at = MAGIC.len() as u64;
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| mcap_err(&path, Place::Within(fed), e))? {
            LinearReadEvent::ReadRequest(need) => {
                let n = r
                    .read(reader.insert(need.min(READ_BYTES)))
                    .map_err(|e| LogError::Io { path: path.clone(), cause: e })?;
                reader.notify_read(n);
                fed += n as u64;
            }
            LinearReadEvent::Record { opcode, data } => {
                let at = next_at;
                next_at += (RECORD_HEADER + data.len()) as u64;
                if opcode == op::CHUNK {
                    read_chunk(at, data, &mut records)?;
                } else {
                    records.take(opcode, data, Place::Within(fed))?;
                }
            }
        }
    }
    let kinds: Vec<String> =
        records.compressions.into_iter().map(|c| if c.is_empty() { "uncompressed".to_string() } else { c }).collect();
    Ok(if kinds.is_empty() { "MCAP".to_string() } else { format!("MCAP ({} chunks)", kinds.join(" and ")) })
}

/// Reads the records of the chunk whose record, at byte `at` of the file, has body `body`.
///
/// Each chunk is handed to a reader of its own: its header and compressed records only (any bytes after them
/// in the record dropped), then the end of the input. Why: the crate's decompression loop
/// (`decompress_inner`) feeds the decompressor the chunk's compressed bytes not yet read, and asks for more
/// input only when its buffer holds fewer than the decompressor wants; once a chunk's compressed data is
/// used up short of the uncompressed size the chunk declares, it feeds the decompressor nothing, forever, as
/// long as its buffer holds bytes from past the chunk (found by fuzzing: a zstd chunk declaring 1.3 MB and
/// holding 119 KB). A reader that holds nothing past the chunk asks for more instead, is told the input
/// ends, and fails. Cheaper than checking each chunk first, which would decompress it twice; the records of
/// an uncompressed chunk still go through `mcap_frames` first, as part of the file.
fn read_chunk(at: u64, body: &[u8], records: &mut Records) -> Result<(), LogError> {
    let path = records.bag.path.clone();
    let err =
        |what: &str| LogError::Bag { path: path.clone(), message: format!("MCAP, the chunk at byte {at}: {what}") };
    let Some(parts) = chunk_parts(body) else {
        return Err(err("its fields run past the end of its record"));
    };
    let ChunkParts { declared, compression, compressed_bytes, chunk } = parts;
    let compressed = !compression.is_empty();
    // The declared size is what the crate reserves before decompressing: bounded by what the compressed
    // bytes can expand to, and by the log's bound.
    if let Some(ratio) = max_expansion(compression)
        && declared > compressed_bytes.saturating_mul(ratio)
    {
        return Err(err(&format!(
            "it declares {declared} bytes uncompressed from {compressed_bytes} bytes of {compression}, more than \
                 {compression} can expand them to (at most {ratio} times): a corrupt or hostile file"
        )));
    }
    let max_bytes = records.bag.max_bytes();
    if compressed && declared > max_bytes {
        return Err(LogError::TooLarge { path: path.clone(), limit: max_bytes, compressed: true });
    }
    // A compressed chunk is decompressed here, into no more than it declares, and read as the uncompressed
    // chunk it stands for (`mcap_chunk`); an uncompressed one went through `mcap_frames` as part of the file.
    let plain;
    let chunk = if compressed {
        let records = &chunk[chunk.len().saturating_sub(compressed_bytes as usize)..];
        let decompressed = mcap_chunk::decompress(compression, records, declared).map_err(|m| err(&m))?;
        if !mcap_chunk::records_fit(&decompressed) {
            return Err(err("a record inside it runs past its end"));
        }
        plain = mcap_chunk::uncompressed_chunk(chunk, &decompressed).ok_or_else(|| err("its fields are cut short"))?;
        &plain[..]
    } else {
        chunk
    };
    // No record inside a compressed chunk is longer than the chunk declares: the crate reserves what a
    // record's length claims before it reads the record.
    let limit = if compressed { declared.max(chunk.len() as u64) } else { MAX_RECORD_BYTES as u64 };
    let options = LinearReaderOptions::default()
        .with_skip_start_magic(true)
        .with_skip_end_magic(true)
        .with_prevalidate_chunk_crcs(true)
        .with_record_length_limit(usize::try_from(limit).unwrap_or(MAX_RECORD_BYTES).min(MAX_RECORD_BYTES));
    let mut reader = LinearReader::new_with_options(options);
    let mut input = Some(chunk);
    while let Some(event) = reader.next_event() {
        match event {
            // The chunk as a record of its own, then the end of the input.
            Ok(LinearReadEvent::ReadRequest(_)) => match input.take() {
                Some(chunk) => {
                    let buf = reader.insert(RECORD_HEADER + chunk.len());
                    buf[0] = op::CHUNK;
                    buf[1..RECORD_HEADER].copy_from_slice(&(chunk.len() as u64).to_le_bytes());
                    buf[RECORD_HEADER..].copy_from_slice(chunk);
                    reader.notify_read(RECORD_HEADER + chunk.len());
                }
                None => reader.notify_read(0),
            },
            Ok(LinearReadEvent::Record { opcode, data }) => records.take(opcode, data, Place::Chunk(at))?,
            Err(mcap::McapError::UnexpectedEof) if compressed => {
                return Err(err(&format!(
                    "its compressed data holds fewer bytes than the uncompressed size it declares ({declared} bytes)"
                )));
            }
            Err(mcap::McapError::UnexpectedEof) => return Err(err("its records run past its end")),
            Err(mcap::McapError::RecordTooLarge { opcode, len }) if compressed => {
                return Err(err(&format!(
                    "a record (opcode {opcode:#04x}) claims {len} bytes, more than the chunk declares ({declared} \
                     bytes uncompressed)"
                )));
            }
            Err(e) => return Err(mcap_err(&path, Place::Chunk(at), e)),
        }
    }
    Ok(())
}

/// The most bytes one byte of `compression`'s output can decompress to, when the codec bounds it (`None`:
/// uncompressed, or a compression the crate does not read, which it refuses before allocating).
///
/// zstd: a block decompresses to at most 128 KiB (its `Block_Maximum_Size`) and takes at least 4 bytes (a
/// 3-byte block header and an RLE block's one byte), so at most 32768 times. lz4: a sequence that repeats a
/// match of `L` bytes takes a token, a 2-byte offset and one length byte per 255 bytes of `L` past 19, so
/// fewer than 255 times.
fn max_expansion(compression: &str) -> Option<u64> {
    match compression {
        "zstd" => Some(32_768),
        "lz4" => Some(255),
        _ => None,
    }
}

/// A chunk record's parts.
struct ChunkParts<'a> {
    /// The uncompressed size the chunk declares.
    declared: u64,
    /// Its compression's name (empty: uncompressed).
    compression: &'a str,
    /// The length of its (compressed) records.
    compressed_bytes: u64,
    /// Its header and records, without any bytes after them in the record.
    chunk: &'a [u8],
}

/// The parts of a chunk record's `body`; `None` if they run past the record.
fn chunk_parts(body: &[u8]) -> Option<ChunkParts<'_>> {
    let mut f = Fields(body);
    // Start and end time, uncompressed size, CRC, compression, the records' length.
    f.u64()?;
    f.u64()?;
    let declared = f.u64()?;
    let name_len = f.skip(4).then(|| f.len()).flatten()?;
    let name = f.0.get(4..)?.get(..name_len)?;
    if !f.prefixed() {
        return None;
    }
    let compressed_bytes = f.u64()?;
    let records = usize::try_from(compressed_bytes).ok()?;
    let end = (body.len() - f.0.len()).checked_add(records)?;
    // A compression name that is not UTF-8 names no codec: the crate refuses it.
    let compression = std::str::from_utf8(name).unwrap_or("?");
    Some(ChunkParts { declared, compression, compressed_bytes, chunk: body.get(..end)? })
}

/// Whether the length-prefixed fields of a schema, channel or chunk index record (strings, maps, the
/// schema's data) all lie within `body`, so that parsing it reserves no more than the record holds.
fn prefixes_fit(opcode: u8, body: &[u8]) -> bool {
    let mut f = Fields(body);
    match opcode {
        // id; name, encoding, data.
        op::SCHEMA => f.skip(2) && f.prefixed() && f.prefixed() && f.prefixed(),
        // id, schema id; topic, message encoding, metadata (a map of strings).
        op::CHANNEL => f.skip(4) && f.prefixed() && f.prefixed() && f.string_map(),
        // times, chunk offset and length; message index offsets (a map of fixed-size entries), their
        // length; compression.
        op::CHUNK_INDEX => f.skip(32) && f.prefixed() && f.skip(8) && f.prefixed(),
        // Fixed fields, then the data: nothing prefixed.
        _ => true,
    }
}

/// The fields of a record not yet checked.
struct Fields<'a>(&'a [u8]);

impl Fields<'_> {
    /// Passes `n` bytes, if there are.
    fn skip(&mut self, n: usize) -> bool {
        match self.0.get(n..) {
            Some(rest) => {
                self.0 = rest;
                true
            }
            None => false,
        }
    }

    /// Passes a little-endian `u64`, if there is one.
    fn u64(&mut self) -> Option<u64> {
        let value = u64::from_le_bytes(*self.0.first_chunk::<8>()?);
        self.skip(8);
        Some(value)
    }

    /// The length of the `u32`-prefixed field that starts here.
    fn len(&self) -> Option<usize> {
        self.0.first_chunk::<4>().map(|b| u32::from_le_bytes(*b) as usize)
    }

    /// Passes a `u32`-prefixed field (a string, bytes, a map of fixed-size entries), if it fits.
    fn prefixed(&mut self) -> bool {
        self.len().is_some_and(|len| self.skip(4) && self.skip(len))
    }

    /// Passes a map of strings (its byte length, then key and value strings), if it and its entries fit.
    fn string_map(&mut self) -> bool {
        let Some(len) = self.len() else { return false };
        let Some(entries) = self.0.get(4..).and_then(|rest| rest.get(..len)) else { return false };
        let mut entries = Fields(entries);
        while !entries.0.is_empty() {
            if !(entries.prefixed() && entries.prefixed()) {
                return false;
            }
        }
        self.skip(4 + len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `bytes` prefixed by their `u32` length.
    fn prefixed(bytes: &[u8]) -> Vec<u8> {
        [&(bytes.len() as u32).to_le_bytes()[..], bytes].concat()
    }

    #[test]
    fn length_prefixes_must_lie_within_the_record() {
        let channel = |metadata: &[u8]| -> Vec<u8> {
            [&[1, 0, 1, 0][..], &prefixed(b"/scan"), &prefixed(b"cdr"), metadata].concat()
        };
        let entry = [prefixed(b"k"), prefixed(b"v")].concat();
        assert!(prefixes_fit(op::CHANNEL, &channel(&prefixed(&entry))));
        assert!(prefixes_fit(op::CHANNEL, &channel(&prefixed(b""))));
        // A map longer than the record, or an entry's string longer than its map.
        assert!(!prefixes_fit(op::CHANNEL, &channel(&u32::MAX.to_le_bytes())));
        assert!(!prefixes_fit(op::CHANNEL, &channel(&prefixed(&[&entry[..], &[9, 0, 0, 0, b'x']].concat()))));
        // A schema whose name claims 4 GiB, or cut inside its fixed fields.
        let schema = [&[1, 0][..], &prefixed(b"sensor_msgs/msg/LaserScan"), &prefixed(b"ros2msg"), &prefixed(b"")];
        assert!(prefixes_fit(op::SCHEMA, &schema.concat()));
        assert!(!prefixes_fit(op::SCHEMA, &[&[1, 0][..], &u32::MAX.to_le_bytes(), b"name"].concat()));
        assert!(!prefixes_fit(op::CHUNK_INDEX, &[0u8; 31]));
        assert!(prefixes_fit(
            op::CHUNK_INDEX,
            &[&[0u8; 32][..], &prefixed(&[0; 10]), &[0; 8], &prefixed(b"zstd")].concat()
        ));
    }
}
