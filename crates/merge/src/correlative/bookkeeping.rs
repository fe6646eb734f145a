//! What every stage of the search shares: timings, failures, and the map over candidates on rayon's threads.

use crate::alignment::{Evidence, NoAlignment};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// `f` over `items` in order, on rayon or on this thread, each worker with its own scratch `S`.
pub(super) fn map_with_scratch<T: Sync, S: Default, R: Send>(
    parallel: bool,
    items: &[T],
    f: impl Fn(&mut S, &T) -> R + Sync + Send,
) -> Vec<R> {
    if parallel {
        items.par_iter().map_init(S::default, f).collect()
    } else {
        let mut scratch = S::default();
        items.iter().map(|x| f(&mut scratch, x)).collect()
    }
}

/// Fills in a failure.
pub(super) fn fail(reason: String, timings: BTreeMap<String, f64>) -> Box<NoAlignment> {
    Box::new(NoAlignment { reason, matches: 0, timings_ms: timings, evidence: Evidence::default() })
}
