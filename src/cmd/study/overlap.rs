//! `mrslam study overlap`: cut ground-truth maps into pairs of chosen overlap, merge each with every algorithm.

use super::{finish, open_study, run_study, shard_of};
use crate::cmd::args::one_of;
use anyhow::{Context, Result, bail};
use clap::Args;
use mrslam_core::Xyt;
use mrslam_merge::Encoding;
use mrslam_merge::floorplan::FloorplanParams;
use mrslam_studies::journal::{StudyParams, fingerprint};
use mrslam_studies::overlap::{MapSource, MapStyle, OverlapStudy, run_overlap_study};
use mrslam_studies::results::sort_rows;
use mrslam_studies::{self as study, parse_range};
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `mrslam study overlap`.
#[derive(Args)]
#[command(group = clap::ArgGroup::new("source").required(true).args(["map", "world", "floorplans"]))]
pub struct OverlapArgs {
    /// Ground truth: a ROS map_server map (YAML); every pair is cut from it.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Ground truth: a world file (TOML); pairs are cut from its true map.
    #[arg(long)]
    pub world: Option<PathBuf>,
    /// Ground truth: this many generated floor plans (repetition r uses plan r mod N).
    #[arg(long)]
    pub floorplans: Option<usize>,
    /// Size of the generated floor plans, metres, WIDTHxHEIGHT.
    #[arg(long, default_value = "24x18", allow_hyphen_values = true)]
    pub floorplan_size: String,
    /// Cell size of a world's true map or of generated floor plans, metres.
    #[arg(long, default_value_t = 0.05)]
    pub resolution: f64,
    /// Target overlaps: start:stop:step (stop included), a list a,b,c, or one value.
    #[arg(long, default_value = "0.05:0.7:0.05", allow_hyphen_values = true)]
    pub overlaps: String,
    /// Trials per overlap.
    #[arg(long, default_value_t = 30)]
    pub trials: usize,
    /// Algorithms, comma-separated (sift, rmap, correlative, cascade); the default compares the paper's two.
    #[arg(long, default_value = "sift,rmap", value_delimiter = ',')]
    pub algorithms: Vec<String>,
    /// Output folder: study.json, results.csv, summary.csv, plot.png.
    #[arg(long)]
    pub out: PathBuf,
    /// Sharding, resuming and progress.
    #[command(flatten)]
    pub run: super::StudyRun,
    /// Study seed: every trial is seeded from (seed, overlap index, trial index).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Success: rotation error at most this, degrees.
    #[arg(long, default_value_t = 2.0)]
    pub max_rotation_deg: f64,
    /// Success: translation error at most this many cells.
    #[arg(long, default_value_t = 2.0)]
    pub max_translation_cells: f64,
    /// Largest shift of the moved half of a pair, metres.
    #[arg(long, default_value_t = 5.0)]
    pub max_shift: f64,
    /// How the pairs store walls: `walls` (occupied cells, as cut) or `boundary` (walls dropped to unknown in
    /// both maps: the structure only in the free/unknown boundary, as map_server reads light-grey walls).
    #[arg(long, default_value = "walls", value_parser = ["walls", "boundary"])]
    pub map_style: String,
    /// The SIFT merger's map-to-image encoding: `walls` (the default) or `paper` (unknown grey).
    #[arg(long, default_value = "walls", value_parser = one_of::<Encoding>(Encoding::ALL.map(Encoding::name)))]
    pub encoding: Encoding,
}

fn floorplan_size(s: &str) -> Result<(f64, f64)> {
    s.split_once('x')
        .and_then(|(w, h)| Some((w.trim().parse::<f64>().ok()?, h.trim().parse::<f64>().ok()?)))
        .filter(|(w, h)| (4.0..=500.0).contains(w) && (4.0..=500.0).contains(h))
        .with_context(|| format!("--floorplan-size {s}: expected WIDTHxHEIGHT in metres, each 4..500, e.g. 24x18"))
}

