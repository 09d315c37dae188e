//! Errors of problem generation, problem files and dataset manifests.

use std::path::PathBuf;

use amber_fem::FemError;
use amber_mesh::MeshError;
use amber_meshgen::MeshgenError;

/// Everything that can go wrong generating, reading or writing task data.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TaskError {
    /// A file or directory could not be read or written.
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// A file is not valid JSON of the expected shape (this includes a load whose covariance is
    /// not positive definite, which the load's deserialiser rejects).
    #[error("{path}: {source}")]
    Json { path: PathBuf, source: serde_json::Error },
    /// A mesh in a problem file is invalid.
    #[error("{path}: field `{field}`: {source}")]
    Mesh { path: PathBuf, field: &'static str, source: MeshError },
    /// The domain polygon of a problem file is not an L-shape.
    #[error("{path}: field `domain.polygon`: {message}")]
    Polygon { path: PathBuf, message: String },
    /// A geometry file does not describe a domain (the message says why).
    #[error("{path}: {message}")]
    Geometry { path: PathBuf, message: String },
    /// An expert mesh of a dataset folder could not be read (the error names the file).
    #[error("expert mesh {0}")]
    ExpertMesh(MeshError),
    /// A dataset folder is malformed: a missing or empty split, mixed dimensions, a geometry that
    /// does not match its mesh (the message says which).
    #[error("{path}: {message}")]
    Dataset { path: PathBuf, message: String },
    /// A dataset manifest does not define what was asked.
    #[error("{path}: {message}")]
    Manifest { path: PathBuf, message: String },
    /// Generating problem `seed` failed while meshing its domain.
    #[error("problem with seed {seed}: initial mesh: {source}")]
    InitialMesh { seed: u64, source: MeshgenError },
    /// Generating problem `seed` failed in the FEM layer (load or expert heuristic).
    #[error("problem with seed {seed}: {source}")]
    Fem { seed: u64, source: FemError },
}

impl From<amber_stdx::FileError> for TaskError {
    fn from(e: amber_stdx::FileError) -> Self {
        match e {
            amber_stdx::FileError::Io { path, source } => TaskError::Io { path, source },
            amber_stdx::FileError::Json { path, source } => TaskError::Json { path, source },
        }
    }
}
