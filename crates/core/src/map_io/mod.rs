//! ROS map_server maps: YAML metadata plus a PGM (P5 or P2) or PNG image, read and written.
//!
//! Reading follows map_server's `loadMapFromFile`: a pixel's occupancy is `p = (255 - v) / 255`
//! (`v / 255` when `negate` is set); `trinary` mode makes `p > occupied_thresh` occupied,
//! `p < free_thresh` free and the rest unknown; `scale` keeps the in-between values; `raw` takes the
//! pixel value itself as the ROS occupancy (0..100, anything else unknown). Occupancies become log-odds
//! clamped to ±[`ROS_LOGODDS_LIMIT`], so a map read back from disk holds exactly −2, 0 or +2 per cell.
//!
//! The YAML is read with a YAML parser, so everything map_server accepts is accepted (block or flow lists,
//! quoted values, comments); keys map_server ignores are reported as warnings. Errors name the file, the line
//! and the field.

// One concept per module: the YAML file, grey image codecs, grids to images and back, whole maps, previews.
mod cells;
mod error;
mod grey_image;
mod preview;
mod ros_map;
mod yaml;

pub use crate::grid::ROS_LOGODDS_LIMIT;
pub use cells::{PGM_FREE, PGM_OCCUPIED, PGM_UNKNOWN, grid_from_image, grid_to_image, ros_to_log_odds};
pub use error::MapIoError;
pub use grey_image::{
    GreyImage, IMAGE_LIMIT, decode_grey_image, encode_pgm, encode_png, parse_pgm, read_grey_image,
    read_grey_image_limited,
};
pub use preview::{
    OverlayLayer, overlay, preview_image, preview_path, preview_with_path, write_map_preview, write_rgb_png,
};
pub use ros_map::{read_ros_map, read_ros_map_with, resolve_image_path, write_ros_map, write_ros_map_with_preview};
pub use yaml::{
    MAP_YAML_KEYS, MAX_COORDINATE, MAX_RESOLUTION, MIN_RESOLUTION, MapMode, MapYaml, map_yaml_text, parse_map_yaml,
    parse_map_yaml_with,
};