/// Runs `mrslam study overlap`.
pub(super) fn run(a: OverlapArgs) -> Result<ExitCode> {
    let shard = shard_of(a.run.shard.as_deref())?;
    let overlaps = parse_range(&a.overlaps).context("--overlaps")?;
    let (lo, hi) = (mrslam_core::map_io::MIN_RESOLUTION, mrslam_core::map_io::MAX_RESOLUTION);
    if !(lo..=hi).contains(&a.resolution) {
        bail!("--resolution {:e}: must be between {lo} and {hi} metres per cell", a.resolution);
    }
    let mut params = StudyParams::default();
    params.set("kind", "overlap");
    let source = if let Some(path) = &a.map {
        let grid = crate::cmd::map::read_yaml_map(path).with_context(|| format!("--map {}", path.display()))?;
        params.set("map", fingerprint(&grid_bytes(&grid)));
        MapSource::Map(grid)
    } else if let Some(path) = &a.world {
        let grid = study::overlap::world_truth(path, a.resolution).context("--world")?;
        params.set("world", fingerprint(&grid_bytes(&grid)));
        MapSource::Map(grid)
    } else {
        let (w, h) = floorplan_size(&a.floorplan_size)?;
        let count = a.floorplans.unwrap_or(1);
        params.set("floorplans", format!("{count} of {w}x{h} m"));
        let fp = FloorplanParams { width_m: w, height_m: h, resolution: a.resolution, ..FloorplanParams::default() };
        MapSource::Floorplans { count, params: fp }
    };
    let study = OverlapStudy {
        source,
        overlaps,
        trials: a.trials,
        algorithms: study::parse_algorithms(&a.algorithms.iter().map(|s| s.trim()).collect::<Vec<_>>())?,
        seed: a.seed,
        max_rotation_deg: a.max_rotation_deg,
        max_translation_cells: a.max_translation_cells,
        max_shift_m: a.max_shift,
        shard,
        style: if a.map_style == "boundary" { MapStyle::Boundary } else { MapStyle::Walls },
        encoding: a.encoding,
    };
    study.validate()?;
    let selected: Vec<usize> = study.selected_trials().iter().map(|t| t.trial).collect();
    super::name_shard(&mut params, shard, selected.len());
    let overlaps: Vec<String> = study.overlaps.iter().map(|o| o.to_string()).collect();
    let algorithms: Vec<String> = study.algorithms.iter().map(|x| x.name().to_string()).collect();
    params
        .set("resolution", a.resolution)
        .set("overlaps", overlaps.join(","))
        .set("trials", a.trials)
        .set("algorithms", algorithms.join(","))
        .set("seed", a.seed)
        .set("max_rotation_deg", a.max_rotation_deg)
        .set("max_translation_cells", a.max_translation_cells)
        .set("max_shift", a.max_shift)
        .set("map_style", &a.map_style)
        .set("encoding", a.encoding);
    let inputs = a.map.iter().chain(&a.world).map(PathBuf::as_path);
    let (journal, earlier) = open_study(&a.out, inputs, &[], &params, algorithms.len(), a.run.resume)?;
    let (mut rows, n, seconds) =
        run_study(earlier, journal, &selected, a.run.quiet, "overlap study", |p| run_overlap_study(&study, p))?;
    sort_rows(&mut rows, &algorithms);
    finish(&rows, &a.out, n, Some(seconds))
}

/// A grid's size, resolution, origin and cells as bytes, for its fingerprint.
fn grid_bytes(g: &mrslam_core::OccupancyGrid) -> Vec<u8> {
    let Xyt { x, y, theta: t } = Xyt::from_pose(g.origin());
    let mut b = format!("{} {} {} {x} {y} {t}\n", g.width(), g.height(), g.resolution()).into_bytes();
    for c in g.cells() {
        b.extend_from_slice(&c.to_bits().to_le_bytes());
    }
    b
}
