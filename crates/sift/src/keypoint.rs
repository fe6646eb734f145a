//! Keypoints and descriptor sets, in OpenCV's conventions.

/// Bytes per descriptor (4 x 4 cells x 8 orientation bins).
pub const DESCRIPTOR_LEN: usize = 128;

/// A SIFT keypoint, as OpenCV's `cv::KeyPoint`.
///
/// Like OpenCV, positions found with the image doubled (the default) read about +0.25 px too large in x
/// and y: OpenCV's doubling samples with half-pixel centres (doubled pixel `X` lies at input `X/2 - 0.25`)
/// but maps keypoints back by `X/2`. Kept for agreement with OpenCV; subtract 0.25 for unbiased positions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Keypoint {
    /// Column in input-image pixels; pixel centres are at integers, the top-left pixel's centre at 0.
    pub x: f32,
    /// Row in input-image pixels, same convention as `x`.
    pub y: f32,
    /// Diameter of the meaningful neighbourhood (2 x the scale sigma), in input-image pixels.
    pub size: f32,
    /// Orientation in degrees, 0..360, OpenCV convention (measured with y pointing down, clockwise on screen).
    pub angle: f32,
    /// Absolute interpolated DoG value (on the 0..1 intensity scale).
    pub response: f32,
    /// OpenCV packed octave: `octave & 255` (signed byte, -1 for the doubled image) `| layer << 8 |
    /// round((xi + 0.5) * 255) << 16` where `xi` is the sub-layer offset.
    pub octave: i32,
}

impl Keypoint {
    /// Unpacks `octave` into (octave, layer): octave -1 is the doubled image, 0 the input's resolution.
    pub fn octave_layer(&self) -> (i32, i32) {
        let o = self.octave & 255;
        let o = if o < 128 { o } else { o - 256 };
        (o, (self.octave >> 8) & 255)
    }

    /// Scale factor from input-image coordinates to the keypoint's octave image (OpenCV `unpackOctave`).
    pub fn octave_scale(&self) -> f32 {
        let (o, _) = self.octave_layer();
        if o >= 0 { 1.0 / (1u32 << o.min(31)) as f32 } else { (1u32 << (-o).min(31)) as f32 }
    }
}

/// Keypoints and their descriptors.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Features {
    /// The keypoints.
    pub keypoints: Vec<Keypoint>,
    /// `DESCRIPTOR_LEN` bytes per keypoint, in keypoint order, contiguous.
    pub descriptors: Vec<u8>,
}

impl Features {
    /// Number of keypoints.
    pub fn len(&self) -> usize {
        self.keypoints.len()
    }

    /// True when there is no keypoint.
    pub fn is_empty(&self) -> bool {
        self.keypoints.is_empty()
    }

    /// The 128-byte descriptor of keypoint `i` (panics when `i >= len()`).
    pub fn descriptor(&self, i: usize) -> &[u8] {
        &self.descriptors[i * DESCRIPTOR_LEN..(i + 1) * DESCRIPTOR_LEN]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octave_unpacking() {
        let kp =
            Keypoint { x: 0.0, y: 0.0, size: 1.0, angle: 0.0, response: 0.0, octave: 255 | (2 << 8) | (128 << 16) };
        assert_eq!(kp.octave_layer(), (-1, 2));
        assert_eq!(kp.octave_scale(), 2.0);
        let kp = Keypoint { octave: 3 | (1 << 8), ..kp };
        assert_eq!(kp.octave_layer(), (3, 1));
        assert_eq!(kp.octave_scale(), 0.125);
    }
}
