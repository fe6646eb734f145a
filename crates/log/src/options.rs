//! How a log is read: where each scan's odometry comes from, and the bounds of the repairs.

/// Where each scan's odometry comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OdometrySource {
    /// The odometry stream interpolated at the scan's stamp where two readings bracket it; the scan's own
    /// odometry elsewhere (and in logs without an odometry stream), and everywhere when the stream is stamped
    /// in bursts (see [`crate::repair::odometry_at_scans`]). The default: a CARMEN scan line's odometry fields
    /// hold whichever ODOM message arrived last, up to one odometry period away from the scan.
    #[default]
    Interpolated,
    /// The odometry logged with the scan itself (CARMEN: FLASER/RLASER `odom_*`, ROBOTLASER1 robot pose), as
    /// GMapping's log reader takes it.
    Line,
}

impl std::str::FromStr for OdometrySource {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "interpolated" => Ok(OdometrySource::Interpolated),
            "line" => Ok(OdometrySource::Line),
            _ => Err(format!("unknown odometry source '{s}' (expected interpolated or line)")),
        }
    }
}

impl std::fmt::Display for OdometrySource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            OdometrySource::Interpolated => "interpolated",
            OdometrySource::Line => "line",
        })
    }
}

/// Which topics and frame a recorded bag's scans and odometry come from; `None` picks the one candidate
/// the bag has (and refuses a bag with several, naming them). CARMEN logs ignore it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TopicChoice {
    /// The `sensor_msgs/LaserScan` topic of the scans (`--scan`).
    pub scan: Option<String>,
    /// The `nav_msgs/Odometry` topic of the odometry (`--odom`); without one, odometry comes from `/tf`.
    pub odom: Option<String>,
    /// The robot's frame (`--base-frame`): odometry from `/tf` is the transform from the odometry frame to
    /// it, and the laser's mount is its transform to the scan's frame in `/tf_static`.
    pub base_frame: Option<String>,
}

/// How a log is read.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadOptions {
    /// Where each scan's odometry comes from.
    pub odometry: OdometrySource,
    /// A sensor reading stamped more than this many seconds before a sensor reading above it is refused.
    ///
    /// Real logs interleave sensors by arrival, so stamps step back by up to about one second (the
    /// Radish logs: up to 0.9 s); a step of many seconds means two logs concatenated or a clock reset,
    /// which reordering would silently scramble.
    pub max_step_back: f64,
    /// Repair odometry increments that report driving backwards (`tv` < 0) but move the pose forwards: some
    /// robots' odometry integrates the speed's magnitude, so reversing reads as driving ahead. Counted in
    /// [`Repairs::reversed_increments`](crate::Repairs::reversed_increments).
    pub repair_reversing: bool,
    /// Seconds by which each scan was taken before its stamp: odometry is interpolated at the stamp minus
    /// this (0: at the stamp). Only with [`OdometrySource::Interpolated`].
    pub scan_latency: f64,
    /// Longest line a text log may have, bytes ([`MAX_LINE_BYTES`]): a longer one (a device, a binary file)
    /// is refused before it fills memory.
    pub max_line_bytes: usize,
    /// Most bytes a log may hold once decompressed ([`MAX_LOG_BYTES`]; a bag: its messages' bytes): a larger
    /// one (an endless device, a gzip bomb, a bag of chunks that decompress to more) is refused when it
    /// passes the bound, before it exhausts memory.
    pub max_bytes: u64,
    /// The topics and frame of a recorded bag.
    pub topics: TopicChoice,
}

/// The default bound on stamps stepping back, seconds ([`ReadOptions::max_step_back`]).
pub const MAX_STEP_BACK: f64 = 5.0;

/// The default longest line of a text log, bytes: 1 MiB ([`ReadOptions::max_line_bytes`]). A CARMEN
/// ROBOTLASER1 line of a 1081-beam laser with remissions is about 20 KB.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// The default bound on a log's decompressed size, bytes: 2 GiB ([`ReadOptions::max_bytes`]). The largest
/// benchmark logs are under 200 MB.
pub const MAX_LOG_BYTES: u64 = 2 << 30;

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            odometry: OdometrySource::Interpolated,
            max_step_back: MAX_STEP_BACK,
            repair_reversing: true,
            scan_latency: 0.0,
            max_line_bytes: MAX_LINE_BYTES,
            max_bytes: MAX_LOG_BYTES,
            topics: TopicChoice::default(),
        }
    }
}
