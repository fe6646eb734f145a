//! One module per subcommand.

pub mod args;
pub mod eval;
pub mod features;
pub mod interrupt;
pub mod log;
pub mod map;
pub mod merge;
pub mod merge_many;
pub mod merger_args;
pub mod outputs;
pub mod paths;
pub mod replay_plot;
pub mod run;
pub mod run_bag;
pub mod run_folder;
pub mod sim;
pub mod sim_log;
pub mod sim_progress;
pub mod slam;
pub mod slam_eta;
pub mod study;
pub mod viz;
pub mod world;

pub use outputs::{Outputs, kind};

/// The process's peak resident memory, bytes (Linux: VmHWM of /proc/self/status; `None` elsewhere).
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}
