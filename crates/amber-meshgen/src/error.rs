//! Errors of mesh generation.

use amber_mesh::MeshError;

/// Everything that can go wrong generating a mesh.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshgenError {
    /// The geometry is malformed (too few vertices, non-finite, degenerate, hole outside).
    #[error("invalid domain: {0}")]
    InvalidDomain(String),
    /// Two boundary edges intersect.
    #[error("self-intersecting domain: edge {edge_a} of ring {ring_a} intersects edge {edge_b} of ring {ring_b}")]
    SelfIntersecting { ring_a: usize, edge_a: usize, ring_b: usize, edge_b: usize },
    /// The sizing field returned a size that is not a positive finite number.
    #[error("the sizing field returned {value} at {at:?}; sizes must be positive and finite")]
    InvalidSize { at: Vec<f64>, value: f64 },
    /// The mesh would exceed the element cap (sizes too small for the domain).
    #[error("the mesh would exceed the cap of {cap} elements (sizes too small for the domain?)")]
    TooManyElements { cap: usize },
    /// The triangulation library rejected a point.
    #[error("triangulation failed: {0}")]
    Triangulation(String),
    /// The generated mesh failed validation (a bug, reported rather than hidden).
    #[error("generated mesh is invalid: {0}")]
    InvalidMesh(#[from] MeshError),
}
