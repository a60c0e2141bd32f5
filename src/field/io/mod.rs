//! Readers for volume files, behind one interface: [`read_volume`].
//! (Stub: the real readers are being written.)

use super::{FieldError, ScalarField};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// What to do with NaN or infinite values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum NanPolicy {
    /// Refuse the file, naming the count and the first position.
    #[default]
    Error,
    /// Replace them by the smallest finite value.
    Min,
    /// Replace them by the largest finite value.
    Max,
}

/// How to read a headerless raw file.
#[derive(Clone, Debug, PartialEq)]
pub struct RawLayout {
    /// Grid dimensions.
    pub dims: [usize; 3],
    /// Scalar type as NRRD names it: uint8, int16, float32, ...
    pub scalar_type: String,
    /// True for big-endian data.
    pub big_endian: bool,
}

/// Options for [`read_volume`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadOptions {
    /// Layout for raw files whose name does not carry it.
    pub raw: Option<RawLayout>,
    /// NaN and infinity policy.
    pub nan: NanPolicy,
}

/// A volume as read from a file.
#[derive(Clone, Debug)]
pub struct Volume {
    /// The field (values in the file's units, spacing from the header).
    pub field: ScalarField,
    /// The file it came from.
    pub path: PathBuf,
    /// Format name, e.g. "NRRD (gzip)".
    pub format: String,
}

/// Why a volume could not be read.
#[derive(Debug, Error)]
pub enum ReadError {
    /// Any other problem, with the file named.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The values do not make a valid field.
    #[error("{path}: {source}")]
    Field {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: FieldError,
    },
}

/// Reads a volume file, choosing the reader by extension and content.
pub fn read_volume(path: &Path, _opts: &ReadOptions) -> Result<Volume, ReadError> {
    Err(ReadError::Invalid {
        path: path.to_owned(),
        message: "no reader yet".into(),
    })
}
