//! Writes the synthetic test images (map-like and textured, 1024x1024) as PNGs into a directory.
//!
//! usage: cargo run --release -p mrslam-dev --bin gen_images -- DIR

#[path = "../../../crates/sift/src/synth.rs"]
mod synth;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).ok_or("usage: gen_images DIR")?;
    std::fs::create_dir_all(&dir)?;
    for (name, data) in
        [("map_1024.png", synth::map_like(1024, 1024, 1)), ("texture_1024.png", synth::texture(1024, 1024, 2))]
    {
        let path = std::path::Path::new(&dir).join(name);
        image::GrayImage::from_raw(1024, 1024, data).ok_or("bad buffer")?.save(&path)?;
        println!("{}", path.display());
    }
    Ok(())
}
