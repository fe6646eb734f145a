//! `mrslam features IMAGE`: SIFT keypoints of an image or a map, as numbers, JSON and a picture.

use anyhow::{Context, Result, bail};
use clap::Args;
use mrslam_core::map_io;
use mrslam_core::output::write_file_atomic;
use mrslam_merge::Encoding;
use mrslam_merge::MapImage;
use mrslam_sift::{Features, GrayImage, Sift, SiftParams};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Arguments of `mrslam features`.
#[derive(Args)]
pub struct FeaturesArgs {
    /// A PNG or PGM image, or a map YAML (rendered as the merger sees it).
    pub image: PathBuf,
    /// Write the keypoints and descriptors as JSON (the layout of dev/scripts/opencv_sift.py, OpenCV's).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Draw the keypoints over the image (PNG).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// For a map YAML: `walls` (free and unknown alike, the merger's default) or `paper` (unknown grey).
    #[arg(long, default_value = "walls", value_parser = super::args::one_of::<Encoding>(Encoding::ALL.map(Encoding::name)))]
    pub encoding: Encoding,
    /// Do not double the image first (OpenCV doubles it).
    #[arg(long)]
    pub no_upscale: bool,
    /// Keep only the N strongest keypoints.
    #[arg(long)]
    pub max_features: Option<usize>,
}

/// Runs `mrslam features`.
pub fn run(args: FeaturesArgs) -> Result<ExitCode> {
    super::Outputs::reading([args.image.as_path()])
        .maybe("--json", args.json.as_deref(), super::kind::JSON)
        .maybe("--png", args.png.as_deref(), super::kind::PNG)
        .check()?;
    let (img, what) = load(&args.image, args.encoding)?;
    let params = SiftParams { upscale: !args.no_upscale, max_features: args.max_features, ..SiftParams::default() };
    let mut sift = Sift::new(params);
    let t = Instant::now();
    let f = sift.detect_and_compute(&img);
    let ms = t.elapsed().as_secs_f64() * 1e3;
    println!(
        "{}: {}x{} {what}, {} keypoints, detect+describe {ms:.1} ms",
        args.image.display(),
        img.width,
        img.height,
        f.len()
    );
    if let Some(p) = &args.json {
        write_file_atomic(p, json(&f).as_bytes())?;
    }
    if let Some(p) = &args.png {
        draw(&img, &f, p)?;
    }
    Ok(ExitCode::SUCCESS)
}

fn load(path: &Path, encoding: Encoding) -> Result<(GrayImage, &'static str)> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if ext == "yaml" || ext == "yml" {
        let grid = super::map::read_yaml_map(path)?;
        let img = MapImage::render(&grid, &encoding.levels(), 8);
        let g = GrayImage::new(img.width, img.height, img.pixels).with_context(|| format!("{}", path.display()))?;
        return Ok((g, "map image"));
    }
    let grey = map_io::read_grey_image(path)?;
    if grey.width == 0 || grey.height == 0 {
        bail!("{}: empty image", path.display());
    }
    let g = GrayImage::from_u8(grey.width, grey.height, &grey.pixels).with_context(|| format!("{}", path.display()))?;
    Ok((g, "image"))
}

/// The keypoints as dev/scripts/opencv_sift.py writes them.
fn json(f: &Features) -> String {
    let list: Vec<serde_json::Value> = f
        .keypoints
        .iter()
        .enumerate()
        .map(|(i, k)| {
            serde_json::json!({"x": k.x, "y": k.y, "size": k.size, "angle": k.angle, "response": k.response,
                "octave": k.octave, "descriptor": f.descriptor(i)})
        })
        .collect();
    serde_json::to_string(&list).expect("keypoints serialise")
}

/// Draws each keypoint as a circle of its size with a tick along its orientation.
fn draw(img: &GrayImage, f: &Features, path: &Path) -> Result<()> {
    let (w, h) = (img.width, img.height);
    let mut out = image::RgbImage::new(w as u32, h as u32);
    for (i, p) in out.pixels_mut().enumerate() {
        let g = img.data[i].clamp(0.0, 255.0) as u8;
        *p = image::Rgb([g, g, g]);
    }
    let mut put = |x: f64, y: f64| {
        let (px, py) = (x.round(), y.round());
        if px >= 0.0 && py >= 0.0 && (px as usize) < w && (py as usize) < h {
            out.put_pixel(px as u32, py as u32, image::Rgb([230, 40, 40]));
        }
    };
    for k in &f.keypoints {
        let (x, y, r) = (k.x as f64, k.y as f64, (k.size as f64 / 2.0).max(1.5));
        let n = (r * 8.0).ceil().max(12.0) as usize;
        for s in 0..n {
            let a = s as f64 / n as f64 * std::f64::consts::TAU;
            put(x + r * a.cos(), y + r * a.sin());
        }
        // OpenCV's angle is in degrees, counter-clockwise in an image whose y points down.
        let a = -(k.angle as f64).to_radians();
        for s in 0..=(r.ceil() as usize) {
            put(x + s as f64 * a.cos(), y + s as f64 * a.sin());
        }
    }
    let mut bytes = Vec::new();
    out.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .with_context(|| format!("{}: encoding PNG", path.display()))?;
    write_file_atomic(path, &bytes)?;
    Ok(())
}
