//! The targets of amber-train's loaders: a trained model directory (one of its files replaced by
//! the input, then loaded as `amber mesh --model` loads it and applied to a Poisson part) and a
//! training configuration (parsed and validated as `amber train --config` does).

use std::path::Path;

use amber_experiments::{CARD_FILE, ModelCard};
use amber_tasks::poisson::PoissonProblem;
use amber_train::{CnnConfig, FinalStep, LrSchedule, TrainError, TrainedModel, TrainingConfig};

use crate::{ELEMENT_CAP, assert_valid, scratch_dir};

/// A tiny AMBER model of the Poisson task (`amber train --profile smoke --steps 200` with a
/// width of 4 and one message-passing step), file by file.
const AMBER_MODEL: [(&str, &[u8]); 4] = [
    ("model.safetensors", include_bytes!("../models/amber/model.safetensors")),
    ("model.json", include_bytes!("../models/amber/model.json")),
    ("predictor.json", include_bytes!("../models/amber/predictor.json")),
    (CARD_FILE, include_bytes!("../models/amber/card.json")),
];

/// A tiny untrained CNN of the Poisson task (two channels, depth 1, a 16-pixel grid).
const CNN_MODEL: [(&str, &[u8]); 3] = [
    ("cnn.safetensors", include_bytes!("../models/cnn/cnn.safetensors")),
    ("cnn.json", include_bytes!("../models/cnn/cnn.json")),
    (CARD_FILE, include_bytes!("../models/cnn/card.json")),
];

/// The Poisson problem both models are applied to (the unit L-shape's M⁰ of a few triangles).
const PROBLEM: &[u8] = include_bytes!("../../../fuzz/corpus/problem_file/seed-lshape.json");

/// Input channels of a CNN of the Poisson task: its three columns and the inside mask.
const POISSON_CNN_CHANNELS: usize = 4;

/// The largest grid a CNN model is applied to here: finer grids mesh an auxiliary mesh of about
/// two triangles per pixel, legitimate work of seconds.
const APPLIED_RESOLUTION: usize = 64;

/// A model directory: the first byte picks one file of the AMBER or the CNN model (its card
/// included), the rest replaces it. A directory that loads holds a model its loaders vouch for:
/// the documented checks hold (a card with at least one step and a positive M⁰ size, widths that
/// fit the network, positive limits, a CNN grid its network can pool), and one generation step on
/// a Poisson part either meshes or fails as a generation step may (over the budget, inputs the
/// part does not offer), never on the model's own contents.
pub fn model_dir(data: &[u8]) {
    let Some((&pick, contents)) = data.split_first() else { return };
    let pick = pick as usize % (AMBER_MODEL.len() + CNN_MODEL.len());
    let (kind, files, replaced) = if pick < AMBER_MODEL.len() {
        ("amber", &AMBER_MODEL[..], pick)
    } else {
        ("cnn", &CNN_MODEL[..], pick - AMBER_MODEL.len())
    };
    let dir = scratch_dir().join(kind);
    std::fs::create_dir_all(&dir).expect("the scratch directory is writable");
    for (k, &(name, bytes)) in files.iter().enumerate() {
        let bytes = if k == replaced { contents } else { bytes };
        std::fs::write(dir.join(name), bytes).expect("the scratch directory is writable");
    }
    let named = |message: String| {
        let named = files.iter().any(|(name, _)| message.contains(&dir.join(name).display().to_string()));
        assert!(named, "error without the file name: {message}");
    };
    // As `amber mesh --model` reads a model: its card, then the model itself.
    let card = match ModelCard::read(&dir) {
        Ok(card) => card,
        Err(e) => return named(format!("{e:#}")),
    };
    assert!(
        (1..=TrainingConfig::MAX_INFERENCE_STEPS).contains(&card.inference_steps),
        "{} generation steps",
        card.inference_steps
    );
    assert!(card.initial_size > 0.0 && card.initial_size.is_finite(), "M⁰ size {}", card.initial_size);
    let model = match TrainedModel::load(&dir) {
        Ok(model) => model,
        Err(e) => return named(e.to_string()),
    };
    let applies = match &model {
        TrainedModel::Amber(m) => {
            let (features, network) = (&m.predictor.features, m.network.config());
            assert_eq!(features.node_dim(), network.node_features, "node features for the network's width");
            features.edge_dim(2) == network.edge_features
        }
        TrainedModel::Cnn(m) => {
            let (network, resolution) = (&m.predictor.network, m.predictor.resolution);
            assert!(resolution <= CnnConfig::MAX_RESOLUTION, "a grid of {resolution} pixels per axis");
            assert!(resolution.is_multiple_of(network.size_multiple()), "{resolution} pixels for {network:?}");
            network.spatial_axes == 2 && network.in_channels == POISSON_CNN_CHANNELS && resolution <= APPLIED_RESOLUTION
        }
    };
    let limits = model.limits();
    assert!(limits.min_size > 0.0 && limits.min_size.is_finite() && limits.max_elements > 0, "{limits:?}");
    assert!(limits.final_step_scale > 0.0 && limits.final_step_scale.is_finite(), "{limits:?}");
    if applies {
        apply(model);
    }
}

