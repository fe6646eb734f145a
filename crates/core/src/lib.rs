//! Core types of mrslam.
