//! SIFT keypoints and descriptors on grey f32 images.
