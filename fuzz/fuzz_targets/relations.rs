//! A relations file and a trajectory file (the same bytes read as each), scored when both parse.
#![no_main]
use libfuzzer_sys::fuzz_target;
use mrslam_core::relations::{parse_relations, parse_trajectory, score};

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let path = std::path::Path::new("fuzz.txt");
        if let (Ok(r), Ok(t)) = (parse_relations(text, path), parse_trajectory(text, path)) {
            let _ = score(&t, &r, 0.001);
        }
    }
});
