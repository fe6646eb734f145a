//! A map's image: PGM (P5/P2) by our parser, PNG by the image crate; a decoded image becomes a grid.
#![no_main]
use libfuzzer_sys::fuzz_target;
use mrslam_core::map_io::{MapMode, MapYaml, decode_grey_image, grid_from_image};

fuzz_target!(|data: &[u8]| {
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
