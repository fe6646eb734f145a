//! The record framing of an MCAP stream, checked as its bytes pass to the `mcap` crate's reader: every record
//! inside an uncompressed chunk must end within the chunk.
//!
//! Why: the crate's linear reader walks an uncompressed chunk's records straight from the stream, subtracting
//! each record's claimed length from what is left of the chunk; a record that claims to run past the chunk's
//! end overflows that subtraction (a panic where overflow checks are on, a reader that wanders past the chunk
//! where they are off). Found by fuzzing (`mcap_bag`). Compressed chunks are checked by the crate itself as it
//! decompresses them, each by a reader that sees nothing past the chunk (`mcap_bag::read_chunk`).

use std::io::{self, Read};

/// MCAP's chunk record opcode.
const CHUNK: u8 = 0x06;
/// MCAP's footer record opcode: the end magic follows it.
const FOOTER: u8 = 0x02;
/// A record's opcode and length: one byte and a little-endian u64.
const RECORD_HEADER: usize = 9;
/// A chunk's fixed fields before its compression name: start and end time, uncompressed size, CRC.
const CHUNK_FIXED: usize = 8 + 8 + 8 + 4;

/// What the next bytes of the stream are.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Part {
    /// The start magic (8 bytes, left to the crate to check).
    StartMagic,
    /// A top-level record's opcode and length.
    RecordHeader,
    /// A chunk's time range, uncompressed size and CRC.
    ChunkFixed,
    /// The length of a chunk's compression name.
    CompressionLength,
    /// A chunk's records' length (after its compression name).
    RecordsLength,
    /// The opcode and length of a record inside an uncompressed chunk.
    InnerHeader,
    /// Bytes passed unread (a record's body, a compression name, compressed records).
    Skip,
    /// After the footer: the end magic and anything after it, passed unread.
    Tail,
}

/// A reader passing an MCAP stream through unchanged, or failing with `InvalidData` (naming the byte offset)
/// at the first record of an uncompressed chunk that runs past the chunk.
pub(crate) struct McapFrames<R> {
    inner: R,
    /// Bytes of the stream seen so far.
    offset: u64,
    part: Part,
    /// The bytes of the field being read.
    field: [u8; CHUNK_FIXED],
    /// How many of them are in.
    filled: usize,
    /// Bytes left to skip, in [`Part::Skip`].
    skip: u64,
    /// Where to go after the skip.
    after_skip: Part,
    /// Bytes left of the current top-level record's body.
    record_left: u64,
    /// Bytes left of the current uncompressed chunk's records.
    records_left: u64,
    /// Whether the current chunk has a compression name.
    compressed: bool,
    /// Whether the current top-level record is the footer.
    footer: bool,
}

impl<R: Read> McapFrames<R> {
    /// Checks the stream `inner` as it is read.
    pub(crate) fn new(inner: R) -> Self {
        McapFrames {
            inner,
            offset: 0,
            part: Part::StartMagic,
            field: [0; CHUNK_FIXED],
            filled: 0,
            skip: 0,
            after_skip: Part::RecordHeader,
            record_left: 0,
            records_left: 0,
            compressed: false,
            footer: false,
        }
    }

    /// The size of the field `part` reads.
    fn field_len(part: Part) -> usize {
        match part {
            Part::StartMagic => 8,
            Part::RecordHeader | Part::InnerHeader => RECORD_HEADER,
            Part::ChunkFixed => CHUNK_FIXED,
            Part::CompressionLength => 4,
            Part::RecordsLength => 8,
            Part::Skip | Part::Tail => 0,
        }
    }

    /// Skips `n` bytes, then reads `then`.
    fn skip_then(&mut self, n: u64, then: Part) {
        self.skip = n;
        self.after_skip = then;
        self.part = Part::Skip;
    }

    /// A little-endian u64 of the field from byte `at`.
    fn u64_at(&self, at: usize) -> u64 {
        let mut b = [0; 8];
        b.copy_from_slice(&self.field[at..at + 8]);
        u64::from_le_bytes(b)
    }

    /// Takes the field just read; fails naming the offset where the stream breaks its framing.
    fn field_done(&mut self, end: u64) -> Result<(), String> {
        let start = end - Self::field_len(self.part) as u64;
        let in_chunk = |s: &mut Self, n: u64| -> Result<(), String> {
            s.record_left = s
                .record_left
                .checked_sub(n)
                .ok_or_else(|| format!("the chunk record at byte {start} is shorter than its own fields"))?;
            Ok(())
        };
        match self.part {
            Part::StartMagic => self.part = Part::RecordHeader,
            Part::RecordHeader => {
                let (opcode, len) = (self.field[0], self.u64_at(1));
                self.record_left = len;
                self.footer = opcode == FOOTER;
                if opcode == CHUNK {
                    self.part = Part::ChunkFixed;
                } else {
                    self.skip_then(len, Part::RecordHeader);
                }
            }
            Part::ChunkFixed => {
                in_chunk(self, CHUNK_FIXED as u64)?;
                self.part = Part::CompressionLength;
            }
            Part::CompressionLength => {
                in_chunk(self, 4)?;
                let n = u64::from(u32::from_le_bytes([self.field[0], self.field[1], self.field[2], self.field[3]]));
                in_chunk(self, n)?;
                self.compressed = n > 0;
                self.skip_then(n, Part::RecordsLength);
            }
            Part::RecordsLength => {
                in_chunk(self, 8)?;
                let records = self.u64_at(0);
                in_chunk(self, records)?;
                if self.compressed {
                    self.skip_then(records + self.record_left, Part::RecordHeader);
                } else {
                    self.records_left = records;
                    self.part = Part::InnerHeader;
                }
            }
            Part::InnerHeader => {
                let len = self.u64_at(1);
                let left = self.records_left - RECORD_HEADER as u64;
                if len > left {
                    return Err(format!(
                        "the record at byte {start} inside a chunk claims {len} bytes, {left} are left in its chunk"
                    ));
                }
                self.records_left = left - len;
                self.skip_then(len, Part::InnerHeader);
            }
            Part::Skip | Part::Tail => {}
        }
        Ok(())
    }

