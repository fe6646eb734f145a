//! Descriptor matching: nearest neighbour in descriptor space with Lowe's ratio test (paper Alg. 3, line 6).

use mrslam_sift::{DESCRIPTOR_LEN, Features};
use rayon::prelude::*;

/// A correspondence between feature `a` of the first set and feature `b` of the second.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Match {
    /// Index in the first feature set.
    pub a: usize,
    /// Index in the second feature set.
    pub b: usize,
    /// Euclidean descriptor distance.
    pub distance: f32,
}

/// Matching parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MatchParams {
    /// Lowe's ratio: keep a match when nearest < ratio × second nearest (Lowe 2004 uses 0.8; 0.75 here).
    pub ratio: f32,
    /// Keep only matches that are also the nearest neighbour in the other direction.
    pub mutual: bool,
    /// Spread the queries over threads.
    pub parallel: bool,
    /// Candidates kept per feature: 1 is Lowe's nearest neighbour with the ratio test (the paper); k > 1
    /// keeps the k nearest neighbours without it and leaves the choice to geometric consensus.
    ///
    /// Maps drawn by different lidars give the same corner different descriptors: on the paper corridor the
    /// true partner is the nearest for few keypoints but among the four nearest for half of them.
    #[serde(default = "one")]
    pub candidates: usize,
}

fn one() -> usize {
    1
}

impl Default for MatchParams {
    fn default() -> Self {
        MatchParams { ratio: 0.75, mutual: false, parallel: false, candidates: 1 }
    }
}

#[inline(always)]
fn dist2(a: &[u8], b: &[u8]) -> u32 {
    // Exact integer distance; the compiler vectorises this fixed-length loop (16-bit differences, their
    // squares summed pairwise into 32 bits).
    let (a, b): (&[u8; DESCRIPTOR_LEN], &[u8; DESCRIPTOR_LEN]) =
        (a.try_into().expect("a descriptor"), b.try_into().expect("a descriptor"));
    let mut s = 0i32;
    for k in 0..DESCRIPTOR_LEN {
        let d = a[k] as i16 - b[k] as i16;
        s += d as i32 * d as i32;
    }
    s as u32
}

mrslam_sift::cpu_dispatch! {
    /// Nearest and second-nearest squared distances from `q` to the descriptors of `set`, with the nearest index.
    fn two_nearest(q: &[u8], set: &[u8]) -> (usize, u32, u32);
    "avx2" => two_nearest_avx2 => two_nearest_impl(q, set);
    _ => two_nearest_impl(q, set)
}

#[inline(always)]
fn two_nearest_impl(q: &[u8], set: &[u8]) -> (usize, u32, u32) {
    let (mut bi, mut b1, mut b2) = (usize::MAX, u32::MAX, u32::MAX);
    for (i, d) in set.chunks_exact(DESCRIPTOR_LEN).enumerate() {
        let s = dist2(q, d);
        if s < b1 {
            b2 = b1;
            b1 = s;
            bi = i;
        } else if s < b2 {
            b2 = s;
        }
    }
    (bi, b1, b2)
}

mrslam_sift::cpu_dispatch! {
    /// The `k` nearest descriptors of `set` to `q` as (index, squared distance), nearest first.
    fn k_nearest(q: &[u8], set: &[u8], k: usize, out: &mut Vec<(usize, u32)>);
    "avx2" => k_nearest_avx2 => k_nearest_impl(q, set, k, out);
    _ => k_nearest_impl(q, set, k, out)
}

#[inline(always)]
fn k_nearest_impl(q: &[u8], set: &[u8], k: usize, out: &mut Vec<(usize, u32)>) {
    out.clear();
    for (i, d) in set.chunks_exact(DESCRIPTOR_LEN).enumerate() {
        let s = dist2(q, d);
        if out.len() < k || s < out[out.len() - 1].1 {
            let at = out.partition_point(|&(_, e)| e <= s);
            out.insert(at, (i, s));
            out.truncate(k);
        }
    }
}

