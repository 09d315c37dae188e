//! Errors of the training and inference loops.

use std::path::PathBuf;

use amber_graph::GraphError;
use amber_mpn::MpnError;
use amber_tasks::ProblemError;

/// Everything that can go wrong training AMBER or rolling it out.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TrainError {
    /// The configuration is inconsistent; the message names the field.
    #[error("invalid training configuration: {0}")]
    InvalidConfig(String),
    /// Training needs at least one problem.
    #[error("no training problems")]
    NoProblems,
    /// One problem's step failed (FEM, graph, labels, metrics, or a broken mesh generator).
    #[error("problem {problem}: {source}")]
    Problem { problem: usize, source: ProblemError },
    /// Batching or normalising graphs failed.
    #[error("graph batch: {0}")]
    Graph(#[from] GraphError),
    /// The network failed (shapes, candle, checkpoint files).
    #[error("network: {0}")]
    Network(#[from] MpnError),
    /// The CNN baseline failed (configuration, rasterisation, shapes, model files).
    #[error("CNN: {0}")]
    Cnn(#[from] amber_cnn::CnnError),
    /// A file or directory could not be read or written.
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// A file is not valid JSON of the expected shape.
    #[error("{path}: {source}")]
    Json { path: PathBuf, source: serde_json::Error },
    /// A generation step of [`crate::generate`] produced no mesh (over the budget, or the
    /// generator failed); `step` counts from 1.
    #[error("generation step {step}: {reason}")]
    Generation { step: usize, reason: String },
    /// The last step of [`crate::generate`], within the user's size bounds, would have more
    /// elements than the bounds' cap.
    #[error("generation step {step}: the field within the size bounds asks for more than the cap of {cap} elements")]
    OverCap { step: usize, cap: usize },
    /// A model file holds values no model can have (non-finite or negative moments, limits that
    /// are not positive) or that do not fit its network; the message names the field.
    #[error("{path}: {message}")]
    InvalidModel { path: PathBuf, message: String },
    /// The model reads node inputs that the domain it should mesh does not offer (e.g. a part's
    /// own inputs, which its `<stem>.inputs.json` gives).
    #[error("the model reads the input{} {} that the domain does not offer", if .0.len() == 1 { "" } else { "s" }, .0.join(", "))]
    MissingInputs(Vec<String>),
    /// A checkpoint is missing a piece or does not fit the run it should resume.
    #[error("checkpoint {path}: {message}")]
    Checkpoint { path: PathBuf, message: String },
}

impl From<amber_stdx::FileError> for TrainError {
    fn from(e: amber_stdx::FileError) -> Self {
        match e {
            amber_stdx::FileError::Io { path, source } => TrainError::Io { path, source },
            amber_stdx::FileError::Json { path, source } => TrainError::Json { path, source },
        }
    }
}

/// `Result` with [`TrainError`].
pub type Result<T, E = TrainError> = std::result::Result<T, E>;

/// Tags a problem's error with its index.
pub(crate) fn in_problem<E: Into<ProblemError>>(problem: usize) -> impl FnOnce(E) -> TrainError {
    move |e| TrainError::Problem { problem, source: e.into() }
}

/// Wraps an I/O error with its path.
pub(crate) fn io_error(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> TrainError {
    let path = path.into();
    move |source| TrainError::Io { path, source }
}
