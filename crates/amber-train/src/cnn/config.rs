//! Every knob of a CNN training run ([`CnnConfig`]) and its named profiles.

use amber_cnn::UNetConfig;
use amber_graph::Aggregation;
use amber_nn::Objective;
use serde::{Deserialize, Serialize};

use crate::config::{PAPER_LEARNING_RATE, PAPER_MAX_GRAD_NORM};
use crate::error::{Result, TrainError};
use crate::{DataConfig, Profile};

/// Every knob of a CNN training run. Defaults are the `quick` profile.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CnnConfig {
    /// Seeds the network initialisation and the image subsets.
    pub seed: u64,
    /// Data the run reads.
    pub data: DataConfig,
    /// Pixels (voxels) per axis of the grid over the bounding box; a multiple of 16.
    pub resolution: usize,
    /// Channels of the U-Net's first level (the paper's runs 64, its text 32).
    pub initial_channels: usize,
    /// Output transform and loss (`loss` in the JSON); not `softplus_residual`, which needs a
    /// current mesh.
    #[serde(rename = "loss")]
    pub objective: Objective,
    /// Mean or max projection of the expert onto the auxiliary mesh.
    pub aggregation: Aggregation,
    /// Gradient steps.
    pub steps: u64,
    /// Adam learning rate.
    pub learning_rate: f64,
    /// Global gradient-norm clip.
    pub max_grad_norm: Option<f64>,
    /// Training images per step, drawn without replacement; `None`: all (the paper).
    pub images_per_step: Option<usize>,
    /// Normalise the input channels by their moments over all training pixels.
    pub normalise_inputs: bool,
    /// Regress the targets standardised by their moments over the training pixels inside the
    /// geometry (the later version's "Image (Var.)"); not with `softplus_mse`, whose targets are
    /// sizes behind a non-linear output.
    pub normalise_labels: bool,
    /// Element budget = `budget_factor` × the largest training expert mesh.
    pub budget_factor: f64,
    /// Predictions are clipped below at this quantile of the training experts' element sizes.
    pub min_size_quantile: f64,
    /// Write a checkpoint every this many steps (and at the end).
    pub checkpoint_interval: u64,
}

impl Default for CnnConfig {
    fn default() -> Self {
        Self::quick()
    }
}

impl CnnConfig {
    /// The finest grid a run (and a model file) may ask for, pixels per axis.
    pub const MAX_RESOLUTION: usize = 2_048;

    /// The paper's runs (spec §8, reference notes §8): resolution 256, 64 initial channels, MSE
    /// on log sizes, mean labels, all 20 images in every one of 25,600 steps, Adam 3e-4, clip
    /// 0.5. GPU scale.
    pub fn paper() -> Self {
        Self {
            seed: 0,
            data: DataConfig::default(),
            resolution: 256,
            initial_channels: 64,
            objective: Objective::LogMse,
            aggregation: Aggregation::Mean,
            steps: 25_600,
            learning_rate: PAPER_LEARNING_RATE,
            max_grad_norm: Some(PAPER_MAX_GRAD_NORM),
            images_per_step: None,
            normalise_inputs: true,
            normalise_labels: false,
            budget_factor: 1.2,
            min_size_quantile: 0.0,
            checkpoint_interval: 1_000,
        }
    }

    /// Two CPU cores: the paper's text width (32 channels), 2 random images per step,
    /// standardised log-size targets and learning rate 1e-3,
    /// which spare the hundreds of steps the output layer otherwise needs just to reach log sizes
    /// around −5.
    pub fn quick() -> Self {
        Self {
            initial_channels: 32,
            steps: 400,
            learning_rate: 1e-3,
            images_per_step: Some(2),
            normalise_labels: true,
            checkpoint_interval: 100,
            ..Self::paper()
        }
    }

