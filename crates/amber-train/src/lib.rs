//! The two methods' training and inference loops, for any task (`amber_tasks::Problem`): AMBER
//! (`amber`: the replay buffer with least-used batching and stratified additions, running input
//! and label normalisation, the training loop with a JSON-lines log) and the U-Net baseline
//! (`cnn`), over what they share: checkpoints that resume exactly, one rollout loop with its
//! metrics against the expert ([`rollouts`], for any [`SizingModel`]), and the method as one
//! configuration or one trained model ([`MethodConfig`], [`TrainedModel`]). Never sees a tensor:
//! the networks' crates take and return plain slices.
//!
//! Configuration is one typed struct ([`TrainingConfig`]) with named profiles. The crate never
//! prints: progress goes through [`TrainingObserver`]; argument parsing and plotting belong to the
//! binaries.
//!
//! Determinism: a run is a function of its configuration (seed included) and problems, bit for
//! bit, at any number of rayon threads and across resumes: every parallel float reduction of the
//! networks' ops (weight and bias gradients) sums in fixed chunks chosen by the size of the data
//! alone and combines them in order (`amber_nn::reduce`), and everything else parallel here maps
//! items independently and collects them in order (`tests/determinism.rs` compares the model
//! files of runs at one and two threads).
//!
//! Model files are checked when read: non-finite weights, weights of the wrong shape for the
//! configuration, moments with negative variances or a zero count and limits that are not
//! positive are errors naming the file and the tensor or field.

mod amber;
mod checkpoint;
mod cnn;
mod config;
mod error;
mod method;
mod model_file;
mod observer;
mod rollout;

pub use amber::{
    Addition, AmberModel, AmberSizing, AmberStepReport, BufferEntry, CONFIG_FILE, LOG_FILE, MODEL_DIR, Predictor,
    ReplayBuffer, Sample, SourceSelection, TargetTransform, Training, TrainingConfig, WEIGHTS_FILE,
};
pub use amber_mpn::NetworkConfig;
pub use amber_nn::{Backend, Objective};
pub use checkpoint::{AdditionCounts, CHECKPOINTS_DIR, latest_checkpoint};
pub use cnn::{
    CNN_PREDICTOR_FILE, CNN_WEIGHTS_FILE, CnnConfig, CnnModel, CnnPredictor, CnnSizing, CnnStepReport, CnnTraining,
};
pub use config::{DataConfig, LrSchedule, Profile};
pub use error::{Result, TrainError};
pub use method::{MethodConfig, TrainedModel};
pub use observer::{StepReport, TrainingObserver};
pub use rollout::{
    Evaluation, EvaluationSummary, FinalStep, FinalStepFit, GeneratedStep, MeshMetrics, PredictedField, Reference,
    Rollout, RolloutStep, SizingModel, StepStatus, StepSummary, fit_final_step, generate, rollouts,
};
