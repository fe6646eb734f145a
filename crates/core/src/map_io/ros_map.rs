//! A whole map_server map, read (the YAML and the image it names) and written (YAML, PGM and a preview).

use super::cells::{grid_from_image, grid_to_image};
use super::error::{MapIoError, io_err};
use super::grey_image::{encode_pgm, read_grey_image};
use super::preview::{preview_path, write_map_preview};
use super::yaml::{key_line, map_yaml_text, parse_map_yaml_with};
use crate::grid::OccupancyGrid;
use crate::output::write_file_atomic;
use std::path::{Path, PathBuf};

/// Reads a map_server YAML file and the image it names.
pub fn read_ros_map(yaml_path: &Path) -> Result<OccupancyGrid, MapIoError> {
    read_ros_map_with(yaml_path, &mut |_| {})
}

/// Reads a map_server YAML file and the image it names, calling `warn` for each key map_server ignores.
pub fn read_ros_map_with(yaml_path: &Path, warn: &mut dyn FnMut(String)) -> Result<OccupancyGrid, MapIoError> {
    let text = crate::input::read_text_limited(yaml_path, crate::input::CONFIG_LIMIT).map_err(io_err(yaml_path))?;
    let meta = parse_map_yaml_with(&text, yaml_path, warn)?;
    let image_path = resolve_image_path(yaml_path, &meta.image);
    let img = read_grey_image(&image_path).map_err(|cause| MapIoError::ImageOf {
        yaml: yaml_path.to_path_buf(),
        line: key_line(&text, "image"),
        cause: Box::new(cause),
    })?;
    grid_from_image(&img, &meta).map_err(|cause| MapIoError::Grid { path: yaml_path.to_path_buf(), cause })
}

/// Resolves the YAML's `image` field against the YAML file's folder.
pub fn resolve_image_path(yaml_path: &Path, image: &str) -> PathBuf {
    let p = Path::new(image);
    if p.is_absolute() { p.to_path_buf() } else { yaml_path.parent().unwrap_or(Path::new(".")).join(p) }
}

/// Writes a grid as map_server files: `yaml_path` and a trinary PGM beside it with the same stem.
///
/// Both files are written to temporary names and renamed into place, the YAML last, so a reader never
/// sees a half-written map.
pub fn write_ros_map(grid: &OccupancyGrid, yaml_path: &Path) -> Result<(), MapIoError> {
    let pgm_path = yaml_path.with_extension("pgm");
    let image_name = pgm_path.file_name().and_then(|s| s.to_str()).unwrap_or("map.pgm").to_string();
    write_file_atomic(&pgm_path, &encode_pgm(&grid_to_image(grid)))?;
    Ok(write_file_atomic(yaml_path, map_yaml_text(grid, &image_name).as_bytes())?)
}