    /// For CI: two easy problems on a 32² grid, a narrow network, a few steps.
    pub fn smoke() -> Self {
        Self {
            data: DataConfig { train_problems: 2, val_problems: 2 },
            resolution: 32,
            initial_channels: 8,
            steps: 20,
            images_per_step: None,
            checkpoint_interval: 10,
            ..Self::quick()
        }
    }

    /// The config of a named profile.
    pub fn profile(profile: Profile) -> Self {
        match profile {
            Profile::Smoke => Self::smoke(),
            Profile::Quick => Self::quick(),
            Profile::Paper => Self::paper(),
        }
    }

    /// The U-Net of this run for inputs with `in_channels` channels in `D` dimensions.
    pub fn network<const D: usize>(&self, in_channels: usize) -> UNetConfig {
        UNetConfig { spatial_axes: D, in_channels, initial_channels: self.initial_channels, depth: 4 }
    }

    /// Checks ranges; the message names the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(TrainError::InvalidConfig(m.to_owned()));
        let multiple = UNetConfig { spatial_axes: 2, in_channels: 1, initial_channels: 1, depth: 4 }.size_multiple();
        if self.resolution == 0 || !self.resolution.is_multiple_of(multiple) {
            return bad("resolution must be a positive multiple of 16 (four poolings by 2)");
        }
        if self.initial_channels == 0 || self.steps == 0 || self.checkpoint_interval == 0 {
            return bad("initial_channels, steps and checkpoint_interval must be positive");
        }
        if !(self.learning_rate.is_finite() && self.learning_rate > 0.0) {
            return bad("learning_rate must be positive");
        }
        if self.max_grad_norm.is_some_and(|c| !(c.is_finite() && c > 0.0)) {
            return bad("max_grad_norm must be positive");
        }
        if self.images_per_step == Some(0) {
            return bad("images_per_step must be positive (or absent: all)");
        }
        if !(self.budget_factor.is_finite() && self.budget_factor > 0.0) {
            return bad("budget_factor must be positive");
        }
        if !(0.0..=1.0).contains(&self.min_size_quantile) {
            return bad("min_size_quantile must be in [0, 1]");
        }
        if self.objective.needs_current_size() {
            return bad("loss softplus_residual needs a current mesh; the CNN predicts from the geometry alone");
        }
        if self.normalise_labels && !self.objective.supports_label_normalisation() {
            return bad("normalise_labels needs loss log_mse or mse");
        }
        // Upper bounds that a machine can hold, so that a typo is an error, not an abort.
        if self.resolution > Self::MAX_RESOLUTION
            || self.initial_channels > 1_024
            || self.data.train_problems > 1_000_000
        {
            return Err(TrainError::InvalidConfig(format!(
                "resolution at most {}, initial_channels at most 1024, data.train_problems at most 1000000",
                Self::MAX_RESOLUTION
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profiles_are_valid_and_round_trip_through_json() {
        for profile in Profile::ALL {
            let config = CnnConfig::profile(profile);
            config.validate().unwrap();
            let json = serde_json::to_string(&config).unwrap();
            assert_eq!(serde_json::from_str::<CnnConfig>(&json).unwrap(), config);
        }
        let partial: CnnConfig = serde_json::from_str(r#"{"resolution": 64, "loss": "softplus_mse"}"#).unwrap();
        assert_eq!(partial, CnnConfig { resolution: 64, objective: Objective::SoftplusMse, ..CnnConfig::quick() });
        assert!(CnnConfig { resolution: 40, ..CnnConfig::quick() }.validate().is_err());
        assert!(CnnConfig { images_per_step: Some(0), ..CnnConfig::quick() }.validate().is_err());
        assert!(
            CnnConfig { objective: Objective::SoftplusMse, normalise_labels: true, ..CnnConfig::quick() }
                .validate()
                .is_err()
        );
        assert!(CnnConfig { objective: Objective::SoftplusResidual, ..CnnConfig::quick() }.validate().is_err());
    }
}
