//! The U-Net baseline (spec §8) as a method: its configuration, the trained model with its
//! rasterisation of a problem, and its training loop.

mod config;
mod model;
mod train;

pub use config::CnnConfig;
pub use model::{CNN_PREDICTOR_FILE, CNN_WEIGHTS_FILE, CnnModel, CnnPredictor, CnnSizing};
pub use train::{CnnStepReport, CnnTraining};
