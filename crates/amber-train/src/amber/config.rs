//! Every knob of an AMBER training run ([`TrainingConfig`]) and its named profiles.

use amber_graph::{Aggregation, EdgeFeature};
use amber_mpn::{MpnConfig, NetworkConfig};
use amber_nn::{Backend, Objective};
use serde::{Deserialize, Serialize};

use crate::config::{PAPER_LEARNING_RATE, PAPER_MAX_GRAD_NORM};
use crate::error::{Result, TrainError};
use crate::{DataConfig, LrSchedule, Profile};

/// How the source of a new buffer entry is chosen (spec §6, reference notes §6.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SourceSelection {
    /// A depth uniformly among the depths present (≤ the maximum), then an entry of that depth.
    Stratified,
    /// An entry uniformly among all entries of allowed depth (the "random additions" ablation).
    Uniform,
}

/// Every knob of a training run. Defaults are the `quick` profile.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrainingConfig {
    /// Seeds the network initialisation, edge dropout and buffer sampling.
    pub seed: u64,
    /// Data the run reads.
    pub data: DataConfig,
    /// AMBER-Mean or AMBER-Max labels (spec §3).
    pub aggregation: Aggregation,
    /// Output transform and loss.
    pub objective: Objective,
    /// Normalise the training targets by their running moments (not for a softplus in the loss,
    /// see [`Objective::supports_label_normalisation`]).
    pub normalise_labels: bool,
    /// Normalise node and edge features by their running moments (off: the ablation).
    pub normalise_inputs: bool,
    /// Extra node inputs appended in order to the task's features, by column name: `log_size`
    /// (log h(K), any task) or one of the task's optional inputs
    /// (`amber_tasks::Problem::optional_inputs`); none in the paper.
    pub inputs: Vec<String>,
    /// The edge features, replacing the task's own (the paper's: Poisson the midpoint distance,
    /// Console the 3D midpoint difference vector); e.g. `["midpoint_distance"]` gives Console a
    /// network that cannot tell a part's orientation. None: the task's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_features: Option<Vec<EdgeFeature>>,
    /// Turn every graph of every training batch by a random rotation or reflection (its edge
    /// vectors, `midpoint_difference`), so that the network cannot learn the training parts'
    /// orientations and sees each part from many sides; the input normaliser then treats every
    /// axis alike. Needs an edge vector feature; off in the paper.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub random_orientation: bool,
    /// The network.
    pub network: NetworkConfig,
    /// Gradient steps.
    pub steps: u64,
    /// Peak Adam learning rate.
    pub learning_rate: f64,
    /// Learning-rate schedule.
    pub lr_schedule: LrSchedule,
    /// Global gradient-norm clip.
    pub max_grad_norm: Option<f64>,
    /// Keep an exponential moving average of the weights with this decay per step (Polyak
    /// averaging, `amber_mpn::MpnTrainer::with_weight_average`): the average is the model that
    /// fills the buffer, validates and is written; off in the paper.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weight_average_decay: Option<f64>,
    /// Node budget of one batch (least-used graphs first, stop at the first that does not fit).
    pub batch_nodes: usize,
    /// Generated meshes kept in the FIFO part of the buffer (protected entries not counted).
    pub buffer_capacity: usize,
    /// One new buffer entry after every `add_interval` gradient steps.
    pub add_interval: u64,
    /// Deepest entry used as the source of a new entry (new entries get source depth + 1).
    pub max_source_depth: usize,
    /// How the source entry is chosen.
    pub source_selection: SourceSelection,
    /// Element budget = `budget_factor` × the largest training expert mesh.
    pub budget_factor: f64,
    /// Predicted sizes are clipped below at this quantile of all training expert element sizes
    /// (0: the minimum, as for Poisson; the Console task uses 0.005).
    pub min_size_quantile: f64,
    /// Generation steps T of a rollout (validation and inference).
    pub inference_steps: usize,
    /// After training, fit the model's final step scale to the training experts' element counts
    /// (`fit_final_step`); off in the paper.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub calibrate_element_count: bool,
    /// With `calibrate_element_count`, also fit the last step's element count as a regression of
    /// the training experts' log counts on the model's (`amber_tasks::FinalCount`): a model whose
    /// counts do not follow its experts' then meshes every geometry to their typical count.
    /// Omitted from the JSON when off.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub count_regression: bool,
    /// Write a checkpoint every this many steps (and at the end).
    pub checkpoint_interval: u64,
    /// Roll out the validation problems every this many steps (and at the end); 0: never.
    pub validation_interval: u64,
    /// Where the network trains: `"cpu"` (the fused kernels), or `{"cuda": 0}` in a build with
    /// the `cuda` feature (stock candle ops; not bit-reproducible, CUDA's scatter-adds race).
    /// Rollouts, meshing and inference stay on the CPU.
    #[serde(skip_serializing_if = "Backend::is_cpu")]
    pub device: Backend,
}

