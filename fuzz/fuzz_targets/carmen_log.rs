//! A CARMEN laser log's bytes.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = mrslam_core::CarmenLog::parse(data, std::path::Path::new("fuzz.clf"));
});
