//! The learning tasks: what a task is ([`Domain`]: initial mesh, input columns on any mesh of the
//! domain, re-meshing from a sizing field; [`Problem`]: a domain with its expert mesh), what every
//! task shares (mesh states with their graphs, labels, one generation step under h_min and the
//! element budget, meshing to a requested element count), geometry-only domains
//! ([`part::SolidPart`], [`part::PlanarPart`]), datasets as folders of expert meshes
//! ([`folder`]), and the tasks themselves beside their data. Poisson (spec §1): the random
//! L-shape and Gaussian-mixture load, M⁰, the expert mesh, one JSON file per problem (readable
//! from the reference's format too), the dataset splits of `datasets/poisson.json` with a
//! content-hash cache. Console (spec §9): a dataset folder; its module keeps the paper's M⁰ size
//! and split.
//!
//! Depends on the mesh, meshing, FEM, graph and metric layers; knows nothing of networks,
//! training loops or candle, and never prints (progress is reported through a callback).

pub mod cad;
pub mod console;
mod error;
mod expert;
pub mod folder;
pub mod part;
pub mod poisson;
mod problem;

pub use error::TaskError;
pub use problem::{
    Column, Domain, ELEMENT_COUNT_TOLERANCE, FinalCount, LOG_SIZE_COLUMN, MeshLimits, MeshState, Problem, ProblemError,
    RefineBox, RefineFace, SizeBounds, StepOutcome, WithExpert, generation_step, labels, mesh_to_element_count,
    with_inputs,
};
