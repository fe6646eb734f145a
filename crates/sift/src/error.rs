//! Errors of the SIFT crate.

use thiserror::Error;

/// What can go wrong when building an image for SIFT.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum SiftError {
    /// The pixel buffer's length is not `width * height`.
    #[error("image data has {got} pixels, expected {width}x{height} = {expected}")]
    DataLength {
        /// Image width in pixels.
        width: usize,
        /// Image height in pixels.
        height: usize,
        /// `width * height`.
        expected: usize,
        /// Length of the buffer given.
        got: usize,
    },
    /// A pixel is NaN or infinite.
    #[error("pixel ({x}, {y}) is not finite")]
    NonFinitePixel {
        /// Column of the first offending pixel.
        x: usize,
        /// Row of the first offending pixel.
        y: usize,
    },
    /// The image is too large to be processed (its doubled size overflows memory addressing).
    #[error("image {width}x{height} is too large")]
    TooLarge {
        /// Image width in pixels.
        width: usize,
        /// Image height in pixels.
        height: usize,
    },
}