impl Default for TrainingConfig {
    fn default() -> Self {
        Self::quick()
    }
}

impl TrainingConfig {
    /// The most generation steps a rollout may take (`inference_steps`, and a model card's).
    pub const MAX_INFERENCE_STEPS: usize = 10_000;

    /// The most parameters the network may have ([`Self::network_parameters`]): 1.6 GB of
    /// weights, gradients and Adam moments (the widest network, 1,024, at the default 10 steps
    /// has 86 million).
    pub const MAX_NETWORK_PARAMETERS: usize = 100_000_000;

    /// The paper's settings (spec §5, §6): Poisson hard, AMBER-Mean, softplus output with MSE on
    /// raw sizes, constant Adam 3e-4, clip 0.5, 400,000-node batches, 1,000-entry buffer with an
    /// addition every 8 steps, 128,000 steps, validation every 256-step iteration. Meant for a GPU
    /// (set [`TrainingConfig::device`]).
    pub fn paper() -> Self {
        Self {
            seed: 0,
            data: DataConfig::default(),
            aggregation: Aggregation::Mean,
            objective: Objective::SoftplusMse,
            normalise_labels: false,
            normalise_inputs: true,
            inputs: Vec::new(),
            edge_features: None,
            random_orientation: false,
            network: NetworkConfig::default(),
            steps: 128_000,
            learning_rate: PAPER_LEARNING_RATE,
            lr_schedule: LrSchedule::Constant,
            max_grad_norm: Some(PAPER_MAX_GRAD_NORM),
            weight_average_decay: None,
            batch_nodes: 400_000,
            buffer_capacity: 1_000,
            add_interval: 8,
            max_source_depth: 4,
            source_selection: SourceSelection::Stratified,
            budget_factor: 1.2,
            min_size_quantile: 0.0,
            inference_steps: 5,
            calibrate_element_count: false,
            count_regression: false,
            checkpoint_interval: 2_560,
            validation_interval: 2_560,
            device: Backend::Cpu,
        }
    }

    /// The default: the best quality reachable within about 30 minutes of training per variant
    /// on two CPU cores. The later version's levers (§11): residual in softplus space with
    /// normalised labels, learning rate 1e-3 with 5 % warm-up and linear decay; plus the log-size
    /// input and the network's graph context. Small batches (12,000 nodes, about one generated
    /// mesh) so that many steps fit, an addition every 4 steps so the buffer fills with the
    /// model's own meshes early, a 500-entry buffer. Tasks adjust it (amber-experiments'
    /// profile table); the evidence is in docs/PROFILES.md.
    pub fn quick() -> Self {
        Self {
            objective: Objective::SoftplusResidual,
            normalise_labels: true,
            inputs: vec![amber_tasks::LOG_SIZE_COLUMN.into()],
            network: NetworkConfig { graph_context: true, ..NetworkConfig::default() },
            steps: 2_500,
            learning_rate: 1e-3,
            lr_schedule: LrSchedule::WarmupLinearDecay { warmup_fraction: 0.05 },
            batch_nodes: 12_000,
            buffer_capacity: 500,
            add_interval: 4,
            checkpoint_interval: 250,
            validation_interval: 1_250,
            ..Self::paper()
        }
    }

