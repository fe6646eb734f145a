//! A world file's text (beside the shipped worlds, so a bitmap path resolves as theirs do), then the world.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/fuzz.toml");
        if let Ok(spec) = mrslam_sim::WorldSpec::from_toml_str(text, &path) {
            let _ = mrslam_sim::World::from_spec(&spec);
        }
    }
});
