//! `mrslam`: the command-line front end of the multi-robot SLAM and map-merging testbed.
//!
//! A thin layer: argument parsing, progress, summaries and exit codes. The algorithms live in the
//! library crates under `crates/`.

mod cmd;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::process::ExitCode;

/// The exit codes, shown under `--help` (README.md has the same table).
const EXIT_CODES: &str = "\
Exit codes:
  0  success
  1  failure or bad input: a file, a value or the command line itself (the message names the file, line
     and field, or the flag)
  2  `mrslam merge` only: the merge was refused (no reliable transform); no merged map is written. With three
     or more maps: some map could not be placed in the first map's frame (no chain of accepted pairs joins
     them); the maps that could are merged and written
  130  `mrslam run`, `slam`, `sim log`: interrupted (Ctrl-C; SIGTERM exits 143, SIGHUP 129): the outputs are as
       before the command, its hidden temporary files removed";

/// Multi-robot SLAM and map merging testbed: simulate, map, merge, evaluate.
#[derive(Parser)]
#[command(name = "mrslam", version, about, long_about = None, propagate_version = true, after_help = EXIT_CODES)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Inspect and convert ROS map_server maps.
    #[command(subcommand)]
    Map(cmd::map::MapCommand),
    /// Detect SIFT keypoints in an image or a map; print, save as JSON, draw.
    Features(cmd::features::FeaturesArgs),
    /// Merge two or more maps of unknown relative pose (exit 2 when a map cannot be placed).
    Merge(cmd::merge::MergeArgs),
    /// Inspect laser logs (CARMEN, ROS 1 and ROS 2 bags).
    #[command(subcommand)]
    Log(cmd::log::LogCommand),
    /// Evaluate results: a trajectory against benchmark relations.
    #[command(subcommand)]
    Eval(cmd::eval::EvalCommand),
    /// Run a scenario end to end: simulate both robots, map, merge, evaluate against truth.
    Run(cmd::run::RunArgs),
    /// Map a laser log (CARMEN or a ROS bag) with GMapping-style particle filter SLAM.
    Slam(cmd::slam::SlamArgs),
    /// The simulator: replay a real log in a world; write a simulated run as a log with its truth.
    #[command(subcommand)]
    Sim(cmd::sim::SimCommand),
    /// Simulated worlds: make one from a map.
    #[command(subcommand)]
    World(cmd::world::WorldCommand),
    /// Studies: many seeded merge trials across overlaps, or team runs across robots, ranges and coordinations;
    /// rates and means with intervals, plots, shards.
    #[command(subcommand)]
    Study(cmd::study::StudyCommand),
}

/// A closed pipe (`mrslam ... | head`) ends the process as it ends other Unix tools, by SIGPIPE, instead of a
/// panic at the next print (Rust ignores SIGPIPE, so `println!` would meet EPIPE). Outputs are written under
/// temporary names and renamed when complete, so a run ended this way leaves nothing that looks complete.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any other thread exists; SIG_DFL is a valid disposition for
    // SIGPIPE and no Rust code relies on SIGPIPE being ignored here.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// The command line, every flag's value allowed to be a negative number: `--seed -1` or `--max-shift -5` is
/// then refused by the flag's own type or range check, not by clap's advice to write `-- -1`.
fn command() -> clap::Command {
    fn negatives(cmd: clap::Command) -> clap::Command {
        cmd.mut_args(|a| if a.get_action().takes_values() { a.allow_negative_numbers(true) } else { a })
            .mut_subcommands(negatives)
    }
    negatives(Cli::command())
}

fn main() -> ExitCode {
    restore_sigpipe();
    let cli = match command().try_get_matches().and_then(|m| Cli::from_arg_matches(&m)) {
        Ok(cli) => cli,
        Err(e) => {
            // clap exits 2 on a usage error; 2 is reserved for a refused merge, so usage errors exit 1.
            let _ = e.print();
            return if e.use_stderr() { ExitCode::from(1) } else { ExitCode::SUCCESS };
        }
    };
    let result = match cli.command {
        Command::Map(c) => cmd::map::run(c),
        Command::World(c) => cmd::world::run(c),
        Command::Sim(c) => cmd::sim::run(c),
        Command::Log(c) => cmd::log::run(c),
        Command::Eval(c) => cmd::eval::run(c),
        Command::Merge(a) => cmd::merge::run(a),
        Command::Features(a) => cmd::features::run(a),
        Command::Slam(a) => cmd::slam::run(a),
        Command::Run(a) => cmd::run::run(a),
        Command::Study(c) => cmd::study::run(c),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}