    /// For CI: two easy training problems, a small network and a few hundred steps; every part
    /// of the loop (additions, eviction, checkpoints, validation) runs at least once.
    pub fn smoke() -> Self {
        Self {
            data: DataConfig { train_problems: 2, val_problems: 2 },
            network: NetworkConfig { latent_dim: 32, message_passing_steps: 4, ..Self::quick().network },
            steps: 200,
            batch_nodes: 4_000,
            buffer_capacity: 20,
            add_interval: 4,
            checkpoint_interval: 100,
            validation_interval: 100,
            inference_steps: 3,
            ..Self::quick()
        }
    }

    /// Parameters of the configured network for the widest inputs a task gives it (node: the
    /// Poisson task's four features and the configured inputs; edge: the 3D midpoint difference).
    pub fn network_parameters(&self) -> usize {
        let widest =
            MpnConfig { node_features: 4 + self.inputs.len(), edge_features: 3, network: self.network.clone() };
        widest.num_parameters()
    }

    /// The config of a named profile.
    pub fn profile(profile: Profile) -> Self {
        match profile {
            Profile::Smoke => Self::smoke(),
            Profile::Quick => Self::quick(),
            Profile::Paper => Self::paper(),
        }
    }

    /// Checks ranges and combinations; the message names the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(TrainError::InvalidConfig(m.to_owned()));
        if self.steps == 0 {
            return bad("steps must be positive");
        }
        if self.edge_features.as_ref().is_some_and(Vec::is_empty) {
            return bad("edge_features must name at least one feature (or be left out: the task's)");
        }
        if !(self.learning_rate.is_finite() && self.learning_rate > 0.0) {
            return bad("learning_rate must be positive");
        }
        if let LrSchedule::WarmupLinearDecay { warmup_fraction } = self.lr_schedule
            && !(0.0..1.0).contains(&warmup_fraction)
        {
            return bad("lr_schedule.warmup_fraction must be in [0, 1)");
        }
        if self.max_grad_norm.is_some_and(|c| !(c.is_finite() && c > 0.0)) {
            return bad("max_grad_norm must be positive");
        }
        if self.count_regression && !self.calibrate_element_count {
            return bad("count_regression needs calibrate_element_count");
        }
        if self.weight_average_decay.is_some_and(|d| !(0.0..1.0).contains(&d)) {
            return bad("weight_average_decay must be in [0, 1)");
        }
        if self.batch_nodes == 0 || self.add_interval == 0 || self.checkpoint_interval == 0 {
            return bad("batch_nodes, add_interval and checkpoint_interval must be positive");
        }
        if !(self.budget_factor.is_finite() && self.budget_factor > 0.0) {
            return bad("budget_factor must be positive");
        }
        if !(0.0..=1.0).contains(&self.min_size_quantile) {
            return bad("min_size_quantile must be in [0, 1]");
        }
        if self.normalise_labels && !self.objective.supports_label_normalisation() {
            return bad("normalise_labels needs an objective other than softplus_mse");
        }
        if self.network.latent_dim == 0 || !(0.0..1.0).contains(&self.network.edge_dropout) {
            return bad("network.latent_dim must be positive and network.edge_dropout in [0, 1)");
        }
        if self.data.train_problems == 0 {
            return bad("data.train_problems must be positive");
        }
        if self.inference_steps == 0 {
            // Validation would score M⁰ alone, and the model's card would hold no step to take.
            return bad("inference_steps must be positive");
        }
        // Upper bounds that a machine can hold, so that a typo is an error, not an abort.
        let limits: [(&str, u64, u64); 7] = [
            ("network.latent_dim", self.network.latent_dim as u64, 1_024),
            ("network.message_passing_steps", self.network.message_passing_steps as u64, 256),
            ("batch_nodes", self.batch_nodes as u64, 100_000_000),
            ("buffer_capacity", self.buffer_capacity as u64, 1_000_000),
            ("data.train_problems", self.data.train_problems as u64, DataConfig::MAX_PROBLEMS as u64),
            ("data.val_problems", self.data.val_problems as u64, DataConfig::MAX_PROBLEMS as u64),
            ("inference_steps", self.inference_steps as u64, Self::MAX_INFERENCE_STEPS as u64),
        ];
        if let Some((field, value, max)) = limits.into_iter().find(|&(_, value, max)| value > max) {
            return Err(TrainError::InvalidConfig(format!("{field} is {value}, at most {max} is supported")));
        }
        // Each width and depth within its bound can still multiply to a network no machine holds.
        let parameters = self.network_parameters();
        if parameters > Self::MAX_NETWORK_PARAMETERS {
            return Err(TrainError::InvalidConfig(format!(
                "network: {parameters} parameters (latent_dim {}, {} message-passing steps), at most {} are supported",
                self.network.latent_dim,
                self.network.message_passing_steps,
                Self::MAX_NETWORK_PARAMETERS
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
            let config = TrainingConfig::profile(profile);
            config.validate().unwrap();
            let json = serde_json::to_string(&config).unwrap();
            assert_eq!(serde_json::from_str::<TrainingConfig>(&json).unwrap(), config);
            assert_eq!(profile.name().parse::<Profile>().unwrap(), profile);
        }
        let partial: TrainingConfig = serde_json::from_str(r#"{"steps": 10, "aggregation": "max"}"#).unwrap();
        let expected = TrainingConfig { steps: 10, aggregation: Aggregation::Max, ..TrainingConfig::quick() };
        assert_eq!(partial, expected, "absent fields are the quick profile's");
        assert!(serde_json::from_str::<TrainingConfig>(r#"{"stepz": 10}"#).is_err());
        // The device joined the config after runs were cached under its JSON: the CPU is not
        // written, so their keys stay.
        assert!(!serde_json::to_string(&TrainingConfig::quick()).unwrap().contains("device"));
        assert!(!serde_json::to_string(&TrainingConfig::quick()).unwrap().contains("count_regression"));
        let uncalibrated = TrainingConfig { count_regression: true, ..TrainingConfig::paper() };
        assert!(uncalibrated.validate().unwrap_err().to_string().contains("needs calibrate_element_count"));
        let gpu: TrainingConfig = serde_json::from_str(r#"{"device": {"cuda": 0}}"#).unwrap();
        assert_eq!(gpu.device, Backend::Cuda(0));
        let bad =
            TrainingConfig { objective: Objective::SoftplusMse, normalise_labels: true, ..TrainingConfig::quick() };
        assert!(bad.validate().is_err());
        let huge = TrainingConfig {
            network: NetworkConfig { latent_dim: 1_000_000_000, ..NetworkConfig::default() },
            ..TrainingConfig::quick()
        };
        let message = huge.validate().unwrap_err().to_string();
        assert!(message.contains("network.latent_dim") && message.contains("1024"), "{message}");
    }

    #[test]
    fn networks_must_fit_and_rollouts_take_a_step() {
        // As the fuzz input fuzz/corpus/training_config/crash-network-too-large (1.9 billion
        // parameters, 28 GB of training state): each field within its own bound.
        let wide_and_deep = |latent_dim, message_passing_steps| TrainingConfig {
            network: NetworkConfig { latent_dim, message_passing_steps, ..TrainingConfig::quick().network },
            ..TrainingConfig::quick()
        };
        let message = wide_and_deep(1_024, 256).validate().unwrap_err().to_string();
        assert!(message.contains("network: 2151953409 parameters") && message.contains("100000000"), "{message}");
        wide_and_deep(1_024, 10).validate().unwrap();
        // As fuzz/corpus/training_config/crash-zero-inference-steps: a model trained so had a card
        // that `amber mesh` cannot use.
        let none = TrainingConfig { inference_steps: 0, ..TrainingConfig::quick() };
        assert!(none.validate().unwrap_err().to_string().contains("inference_steps must be positive"));
        wide_and_deep(64, 256).validate().unwrap();
        assert!(wide_and_deep(1_024, 12).validate().is_err());
    }
}
