//! Task definitions and their datasets. Today: the Poisson task of spec §1 — the random L-shape
//! and Gaussian-mixture load ([`poisson::PoissonProblem`]), its initial mesh M⁰ and expert mesh
//! M*, one JSON file per problem (readable from the reference's data format too), and the
//! dataset splits of `datasets/poisson.json` with a content-hash cache.
//!
//! Depends on the mesh, meshing and FEM layers; it knows nothing of graphs or learning, and never
//! prints (progress is reported through a callback).

pub mod console;
mod error;
pub mod poisson;

pub use error::TaskError;
