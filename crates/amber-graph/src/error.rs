//! Errors of graph building, label projection, normalisation and batching.

use std::path::PathBuf;

use amber_mesh::MeshError;

/// Everything that can go wrong turning meshes into graphs, labels and batches.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GraphError {
    /// The mesh is not a valid element graph (e.g. a facet shared by three elements).
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The feature set asks for a per-element column the caller did not provide.
    #[error("feature column `{name}` was not provided")]
    MissingColumn { name: String },
    /// A per-element column does not have one value per element.
    #[error("feature column `{name}` has {len} values, expected one per element ({expected})")]
    ColumnLength { name: String, len: usize, expected: usize },
    /// A per-element column holds NaN or infinity.
    #[error("feature column `{name}` is not finite at element {element}")]
    NonFiniteColumn { name: String, element: usize },
    /// Feature widths of graphs, batches and normaliser disagree.
    #[error("{what}: expected width {expected}, found {found}")]
    DimensionMismatch { what: &'static str, expected: usize, found: usize },
    /// A flat feature array does not split into rows of the expected width.
    #[error("{len} feature values do not form rows of width {dim}")]
    RaggedFeatures { len: usize, dim: usize },
    /// More nodes or edges than the `u32` indices of [`crate::GraphBatch`] can address.
    #[error("{count} {what} exceed the u32 index range")]
    TooLarge { what: &'static str, count: usize },
    /// A batch needs at least one graph (its feature widths come from the graphs).
    #[error("cannot batch zero graphs")]
    EmptyBatch,
    /// A [`crate::GraphBatch`] breaks one of its documented invariants.
    #[error("invalid graph batch: {reason}")]
    InvalidBatch { reason: String },
    /// A saved normaliser is inconsistent (lengths, non-finite or negative moments).
    #[error("{path}: invalid normaliser: {reason}")]
    InvalidNormaliser { path: PathBuf, reason: String },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// A file is not valid JSON for the expected type.
    #[error("{path}: {source}")]
    Json { path: PathBuf, source: serde_json::Error },
}
