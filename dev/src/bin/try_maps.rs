//! Merges two map files under several merger settings and prints each answer:
//! `cargo run --release -p mrslam-dev --bin try_maps -- A.yaml B.yaml`.

use mrslam_core::map_io::read_ros_map;
use mrslam_merge::{MapEncoding, MergeParams, SiftMerger, SiftMergerParams, merge};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let a = read_ros_map(args[1].as_ref()).expect("map a");
    let b = read_ros_map(args[2].as_ref()).expect("map b");
    for enc in [MapEncoding::WALLS, MapEncoding::PAPER] {
        for dil in [0usize, 1, 2] {
            for ratio in [0.75f32, 0.8] {
                let mut p = SiftMergerParams { encoding: enc, wall_dilation: dil, ..Default::default() };
                p.matching.ratio = ratio;
                let out =
                    merge(&SiftMerger::new(p), &a, &b, &MergeParams { verify_enabled: false, ..Default::default() });
                let r = &out.report;
                println!(
                    "enc {:?} dil {dil} ratio {ratio}: {:?} inl {}/{} omega {:?} walls {:?}",
                    enc.unknown,
                    r.transform.map(|t| (t.x, t.y, t.theta)),
                    r.inliers,
                    r.matches,
                    r.acceptance_index,
                    r.wall_agreement
                );
            }
        }
    }
}
