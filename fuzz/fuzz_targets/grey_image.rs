//! A map's image: read from a file as map YAML's `image` is (its first bytes sniffed, its size bounded: 4 KiB
//! here, so that inputs reach the bound), then decoded (PGM (P5/P2) by our parser, PNG by the image crate)
//! and made a grid.
#![no_main]
use libfuzzer_sys::fuzz_target;
use mrslam_core::map_io::{MapMode, MapYaml, decode_grey_image, grid_from_image, read_grey_image_limited};

fuzz_target!(|data: &[u8]| {
    // One file per fuzzing process, rewritten for each input.
    let file = std::env::temp_dir().join(format!("mrslam-fuzz-{}.pgm", std::process::id()));
    if std::fs::write(&file, data).is_ok() {
        let _ = read_grey_image_limited(&file, 4096);
    }
    if let Ok(img) = decode_grey_image(data, std::path::Path::new("fuzz.pgm")) {
        let meta = MapYaml {
            image: String::new(),
            resolution: 0.05,
            origin: [0.0; 3],
            negate: false,
            occupied_thresh: 0.65,
            free_thresh: 0.196,
            mode: MapMode::Trinary,
        };
        let _ = grid_from_image(&img, &meta);
    }
});
