//! Errors of the filter.

/// What can go wrong feeding the filter.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum SlamError {
    /// A parameter is outside its domain.
    #[error("bad parameter: {0}")]
    BadParams(#[from] crate::params::ParamError),
    /// The laser's mount pose is not finite.
    #[error("laser offset is not finite")]
    BadLaserOffset,
    /// An odometry reading has a non-finite stamp or pose, or a pose implausibly far away.
    #[error("bad odometry at t = {stamp}: {message}")]
    BadOdometry {
        /// Stamp of the reading.
        stamp: f64,
        /// What is wrong.
        message: String,
    },
    /// A scan's geometry (stamp, angles, range limits) is not usable.
    #[error("bad scan at t = {stamp}: {message}")]
    BadScan {
        /// Stamp of the scan.
        stamp: f64,
        /// What is wrong.
        message: String,
    },
    /// A reading is older than the previous one.
    #[error("time went backwards: {what} stamp {got} is before the previous {previous}")]
    TimeWentBackwards {
        /// "odometry" or "scan".
        what: &'static str,
        /// Previous stamp, seconds.
        previous: f64,
        /// Offending stamp, seconds.
        got: f64,
    },
    /// The map would outgrow the size limit (poses far from the start).
    #[error("map too large: {0}")]
    MapTooLarge(String),
}
