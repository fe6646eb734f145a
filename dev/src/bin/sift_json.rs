//! Runs mrslam-sift on an image file (PNG/PGM) and writes the keypoints as JSON in the layout of
//! `opencv_sift.py --json`: a list of {x, y, size, angle, response, octave, descriptor}.
//!
//! usage: cargo run --release -p mrslam-dev --bin sift_json -- IMAGE OUT.json [--runs N]

use mrslam_sift::{GrayImage, Sift, SiftParams};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(input), Some(output)) = (args.get(1), args.get(2)) else {
        return Err("usage: sift_json IMAGE OUT.json [--runs N]".into());
    };
    let runs: usize = match args.iter().position(|a| a == "--runs") {
        Some(i) => args.get(i + 1).ok_or("--runs needs a value")?.parse()?,
        None => 1,
    };
    let img = image::open(input)?.to_luma8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let img = GrayImage::from_u8(w, h, img.as_raw())?;
    let mut sift = Sift::new(SiftParams::default());
    let mut times = Vec::new();
    let mut f = sift.detect_and_compute(&img);
    for _ in 0..runs {
        let t0 = Instant::now();
        f = sift.detect_and_compute(&img);
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    if !times.is_empty() {
        println!(
            "mrslam-sift: {w}x{h} px, {} keypoints, median {:.1} ms (min {:.1}, max {:.1}) over {runs} runs, 1 thread",
            f.len(),
            times[times.len() / 2],
            times[0],
            times[times.len() - 1]
        );
    }
    let list: Vec<serde_json::Value> = f
        .keypoints
        .iter()
        .enumerate()
        .map(|(i, k)| {
            serde_json::json!({"x": k.x, "y": k.y, "size": k.size, "angle": k.angle, "response": k.response,
                "octave": k.octave, "descriptor": f.descriptor(i)})
        })
        .collect();
    std::fs::write(output, serde_json::to_string(&list)?)?;
    Ok(())
}
