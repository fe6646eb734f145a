//! The merge algorithms by name: the one list scenario files, studies and the command line accept.

use std::fmt;
use std::str::FromStr;

/// A map-merging algorithm of this crate, named as reports, scenario files and the command line name it.
///
/// ```
/// use mrslam_merge::Algorithm;
/// let a: Algorithm = "rmap".parse().unwrap();
/// assert_eq!(a, Algorithm::Rmap);
/// assert_eq!(a.to_string(), "rmap");
/// assert!("magic".parse::<Algorithm>().unwrap_err().to_string().contains("sift, rmap, correlative, cascade"));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algorithm {
    /// `sift`: the paper's SIFT merger (Algorithm 3), [`crate::SiftMerger`].
    Sift,
    /// `rmap`: Park's R-map baseline (Algorithm 1), [`crate::RmapMerger`].
    Rmap,
    /// `correlative`: global correlative search by branch and bound, [`crate::CorrelativeMerger`].
    Correlative,
    /// `cascade`: `sift`, then `sift` with boundary walls, then `correlative`, the first the gate accepts,
    /// [`crate::Cascade`].
    Cascade,
}

impl Algorithm {
    /// Every algorithm, in the order they are listed and compared.
    pub const ALL: [Algorithm; 4] = [Algorithm::Sift, Algorithm::Rmap, Algorithm::Correlative, Algorithm::Cascade];

    /// The name (`sift`, `rmap`, `correlative`, `cascade`): what [`FromStr`] reads, [`Display`](fmt::Display) writes and
    /// [`crate::Merger::name`] returns.
    pub const fn name(self) -> &'static str {
        match self {
            Algorithm::Sift => "sift",
            Algorithm::Rmap => "rmap",
            Algorithm::Correlative => "correlative",
            Algorithm::Cascade => "cascade",
        }
    }

    /// The names of [`Algorithm::ALL`], comma-separated: `sift, rmap, correlative, cascade`.
    pub fn names() -> String {
        Algorithm::ALL.map(Algorithm::name).join(", ")
    }
}

impl fmt::Display for Algorithm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl AsRef<str> for Algorithm {
    fn as_ref(&self) -> &str {
        self.name()
    }
}

/// A name that is not one of [`Algorithm::ALL`]; its message lists the valid names.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown algorithm `{0}` (expected one of {names})", names = Algorithm::names())]
pub struct UnknownAlgorithm(pub String);

impl FromStr for Algorithm {
    type Err = UnknownAlgorithm;
    fn from_str(s: &str) -> Result<Self, UnknownAlgorithm> {
        Algorithm::ALL.into_iter().find(|a| a.name() == s).ok_or_else(|| UnknownAlgorithm(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_list_the_valid_ones() {
        for a in Algorithm::ALL {
            assert_eq!(a.to_string().parse::<Algorithm>(), Ok(a));
        }
        assert_eq!(Algorithm::names(), "sift, rmap, correlative, cascade");
        assert_eq!(
            "SIFT".parse::<Algorithm>().unwrap_err().to_string(),
            "unknown algorithm `SIFT` (expected one of sift, rmap, correlative, cascade)"
        );
    }
}
