//! The messages of a recorded bag as its reader meets them, in file order: every topic counted, the
//! scan, odometry and TF topics decoded (whatever the bag format), each message with its place.
//!
//! A bag reader streams (one chunk in memory at a time) and hands each message to [`BagMessages::add`];
//! the choice of topics is made once the whole bag is read ([`crate::bag_assemble`]).

use crate::bag_summary::TopicSummary;
use crate::error::LogError;
use crate::ros_msg::{Msg, MsgKind, OdometryMsg, ScanMsg, TransformMsg};
use crate::source::Source;
use crate::{cdr_msg, ros1_msg};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The most beams a scan may have: the bound the CARMEN reader puts on a line's beam count.
pub(crate) const MAX_BEAMS: usize = 100_000;

/// The largest record a bag reader loads (a chunk, compressed or not, or one message), bytes.
pub(crate) const MAX_RECORD_BYTES: usize = 1 << 30;

/// How a bag serializes its messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Wire {
    /// ROS 1 serialization (ROS 1 bags).
    Ros1,
    /// CDR (ROS 2 bags).
    Cdr,
}

/// A decoded message with its place in the bag.
#[derive(Debug, Clone)]
pub(crate) struct Arrived<T> {
    /// Its rank among every decoded message of the bag, in file order.
    pub arrival: usize,
    /// Its topic and index.
    pub source: Source,
    /// The message.
    pub msg: T,
}

/// Every message of a bag, counted by topic; those of the decodable types decoded.
#[derive(Debug)]
pub(crate) struct BagMessages {
    /// The bag's path, for errors.
    pub path: PathBuf,
    /// Each topic's type, count and bag-time span.
    pub topics: BTreeMap<String, TopicSummary>,
    /// Scans by topic.
    pub scans: BTreeMap<String, Vec<Arrived<ScanMsg>>>,
    /// Odometry by topic.
    pub odometry: BTreeMap<String, Vec<Arrived<OdometryMsg>>>,
    /// The transforms of every TF topic but the static ones (`/tf`).
    pub transforms: Vec<Arrived<TransformMsg>>,
    /// The transforms of `/tf_static` (topics named `..._static`).
    pub static_transforms: Vec<TransformMsg>,
    arrivals: usize,
    /// The bytes of every message so far (decompressed), and their bound.
    bytes: u64,
    max_bytes: u64,
}

impl BagMessages {
    /// No messages yet, of the bag at `path`, whose messages may hold `max_bytes` in all
    /// ([`ReadOptions::max_bytes`](crate::ReadOptions::max_bytes)).
    pub(crate) fn new(path: &Path, max_bytes: u64) -> BagMessages {
        BagMessages {
            path: path.to_path_buf(),
            topics: BTreeMap::new(),
            scans: BTreeMap::new(),
            odometry: BTreeMap::new(),
            transforms: Vec::new(),
            static_transforms: Vec::new(),
            arrivals: 0,
            bytes: 0,
            max_bytes,
        }
    }

    /// The next message of the bag in file order: on `topic` of type `type_name`, at bag time
    /// `bag_time_ns` (nanoseconds), serialized as `wire` says.
    pub(crate) fn add(
        &mut self,
        topic: &str,
        type_name: &str,
        wire: Wire,
        bag_time_ns: u64,
        bytes: &[u8],
    ) -> Result<(), LogError> {
        // Bounded here, where every reader's messages arrive decompressed: a bag bomb (small chunks that
        // decompress to many messages) is refused when their bytes pass the bound, before they fill memory.
        self.bytes += bytes.len() as u64;
        if self.bytes > self.max_bytes {
            return Err(LogError::TooLarge { path: self.path.clone(), limit: self.max_bytes, compressed: false });
        }
        let t = bag_time_ns as f64 * 1e-9;
        let summary = self.topics.entry(topic.to_string()).or_insert_with(|| TopicSummary {
            name: topic.to_string(),
            type_name: type_name.to_string(),
            count: 0,
            first: t,
            last: t,
        });
        let index = summary.count;
        summary.count += 1;
        summary.first = summary.first.min(t);
        summary.last = summary.last.max(t);
        let Some(kind) = MsgKind::of(type_name) else { return Ok(()) };
        let source = Source::Message { topic: topic.to_string(), index };
        let err = |message: String| LogError::Record {
            path: self.path.clone(),
            at: source.clone(),
            kind: type_name.to_string(),
            message,
        };
        let msg = match wire {
            Wire::Ros1 => ros1_msg::decode(kind, bytes),
            Wire::Cdr => cdr_msg::decode(kind, bytes),
        }
        .map_err(err)?;
        let arrival = self.arrivals;
        self.arrivals += 1;
        match msg {
            Msg::Scan(scan) => {
                if scan.ranges.len() > MAX_BEAMS {
                    return Err(err(format!("{} beams is implausibly large", scan.ranges.len())));
                }
                self.scans.entry(topic.to_string()).or_default().push(Arrived { arrival, source, msg: scan });
            }
            Msg::Odometry(odometry) => {
                self.odometry.entry(topic.to_string()).or_default().push(Arrived { arrival, source, msg: odometry })
            }
            Msg::Transforms(transforms) if topic.ends_with("_static") => self.static_transforms.extend(transforms),
            Msg::Transforms(transforms) => self.transforms.extend(transforms.into_iter().map(|msg| Arrived {
                arrival,
                source: source.clone(),
                msg,
            })),
        }
        Ok(())
    }

    /// The most bytes the bag's messages may hold ([`ReadOptions::max_bytes`](crate::ReadOptions::max_bytes)).
    pub(crate) fn max_bytes(&self) -> u64 {
        self.max_bytes
    }

    /// An error about this bag.
    pub(crate) fn error(&self, message: String) -> LogError {
        LogError::Bag { path: self.path.clone(), message }
    }
}
