//! Exploration planning benchmarks on FR079 (the real map, its east half unseen): one robot's reach (the
//! cheapest-path search over the cells it may stand on) and a four-robot team's plan (the distance transform,
//! every member's reach and frontier clusters, the assignment).
#![allow(missing_docs, reason = "criterion_group! defines an undocumented public function")]

use criterion::{Criterion, criterion_group, criterion_main};
use mrslam_core::{CellState, OccupancyGrid, Pose2, pose};
use mrslam_testbed::frontier::{Clearance, Reach, WallDistance};
use mrslam_testbed::joint_plan::{Member, TeamParams, plan_team};
use std::hint::black_box;

/// FR079's map with every cell east of its middle unknown.
fn half_seen() -> OccupancyGrid {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../worlds/fr079/fr079.yaml");
    let mut g = mrslam_core::map_io::read_ros_map(&p).expect("worlds/fr079/fr079.yaml");
    for iy in 0..g.height() {
        for ix in g.width() / 2..g.width() {
            g.set(ix, iy, 0.0);
        }
    }
    g
}

/// Four poses on free cells at least 0.5 m from walls, spread over the seen half (west to east).
fn poses(g: &OccupancyGrid, walls: &WallDistance) -> Vec<Pose2> {
    let roomy = |ix: usize, iy: usize| {
        g.state(ix, iy) == CellState::Free && walls.squared_cells(ix, iy).is_some_and(|d2| d2 >= 100)
    };
    [0.1, 0.2, 0.3, 0.45]
        .iter()
        .map(|f| {
            let ix0 = (g.width() as f64 * f) as usize;
            let (ix, iy) = (ix0..g.width())
                .flat_map(|ix| (0..g.height()).map(move |iy| (ix, iy)))
                .find(|&(ix, iy)| roomy(ix, iy))
                .expect("a free cell");
            let c = g.cell_center(ix as i64, iy as i64);
            pose(c.x, c.y, 0.0)
        })
        .collect()
}

fn bench_plan(c: &mut Criterion) {
    let g = half_seen();
    let walls = WallDistance::new(&g);
    let at = poses(&g, &walls);
    let clearance = Clearance { hard: 0.3, preferred: 0.5 };
    c.bench_function("reach_fr079", |b| {
        b.iter(|| black_box(Reach::new(black_box(&g), &walls, &at[0], clearance)));
    });
    let members: Vec<Member> = at.iter().map(|&p| Member { pose: p, clearance, avoid: &[] }).collect();
    c.bench_function("team_plan_fr079_4_robots", |b| {
        b.iter(|| black_box(plan_team(black_box(&g), &members, &TeamParams::default())));
    });
}

criterion_group!(benches, bench_plan);
criterion_main!(benches);
