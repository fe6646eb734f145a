//! `mrslam map info|convert`: look at and convert ROS map_server maps.

use super::paths::extension;
use anyhow::{Context, Result, bail};
use clap::Subcommand;
use mrslam_core::Xyt;
use mrslam_core::map_io::{self, GreyImage, MapMode, MapYaml};
use mrslam_core::{OccupancyGrid, map_io::grid_from_image};
use mrslam_merge::pairs::{MAX_SHIFT_M, PairSpec, cut_pair};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Map subcommands.
#[derive(Subcommand)]
pub enum MapCommand {
    /// Print a map's size, resolution, origin, cell counts and the bounding box of its known cells.
    Info {
        /// Map YAML (map_server format), or a PGM/PNG image (read at --resolution).
        map: PathBuf,
        /// Metres per pixel when MAP is a bare image.
        #[arg(long, default_value_t = 0.05)]
        resolution: f64,
    },
    /// Convert a map between forms: YAML+PGM, bare PGM or PNG, chosen by OUT's extension.
    Convert {
        /// Input: map YAML, or a PGM/PNG image (read at --resolution, origin 0).
        input: PathBuf,
        /// Output: .yaml (writes a trinary PGM and a PNG preview beside it), .pgm or .png (trinary image only).
        output: PathBuf,
        /// Metres per pixel when INPUT is a bare image.
        #[arg(long, default_value_t = 0.05)]
        resolution: f64,
    },
    /// Cut a map into two overlapping halves and move the second at random: a merge test pair with its truth.
    Cut {
        /// Map YAML to cut.
        map: PathBuf,
        /// First half (stays in the map's frame): a map YAML, written with its PGM and a PNG preview beside it.
        a: PathBuf,
        /// Second half (rotated and shifted; the true transform is printed): a map YAML, written with its PGM and
        /// a PNG preview beside it.
        b: PathBuf,
        /// Jaccard overlap of the halves' known cells; negative leaves a gap of that fraction.
        #[arg(long, default_value_t = 0.3, allow_negative_numbers = true)]
        overlap: f64,
        /// Largest shift of the second half, metres (0..=1000).
        #[arg(long, default_value_t = 5.0)]
        max_shift: f64,
        /// Seed of the cut direction and the move.
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
}

/// Fewest known cells a map must have for `map cut`.
pub const MIN_KNOWN_TO_CUT: usize = 100;

/// Reads a map YAML, printing a warning for each key map_server would ignore (a typo, most likely). A file that
/// is not there, a folder, or an image given where the YAML belongs is refused saying so.
pub fn read_yaml_map(path: &Path) -> Result<OccupancyGrid> {
    check_map_file(path)?;
    if matches!(extension(path).as_str(), "pgm" | "png") {
        bail!(
            "{}: an image, where a map YAML (.yaml) was expected: the YAML gives the image its resolution and \
             origin (`mrslam map convert {} MAP.yaml` writes one, at 0.05 m unless --resolution)",
            path.display(),
            path.display()
        );
    }
    Ok(map_io::read_ros_map_with(path, &mut |w| eprintln!("warning: {w}"))?)
}

/// Fails unless `path` is a file: not there, or a folder, is said so plainly.
fn check_map_file(path: &Path) -> Result<()> {
    if path.is_dir() {
        bail!("{}: is a folder; expected a map YAML, or a PGM or PNG image", path.display());
    }
    if !path.exists() {
        bail!("{}: no such file", path.display());
    }
    Ok(())
}

/// Runs a map subcommand.
pub fn run(cmd: MapCommand) -> Result<ExitCode> {
    match cmd {
        MapCommand::Info { map, resolution } => {
            let grid = load_map(&map, resolution)?;
            print!("{}", info_text(&map, &grid));
        }
        MapCommand::Convert { input, output, resolution } => {
            super::Outputs::reading([input.as_path()]).file("OUT", &output, super::kind::ANY_MAP).check()?;
            let grid = load_map(&input, resolution)?;
            save_map(&grid, &output)?;
            println!(
                "wrote {} ({}x{} cells at {} m)",
                output.display(),
                grid.width(),
                grid.height(),
                grid.resolution()
            );
        }
        MapCommand::Cut { map, a, b, overlap, max_shift, seed } => {
            let spec = PairSpec { overlap, max_shift_m: max_shift, rotate: true };
            if !(-0.9..0.95).contains(&overlap) {
                bail!("--overlap {overlap}: must lie in [-0.9, 0.95)");
            }
            if !(0.0..=MAX_SHIFT_M).contains(&max_shift) {
                bail!("--max-shift {max_shift}: must be a number of metres in 0..={MAX_SHIFT_M}");
            }
            super::Outputs::reading([map.as_path()])
                .file("A", &a, super::kind::MAP)
                .file("B", &b, super::kind::MAP)
                .check()?;
            let grid = load_map(&map, 0.05)?;
            let (free, occupied, _) = grid.state_counts();
            if free + occupied < MIN_KNOWN_TO_CUT {
                bail!(
                    "{}: {} known cells ({}x{} map): too few to cut into a pair (need at least {MIN_KNOWN_TO_CUT})",
                    map.display(),
                    free + occupied,
                    grid.width(),
                    grid.height()
                );
            }
            let pair = cut_pair(&grid, &spec, seed);
            if overlap > 0.0 && pair.overlap == 0.0 {
                bail!("{}: the halves share no known cell although --overlap is {overlap}", map.display());
            }
            map_io::write_ros_map_with_preview(&pair.a, &a)?;
            map_io::write_ros_map_with_preview(&pair.b, &b)?;
            let Xyt { x, y, theta: th } = Xyt::from_pose(&pair.t_a_b);
            println!("wrote {} and {} (overlap {:.3})", a.display(), b.display(), pair.overlap);
            println!("true transform b -> a: x {x:.4} m, y {y:.4} m, theta {th:.5} rad ({:.3} deg)", th.to_degrees());
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Loads a map from a YAML file, or from a bare image at the given resolution.
pub fn load_map(path: &Path, resolution: f64) -> Result<OccupancyGrid> {
    check_map_file(path)?;
    let (lo, hi) = (map_io::MIN_RESOLUTION, map_io::MAX_RESOLUTION);
    if !(lo..=hi).contains(&resolution) {
        bail!("--resolution {resolution:e}: must be between {lo} and {hi} metres per pixel");
    }
    match extension(path).as_str() {
        "yaml" | "yml" => read_yaml_map(path),
        "pgm" | "png" => {
            let img = map_io::read_grey_image(path)?;
            let meta = MapYaml {
                image: path.display().to_string(),
                resolution,
                origin: [0.0; 3],
                negate: false,
                occupied_thresh: 0.65,
                free_thresh: 0.196,
                mode: MapMode::Trinary,
            };
            grid_from_image(&img, &meta).with_context(|| format!("{}", path.display()))
        }
        "" => bail!("{}: no file extension; expected a map YAML (.yaml), or a PGM or PNG image", path.display()),
        other => bail!("{}: unknown map format `.{other}` (expected .yaml, .pgm or .png)", path.display()),
    }
}

/// Saves a map as YAML+PGM, or as a bare trinary PGM or PNG, by the path's extension.
pub fn save_map(grid: &OccupancyGrid, path: &Path) -> Result<()> {
    match extension(path).as_str() {
        "yaml" | "yml" => map_io::write_ros_map_with_preview(grid, path)?,
        "pgm" => mrslam_core::output::write_file_atomic(path, &map_io::encode_pgm(&map_io::grid_to_image(grid)))?,
        "png" => {
            let img: GreyImage = map_io::grid_to_image(grid);
            mrslam_core::output::write_file_atomic(path, &map_io::encode_png(&img, path)?)?
        }
        other => bail!("{}: unknown output format `.{other}` (expected .yaml, .pgm or .png)", path.display()),
    }
    Ok(())
}

/// The human summary `map info` prints.
pub fn info_text(path: &Path, grid: &OccupancyGrid) -> String {
    let (free, occ, unknown) = grid.state_counts();
    let Xyt { x, y, theta: yaw } = Xyt::from_pose(grid.origin());
    let res = grid.resolution();
    let mut s = format!(
        "map:        {}\nsize:       {} x {} cells ({:.2} x {:.2} m)\nresolution: {} m/cell\norigin:     x {:.3} m, y {:.3} m, yaw {:.4} rad\ncells:      {} free, {} occupied, {} unknown\n",
        path.display(),
        grid.width(),
        grid.height(),
        grid.width() as f64 * res,
        grid.height() as f64 * res,
        res,
        x,
        y,
        yaw,
        free,
        occ,
        unknown
    );
    match grid.known_bounds() {
        Some((x0, y0, x1, y1)) => {
            let lo = grid.cell_f_to_world(x0 as f64, y0 as f64);
            let hi = grid.cell_f_to_world(x1 as f64 + 1.0, y1 as f64 + 1.0);
            s += &format!(
                "known bbox: cells x {x0}..={x1}, y {y0}..={y1} ({} x {} cells); map frame ({:.3}, {:.3}) to ({:.3}, {:.3}) m\n",
                x1 - x0 + 1,
                y1 - y0 + 1,
                lo.x,
                lo.y,
                hi.x,
                hi.y
            );
        }
        None => s += "known bbox: none (no known cells)\n",
    }
    s
}
