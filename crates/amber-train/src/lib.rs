//! AMBER's training and inference loops, for any task (`amber_tasks::Problem`): the replay buffer with least-used batching
//! and stratified additions, running input and label normalisation, the training loop with
//! checkpoints that resume exactly and a JSON-lines log, and rollouts of a trained model with
//! their metrics against the expert.
//!
//! Configuration is one typed struct ([`TrainingConfig`]) with named profiles. The crate never
//! prints: progress goes through [`TrainingObserver`]; argument parsing and plotting belong to the
//! binaries.
//!
//! Determinism: a run is a function of its configuration (seed included) and problems. With one
//! rayon thread it is bit-for-bit reproducible, across resumes too; with more threads the
//! network's parallel gradient reductions sum in a scheduling-dependent order, so runs agree only
//! to rounding at first and then drift apart.

mod buffer;
mod checkpoint;
mod cnn;
mod config;
mod error;
mod inference;
mod model;
mod target;
mod train;

pub use buffer::{BufferEntry, ReplayBuffer, Sample};
pub use checkpoint::{AdditionCounts, CHECKPOINTS_DIR, latest_checkpoint};
pub use cnn::{
    CNN_PREDICTOR_FILE, CNN_WEIGHTS_FILE, CnnConfig, CnnModel, CnnObserver, CnnPredictor, CnnStepReport, CnnTraining,
    cnn_rollouts,
};
pub use config::{DataConfig, LrSchedule, NetworkConfig, Objective, Profile, SourceSelection, TrainingConfig};
pub use error::{Result, TrainError};
pub use inference::{
    Evaluation, EvaluationSummary, MeshMetrics, Reference, Rollout, RolloutStep, StepStatus, StepSummary, rollouts,
};
pub use model::{AmberModel, Predictor, WEIGHTS_FILE};
pub use target::{TargetTransform, softplus, softplus_inverse};
pub use train::{Addition, CONFIG_FILE, LOG_FILE, MODEL_DIR, StepReport, Training, TrainingObserver};
