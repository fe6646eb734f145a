//! A map_server YAML file's text.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = mrslam_core::map_io::parse_map_yaml(text, std::path::Path::new("fuzz.yaml"));
    }
});
