//! A CARMEN laser log's bytes.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let options = mrslam_log::ReadOptions::default();
    let _ = mrslam_log::carmen::parse(data, std::path::Path::new("fuzz.clf"), &options);
});
