//! Small files that claim large sizes in their headers (a string of 4 GiB, a record of 1 GiB) must not make
//! the readers allocate what they claim: every allocation of this test binary is measured (its own global
//! allocator), and one larger than [`REFUSED`] fails as it would without memory to spare.
#![allow(clippy::unwrap_used, reason = "test code: a failed unwrap fails the test")]

use mrslam_log::{ReadOptions, read_log};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Allocations larger than this fail (the process aborts, as it would on a machine short of memory).
const REFUSED: usize = 256 << 20;

/// The system allocator, keeping the largest allocation since the last reset.
struct Measured;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

// SAFETY: each method passes its arguments to the system allocator unchanged, or returns null (a failed
// allocation, which callers handle).
unsafe impl GlobalAlloc for Measured {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        if layout.size() > REFUSED {
            return std::ptr::null_mut();
        }
        // SAFETY: the caller's contract is the system allocator's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        if new_size > REFUSED {
            return std::ptr::null_mut();
        }
        // SAFETY: `ptr` was allocated by `System` with `layout`; the caller's contract is the system's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Measured = Measured;

const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// An MCAP record: opcode, `u64` length, content.
fn mcap_record(op: u8, content: &[u8]) -> Vec<u8> {
    [&[op][..], &(content.len() as u64).to_le_bytes(), content].concat()
}

/// A header of `n` claimed bytes followed by `real` bytes of the field it claims them for.
fn claims(n: u32, real: &[u8]) -> Vec<u8> {
    [&n.to_le_bytes()[..], real].concat()
}

/// An MCAP chunk record compressed as `compression` says, declaring `declared` bytes uncompressed (CRC
/// `crc`), holding `records` as its compressed data.
fn mcap_chunk(compression: &str, declared: u64, crc: u32, records: &[u8]) -> Vec<u8> {
    let body = [
        &[0u8; 16][..],
        &declared.to_le_bytes(),
        &crc.to_le_bytes(),
        &(compression.len() as u32).to_le_bytes(),
        compression.as_bytes(),
        &(records.len() as u64).to_le_bytes(),
        records,
    ];
    mcap_record(0x06, &body.concat())
}

/// A zstd frame holding `content` as one raw block (single segment, its size in one byte, no checksum).
fn zstd_raw(content: &[u8]) -> Vec<u8> {
    let n = u8::try_from(content.len()).unwrap();
    let block = (u32::from(n) << 3 | 1).to_le_bytes();
    [&[0x28, 0xb5, 0x2f, 0xfd, 0x20, n][..], &block[..3], content].concat()
}

#[test]
fn small_files_claiming_large_fields_allocate_little() {
    let huge = 0xFFFF_FFF0;
    let cases: Vec<(&str, Vec<u8>)> = vec![
        // An MCAP header whose profile string claims 4 GiB.
        ("header.mcap", [MCAP_MAGIC, &mcap_record(0x01, &claims(huge, b"ros2"))].concat()),
        // A channel whose topic claims 4 GiB.
        (
            "channel.mcap",
            [MCAP_MAGIC, &mcap_record(0x04, &[&[1, 0, 1, 0][..], &claims(huge, b"/scan")].concat())].concat(),
        ),
        // A chunk whose compression name claims 4 GiB: its header cannot be read without it.
        (
            "chunk.mcap",
            [MCAP_MAGIC, &mcap_record(0x06, &[&[0u8; 28][..], &claims(huge, b"zstd"), &[0; 16]].concat())].concat(),
        ),
        // Compressed chunks of 64 bytes declaring 1 GiB uncompressed: the `mcap` crate reserves what a chunk
        // declares before it decompresses.
        ("zstd_chunk.mcap", [MCAP_MAGIC, &mcap_chunk("zstd", (1 << 30) - 1, 1, &[0x5a; 64])].concat()),
        ("lz4_chunk.mcap", [MCAP_MAGIC, &mcap_chunk("lz4", (1 << 30) - 1, 1, &[0x5a; 64])].concat()),
        // A zstd chunk of 9 bytes uncompressed holding a message record that claims 1 GiB: the crate reserves
        // what a record inside a chunk claims before it decompresses the record.
        (
            "zstd_record.mcap",
            [
                MCAP_MAGIC,
                &mcap_chunk("zstd", 9, 0, &zstd_raw(&[&[0x05][..], &((1u64 << 30) - 1).to_le_bytes()].concat())),
            ]
            .concat(),
        ),
        // A ROS 1 record whose header claims 1 GiB.
        ("record.bag", [&b"#ROSBAG V2.0\n"[..], &claims((1 << 30) - 1, b"op=\x03")].concat()),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        LARGEST.store(0, Ordering::Relaxed);
        let read = read_log(&path, &ReadOptions::default());
        let largest = LARGEST.load(Ordering::Relaxed);
        let e = read.map(|_| ()).unwrap_err().to_string();
        assert!(e.starts_with(&path.display().to_string()), "{name}: {e}");
        assert!(largest < 16 << 20, "{name} ({} bytes): an allocation of {largest} bytes; {e}", bytes.len());
    }
}