/// [`write_ros_map`], then the map's PNG preview beside it ([`preview_path`]): what the command line and the
/// testbed write for every map, so that a person can look at it without a viewer.
pub fn write_ros_map_with_preview(grid: &OccupancyGrid, yaml_path: &Path) -> Result<(), MapIoError> {
    write_ros_map(grid, yaml_path)?;
    write_map_preview(grid, &preview_path(yaml_path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{LogOddsParams, ROS_LOGODDS_LIMIT};
    use crate::se2::pose;

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    fn sample_grid() -> OccupancyGrid {
        let mut g = OccupancyGrid::new(7, 5, 0.05, pose(-1.0, 2.5, 0.25)).unwrap();
        for iy in 0..5 {
            for ix in 0..7 {
                let l = match (ix + 2 * iy) % 3 {
                    0 => ROS_LOGODDS_LIMIT,
                    1 => -ROS_LOGODDS_LIMIT,
                    _ => 0.0,
                };
                g.set(ix, iy, l);
            }
        }
        g
    }

    #[test]
    fn write_then_read_gives_same_cells() {
        let dir = tempfile::tempdir().unwrap();
        let g = sample_grid();
        let p = dir.path().join("map.yaml");
        write_ros_map(&g, &p).unwrap();
        let back = read_ros_map(&p).unwrap();
        assert_eq!(back.cells(), g.cells());
        assert_eq!((back.width(), back.height()), (7, 5));
        let crate::se2::Xyt { x, y, theta: t } = crate::se2::Xyt::from_pose(back.origin());
        assert!((x + 1.0).abs() < 1e-12 && (y - 2.5).abs() < 1e-12 && (t - 0.25).abs() < 1e-12);
        assert!(dir.path().join("map.pgm").exists());
        // no temporary files left behind
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn scan_built_grid_survives_round_trip_by_state() {
        let mut g = OccupancyGrid::new(10, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        let scan = crate::scan::LaserScan {
            stamp: 0.0,
            angle_min: -1.0,
            angle_increment: 0.05,
            range_min: 0.05,
            range_max: 3.0,
            ranges: vec![0.8; 40],
        };
        for _ in 0..3 {
            g.integrate_scan(&scan, &pose(0.5, 0.5, 0.3), &LogOddsParams::default()).unwrap();
        }
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.yaml");
        write_ros_map(&g, &p).unwrap();
        let back = read_ros_map(&p).unwrap();
        for iy in 0..g.height() {
            for ix in 0..g.width() {
                assert_eq!(back.state(ix, iy), g.state(ix, iy));
            }
        }
    }

    #[test]
    fn reads_both_pgm_kinds_with_negate_and_thresholds() {
        let dir = tempfile::tempdir().unwrap();
        // 4x1 pixels: black, dark grey 100, light grey 205, white. p = (255 - v)/255 = 1, .61, .196, 0
        let p5 = [b"P5\n4 1\n255\n".as_slice(), &[0u8, 100, 205, 255]].concat();
        write(dir.path(), "b.pgm", &p5);
        write(dir.path(), "a.pgm", b"P2\n# ascii\n4 1\n15\n0 6 12 15\n");
        let meta = "resolution: 0.1\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
        for (img, negate, expect) in [
            ("b.pgm", 0, [100, -1, -1, 0]),
            ("b.pgm", 1, [0, -1, 100, 100]),
            // maxval 15: 0 6 12 15 scale to 0 102 204 255, p = 1, .6, .2, 0
            ("a.pgm", 0, [100, -1, -1, 0]),
        ] {
            let y = write(dir.path(), "m.yaml", format!("image: {img}\nnegate: {negate}\n{meta}").as_bytes());
            let g = read_ros_map(&y).unwrap();
            let got: Vec<i8> = g
                .to_ros_int8()
                .iter()
                .map(|&v| {
                    if v == -1 {
                        -1
                    } else if v > 50 {
                        100
                    } else {
                        0
                    }
                })
                .collect();
            let expect: Vec<i8> = expect.iter().map(|&v| v as i8).collect();
            assert_eq!(got, expect, "{img} negate {negate}");
        }
    }

    #[test]
    fn scale_and_raw_modes() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "r.pgm", &[b"P5 3 1 255\n".as_slice(), &[0u8, 100, 255]].concat());
        let y = write(dir.path(), "r.yaml", b"image: r.pgm\nresolution: 1\norigin: [0,0,0]\nmode: raw\n");
        let g = read_ros_map(&y).unwrap();
        assert_eq!(g.to_ros_int8(), vec![0, 100, -1]);
        write(dir.path(), "s.pgm", &[b"P5 3 1 255\n".as_slice(), &[0u8, 110, 255]].concat());
        let y = write(dir.path(), "s.yaml", b"image: s.pgm\nresolution: 1\norigin: [0,0,0]\nmode: scale\n");
        let g = read_ros_map(&y).unwrap();
        let v = g.to_ros_int8();
        assert_eq!((v[0], v[2]), (100, 0));
        assert!(v[1] > 0 && v[1] < 100, "graded value kept: {}", v[1]);
    }

    #[test]
    fn an_unreadable_image_is_named_with_the_yaml_line() {
        let dir = tempfile::tempdir().unwrap();
        let y = write(dir.path(), "m.yaml", b"image: gone.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
        let e = read_ros_map(&y).unwrap_err().to_string();
        assert!(e.contains("gone.pgm") && e.starts_with(&format!("{}:1: field `image`: ", y.display())), "{e}");
    }
}
