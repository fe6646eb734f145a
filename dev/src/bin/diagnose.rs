//! Checks SIFT matches between two maps against a known transform: how many keypoints lie in the shared
//! part, how many matches are true, and where the ratio test loses the true ones.
//! `cargo run --release -p mrslam-dev --bin diagnose -- A.yaml B.yaml X Y THETA [dilation] [ratio] [paper]`
//! (X Y THETA: the true `T_a_b`, points of b's frame into a's).

use mrslam_core::map_io::read_ros_map;
use mrslam_core::{CellState, Pose2};
use mrslam_merge::MapImage;
use mrslam_merge::dev::match_features;
use mrslam_merge::dev::{refine, wall_points};
use mrslam_merge::{MapEncoding, MatchParams, RefineParams};
use mrslam_sift::{GrayImage, Sift, SiftParams};
use nalgebra::{Point2, Vector2};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let res: f64 = std::env::var("RES").ok().map_or(0.0, |s| s.parse().expect("RES"));
    let load = |p: &str| {
        let g = read_ros_map(p.as_ref()).expect("map");
        if res > 0.0 { mrslam_merge::resample::to_resolution(&g, res) } else { g }
    };
    let (a, b) = (load(&args[1]), load(&args[2]));
    let num = |i: usize| args[i].parse::<f64>().expect("number");
    let t0 = Pose2::new(Vector2::new(num(3), num(4)), num(5));
    // The SLAM maps drift: the transform that best aligns their shared walls is the local truth.
    let walls_b = wall_points(&b);
    let rp = RefineParams { radius_cells: 12, iterations: 30, ..Default::default() };
    let t = refine(&a, &walls_b, &t0, &rp);
    println!(
        "true start transform {:.3} {:.3} {:.4}; walls align at {:.3} {:.3} {:.4}",
        t0.translation.x,
        t0.translation.y,
        t0.rotation.angle(),
        t.translation.x,
        t.translation.y,
        t.rotation.angle()
    );
    let dil = args.get(6).map_or(0, |s| s.parse().expect("dilation"));
    let ratio = args.get(7).map_or(0.75, |s| s.parse().expect("ratio"));
    let enc = if args.get(8).is_some_and(|s| s == "paper") { MapEncoding::PAPER } else { MapEncoding::WALLS };
    let env = |k: &str, d: f64| std::env::var(k).ok().map_or(d, |s| s.parse().expect(k));
    let upscale = env("UPSCALE", 1.0) > 0.0;
    let sp = SiftParams {
        upscale,
        sigma: env("SIGMA", 1.6) as f32,
        contrast_threshold: env("CONTRAST", 0.04) as f32,
        ..SiftParams::default()
    };
    let bias = if upscale { 0.25 } else { 0.0 };
    let mut sift = Sift::new(sp);
    let mut feats = |g| {
        let img = MapImage::render_dilated(g, &enc, 8, dil);
        let f = sift.detect_and_compute(&GrayImage::new(img.width, img.height, img.pixels.clone()).expect("image"));
        let pts: Vec<Point2<f64>> =
            f.keypoints.iter().map(|k| img.pixel_to_map(g, k.x as f64 - bias, k.y as f64 - bias)).collect();
        (f, pts)
    };
    let (fa, pa) = feats(&a);
    let (fb, pb) = feats(&b);
    let known_in_a = |p: &Point2<f64>| a.world_to_cell(p).is_some_and(|(x, y)| a.state(x, y) != CellState::Unknown);
    let shared_b = pb.iter().filter(|p| known_in_a(&(t * **p))).count();
    println!("keypoints: a {} b {} (b's in a's known part: {shared_b})", pa.len(), pb.len());
    // True partners: a keypoint of a within 2 cells of b's keypoint carried over.
    let tol: f64 = std::env::var("TOL").ok().map_or(2.0 * a.resolution(), |s| s.parse().expect("TOL"));
    let partner = |j: usize| {
        let q = t * pb[j];
        (0..pa.len()).filter(|&i| (pa[i] - q).norm() < tol).collect::<Vec<_>>()
    };
    let with_partner = (0..pb.len()).filter(|&j| !partner(j).is_empty()).count();
    println!("b keypoints with a true partner in a (within {tol:.2} m): {with_partner}");
    println!("descriptor rank of the true partner: {:?}", partner_ranks(&fa, &fb, &pa, &pb, &t, tol));
    let m = match_features(&fa, &fb, &MatchParams { ratio, ..Default::default() });
    let good = m.iter().filter(|mm| (pa[mm.a] - t * pb[mm.b]).norm() < tol).count();
    println!("matches at ratio {ratio}: {} of which true {good}", m.len());
    let all = match_features(&fa, &fb, &MatchParams { ratio: 1.0, ..Default::default() });
    let nn_true = all.iter().filter(|mm| (pa[mm.a] - t * pb[mm.b]).norm() < tol).count();
    println!("nearest neighbours that are true (no ratio test): {nn_true} of {}", all.len());
}

/// Rank of each b keypoint's true partner among a's descriptors (0 = nearest), for partners within `tol`.
fn partner_ranks(
    fa: &mrslam_sift::Features,
    fb: &mrslam_sift::Features,
    pa: &[Point2<f64>],
    pb: &[Point2<f64>],
    t: &Pose2,
    tol: f64,
) -> Vec<usize> {
    let d = |i: usize, j: usize| -> u32 {
        fa.descriptor(i).iter().zip(fb.descriptor(j)).map(|(&x, &y)| (x as i32 - y as i32).pow(2) as u32).sum()
    };
    let mut ranks = Vec::new();
    for (j, pj) in pb.iter().enumerate() {
        let q = t * pj;
        let partners: Vec<usize> = (0..pa.len()).filter(|&i| (pa[i] - q).norm() < tol).collect();
        if partners.is_empty() {
            continue;
        }
        let best = partners.iter().map(|&i| d(i, j)).min().unwrap_or(u32::MAX);
        ranks.push((0..pa.len()).filter(|&i| d(i, j) < best).count());
    }
    ranks.sort_unstable();
    ranks
}
