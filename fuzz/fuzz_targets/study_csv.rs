//! A study's results.csv.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let path = std::path::Path::new("results.csv");
        if let Ok(rows) = mrslam_studies::results::parse_results(text, path) {
            let _ = mrslam_studies::summary::summarise(&rows);
        }
    }
});
