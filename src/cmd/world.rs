//! `mrslam world from-map MAP.yaml -o WORLD.toml`: any building's map as a simulated world.

use anyhow::{Context, Result, bail};
use clap::Subcommand;
use mrslam_core::Xyt;
use mrslam_core::output::write_file_atomic;
use mrslam_sim::from_map::{START_CLEARANCE_M, start_poses, world_toml};
use mrslam_sim::{World, WorldSpec};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// World subcommands.
#[derive(Subcommand)]
pub enum WorldCommand {
    /// Write a world whose obstacles are a map's occupied cells (the bitmap layer), with two start poses
    /// (`start_a`, `start_b`) where a robot fits and can drive from one to the other.
    FromMap {
        /// Map YAML (map_server format); the world file names it, relative to the world file when it can.
        map: PathBuf,
        /// Output world file (.toml).
        #[arg(short, long)]
        output: PathBuf,
        /// Room the start poses keep from every cell not known free, metres.
        #[arg(long, default_value_t = START_CLEARANCE_M)]
        clearance: f64,
    },
}

/// Runs a world subcommand.
pub fn run(cmd: WorldCommand) -> Result<ExitCode> {
    match cmd {
        WorldCommand::FromMap { map, output, clearance } => from_map(&map, &output, clearance),
    }
}

fn from_map(map: &Path, output: &Path, clearance: f64) -> Result<ExitCode> {
    super::Outputs::reading([map]).file("--output", output, super::kind::TOML).check()?;
    if !(clearance.is_finite() && clearance > 0.0) {
        bail!("--clearance {clearance}: must be a positive number of metres");
    }
    let grid = super::map::read_yaml_map(map)?;
    let (_, occupied, _) = grid.state_counts();
    if occupied == 0 {
        bail!("{}: no occupied cell: a world made from it would have no obstacle", map.display());
    }
    let Some(starts) = start_poses(&grid, clearance) else {
        bail!(
            "{}: no free cell has {clearance} m of room from every cell not known free: no place to start a robot \
             (a smaller --clearance?)",
            map.display()
        );
    };
    let name = map.file_stem().map_or_else(|| "map".to_string(), |s| s.to_string_lossy().into_owned());
    let description = format!("the occupied cells of {} as obstacles", map.display());
    let named: Vec<(String, mrslam_core::Pose2)> =
        ["start_a", "start_b"].iter().map(|s| s.to_string()).zip(starts).collect();
    let text = world_toml(&name, &description, &map_reference(map, output)?, &named);
    // Read back before writing: the file must load as a world.
    let spec = WorldSpec::from_toml_str(&text, output).context("the world made from the map does not load")?;
    let world = World::from_spec(&spec).context("the world made from the map does not build")?;
    write_file_atomic(output, text.as_bytes())?;
    println!(
        "world {}: {} occupied cells of {} ({}x{} at {} m) as {} obstacles",
        output.display(),
        occupied,
        map.display(),
        grid.width(),
        grid.height(),
        grid.resolution(),
        world.obstacles().len()
    );
    for (n, p) in &named {
        let Xyt { x, y, .. } = Xyt::from_pose(p);
        println!("{n}: x {x:.2} m, y {y:.2} m");
    }
    Ok(ExitCode::SUCCESS)
}

/// How the world file at `output` names `map`: relative to the world file's folder when the map lies under it,
/// else the map's absolute path.
fn map_reference(map: &Path, output: &Path) -> Result<String> {
    let map = std::fs::canonicalize(map).with_context(|| format!("{}", map.display()))?;
    let dir = output.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let dir = std::fs::canonicalize(dir).with_context(|| format!("{}: its folder", output.display()))?;
    let path = map.strip_prefix(&dir).map(Path::to_path_buf).unwrap_or(map);
    path.to_str().map(str::to_string).with_context(|| format!("{}: not UTF-8", path.display()))
}
