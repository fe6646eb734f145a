//! A run's coverage samples resampled onto the study's common time grid, so that runs of different lengths
//! average point by point.

/// The number of grid points from 0 to `duration` seconds, `step` apart (both ends included when `duration` is
/// a whole number of steps).
pub fn grid_len(duration: f64, step: f64) -> usize {
    (duration / step + 1e-6).floor() as usize + 1
}

/// The coverage at t = 0, `step`, 2 `step`, … (`len` points) of a run sampled at `samples` ((time s, share),
/// oldest first): at each grid time, the last sample at or before it (`tolerance` seconds of slack for the
/// simulator's clock), 0 before the first sample, and the last sample's share after the run ended. A run ends
/// when the exploration is over (or at the duration), so the map it ended with is the map from then on.
pub fn resample(samples: &[[f64; 2]], step: f64, len: usize, tolerance: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(len);
    let mut next = 0;
    let mut current = 0.0;
    for k in 0..len {
        let t = k as f64 * step;
        while next < samples.len() && samples[next][0] <= t + tolerance {
            current = samples[next][1];
            next += 1;
        }
        out.push(current);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_held_until_the_next_and_after_the_end() {
        assert_eq!(grid_len(10.0, 2.0), 6);
        assert_eq!(grid_len(9.0, 2.0), 5);
        assert_eq!(grid_len(0.3 * 3.0, 0.3), 4);
        // Samples slightly after the grid times (the simulator's clock), one missing, the run over at 6 s.
        let samples = [[0.000_000_1, 0.1], [2.000_000_1, 0.3], [5.0, 0.6], [6.0, 0.7]];
        assert_eq!(resample(&samples, 2.0, 6, 0.005), [0.1, 0.3, 0.3, 0.7, 0.7, 0.7]);
        assert_eq!(resample(&[], 2.0, 3, 0.005), [0.0, 0.0, 0.0]);
        assert_eq!(resample(&[[3.0, 0.5]], 2.0, 3, 0.005), [0.0, 0.0, 0.5]);
    }
}
