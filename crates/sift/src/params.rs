//! Parameters, named and defaulted as OpenCV's `cv::SIFT`.
//!
//! Value scale: images are on the 8-bit scale 0..255 (OpenCV's float path, `SIFT_FIXPT_SCALE = 1`).
//! The DoG pre-threshold is `floor(0.5 * contrast_threshold / n_octave_layers * 255)` on that scale and
//! the final contrast test is `|D(x̂)| / 255 * n_octave_layers >= contrast_threshold`, exactly as OpenCV.

/// SIFT parameters; `Default` gives OpenCV's defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct SiftParams {
    /// Keep at most this many keypoints, strongest response first (OpenCV `nfeatures`; `None` keeps all).
    pub max_features: Option<usize>,
    /// Layers per octave in which extrema are sought (OpenCV `nOctaveLayers`, default 3).
    pub n_octave_layers: usize,
    /// Contrast threshold on the 0..1 intensity scale, divided by `n_octave_layers` as OpenCV does (default 0.04).
    pub contrast_threshold: f32,
    /// Edge threshold: the ratio of principal curvatures must stay below it (default 10).
    pub edge_threshold: f32,
    /// Blur of the first layer of each octave (default 1.6).
    pub sigma: f32,
    /// Blur already present in the input image (OpenCV `SIFT_INIT_SIGMA`, default 0.5).
    pub init_sigma: f32,
    /// Double the image before building the pyramid (OpenCV's `firstOctave = -1`, default true).
    pub upscale: bool,
    /// Number of octaves; `None` derives it from the image size as OpenCV does
    /// (`round(log2(min(w, h) of the base image) - 2)`, plus one when the image is doubled).
    pub n_octaves: Option<usize>,
    /// Keypoints closer than this to an octave image's border are ignored (OpenCV `SIFT_IMG_BORDER`, 5).
    pub border: usize,
    /// Maximum sub-pixel interpolation steps before a candidate is dropped (OpenCV `SIFT_MAX_INTERP_STEPS`, 5).
    pub max_interp_steps: usize,
    /// Run the blurs and the per-keypoint work (refinement, orientation, descriptor) on the rayon pool, each
    /// octave's layers held whole (default false: one thread, the layers through a sliding window of rows, a
    /// fraction of the memory); identical output either way.
    pub parallel: bool,
}

impl Default for SiftParams {
    fn default() -> Self {
        Self {
            max_features: None,
            n_octave_layers: 3,
            contrast_threshold: 0.04,
            edge_threshold: 10.0,
            sigma: 1.6,
            init_sigma: 0.5,
            upscale: true,
            n_octaves: None,
            border: 5,
            max_interp_steps: 5,
            parallel: false,
        }
    }
}

impl SiftParams {
    /// The DoG magnitude a pixel must exceed to be tested as an extremum (OpenCV's integer `threshold`).
    pub fn pre_threshold(&self) -> f32 {
        let n = self.n_octave_layers.max(1) as f64;
        (0.5 * f64::from(self.contrast_threshold) / n * 255.0).floor() as f32
    }
}
