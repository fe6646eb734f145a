//! Compares two rerun recordings message by message: exit 0 when they hold the same messages, 1 with the first
//! difference printed when not, 2 when a file cannot be read.
//!
//! `cargo run -p mrslam-dev --bin rrd_diff -- A.rrd B.rrd` (used by `dev/scripts/same_behaviour.py compare`).

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [a, b] = args.as_slice() else {
        eprintln!("usage: rrd_diff A.rrd B.rrd");
        return ExitCode::from(2);
    };
    match mrslam_viz::inspect::first_difference(a, b) {
        Ok(None) => ExitCode::SUCCESS,
        Ok(Some(diff)) => {
            println!("{diff}");
            ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("{e}");
            ExitCode::from(2)
        }
    }
}
