//! Shared helpers of the integration tests (included with `mod common;`).
#![allow(dead_code)]

use mrslam_sim::{WallSpec, WorldSpec};

/// A closed rectangular room whose interior is `[t/2, w - t/2] x [t/2, h - t/2]` for wall thickness `t`.
pub fn room(w: f64, h: f64, t: f64) -> WorldSpec {
    WorldSpec {
        name: "room".into(),
        walls: vec![WallSpec { points: vec![[0.0, 0.0], [w, 0.0], [w, h], [0.0, h], [0.0, 0.0]], thickness: t }],
        ..WorldSpec::default()
    }
}

/// Distance from (px, py) along angle `a` to the inside of the box `[x0, x1] x [y0, y1]`.
pub fn box_range(px: f64, py: f64, a: f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let (s, c) = a.sin_cos();
    let mut t = f64::INFINITY;
    if c > 1e-12 {
        t = t.min((x1 - px) / c);
    } else if c < -1e-12 {
        t = t.min((x0 - px) / c);
    }
    if s > 1e-12 {
        t = t.min((y1 - py) / s);
    } else if s < -1e-12 {
        t = t.min((y0 - py) / s);
    }
    t
}

/// Path of a world file in the repository's `worlds/` folder.
pub fn world_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../worlds").join(name)
}
