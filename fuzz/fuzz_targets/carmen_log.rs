//! A CARMEN laser log's bytes, read with the default bounds and with small ones (so that inputs of a few KB
//! reach the line and total bounds).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.clf");
    let options = mrslam_log::ReadOptions::default();
    let _ = mrslam_log::carmen::parse(data, path, &options);
    let small = mrslam_log::ReadOptions { max_line_bytes: 64, max_bytes: 1024, ..options };
    let _ = mrslam_log::carmen::parse(data, path, &small);
});
