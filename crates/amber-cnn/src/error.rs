//! Errors of the CNN baseline: configurations, shapes, model files.

use std::path::PathBuf;

/// Everything that can go wrong building, running, saving or loading the U-Net or rasterising
/// its inputs.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CnnError {
    /// A configuration value is out of range; the message names the field.
    #[error("invalid CNN configuration: {0}")]
    InvalidConfig(String),
    /// Images, labels or features do not fit each other or the network.
    #[error("shape mismatch: {0}")]
    Shape(String),
    /// The mesh to rasterise has no elements or no extent.
    #[error("cannot rasterise: {0}")]
    EmptyMesh(String),
    /// A model file is missing a tensor or does not fit its configuration.
    #[error("model file {}: {message}", .path.display())]
    ModelFile { path: PathBuf, message: String },
    /// A file could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io { path: PathBuf, source: std::io::Error },
    /// A configuration file is not valid JSON of the expected shape.
    #[error("{}: {source}", .path.display())]
    Json { path: PathBuf, source: serde_json::Error },
    /// candle failed.
    #[error(transparent)]
    Candle(#[from] candle_core::Error),
}

impl From<amber_stdx::FileError> for CnnError {
    fn from(e: amber_stdx::FileError) -> Self {
        match e {
            amber_stdx::FileError::Io { path, source } => CnnError::Io { path, source },
            amber_stdx::FileError::Json { path, source } => CnnError::Json { path, source },
        }
    }
}

/// `Result` with [`CnnError`].
pub type Result<T, E = CnnError> = std::result::Result<T, E>;
