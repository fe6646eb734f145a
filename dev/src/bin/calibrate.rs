//! Measures what the merger's defaults rest on: success and false-merge rates of both map encodings on
//! generated floor-plan pairs, with the verification statistics of correct and wrong answers.
//!
//! Variants: `walls` and `paper` encodings with OpenCV's doubled image, `walls-1x` without doubling, and
//! `robust` (walls grown one cell, 6 candidates per feature, 4 hypotheses: the setting for SLAM maps).
//!
//! `cargo run --release -p mrslam-dev --bin calibrate -- [PAIRS] [VARIANT]`

use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::pairs::{PairSpec, cut_pair};
use mrslam_merge::{MapEncoding, MergeParams, SiftMerger, SiftMergerParams, merge};

fn main() {
    let n: u64 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(40);
    let only = std::env::args().nth(2);
    let raw = MergeParams { verify_enabled: false, ..MergeParams::default() };
    let mut one_x = SiftMergerParams::default();
    one_x.sift.upscale = false;
    let variants = [
        ("walls", SiftMergerParams::default()),
        ("paper", SiftMergerParams { encoding: MapEncoding::PAPER, ..Default::default() }),
        ("walls-1x", one_x),
        ("robust", SiftMergerParams::robust()),
    ];
    for (name, params) in variants {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let merger = SiftMerger::new(params);
        for overlap in [-0.1, 0.1, 0.2, 0.3, 0.5] {
            let (mut correct, mut accepted_ok, mut accepted_wrong) = (0, 0, 0);
            let mut stats_wrong: Vec<(usize, usize, f64, usize, f64)> = Vec::new();
            let mut stats_ok: Vec<(usize, usize, f64, usize, f64)> = Vec::new();
            let mut time = 0.0;
            for s in 0..n {
                let map = generate(1000 + s, &FloorplanParams::default());
                let pair = cut_pair(&map, &PairSpec { overlap, ..Default::default() }, s);
                let out = merge(&merger, &pair.a, &pair.b, &raw);
                time += out.report.time_ms;
                let gated_out = merge(&merger, &pair.a, &pair.b, &MergeParams::default()).report;
                // The gate may take an alternative hypothesis: judge what it accepted, not the raw answer.
                if let Some(g) = gated_out.transform.filter(|_| gated_out.accepted) {
                    let e = g.to_pose().inverse() * pair.t_a_b;
                    let (dt, da) = (e.translation.vector.norm(), e.rotation.angle().abs().to_degrees());
                    if dt > 2.0 * map.resolution() || da > 1.0 {
                        accepted_wrong += 1;
                        println!("      accepted wrong: seed {s}, error {dt:.3} m, {da:.2} deg");
                    } else {
                        accepted_ok += 1;
                    }
                }
                let Some(t) = out.report.transform else { continue };
                let est = t.to_pose();
                let err = est.inverse() * pair.t_a_b;
                let ok = err.translation.vector.norm() <= 2.0 * map.resolution()
                    && err.rotation.angle().abs() <= 1f64.to_radians();
                let st = (
                    out.report.inliers,
                    out.report.matches,
                    out.report.acceptance_index.unwrap_or(0.0),
                    out.report.common_cells,
                    out.report.wall_agreement.unwrap_or(0.0),
                );
                if ok {
                    correct += 1;
                    stats_ok.push(st);
                } else {
                    stats_wrong.push(st);
                }
            }
            let worst_wrong = stats_wrong
                .iter()
                .map(|s| (s.0, s.0 as f64 / (8.0 + 0.3 * s.1 as f64), s.2, s.3, s.4))
                .fold((0, 0.0f64, 0.0f64, 0, 0.0f64), |m, s| {
                    (m.0.max(s.0), m.1.max(s.1), m.2.max(s.2), m.3.max(s.3), m.4.max(s.4))
                });
            let weakest_ok = stats_ok
                .iter()
                .map(|s| (s.0, s.0 as f64 / (8.0 + 0.3 * s.1 as f64), s.2, s.3, s.4))
                .fold((usize::MAX, f64::MAX, f64::MAX, usize::MAX, f64::MAX), |m, s| {
                    (m.0.min(s.0), m.1.min(s.1), m.2.min(s.2), m.3.min(s.3), m.4.min(s.4))
                });
            println!(
                "{name:5} overlap {overlap:5.2}: raw correct {correct}/{n}, accepted correct {accepted_ok}, accepted wrong {accepted_wrong}, mean {:.0} ms",
                time / n as f64
            );
            println!(
                "      wrong answers max (inliers, conf, omega, common, walls) = {worst_wrong:?}; correct min = {weakest_ok:?}"
            );
        }
    }
}
