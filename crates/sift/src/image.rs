//! Grey input images.

use crate::error::SiftError;

/// Largest side accepted (the doubled image must stay addressable): 2^24 pixels.
const MAX_SIDE: usize = 1 << 24;

/// A borrowed view of a row-major f32 image (a pyramid layer, a DoG layer): its pixels and size, passed as one
/// argument where functions took `(data, w, h, ...)`. The view may hold only a window of the image's rows.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Plane<'a> {
    /// The pixels of rows `y0 ..`, row-major.
    pub data: &'a [f32],
    /// Width, pixels.
    pub w: usize,
    /// Height of the whole image, pixels.
    pub h: usize,
    /// The image row `data` starts at (0 when the view holds the whole image).
    pub y0: usize,
}

impl<'a> Plane<'a> {
    /// The view of `data` as a `w` x `h` image.
    #[inline]
    pub fn new(data: &'a [f32], w: usize, h: usize) -> Self {
        Plane { data, w, h, y0: 0 }
    }

    /// The view of rows `y0 ..` of a `w` x `h` image, held in `data` from its start.
    #[inline]
    pub fn window(data: &'a [f32], w: usize, h: usize, y0: usize) -> Self {
        Plane { data, w, h, y0 }
    }

    /// The image rows the view holds: `y0 .. y0 + data.len() / w`, clipped to the image.
    #[inline]
    pub fn rows(&self) -> std::ops::Range<usize> {
        let held = self.data.len().checked_div(self.w).unwrap_or(0);
        self.y0..(self.y0 + held).min(self.h)
    }
}

/// A grey image, row-major, values on the 8-bit scale 0..255 (like OpenCV's `CV_8U` input).
#[derive(Debug, Clone, PartialEq)]
pub struct GrayImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width * height` pixel values, row after row, nominally in 0..255.
    pub data: Vec<f32>,
}

impl GrayImage {
    /// Builds an image, checking the buffer length and that every pixel is finite.
    pub fn new(width: usize, height: usize, data: Vec<f32>) -> Result<Self, SiftError> {
        check_size(width, height)?;
        let expected = width * height;
        if data.len() != expected {
            return Err(SiftError::DataLength { width, height, expected, got: data.len() });
        }
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            return Err(SiftError::NonFinitePixel { x: i % width, y: i / width });
        }
        Ok(Self { width, height, data })
    }

    /// Builds an image from 8-bit grey values.
    pub fn from_u8(width: usize, height: usize, data: &[u8]) -> Result<Self, SiftError> {
        check_size(width, height)?;
        let expected = width * height;
        if data.len() != expected {
            return Err(SiftError::DataLength { width, height, expected, got: data.len() });
        }
        Ok(Self { width, height, data: data.iter().map(|&v| f32::from(v)).collect() })
    }

    /// Pixel value at column `x`, row `y` (panics when out of bounds, like slice indexing).
    pub fn get(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.width + x]
    }

    /// True when the image has no pixel.
    pub fn is_empty(&self) -> bool {
        self.width == 0 || self.height == 0
    }
}

fn check_size(width: usize, height: usize) -> Result<(), SiftError> {
    if width > MAX_SIDE
        || height > MAX_SIDE
        || (2 * width).checked_mul(2 * height).is_none_or(|n| n > (isize::MAX as usize) / 8)
    {
        return Err(SiftError::TooLarge { width, height });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn new_checks_length() {
        assert!(matches!(GrayImage::new(2, 2, vec![0.0; 3]), Err(SiftError::DataLength { .. })));
        assert!(GrayImage::new(2, 2, vec![0.0; 4]).is_ok());
        assert!(GrayImage::new(0, 0, vec![]).is_ok());
    }

    #[test]
    fn new_rejects_non_finite() {
        let mut d = vec![0.0; 6];
        d[4] = f32::NAN;
        assert_eq!(GrayImage::new(3, 2, d), Err(SiftError::NonFinitePixel { x: 1, y: 1 }));
        let mut d = vec![0.0; 6];
        d[2] = f32::INFINITY;
        assert_eq!(GrayImage::new(3, 2, d), Err(SiftError::NonFinitePixel { x: 2, y: 0 }));
    }

    #[test]
    fn from_u8_converts() {
        let img = GrayImage::from_u8(2, 1, &[0, 255]).unwrap();
        assert_eq!(img.data, vec![0.0, 255.0]);
        assert!(GrayImage::from_u8(2, 2, &[0]).is_err());
        assert!(GrayImage::from_u8(usize::MAX, 2, &[0]).is_err());
    }
}
