//! What can go wrong reading or writing a map; every error names the file.

use crate::grid::{GridError, MAX_CELLS};
use std::path::{Path, PathBuf};

/// Everything that can go wrong reading or writing a map; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum MapIoError {
    /// The file could not be read or written.
    #[error("{path}: {cause}")]
    Io {
        /// File at fault.
        path: PathBuf,
        /// Underlying error.
        cause: std::io::Error,
    },
    /// A YAML line could not be understood.
    #[error("{}: {message}", at(path, *line))]
    Yaml {
        /// File at fault.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A field has a value that is not allowed.
    #[error("{}: field `{field}`: {message}", at(path, *line))]
    BadField {
        /// File at fault.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// Field name.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// A required field is absent.
    #[error("{path}: missing required field `{field}`")]
    MissingField {
        /// File at fault.
        path: PathBuf,
        /// Field name.
        field: &'static str,
    },
    /// The image is not a valid PGM.
    #[error("{path}: not a valid PGM image: {message}")]
    Pgm {
        /// File at fault.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The image could not be decoded.
    #[error("{path}: cannot decode image: {message}")]
    Image {
        /// File at fault.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The image is larger than this program accepts.
    #[error("{path}: image of {width}x{height} pixels exceeds the limit of {MAX_CELLS} cells")]
    TooLarge {
        /// File at fault.
        path: PathBuf,
        /// Width claimed.
        width: usize,
        /// Height claimed.
        height: usize,
    },
    /// The image a map YAML names could not be read.
    #[error("{}: field `image`: {cause}", at(yaml, *line))]
    ImageOf {
        /// The YAML naming the image.
        yaml: PathBuf,
        /// Line of its `image` field.
        line: usize,
        /// Why the image could not be read (names the image).
        cause: Box<MapIoError>,
    },
    /// The grid could not be built.
    #[error("{path}: {cause}")]
    Grid {
        /// File at fault.
        path: PathBuf,
        /// Underlying error.
        cause: GridError,
    },
}

/// `file:line`, or the file alone when the line is not known (0).
pub(super) fn at(path: &Path, line: usize) -> String {
    if line == 0 { path.display().to_string() } else { format!("{}:{line}", path.display()) }
}

pub(super) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> MapIoError + '_ {
    move |cause| MapIoError::Io { path: path.to_path_buf(), cause }
}

impl From<crate::output::WriteError> for MapIoError {
    fn from(e: crate::output::WriteError) -> Self {
        MapIoError::Io { path: e.path, cause: e.cause }
    }
}
