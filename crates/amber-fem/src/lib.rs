//! P1 finite elements for the Poisson task: the space on a simplicial mesh with homogeneous
//! Dirichlet conditions ([`P1Space`]), stiffness and load assembly (parallel over elements),
//! the sparse Cholesky solve (faer), the residual error estimator and θ-marking, Gaussian-mixture
//! loads, and the expert refinement heuristic that produces the expert meshes.
//!
//! Depends on amber-mesh and amber-meshgen (refinement and smoothing) only; it knows nothing of
//! graphs, learning or files.
//!
//! ```
//! use amber_fem::{P1Space, Quadrature};
//! use amber_mesh::Mesh2;
//! let square = Mesh2::new(
//!     vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]],
//!     vec![0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4],
//! )?;
//! let space = P1Space::new(&square)?;
//! let quadrature = Quadrature::simplex::<2>(2)?;
//! let solution = space.solve_poisson(&space.sample_load(&|_: [f64; 2]| 1.0, &quadrature)?)?;
//! // One interior dof: K = 4, F = 4 · (1/4)/3.
//! assert!((solution.u[4] - 1.0 / 12.0).abs() < 1e-15);
//! # Ok::<(), amber_fem::FemError>(())
//! ```

mod error;
mod estimator;
mod expert;
mod load;
mod ordering;
mod poisson;
mod quadrature;
mod space;

pub use error::FemError;
pub use estimator::mark_theta;
pub use expert::ExpertHeuristic;
pub use load::{GaussianMixture, GaussianMixtureParams, Load};
pub use poisson::{LoadSamples, PoissonSolution, StiffnessMatrix};
pub use quadrature::Quadrature;
pub use space::{ElementGeometry, ElementStats, P1Space, element_stats};