    /// Moves the framing over `bytes`, the next bytes of the stream.
    fn check(&mut self, mut bytes: &[u8]) -> Result<(), String> {
        while !bytes.is_empty() {
            match self.part {
                Part::Tail => return Ok(()),
                Part::Skip => {
                    let n = self.skip.min(bytes.len() as u64);
                    self.skip -= n;
                    self.offset += n;
                    bytes = &bytes[n as usize..];
                    if self.skip == 0 {
                        self.part = self.after_skip;
                        if self.part == Part::RecordHeader && self.footer {
                            self.part = Part::Tail;
                        }
                    }
                }
                Part::InnerHeader if self.records_left == 0 => {
                    self.skip_then(self.record_left, Part::RecordHeader);
                }
                Part::InnerHeader if self.records_left < RECORD_HEADER as u64 => {
                    return Err(format!(
                        "at byte {}: {} bytes left in a chunk, too few for a record",
                        self.offset, self.records_left
                    ));
                }
                part => {
                    let want = Self::field_len(part);
                    let n = (want - self.filled).min(bytes.len());
                    self.field[self.filled..self.filled + n].copy_from_slice(&bytes[..n]);
                    self.filled += n;
                    self.offset += n as u64;
                    bytes = &bytes[n..];
                    if self.filled == want {
                        self.filled = 0;
                        self.field_done(self.offset)?;
                    }
                }
            }
        }
        Ok(())
    }
}

impl<R: Read> Read for McapFrames<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.check(&buf[..n]).map_err(|message| io::Error::new(io::ErrorKind::InvalidData, message))?;
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record: opcode, length, body.
    fn record(opcode: u8, body: &[u8]) -> Vec<u8> {
        [&[opcode][..], &(body.len() as u64).to_le_bytes(), body].concat()
    }

    /// A chunk record holding `records` under `compression`, the records' length given as `claimed`.
    fn chunk(compression: &str, records: &[u8], claimed: u64) -> Vec<u8> {
        let body = [
            &[0u8; CHUNK_FIXED][..],
            &(compression.len() as u32).to_le_bytes(),
            compression.as_bytes(),
            &claimed.to_le_bytes(),
            records,
        ]
        .concat();
        record(CHUNK, &body)
    }

    /// Reads `stream` through the check, a few bytes at a time.
    fn read_all(stream: &[u8]) -> io::Result<Vec<u8>> {
        let mut r = McapFrames::new(stream);
        let mut out = Vec::new();
        let mut buf = [0; 5];
        loop {
            let n = r.read(&mut buf)?;
            if n == 0 {
                return Ok(out);
            }
            out.extend_from_slice(&buf[..n]);
        }
    }

    #[test]
    fn a_well_framed_stream_passes_unchanged_and_a_record_past_its_chunk_is_refused() {
        let message = record(0x05, &[7; 30]);
        let inner = [message.clone(), record(0x07, &[1; 3])].concat();
        let good = [
            &b"\x89MCAP0\r\n"[..],
            &record(0x01, b"header"),
            &chunk("", &inner, inner.len() as u64),
            &chunk("zstd", &[9; 12], 12),
            &record(FOOTER, &[0; 20]),
            b"\x89MCAP0\r\n",
        ]
        .concat();
        assert_eq!(read_all(&good).unwrap(), good);
        // The message claims more than its chunk holds.
        let mut long = message.clone();
        long[1..9].copy_from_slice(&1000u64.to_le_bytes());
        let bad = [&b"\x89MCAP0\r\n"[..], &chunk("", &long, long.len() as u64)].concat();
        let e = read_all(&bad).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        assert!(e.to_string().contains("claims 1000 bytes"), "{e}");
        // A chunk whose records claim more than the chunk record holds.
        let bad = [&b"\x89MCAP0\r\n"[..], &chunk("", &message, 10_000)].concat();
        assert!(read_all(&bad).unwrap_err().to_string().contains("shorter than its own fields"));
        // A compressed chunk's bytes are the crate's to check.
        let ok = [&b"\x89MCAP0\r\n"[..], &chunk("lz4", &long, long.len() as u64)].concat();
        assert_eq!(read_all(&ok).unwrap(), ok);
    }
}
