//! What can go wrong when recording or reading a recording.

use std::path::PathBuf;

/// A visualisation error; every variant names the file or address at fault.
#[derive(Debug, thiserror::Error)]
pub enum VizError {
    /// The `.rrd` file cannot be created (missing folder, no permission, a folder in the way, ...).
    #[error("{path}: cannot write the recording: {cause}")]
    CreateFile {
        /// The file asked for.
        path: PathBuf,
        /// Why not.
        cause: String,
    },
    /// `--spawn` was asked for but no `rerun` viewer is on PATH.
    #[error(
        "--spawn: no `rerun` viewer on PATH; install it with `pip install rerun-sdk==0.36.3`, \
         or record to a file with --rrd FILE and open that later"
    )]
    NoViewer,
    /// `--connect`: nothing answers at the address.
    #[error(
        "--connect {addr}: no rerun viewer answers there ({cause}); start one with `rerun`, or use --spawn or \
         --rrd FILE"
    )]
    NoViewerAt {
        /// The address given.
        addr: String,
        /// What the connection attempt said.
        cause: String,
    },
    /// The viewer could not be started.
    #[error("--spawn: cannot start the rerun viewer: {0}")]
    Spawn(String),
    /// A `--connect` address that is neither HOST:PORT nor a `rerun+http://HOST:PORT/proxy` URL.
    #[error("--connect {addr}: not a viewer address ({why}); expected HOST:PORT or rerun+http://HOST:PORT/proxy")]
    BadAddress {
        /// The address given.
        addr: String,
        /// What is wrong with it.
        why: String,
    },
    /// Data could not be turned into a rerun chunk (a bug, not bad input).
    #[error("recording `{entity}`: {cause}")]
    Encode {
        /// Entity path being logged.
        entity: String,
        /// What rerun said.
        cause: String,
    },
    /// Pending data could not be written out when the recording was closed.
    #[error("{target}: flushing the recording failed: {cause}")]
    Flush {
        /// File or address.
        target: String,
        /// What rerun said.
        cause: String,
    },
    /// A recording file could not be read back.
    #[error("{path}: cannot read the recording: {cause}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why not.
        cause: String,
    },
}
