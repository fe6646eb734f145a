//! Information matrices of (x, y, θ) estimates, stored as their upper triangle.

use nalgebra::{Matrix3, Vector3};
use std::ops::{Index, IndexMut};

/// The information (inverse covariance) of an (x, y, θ) estimate: the upper triangle of the symmetric 3x3
/// matrix, entries 00 01 02 11 12 22 (indexable as `info[k]`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Information(pub [f64; 6]);

impl Information {
    /// No information at all.
    pub const ZERO: Information = Information([0.0; 6]);

    /// Independent errors: `sigma` metres along x and along y, `heading_sigma` radians in θ.
    pub fn from_sigmas(sigma: f64, heading_sigma: f64) -> Self {
        let (i, h) = (1.0 / (sigma * sigma), 1.0 / (heading_sigma * heading_sigma));
        Information([i, 0.0, 0.0, i, 0.0, h])
    }

    /// The upper triangle of the symmetric matrix `m`.
    pub fn from_matrix(m: &Matrix3<f64>) -> Self {
        Information([m[(0, 0)], m[(0, 1)], m[(0, 2)], m[(1, 1)], m[(1, 2)], m[(2, 2)]])
    }

    /// The full symmetric 3x3 matrix.
    pub fn matrix(&self) -> Matrix3<f64> {
        let h = &self.0;
        Matrix3::new(h[0], h[1], h[2], h[1], h[3], h[4], h[2], h[4], h[5])
    }

    /// eᵀ Ω e: the squared Mahalanobis distance of the error `err`.
    pub fn mahalanobis2(&self, err: &[f64; 3]) -> f64 {
        let e = Vector3::from(*err);
        e.dot(&(self.matrix() * e))
    }
}

impl Index<usize> for Information {
    type Output = f64;
    fn index(&self, k: usize) -> &f64 {
        &self.0[k]
    }
}

impl IndexMut<usize> for Information {
    fn index_mut(&mut self, k: usize) -> &mut f64 {
        &mut self.0[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_upper_triangle_round_trips_through_the_full_matrix() {
        let h = Information([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let m = h.matrix();
        assert_eq!(m, m.transpose());
        assert_eq!(Information::from_matrix(&m), h);
        assert_eq!(h.mahalanobis2(&[1.0, 0.0, 0.0]), 1.0);
        assert_eq!(h.mahalanobis2(&[0.0, 1.0, 1.0]), 4.0 + 2.0 * 5.0 + 6.0);
    }
}
