//! Errors of the network: shapes, configurations, checkpoints.

use std::path::PathBuf;

/// Everything that can go wrong building, running, saving or loading the network.
#[derive(Debug, thiserror::Error)]
pub enum MpnError {
    #[error("{what} has {got} features per row, the network expects {expected}")]
    FeatureDim { what: &'static str, expected: usize, got: usize },
    #[error("invalid graph: {0}")]
    InvalidGraph(String),
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    #[error("checkpoint {}: {message}", .path.display())]
    Checkpoint { path: PathBuf, message: String },
    #[error("reading or writing {}: {source}", .path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("checkpoint config {}: {source}", .path.display())]
    Json { path: PathBuf, source: serde_json::Error },
    #[error(transparent)]
    Candle(#[from] candle_core::Error),
}

pub type Result<T, E = MpnError> = std::result::Result<T, E>;
