//! A sweep file's text, beside the shipped scenarios (so `scenario = "paper_corridor.toml"` resolves).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/fuzz_sweep.toml");
        let _ = mrslam_studies::Sweep::parse(text, &path);
    }
});