/// Matches every feature of `a` to its nearest neighbour in `b` that passes the ratio test, or, with
/// `candidates` > 1, to its k nearest neighbours.
///
/// Results are ordered by index in `a` (then by distance), so they do not depend on thread scheduling.
/// Public (through the crate's `dev` module) only for the tests, benches and development probes.
pub fn match_features(a: &Features, b: &Features, p: &MatchParams) -> Vec<Match> {
    if a.is_empty() || b.len() < 2 {
        return Vec::new();
    }
    if p.candidates > 1 {
        let query = |i: usize| -> Vec<Match> {
            let mut near = Vec::with_capacity(p.candidates + 1);
            k_nearest(a.descriptor(i), &b.descriptors, p.candidates, &mut near);
            near.iter().map(|&(j, d)| Match { a: i, b: j, distance: (d as f32).sqrt() }).collect()
        };
        return if p.parallel {
            (0..a.len()).into_par_iter().flat_map_iter(query).collect()
        } else {
            (0..a.len()).flat_map(query).collect()
        };
    }
    let ratio2 = (p.ratio as f64).powi(2);
    let query = |i: usize| -> Option<Match> {
        let (j, d1, d2) = two_nearest(a.descriptor(i), &b.descriptors);
        ((d1 as f64) < ratio2 * d2 as f64).then_some(Match { a: i, b: j, distance: (d1 as f32).sqrt() })
    };
    let mut matches: Vec<Match> = if p.parallel {
        (0..a.len()).into_par_iter().filter_map(query).collect()
    } else {
        (0..a.len()).filter_map(query).collect()
    };
    if p.mutual {
        matches.retain(|m| two_nearest(b.descriptor(m.b), &a.descriptors).0 == m.a);
    }
    matches
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_sift::Keypoint;

    fn features(descs: &[[u8; 4]]) -> Features {
        let mut f = Features::default();
        for d in descs {
            f.keypoints.push(Keypoint { x: 0.0, y: 0.0, size: 1.0, angle: 0.0, response: 1.0, octave: 0 });
            let mut full = [0u8; DESCRIPTOR_LEN];
            full[..4].copy_from_slice(d);
            f.descriptors.extend_from_slice(&full);
        }
        f
    }

    #[test]
    fn ratio_test_drops_ambiguous_matches() {
        let a = features(&[[10, 0, 0, 0], [0, 50, 0, 0]]);
        let b = features(&[[0, 50, 1, 0], [11, 0, 0, 0], [0, 51, 0, 0]]);
        let m = match_features(&a, &b, &MatchParams::default());
        // a0 -> b1 clearly; a1 is equally near b0 and b2: ambiguous, dropped
        assert_eq!(m.len(), 1);
        assert_eq!((m[0].a, m[0].b), (0, 1));
        assert!((m[0].distance - 1.0).abs() < 1e-6);
    }

    #[test]
    fn mutual_check_and_parallel_agree() {
        let a = features(&[[10, 0, 0, 0], [200, 0, 0, 0], [0, 90, 0, 0]]);
        let b = features(&[[12, 0, 0, 0], [0, 90, 0, 0], [100, 100, 100, 100]]);
        let p = MatchParams { ratio: 0.9, mutual: true, ..Default::default() };
        let serial = match_features(&a, &b, &p);
        let par = match_features(&a, &b, &MatchParams { parallel: true, ..p });
        assert_eq!(serial, par);
        assert!(serial.iter().all(|m| (m.a, m.b) == (0, 0) || (m.a, m.b) == (2, 1)));
    }

    #[test]
    fn k_candidates_are_the_k_nearest_in_order() {
        let a = features(&[[10, 0, 0, 0], [0, 50, 0, 0]]);
        let b = features(&[[0, 50, 1, 0], [11, 0, 0, 0], [0, 51, 0, 0], [40, 0, 0, 0]]);
        let p = MatchParams { candidates: 2, ..Default::default() };
        let m: Vec<(usize, usize)> = match_features(&a, &b, &p).iter().map(|m| (m.a, m.b)).collect();
        // a1 keeps both of its equally near partners, which the ratio test would drop
        assert_eq!(m, vec![(0, 1), (0, 3), (1, 0), (1, 2)]);
        assert_eq!(match_features(&a, &b, &MatchParams { parallel: true, ..p }).len(), 4);
    }
}
