//! Errors of mesh construction, I/O and queries.

use std::path::PathBuf;

/// Everything that can go wrong building, reading or writing a mesh.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// A mesh needs at least one element.
    #[error("the mesh has no elements")]
    Empty,
    /// The flat connectivity length is not a multiple of the nodes per element.
    #[error("connectivity has {len} indices, not a multiple of {nodes_per_element} nodes per element")]
    Connectivity { len: usize, nodes_per_element: usize },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex { vertex: usize },
    /// An element references a vertex that does not exist.
    #[error("element {element} references vertex {vertex}, but the mesh has {num_vertices} vertices")]
    VertexOutOfRange { element: usize, vertex: u32, num_vertices: usize },
    /// An element is degenerate or inverted.
    #[error("element {element} has non-positive volume {volume:e} (degenerate or inverted)")]
    NonPositiveElement { element: usize, volume: f64 },
    /// A facet is shared by more than two elements.
    #[error("facet {facet:?} is shared by more than two elements (non-manifold mesh)")]
    NonManifoldFacet { facet: Vec<u32> },
    /// Two elements share a facet from the same side.
    #[error("elements {} and {} overlap: they lie on the same side of their shared facet", elements[0], elements[1])]
    OverlappingElements { elements: [usize; 2] },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// A file was read but its content is malformed.
    #[error("{path}:{line}: {message}")]
    Parse { path: PathBuf, line: usize, message: String },
    /// A binary part of a file is malformed at this byte offset.
    #[error("{path}: byte {offset}: {message}")]
    AtByte { path: PathBuf, offset: usize, message: String },
    /// A file's content is malformed or cannot be represented, where no line number applies.
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    /// A file holds a mesh of another dimension than the one asked for.
    #[error("{path}: holds a {found}D mesh, expected {expected}D")]
    DimensionMismatch { path: PathBuf, expected: usize, found: usize },
    /// A file was parsed but its elements do not form a valid mesh.
    #[error("{path}: {source}")]
    InvalidMesh { path: PathBuf, source: Box<MeshError> },
    /// A data field has the wrong number of values for the mesh it belongs to.
    #[error("{path}: {field} has {len} values, expected {expected}")]
    DataLength { path: PathBuf, field: String, len: usize, expected: usize },
    /// The file extension names no supported format.
    #[error("{path}: unsupported mesh format (expected one of {expected})")]
    UnsupportedFormat { path: PathBuf, expected: &'static str },
}

impl From<amber_stdx::FileError> for MeshError {
    fn from(e: amber_stdx::FileError) -> Self {
        match e {
            amber_stdx::FileError::Io { path, source } => MeshError::Io { path, source },
            amber_stdx::FileError::Json { path, source } => MeshError::Format { path, message: source.to_string() },
        }
    }
}