/// One generation step of `model` on the Poisson problem, under the targets' element cap.
fn apply(mut model: TrainedModel) {
    let problem = PoissonProblem::from_json(PROBLEM, Path::new("seed-lshape.json")).expect("the seed problem reads");
    let limits = model.limits_mut();
    // The generator's own cap is four times the budget.
    limits.max_elements = limits.max_elements.min(ELEMENT_CAP / 4);
    limits.scale_to_budget = true;
    match model.generate(&problem, 1, FinalStep::default()) {
        Ok(steps) => {
            for step in steps {
                assert_valid(&step.mesh);
                assert!(step.mesh.num_elements() <= ELEMENT_CAP, "{} triangles over the cap", step.mesh.num_elements());
            }
        }
        Err(TrainError::MissingInputs(_) | TrainError::Generation { .. }) => {}
        Err(e) => panic!("a model that loaded fails on a Poisson part: {e}"),
    }
}

/// Bytes of training state per network parameter: the weight, its gradient and Adam's two moments.
const TRAINING_BYTES_PER_PARAMETER: usize = 16;

/// What amber promises every command's memory stays under (issue #26).
const MEMORY_BUDGET: usize = 2 << 30;

/// A training configuration (the first byte picks AMBER's or the CNN's), parsed as `amber train
/// --config` merges it over a profile (absent fields keep the quick profile's) and validated. A
/// configuration that validates is within its documented bounds, its network's training state
/// fits in the memory budget, and its learning rate stays within [0, peak] over the run.
pub fn training_config(data: &[u8]) {
    let Some((&kind, json)) = data.split_first() else { return };
    if kind % 2 == 0 {
        let Ok(config) = serde_json::from_slice::<TrainingConfig>(json) else { return };
        if config.validate().is_err() {
            return;
        }
        let network = &config.network;
        assert!((1..=1_024).contains(&network.latent_dim), "latent_dim {}", network.latent_dim);
        assert!(network.message_passing_steps <= 256, "{} steps", network.message_passing_steps);
        assert!(config.data.train_problems >= 1 && config.data.train_problems <= 100_000);
        let steps = config.inference_steps;
        assert!((1..=TrainingConfig::MAX_INFERENCE_STEPS).contains(&steps), "{steps} generation steps");
        let parameters = config.network_parameters();
        assert!(
            parameters.saturating_mul(TRAINING_BYTES_PER_PARAMETER) <= MEMORY_BUDGET,
            "{parameters} parameters accepted: {} GB of training state",
            parameters.saturating_mul(TRAINING_BYTES_PER_PARAMETER) >> 30
        );
        assert_schedule(config.lr_schedule, config.learning_rate, config.steps);
    } else {
        let Ok(config) = serde_json::from_slice::<CnnConfig>(json) else { return };
        if config.validate().is_err() {
            return;
        }
        assert!(config.resolution <= CnnConfig::MAX_RESOLUTION && config.resolution.is_multiple_of(16));
        assert!((1..=1_024).contains(&config.initial_channels), "initial_channels {}", config.initial_channels);
        assert_schedule(LrSchedule::Constant, config.learning_rate, config.steps);
    }
}

/// The rate of the first, middle and last steps lies in [0, peak].
fn assert_schedule(schedule: LrSchedule, peak: f64, steps: u64) {
    for step in [0, steps / 2, steps - 1] {
        let rate = schedule.rate(peak, step, steps);
        assert!((0.0..=peak).contains(&rate), "{schedule:?}: rate {rate} at step {step} of {steps}, peak {peak}");
    }
}
