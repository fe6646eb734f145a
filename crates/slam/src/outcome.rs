//! What processing a reading did, and the running totals over all readings.

/// Why a scan was not processed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SkipReason {
    /// The robot has not moved (or waited) enough since the last processed scan; its odometry still moved
    /// the particles.
    NotMoved,
    /// The scan has no beams; its odometry still moved the particles.
    EmptyScan,
}

/// Statistics of one processed scan.
#[derive(Debug, Clone, PartialEq)]
pub struct UpdateStats {
    /// Neff of the weights computed at this update (the value the resampling decision was made on).
    pub neff: f64,
    /// Whether the particles were resampled.
    pub resampled: bool,
    /// Particles whose scan-matched pose replaced the motion-model pose (score > minimum_score).
    pub matched_particles: usize,
    /// Mean matcher score over particles.
    pub mean_score: f64,
    /// Beams the matcher used.
    pub beams_matched: usize,
    /// Beams recorded as hits.
    pub beams_mapped: usize,
    /// Beams ignored as invalid (NaN, negative, below the sensor's minimum range).
    pub invalid_beams: usize,
    /// Index of the best particle after the update.
    pub best: usize,
}

/// What [`crate::Rbpf::process`] (or any [`crate::SlamBackend::process`]) did with a reading.
#[derive(Debug, Clone, PartialEq)]
pub enum UpdateOutcome {
    /// The scan was matched and mapped.
    Processed(UpdateStats),
    /// The scan was not processed (odometry still applied).
    Skipped(SkipReason),
}

impl UpdateOutcome {
    /// True when the scan was processed.
    pub fn is_processed(&self) -> bool {
        matches!(self, UpdateOutcome::Processed(_))
    }
    /// Neff of the update, when processed.
    pub fn neff(&self) -> Option<f64> {
        match self {
            UpdateOutcome::Processed(s) => Some(s.neff),
            UpdateOutcome::Skipped(_) => None,
        }
    }
    /// True when the update resampled.
    pub fn resampled(&self) -> bool {
        matches!(self, UpdateOutcome::Processed(s) if s.resampled)
    }
}

/// Running totals over all readings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Counters {
    /// Readings given to [`crate::Rbpf::process`] and accepted.
    pub readings: usize,
    /// Scans processed.
    pub processed: usize,
    /// Scans skipped because the robot had not moved enough.
    pub skipped_not_moved: usize,
    /// Scans skipped because they had no beams.
    pub skipped_empty: usize,
    /// Beams ignored as invalid (NaN, negative, below range_min), over all readings.
    pub invalid_beams: usize,
    /// Resampling steps.
    pub resamples: usize,
    /// Times the particles were re-anchored on the online loop-closure graph (their maps redrawn from it).
    pub reanchors: usize,
}
