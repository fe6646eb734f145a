//! A stand-alone merge of two maps (`mrslam merge A.yaml B.yaml --rrd FILE`): no world and no truth, so map a
//! is drawn in its own frame and map b beside it, with the matches between them and the merged map apart.

use crate::blueprint::{Layout, ViewKind};
use crate::convert::robot_color;
use crate::metrics::Level;
use crate::paths;
use crate::recorder::Recorder;
use crate::run::{MergeView, record_merge};
use mrslam_core::{OccupancyGrid, Pose2, pose};
use rerun::EntityPath;

/// Space left between the two maps drawn side by side, metres.
pub const GAP_M: f64 = 2.0;

/// Bounds (min x, max x, min y) of a grid's known cells in its map frame, or of the whole grid when none is known.
fn known_extent(g: &OccupancyGrid) -> (f64, f64, f64) {
    let (x0, y0, x1, y1) = match g.known_bounds() {
        Some((x0, y0, x1, y1)) => (x0 as f64, y0 as f64, x1 as f64 + 1.0, y1 as f64 + 1.0),
        None => (0.0, 0.0, g.width() as f64, g.height() as f64),
    };
    let corners =
        [g.cell_f_to_world(x0, y0), g.cell_f_to_world(x1, y0), g.cell_f_to_world(x0, y1), g.cell_f_to_world(x1, y1)];
    let min_x = corners.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
    let max_x = corners.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max);
    let min_y = corners.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    (min_x, max_x, min_y)
}

/// Where map b's frame is drawn so that its known cells sit [`GAP_M`] to the right of a's, bottoms aligned.
pub fn beside(a: &OccupancyGrid, b: &OccupancyGrid) -> Pose2 {
    let (_, a_max_x, a_min_y) = known_extent(a);
    let (b_min_x, _, b_min_y) = known_extent(b);
    pose(a_max_x + GAP_M - b_min_x, a_min_y - b_min_y, 0.0)
}

/// Records a stand-alone merge: both maps (named `m.host` and `m.other`), the matches, the merged map, the
/// verdict, and the layout.
pub fn record_pair(rec: &mut Recorder, a: &OccupancyGrid, b: &OccupancyGrid, m: &MergeView<'_>) {
    let (fa, fb) = (Pose2::identity(), beside(a, b));
    let (ca, cb) = (robot_color(0), robot_color(1));
    rec.log_display_frame();
    rec.send_layout(&pair_layout(m.host, m.other, m.algorithm));
    rec.log_map(&paths::map(m.host), a, &fa, ca);
    rec.log_map(&paths::map(m.other), b, &fb, cb);
    rec.log_event(
        Level::Info,
        &format!(
            "maps: {} ({}x{} cells), {} ({}x{} cells)",
            m.host,
            a.width(),
            a.height(),
            m.other,
            b.width(),
            b.height()
        ),
    );
    record_merge(rec, m, (&fa, ca), (&fb, cb), false);
}

/// The layout of a stand-alone merge: the pair with its matches, the merged map, the events.
pub fn pair_layout(a: &str, b: &str, algorithm: &str) -> Layout {
    let pair = Layout::view(
        ViewKind::Spatial2D,
        &format!("{a} and {b}: {algorithm} keypoints and inlier matches"),
        EntityPath::root(),
        &[
            format!("+ {}", paths::map(a)),
            format!("+ {}", paths::map(b)),
            format!("+ {}/**", paths::merge(algorithm, &["keypoints"])),
            format!("+ {}", paths::merge(algorithm, &["matches"])),
        ],
    );
    let merged_path = paths::merge(algorithm, &["merged"]);
    let merged = Layout::view(ViewKind::Spatial2D, "merged map", merged_path.clone(), &[format!("+ {merged_path}")]);
    let events = Layout::view(ViewKind::TextLog, "events", paths::events(), &[format!("+ {}", paths::events())]);
    Layout::Vertical(vec![Layout::Horizontal(vec![pair, merged], vec![2.0, 1.0]), events], vec![4.0, 1.0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn b_is_drawn_right_of_a() {
        let mut a = OccupancyGrid::new(10, 10, 0.1, pose(-1.0, 0.0, 0.0)).unwrap();
        let mut b = OccupancyGrid::new(10, 10, 0.1, pose(5.0, 3.0, 0.0)).unwrap();
        a.set(9, 0, 5.0); // a's known cells end at x = 0
        b.set(0, 0, -5.0); // b's start at x = 5, y = 3
        let f = beside(&a, &b);
        let b_left = f * b.cell_f_to_world(0.0, 0.0);
        assert!((b_left.x - (0.0 + GAP_M)).abs() < 1e-9, "{b_left:?}");
        assert!((b_left.y - 0.0).abs() < 1e-9);
    }
}
