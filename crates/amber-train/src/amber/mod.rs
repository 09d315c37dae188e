//! AMBER as a method: its configuration, the replay buffer, the map between sizes and network
//! targets, the trained model and its training loop.

mod buffer;
mod config;
mod model;
mod target;
mod train;

pub use buffer::{BufferEntry, ReplayBuffer, Sample};
pub use config::{SourceSelection, TrainingConfig};
pub(crate) use model::PREDICTOR_FILE;
pub use model::{AmberModel, AmberSizing, Predictor, WEIGHTS_FILE};
pub use target::TargetTransform;
pub use train::{Addition, AmberStepReport, CONFIG_FILE, LOG_FILE, MODEL_DIR, Training};
