//! Splitting one study across processes: shard K of N runs the trials whose index is K modulo N.

use super::StudyError;

/// One shard of a study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 0-based.
    pub index: usize,
    /// Shards in all.
    pub count: usize,
}

impl Default for Shard {
    fn default() -> Self {
        Shard::ALL
    }
}

impl Shard {
    /// The whole study in one process.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// A shard, checked: `count` ≥ 1 and `index` < `count`.
    pub fn new(index: usize, count: usize) -> Result<Shard, StudyError> {
        if count == 0 {
            return Err(StudyError::Invalid(format!("shard {index}/{count}: the shard count must be at least 1")));
        }
        if index >= count {
            return Err(StudyError::Invalid(format!(
                "shard {index}/{count}: the shard index must lie in 0..{count} (0-based)"
            )));
        }
        Ok(Shard { index, count })
    }

    /// Parses `K/N`.
    pub fn parse(s: &str) -> Result<Shard, StudyError> {
        let bad = || StudyError::Invalid(format!("shard `{s}`: expected K/N with 0 <= K < N, e.g. 3/16"));
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let k = k.trim().parse().map_err(|_| bad())?;
        let n = n.trim().parse().map_err(|_| bad())?;
        Shard::new(k, n)
    }

    /// The shard a Slurm job array gives this process (`SLURM_ARRAY_TASK_ID` of `SLURM_ARRAY_TASK_COUNT`),
    /// when both are set.
    pub fn from_slurm(get: impl Fn(&str) -> Option<String>) -> Result<Option<Shard>, StudyError> {
        match (get("SLURM_ARRAY_TASK_ID"), get("SLURM_ARRAY_TASK_COUNT")) {
            (Some(k), Some(n)) => {
                let bad = |v: &str, name: &str| StudyError::Invalid(format!("{name}={v}: not a whole number"));
                let k = k.trim().parse().map_err(|_| bad(&k, "SLURM_ARRAY_TASK_ID"))?;
                let n = n.trim().parse().map_err(|_| bad(&n, "SLURM_ARRAY_TASK_COUNT"))?;
                Shard::new(k, n).map(Some)
            }
            _ => Ok(None),
        }
    }

    /// Whether this shard runs trial `trial`.
    pub fn selects(&self, trial: usize) -> bool {
        trial % self.count == self.index
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_trials() {
        let shards: Vec<Shard> = (0..3).map(|k| Shard::new(k, 3).unwrap()).collect();
        for t in 0..100 {
            assert_eq!(shards.iter().filter(|s| s.selects(t)).count(), 1);
        }
        assert!(Shard::ALL.selects(17));
        assert!(Shard::parse("1/3").unwrap().selects(4));
        assert!(!Shard::parse("1/3").unwrap().selects(5));
    }

    #[test]
    fn bad_shards_are_refused() {
        for s in ["3/2", "2/2", "0/0", "1", "a/b", "-1/2"] {
            assert!(Shard::parse(s).is_err(), "{s}");
        }
        assert!(Shard::parse("3/2").unwrap_err().to_string().contains("0..2"));
    }

    #[test]
    fn slurm_variables() {
        let env = |id: &'static str, n: &'static str| {
            move |k: &str| match k {
                "SLURM_ARRAY_TASK_ID" => Some(id.to_string()),
                "SLURM_ARRAY_TASK_COUNT" => Some(n.to_string()),
                _ => None,
            }
        };
        assert_eq!(Shard::from_slurm(env("5", "16")).unwrap(), Some(Shard { index: 5, count: 16 }));
        assert!(Shard::from_slurm(env("16", "16")).is_err());
        assert_eq!(Shard::from_slurm(|_| None).unwrap(), None);
    }
}
