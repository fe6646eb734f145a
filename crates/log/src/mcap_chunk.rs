//! A compressed MCAP chunk decompressed here, into at most the size it declares, and handed to the `mcap`
//! crate as the uncompressed chunk it stands for.
//!
//! Why: the crate's decompression loop gives the decompressor its whole output buffer and subtracts what was
//! written from the size the chunk declares; a zstd chunk whose data expands to more than it declares
//! underflows that subtraction (a panic where overflow checks are on; found by fuzzing `mcap_bag`). Read
//! through a `take` of one byte more than declared, such a chunk is refused naming its offset, as is one that
//! expands to less. The chunk is decompressed once either way.

use std::io::Read;

/// A chunk's fixed fields before its compression name: start and end time, uncompressed size, CRC.
const CHUNK_FIXED: usize = 8 + 8 + 8 + 4;
/// A record's opcode and length: one byte and a little-endian u64.
const RECORD_HEADER: usize = 9;

/// The records of a chunk compressed with `compression` (`zstd` or `lz4`), decompressed: exactly `declared`
/// bytes, else why not.
pub(crate) fn decompress(compression: &str, compressed: &[u8], declared: u64) -> Result<Vec<u8>, String> {
    let capacity = usize::try_from(declared).map_err(|_| format!("it declares {declared} bytes uncompressed"))?;
    let mut out = Vec::with_capacity(capacity);
    let limit = declared.saturating_add(1);
    let read = match compression {
        "zstd" => zstd::stream::read::Decoder::new(compressed)
            .and_then(|d| d.take(limit).read_to_end(&mut out))
            .map_err(|e| format!("its zstd data does not decompress: {e}")),
        "lz4" => lz4_flex::frame::FrameDecoder::new(compressed)
            .take(limit)
            .read_to_end(&mut out)
            .map_err(|e| format!("its lz4 data does not decompress: {e}")),
        other => Err(format!("unknown compression `{other}` (MCAP's are zstd and lz4)")),
    }?;
    match (read as u64).cmp(&declared) {
        std::cmp::Ordering::Equal => Ok(out),
        std::cmp::Ordering::Greater => {
            Err(format!("its {compression} data expands to more than the {declared} bytes it declares uncompressed"))
        }
        std::cmp::Ordering::Less => Err(format!(
            "its {compression} data expands to {read} bytes, fewer than the {declared} it declares uncompressed"
        )),
    }
}

/// The body of the uncompressed chunk with the same fixed fields as `chunk` (a chunk record's body, from its
/// start time to the end of its records) and `records` as its records.
pub(crate) fn uncompressed_chunk(chunk: &[u8], records: &[u8]) -> Option<Vec<u8>> {
    let fixed = chunk.get(..CHUNK_FIXED)?;
    let mut body = Vec::with_capacity(CHUNK_FIXED + 4 + 8 + records.len());
    body.extend_from_slice(fixed);
    body.extend_from_slice(&0u32.to_le_bytes());
    body.extend_from_slice(&(records.len() as u64).to_le_bytes());
    body.extend_from_slice(records);
    Some(body)
}

/// Whether every record of `records` (a chunk's records, uncompressed) ends within them.
pub(crate) fn records_fit(records: &[u8]) -> bool {
    let mut rest = records;
    while !rest.is_empty() {
        let Some(len) = rest.get(1..RECORD_HEADER).and_then(|b| <[u8; 8]>::try_from(b).ok()).map(u64::from_le_bytes)
        else {
            return false;
        };
        let Some(end) = usize::try_from(len).ok().and_then(|l| l.checked_add(RECORD_HEADER)) else {
            return false;
        };
        let Some(next) = rest.get(end..) else {
            return false;
        };
        rest = next;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chunk_decompresses_to_exactly_what_it_declares_or_is_refused() {
        let plain: Vec<u8> = (0..5000u32).flat_map(|i| (i % 251).to_le_bytes()).collect();
        let zstd = zstd::stream::encode_all(&plain[..], 3).unwrap();
        let mut lz4 = lz4_flex::frame::FrameEncoder::new(Vec::new());
        std::io::Write::write_all(&mut lz4, &plain).unwrap();
        let lz4 = lz4.finish().unwrap();
        let n = plain.len() as u64;
        for (name, data) in [("zstd", &zstd), ("lz4", &lz4)] {
            assert_eq!(decompress(name, data, n).unwrap(), plain, "{name}");
            let more = decompress(name, data, n - 1).unwrap_err();
            assert!(more.contains("expands to more than"), "{name}: {more}");
            let fewer = decompress(name, data, n + 7).unwrap_err();
            assert!(fewer.contains("fewer than"), "{name}: {fewer}");
            assert!(decompress(name, &data[..data.len() / 2], n).is_err(), "{name}: a cut stream");
        }
        assert!(decompress("brotli", &zstd, n).unwrap_err().contains("unknown compression"));
    }

    #[test]
    fn records_must_end_within_the_chunk() {
        let record = |len: u64, body: usize| -> Vec<u8> {
            let mut r = vec![0x05];
            r.extend_from_slice(&len.to_le_bytes());
            r.extend(std::iter::repeat_n(7u8, body));
            r
        };
        let two: Vec<u8> = [record(3, 3), record(0, 0)].concat();
        assert!(records_fit(&two) && records_fit(&[]));
        assert!(!records_fit(&record(4, 3)), "claims a byte past the end");
        assert!(!records_fit(&record(u64::MAX, 3)), "claims past any length");
        assert!(!records_fit(&[0x05, 1, 0]), "a header cut short");
        let body = uncompressed_chunk(&[1u8; 40][..30], &two).unwrap();
        assert_eq!((body.len(), &body[..28], &body[28..32]), (28 + 4 + 8 + two.len(), &[1u8; 28][..], &[0u8; 4][..]));
    }
}
