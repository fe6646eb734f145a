//! `mrslam run SCENARIO.toml`: a paper scenario end to end — simulate, map, merge, evaluate, report.

use super::outputs::kind;
use super::run_bag::RunBag;
use super::run_folder::{OwnOutput, RunFolder};
use anyhow::{Result, bail};
use clap::Args;
use mrslam_merge::Algorithm;
use mrslam_testbed::runner::{RobotStep, RunOptions, StepTap, output_files, run as run_scenario, write_outputs};
use mrslam_testbed::scenario::Scenario;
use mrslam_viz::RunRecorder;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `mrslam run`.
#[derive(Args)]
pub struct RunArgs {
    /// Scenario file (TOML), e.g. scenarios/paper_corridor.toml.
    pub scenario: PathBuf,
    /// Output folder (default: out/NAME, NAME being the scenario's name; a folder given here is made when its
    /// parent exists). A run replaces or removes only the files an earlier run wrote there (listed in its
    /// run-files.txt, and of the names a run writes), and never a file the scenario reads; a file of its output
    /// names that no run-files.txt lists is refused unless --force.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Merge algorithm to run instead of the scenario's: one name, or `all` to compare them on the same maps.
    #[arg(long)]
    pub algorithm: Option<String>,
    /// Override the scenario's seed.
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Also write the run as a ROS 2 bag (one MCAP file, for `ros2 bag play`, Foxglove or another SLAM): per
    /// robot /NAME/scan, /NAME/odom, /NAME/ground_truth and /NAME/map, /tf, /tf_static, /truth_map and the
    /// merged map (/merged_map).
    #[arg(long, value_name = "OUT.mcap")]
    pub mcap: Option<PathBuf>,
    /// Replace files of the run's output names in --out that no earlier run lists in run-files.txt (your own
    /// files of those names, or a run's from before run-files.txt); without it the run refuses to start.
    #[arg(long)]
    pub force: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Rerun recording of the run.
    #[command(flatten)]
    pub viz: super::viz::VizArgs,
}

/// Runs `mrslam run`.
pub fn run(args: RunArgs) -> Result<ExitCode> {
    let mut scenario = Scenario::from_file(&args.scenario)?;
    if let Some(s) = args.seed {
        scenario.seed = s;
    }
    let algorithms = match args.algorithm.as_deref() {
        None => None,
        Some("all") => Some(Algorithm::ALL.to_vec()),
        Some(a) => match a.parse::<Algorithm>() {
            Ok(a) => Some(vec![a]),
            Err(_) => bail!("--algorithm {a}: unknown (expected {} or all)", Algorithm::names()),
        },
    };
    let out_dir = args.out.clone().unwrap_or_else(|| PathBuf::from("out").join(&scenario.name));
    // The files the scenario reads: never written over, even when they sit in the output folder.
    let mut inputs = vec![args.scenario.clone(), scenario.world_path.clone()];
    inputs.extend(scenario.world.bitmap.as_ref().map(|b| b.map.clone()));
    // Before the long run: the folder can be made, and no output lands on an input or on another output.
    let files = output_files(&scenario, algorithms.as_deref(), &out_dir);
    let own: Vec<OwnOutput> =
        [("--rrd", args.viz.rrd.as_deref(), kind::RRD), ("--mcap", args.mcap.as_deref(), kind::MCAP)]
            .into_iter()
            .filter_map(|(flag, path, kind)| path.map(|p| (flag, p, kind)))
            .collect();
    let folder = RunFolder::prepare(&out_dir, args.out.is_none(), files, &own, &inputs, args.force)?;
    let mut bag = args.mcap.as_deref().map(|p| RunBag::create(p, &scenario)).transpose()?;
    // The same for the recording: a file that cannot be written, or no viewer, fails here.
    let recording_id = format!("{}-seed{}", scenario.name, scenario.seed);
    let name = format!("{} (seed {})", scenario.name, scenario.seed);
    let mut viz = args.viz.open(&recording_id, &name)?.map(RunRecorder::new);
    // Ctrl-C (or SIGTERM, SIGHUP) from here: the folder's files are as they were (this run's are moved there only
    // at the end), and the bag's hidden temporary file goes.
    super::interrupt::on_interrupt(
        format!(
            "mrslam run: interrupted: the outputs of {} are as they were before this run (an earlier run's, if \
             any){}{}",
            out_dir.display(),
            args.viz
                .rrd
                .as_deref()
                .map(|r| format!(
                    "; the recording so far, without its footer: {}",
                    mrslam_viz::partial_path(r).display()
                ))
                .unwrap_or_default(),
            args.mcap.as_deref().map(|m| format!("; no bag written to {}", m.display())).unwrap_or_default()
        ),
        bag.iter().map(|b| b.temporary().to_path_buf()).collect(),
    );
    let bar = super::sim_progress::bar(&scenario.name, scenario.duration, args.quiet);
    let opts = RunOptions {
        algorithms,
        // The bar runs to the expected end of the run (a rendezvous usually comes long before the duration).
        progress: Some(Box::new(|t: f64, end: f64| super::sim_progress::show(&bar, t, end))),
        viz: viz.as_mut(),
        on_step: bag.as_mut().map(|b| Box::new(|s: &RobotStep<'_>| b.step(s)) as StepTap),
    };
    let out = run_scenario(&scenario, opts)?;
    bar.finish_and_clear();
    let bag = bag.map(|b| b.finish(&out)).transpose()?;
    // An interruption waits while the files are moved into place together.
    let (removed, interrupted) = super::interrupt::moving(|| {
        let removed = folder.commit(|staging| Ok(write_outputs(&out, staging)?))?;
        Ok::<_, anyhow::Error>((removed, bag.map(|b| b.commit()).transpose()?))
    });
    if let Some(code) = interrupted {
        eprintln!("mrslam run: interrupted; the outputs were moved into place first ({})", out_dir.display());
        return Ok(ExitCode::from(code));
    }
    let (removed, bag) = removed?;
    for r in removed {
        println!("removed:  {} (an earlier run's, not written by this one)", r.display());
    }
    print!("{}", out.report.summary());
    println!("outputs:  {}", out_dir.display());
    if let Some(b) = bag {
        println!("ROS 2 bag: {}", b.display());
    }
    if let Some(v) = viz {
        let stats = v.finish()?;
        println!("rerun:    {} ({} rows in {} chunks)", args.viz.describe(), stats.rows, stats.chunks);
    }
    Ok(ExitCode::SUCCESS)
}
