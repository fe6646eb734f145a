//! `mrslam log info`: what a CARMEN laser log holds.

use anyhow::Result;
use clap::Subcommand;
use mrslam_core::CarmenLog;
use std::path::PathBuf;
use std::process::ExitCode;

/// Log subcommands.
#[derive(Subcommand)]
pub enum LogCommand {
    /// Print the scans, odometry readings, laser geometry and skipped lines of a CARMEN log (.gz ok).
    Info {
        /// CARMEN log file (plain or gzipped).
        log: PathBuf,
    },
}

/// Runs a log subcommand.
pub fn run(cmd: LogCommand) -> Result<ExitCode> {
    match cmd {
        LogCommand::Info { log } => {
            let parsed = CarmenLog::read(&log)?;
            println!("log:       {}", log.display());
            println!("scans:     {}", parsed.scans.len());
            if let (Some(first), Some(last)) = (parsed.scans.first(), parsed.scans.last()) {
                let s = &first.scan;
                println!(
                    "time:      {:.3} s to {:.3} s ({:.1} s)",
                    s.stamp,
                    last.scan.stamp,
                    last.scan.stamp - s.stamp
                );
                println!(
                    "laser:     {} beams from {:.2} deg every {:.3} deg, range {}..{} m",
                    s.len(),
                    s.angle_min.to_degrees(),
                    s.angle_increment.to_degrees(),
                    s.range_min,
                    s.range_max
                );
            }
            println!("odometry:  {} ODOM lines", parsed.odometry.len());
            println!("params:    {}", parsed.params.len());
            let skipped: Vec<String> = parsed.skipped.iter().map(|(k, n)| format!("{n} {k}")).collect();
            println!("skipped:   {}", if skipped.is_empty() { "none".to_string() } else { skipped.join(", ") });
        }
    }
    Ok(ExitCode::SUCCESS)
}
