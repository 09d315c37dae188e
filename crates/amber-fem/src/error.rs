//! Errors of assembly, solution, loads and the expert heuristic.

use amber_mesh::MeshError;
use amber_meshgen::rgb::RgbError;

/// Everything that can go wrong in the FEM layer.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FemError {
    /// No quadrature rule of that order is tabulated for this dimension.
    #[error("no {dimension}D quadrature rule of order {order} (triangles: up to 5, tetrahedra: up to 2)")]
    UnsupportedQuadrature { dimension: usize, order: usize },
    /// The mesh is not conforming (a facet is shared by more than two elements).
    #[error("the mesh is not conforming: {0}")]
    Mesh(#[from] MeshError),
    /// A solution vector does not match the mesh.
    #[error("solution has {len} values but the mesh has {num_vertices} vertices")]
    SolutionLength { len: usize, num_vertices: usize },
    /// The stiffness matrix is not numerically positive definite.
    #[error("Cholesky factorisation of the {dofs}-dof stiffness matrix failed: {message}")]
    Factorisation { dofs: usize, message: String },
    /// The load is not finite somewhere on the mesh.
    #[error("the load is not finite at a quadrature point of element {element}")]
    NonFiniteLoad { element: usize },
    /// A component of a Gaussian mixture is invalid.
    #[error("Gaussian mixture component {component}: {problem}")]
    InvalidMixture { component: usize, problem: String },
    /// Refining or smoothing in the expert heuristic failed.
    #[error("expert step {step}: {source}")]
    Expert { step: usize, source: RgbError },
}
