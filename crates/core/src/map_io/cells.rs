//! Grids to grey images and back, as map_server reads them (a pixel's occupancy by `negate`, the thresholds
//! and the mode) and as this crate writes them (trinary).

use super::grey_image::GreyImage;
use super::yaml::{MapMode, MapYaml};
use crate::grid::{CellState, GridError, OccupancyGrid, ROS_LOGODDS_LIMIT};
use crate::se2::pose;

/// PGM value written for occupied cells.
pub const PGM_OCCUPIED: u8 = 0;
/// PGM value written for free cells.
pub const PGM_FREE: u8 = 254;
/// PGM value written for unknown cells.
pub const PGM_UNKNOWN: u8 = 205;

/// Builds a grid from an image and its metadata, as map_server does.
pub fn grid_from_image(img: &GreyImage, meta: &MapYaml) -> Result<OccupancyGrid, GridError> {
    let (w, h) = (img.width, img.height);
    let mut cells = vec![0.0f32; w * h];
    let (occ, free) = (meta.occupied_thresh, meta.free_thresh);
    for row in 0..h {
        let iy = h - 1 - row;
        for ix in 0..w {
            let v = img.pixels[row * w + ix];
            let ros: i32 = match meta.mode {
                MapMode::Raw => {
                    if v <= 100 {
                        v as i32
                    } else {
                        -1
                    }
                }
                MapMode::Trinary | MapMode::Scale => {
                    let p = if meta.negate { v as f64 / 255.0 } else { (255.0 - v as f64) / 255.0 };
                    if p > occ {
                        100
                    } else if p < free {
                        0
                    } else if meta.mode == MapMode::Scale {
                        (99.0 * (p - free) / (occ - free)) as i32
                    } else {
                        -1
                    }
                }
            };
            cells[iy * w + ix] = ros_to_log_odds(ros);
        }
    }
    OccupancyGrid::from_cells(w, h, meta.resolution, pose(meta.origin[0], meta.origin[1], meta.origin[2]), cells)
}

/// Log-odds of a ROS occupancy value (−1 unknown, 0..100).
pub fn ros_to_log_odds(v: i32) -> f32 {
    match v {
        v if !(0..=100).contains(&v) => 0.0,
        0 => -ROS_LOGODDS_LIMIT,
        100 => ROS_LOGODDS_LIMIT,
        v => {
            let p = v as f32 / 100.0;
            (p / (1.0 - p)).ln().clamp(-ROS_LOGODDS_LIMIT, ROS_LOGODDS_LIMIT)
        }
    }
}

/// Renders a grid as a trinary grey image, top row first: occupied 0, free 254, unknown 205.
pub fn grid_to_image(grid: &OccupancyGrid) -> GreyImage {
    let (w, h) = (grid.width(), grid.height());
    let mut pixels = vec![PGM_UNKNOWN; w * h];
    for iy in 0..h {
        let row = h - 1 - iy;
        for ix in 0..w {
            pixels[row * w + ix] = match grid.state(ix, iy) {
                CellState::Occupied => PGM_OCCUPIED,
                CellState::Free => PGM_FREE,
                CellState::Unknown => PGM_UNKNOWN,
            };
        }
    }
    GreyImage { width: w, height: h, pixels }
}
