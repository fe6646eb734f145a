//! What a recorded bag holds and which of its topics and frames a read used, for `log info` and summaries.

/// One topic of a bag: its type and how many messages it has when.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicSummary {
    /// The topic's name, e.g. `/scan`.
    pub name: String,
    /// Its message type as the bag names it (`sensor_msgs/LaserScan`, `sensor_msgs/msg/LaserScan`).
    pub type_name: String,
    /// Number of messages.
    pub count: usize,
    /// Bag time of the first message, seconds.
    pub first: f64,
    /// Bag time of the last message, seconds.
    pub last: f64,
}

impl TopicSummary {
    /// Messages per second over the topic's span (none for fewer than two messages or no span).
    pub fn rate(&self) -> Option<f64> {
        let span = self.last - self.first;
        (self.count > 1 && span > 0.0).then(|| (self.count - 1) as f64 / span)
    }
}

/// A bag's topics and what a read took from them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BagSummary {
    /// The bag's format, e.g. "ROS 1 bag (bz2 chunks)" or "ROS 2 bag (MCAP)".
    pub format: String,
    /// Every topic, by name.
    pub topics: Vec<TopicSummary>,
    /// The topic the scans came from.
    pub scan_topic: String,
    /// Where the odometry came from: "topic /odom (odom -> base_link)" or "/tf: odom -> base_link".
    pub odometry: String,
    /// Where the laser's mount came from: "/tf_static: base_link -> laser" or why it is the identity.
    pub laser_mount: String,
}
