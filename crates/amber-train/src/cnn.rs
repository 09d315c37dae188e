//! The U-Net CNN baseline (spec §8, reference notes §8), trained and evaluated on any
//! [`Problem`]: an auxiliary uniform mesh of the problem's geometry with about two elements per
//! pixel carries the task's input columns; they and a ±1 inside mask are rasterised onto an rᴰ
//! grid over the geometry's bounding box; labels are the expert's projected sizing field (mean or
//! max, spec §3) on the auxiliary mesh, copied to the pixels; the loss sees inside pixels only.
//! One prediction is one generation step: the pixel field (outside pixels filled from the nearest
//! inside pixel) is read at the auxiliary elements' midpoints (nearest pixel), clipped at h_min,
//! guarded by the element budget and meshed by the same generator as AMBER's steps.
//!
//! Training uses the same training images every step (all of them, or a seeded random subset
//! when memory asks for it), Adam with global-norm clipping, and checkpoints that resume exactly.

use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_cnn::{CnnLoss, CnnTrainer, PixelGrid, Raster, TrainingImages, UNet, UNetConfig};
use amber_graph::{Aggregation, GraphError, NodeFeature, RunningMoments, VARIANCE_EPSILON};
use amber_mesh::Mesh;
use amber_meshgen::SizingField;
use amber_stdx::{read_json, write_json_atomic};
use amber_tasks::{MeshLimits, Problem, StepOutcome, generation_step, labels};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::checkpoint::{self, OPTIMISER_FILE, ProblemFingerprint, RngState, STATE_FILE, fingerprints, seeded_stream};
use crate::error::{Result, TrainError, in_problem, io_error};
use crate::{BufferEntry, DataConfig, MeshMetrics, Profile, Reference, Rollout, RolloutStep, StepStatus};

/// File of the U-Net weights (and BatchNorm statistics) inside a CNN model directory.
pub const CNN_WEIGHTS_FILE: &str = "cnn.safetensors";
/// File of everything else of a CNN model ([`CnnPredictor`]).
pub const CNN_PREDICTOR_FILE: &str = "cnn.json";

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
    /// Output transform and loss.
    pub loss: CnnLoss,
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
    /// The paper's runs (spec §8, reference notes §8): resolution 256, 64 initial channels, MSE
    /// on log sizes, mean labels, all 20 images in every one of 25,600 steps, Adam 3e-4, clip
    /// 0.5. GPU scale.
    pub fn paper() -> Self {
        Self {
            seed: 0,
            data: DataConfig::default(),
            resolution: 256,
            initial_channels: 64,
            loss: CnnLoss::LogMse,
            aggregation: Aggregation::Mean,
            steps: 25_600,
            learning_rate: 3e-4,
            max_grad_norm: Some(0.5),
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
        if self.normalise_labels && self.loss == CnnLoss::SoftplusMse {
            return bad("normalise_labels needs loss log_mse or mse");
        }
        // Upper bounds that a machine can hold, so that a typo is an error, not an abort.
        if self.resolution > 2_048 || self.initial_channels > 1_024 || self.data.train_problems > 1_000_000 {
            return bad("resolution at most 2048, initial_channels at most 1024, data.train_problems at most 1000000");
        }
        Ok(())
    }
}

/// Everything of a trained CNN except its weights.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CnnPredictor {
    pub network: UNetConfig,
    /// Pixels per axis.
    pub resolution: usize,
    pub loss: CnnLoss,
    /// Moments of the input channels over the training pixels; `None`: inputs are fed raw.
    pub normaliser: Option<RunningMoments>,
    /// Moments of the targets over the inside training pixels; `None`: the network regresses
    /// the raw targets.
    pub label_moments: Option<RunningMoments>,
    /// h_min and the element budget (from the training experts).
    pub limits: MeshLimits,
}

/// One problem's auxiliary mesh, rasterised, with the network input of its pixels.
struct Rasterised<const D: usize> {
    auxiliary: Mesh<D>,
    raster: Raster<D>,
    /// Channel-major `(columns + mask) × pixels`, not normalised.
    channels: Vec<f32>,
}

/// Target size of the auxiliary mesh's elements: the reference's element volume
/// vol(bounding box)/(2·rᴰ), about two elements per pixel.
fn auxiliary_size<const D: usize>(grid: &PixelGrid<D>) -> f64 {
    amber_mesh::size_from_volume::<D>(grid.cell_volume() / 2.0)
}

/// Meshes the auxiliary mesh of `problem` for a grid of `resolution` pixels per axis over its
/// geometry's bounding box, computes its columns and rasterises them.
fn rasterise<const D: usize, P: Problem<D> + ?Sized>(
    problem: &P,
    index: usize,
    resolution: usize,
) -> Result<Rasterised<D>> {
    let initial = problem.initial_mesh();
    let grid = PixelGrid::over_mesh(initial, resolution)?;
    let size = auxiliary_size(&grid);
    let expected = initial.total_volume() / amber_mesh::volume_from_size::<D>(size);
    let cap = (4.0 * expected) as usize + 1_000;
    let auxiliary = problem.remesh(initial, vec![size; initial.num_elements()], cap).map_err(in_problem(index))?;
    let raster = Raster::new(grid, &auxiliary)?;
    // The task's own input columns, in its feature set's order: a problem may compute more
    // (optional AMBER inputs) than the baseline reads.
    let columns = problem.columns(&auxiliary).map_err(in_problem(index))?;
    let values: Vec<&[f64]> = problem
        .feature_set()
        .node
        .iter()
        .filter_map(|feature| match feature {
            NodeFeature::Column(name) => Some(name),
            _ => None,
        })
        .map(|name| {
            let column = columns.iter().find(|c| &c.name == name);
            column
                .map(|c| c.values.as_slice())
                .ok_or_else(|| in_problem(index)(GraphError::MissingColumn { name: name.clone() }))
        })
        .collect::<Result<_>>()?;
    let channels = raster.channels(&values)?;
    Ok(Rasterised { auxiliary, raster, channels })
}

/// Channel-major `channels × pixels` ↔ pixel-major rows (the normaliser's layout).
fn transpose(data: &[f32], rows: usize, cols: usize) -> Vec<f32> {
    let mut out = vec![0.0; data.len()];
    for r in 0..rows {
        for c in 0..cols {
            out[c * rows + r] = data[r * cols + c];
        }
    }
    out
}

impl CnnPredictor {
    /// The normalised network input of one rasterised problem, channel-major `C × pixels`.
    fn input<const D: usize>(&self, sample: &Rasterised<D>) -> Result<Vec<f32>> {
        let (channels, pixels) = (self.network.in_channels, sample.raster.grid.len());
        if sample.channels.len() != channels * pixels {
            return Err(TrainError::InvalidConfig(format!(
                "the problem gives {} input channels, the network takes {channels}",
                sample.channels.len() / pixels
            )));
        }
        Ok(match &self.normaliser {
            Some(moments) => {
                let mut rows = transpose(&sample.channels, channels, pixels);
                moments.normalise(&mut rows)?;
                transpose(&rows, pixels, channels)
            }
            None => sample.channels.clone(),
        })
    }

    /// The predicted size of every auxiliary element: the network's pixel field, outside pixels
    /// filled from inside ones, read at the element midpoints.
    fn predict<const D: usize>(&self, network: &UNet, sample: &Rasterised<D>) -> Result<Vec<f64>> {
        let shape: Vec<usize> = [1, self.network.in_channels].into_iter().chain(sample.raster.grid.shape).collect();
        let z = network.predict(&self.input(sample)?, &shape)?;
        let (scale, shift) = match &self.label_moments {
            Some(m) => ((m.variance()[0] + VARIANCE_EPSILON).sqrt(), m.mean()[0]),
            None => (1.0, 0.0),
        };
        let mut sizes: Vec<f64> = z.into_iter().map(|z| self.loss.size(f64::from(z) * scale + shift)).collect();
        sample.raster.fill_outside(&mut sizes)?;
        let field = sample.raster.grid.sizing(sizes);
        Ok(sample.auxiliary.midpoints().into_iter().map(|x| field.size_at(x)).collect())
    }
}

/// A trained CNN ready for inference.
pub struct CnnModel {
    pub network: UNet,
    pub predictor: CnnPredictor,
}

impl CnnModel {
    /// Writes `cnn.safetensors` and `cnn.json` into `dir` (created if missing).
    pub fn save(network: &UNet, predictor: &CnnPredictor, dir: &Path) -> Result<()> {
        std::fs::create_dir_all(dir).map_err(io_error(dir))?;
        network.save(&dir.join(CNN_WEIGHTS_FILE))?;
        Ok(write_json_atomic(&dir.join(CNN_PREDICTOR_FILE), predictor)?)
    }

    /// Loads a model directory written by [`Self::save`] (a checkpoint directory is one too).
    pub fn load(dir: &Path) -> Result<Self> {
        let predictor: CnnPredictor = read_json(&dir.join(CNN_PREDICTOR_FILE))?;
        let network = UNet::load(predictor.network.clone(), &dir.join(CNN_WEIGHTS_FILE))?;
        Ok(Self { network, predictor })
    }

    /// One generation step from M⁰ for every problem (see [`cnn_rollouts`]).
    pub fn rollouts<const D: usize, P: Problem<D>>(
        &self,
        problems: &[P],
        references: &[Reference<D>],
    ) -> Result<Vec<Rollout<D>>> {
        cnn_rollouts(&self.network, &self.predictor, problems, references)
    }
}

/// One generation step from M⁰ for every problem (the CNN predicts once), as rollouts with the
/// same metrics as AMBER's; `references[i]` belongs to `problems[i]`. A step over the budget or
/// failed keeps M⁰ and its metrics.
pub fn cnn_rollouts<const D: usize, P: Problem<D>>(
    network: &UNet,
    predictor: &CnnPredictor,
    problems: &[P],
    references: &[Reference<D>],
) -> Result<Vec<Rollout<D>>> {
    if problems.len() != references.len() {
        return Err(TrainError::InvalidConfig(format!(
            "{} problems but {} references",
            problems.len(),
            references.len()
        )));
    }
    problems.par_iter().zip(references).enumerate().map(|(i, (p, r))| rollout(network, predictor, p, r, i)).collect()
}

fn rollout<const D: usize, P: Problem<D>>(
    network: &UNet,
    predictor: &CnnPredictor,
    problem: &P,
    reference: &Reference<D>,
    i: usize,
) -> Result<Rollout<D>> {
    let sample = rasterise(problem, i, predictor.resolution)?;
    let sizes = predictor.predict(network, &sample)?;
    let initial = MeshMetrics::of(problem.initial_mesh(), problem.expert_mesh(), reference).map_err(in_problem(i))?;
    let step = match generation_step(problem, &sample.auxiliary, sizes, &predictor.limits) {
        StepOutcome::Meshed(mesh) => {
            let metrics = MeshMetrics::of(&mesh, problem.expert_mesh(), reference).map_err(in_problem(i))?;
            RolloutStep { status: StepStatus::Meshed, mesh, metrics }
        }
        StepOutcome::OverBudget { estimated_elements } => RolloutStep {
            status: StepStatus::OverBudget { estimated_elements },
            mesh: problem.initial_mesh().clone(),
            metrics: initial,
        },
        StepOutcome::Failed { reason } => RolloutStep {
            status: StepStatus::Failed { reason },
            mesh: problem.initial_mesh().clone(),
            metrics: initial,
        },
    };
    Ok(Rollout {
        initial,
        steps: vec![step],
        initial_dcd: reference.initial_dcd,
        reconstruction_dcd: reference.reconstruction_dcd,
    })
}

/// One gradient step of a CNN run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CnnStepReport {
    /// Gradient steps completed, this one included.
    pub step: u64,
    /// Masked loss of the step's images.
    pub loss: f64,
    /// Global gradient norm before clipping.
    pub grad_norm: f64,
    pub images: usize,
    /// Wall time of the step.
    pub seconds: f64,
}

/// Progress callbacks of [`CnnTraining::run`] (the library never prints). Every method has an
/// empty default.
pub trait CnnObserver {
    /// After every gradient step.
    fn step(&mut self, _report: &CnnStepReport, _total_steps: u64) {}
    /// After every checkpoint.
    fn checkpoint(&mut self, _step: u64, _dir: &Path) {}
}

/// Observes nothing.
impl CnnObserver for () {}

/// `state.json` of a CNN checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct CnnState {
    config: CnnConfig,
    step: u64,
    optimiser_steps: u64,
    subset_rng: RngState,
    problems: Vec<ProblemFingerprint>,
}

/// A CNN training run.
pub struct CnnTraining<const D: usize, P: Problem<D>> {
    config: CnnConfig,
    problems: Vec<P>,
    trainer: CnnTrainer,
    predictor: CnnPredictor,
    step: u64,
    subset_rng: ChaCha8Rng,
}

impl<const D: usize, P: Problem<D>> CnnTraining<D, P> {
    /// Rasterises the problems, fits the input normaliser and the limits, and stacks the
    /// training images; the network is built by `network` from the predictor's configuration.
    fn prepare(
        config: &CnnConfig,
        problems: &[P],
        network: impl FnOnce(&CnnPredictor) -> Result<UNet>,
    ) -> Result<(UNet, CnnPredictor, TrainingImages)> {
        config.validate()?;
        if problems.is_empty() {
            return Err(TrainError::NoProblems);
        }
        let samples: Vec<(Rasterised<D>, Vec<f64>)> = problems
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let sample = rasterise(p, i, config.resolution)?;
                let labels = labels(p, &sample.auxiliary, config.aggregation).map_err(in_problem(i))?;
                Ok((sample, labels))
            })
            .collect::<Result<_>>()?;
        let pixels = samples[0].0.raster.grid.len();
        let channels = samples[0].0.channels.len() / pixels;
        if samples.iter().any(|(s, _)| s.channels.len() != channels * pixels) {
            return Err(TrainError::InvalidConfig("the problems give different numbers of input columns".into()));
        }
        let normaliser = config
            .normalise_inputs
            .then(|| {
                let mut moments = RunningMoments::new(channels);
                samples.iter().try_for_each(|(s, _)| moments.update(&transpose(&s.channels, channels, pixels)))?;
                Ok::<_, TrainError>(moments)
            })
            .transpose()?;
        let limits = MeshLimits::from_experts(
            problems.iter().map(|p| p.expert_mesh()),
            config.budget_factor,
            config.min_size_quantile,
        );
        // Targets of the inside pixels, image after image, for the label moments.
        let inside_targets: Vec<f32> = samples
            .iter()
            .flat_map(|(sample, labels)| {
                sample.raster.owners.iter().flatten().map(|&e| config.loss.target(labels[e as usize]) as f32)
            })
            .collect();
        let label_moments = config
            .normalise_labels
            .then(|| {
                let mut moments = RunningMoments::new(1);
                moments.update(&inside_targets)?;
                Ok::<_, TrainError>(moments)
            })
            .transpose()?;
        let predictor = CnnPredictor {
            network: config.network::<D>(channels),
            resolution: config.resolution,
            loss: config.loss,
            normaliser,
            label_moments,
            limits,
        };
        let mut normalised = inside_targets;
        if let Some(moments) = &predictor.label_moments {
            moments.normalise(&mut normalised)?;
        }
        let mut normalised = normalised.into_iter();
        let (mut inputs, mut targets, mut masks) = (Vec::new(), Vec::new(), Vec::new());
        for (sample, _) in &samples {
            inputs.extend(predictor.input(sample)?);
            for owner in &sample.raster.owners {
                targets.push(if owner.is_some() {
                    normalised.next().expect("one target per inside pixel")
                } else {
                    0.0
                });
                masks.push(if owner.is_some() { 1.0f32 } else { 0.0 });
            }
        }
        let spatial = samples[0].0.raster.grid.shape;
        let images = TrainingImages::new(inputs, targets, masks, samples.len(), channels, &spatial)?;
        Ok((network(&predictor)?, predictor, images))
    }

    /// A fresh run on `problems` with a network initialised from the seed.
    pub fn new(config: CnnConfig, problems: Vec<P>) -> Result<Self> {
        let (network, predictor, images) =
            Self::prepare(&config, &problems, |p| Ok(UNet::init(p.network.clone(), config.seed)?))?;
        let trainer = CnnTrainer::new(network, images, config.loss, config.max_grad_norm)?;
        Ok(Self { subset_rng: seeded_stream(config.seed, 3), config, problems, trainer, predictor, step: 0 })
    }

    /// Resumes the newest checkpoint under `out_dir` if there is one (the configuration and
    /// problems must be those of the checkpointed run), else starts afresh.
    pub fn open(config: CnnConfig, problems: Vec<P>, out_dir: &Path) -> Result<Self> {
        match checkpoint::latest_checkpoint(out_dir)? {
            Some(dir) => Self::resume(config, problems, &dir),
            None => Self::new(config, problems),
        }
    }

    /// Restores the run checkpointed in `dir` (the training images are rasterised again).
    pub fn resume(config: CnnConfig, problems: Vec<P>, dir: &Path) -> Result<Self> {
        let fail = |message: &str| TrainError::Checkpoint { path: dir.into(), message: message.into() };
        let state: CnnState = read_json(&dir.join(STATE_FILE))?;
        if state.config != config {
            return Err(fail("the configuration differs from the checkpointed run's"));
        }
        if state.problems != fingerprints(&problems) {
            return Err(fail("the training problems differ from the checkpointed run's"));
        }
        let saved: CnnPredictor = read_json(&dir.join(CNN_PREDICTOR_FILE))?;
        let (network, predictor, images) =
            Self::prepare(&config, &problems, |p| Ok(UNet::load(p.network.clone(), &dir.join(CNN_WEIGHTS_FILE))?))?;
        if saved != predictor {
            return Err(fail("the rasterised problems give another normaliser or limits than the checkpointed run's"));
        }
        let mut trainer = CnnTrainer::new(network, images, config.loss, config.max_grad_norm)?;
        trainer.load_optimiser(&dir.join(OPTIMISER_FILE), state.optimiser_steps)?;
        Ok(Self { subset_rng: state.subset_rng.restore(dir)?, config, problems, trainer, predictor, step: state.step })
    }

    /// The run's configuration.
    pub fn config(&self) -> &CnnConfig {
        &self.config
    }

    /// Gradient steps completed.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// Normaliser, loss and limits.
    pub fn predictor(&self) -> &CnnPredictor {
        &self.predictor
    }

    /// The network (sharing the trained variables; [`cnn_rollouts`] evaluates it as it stands).
    pub fn network(&self) -> &UNet {
        self.trainer.network()
    }

    /// The training problems.
    pub fn problems(&self) -> &[P] {
        &self.problems
    }

    /// One gradient step on all training images (or a random subset of them).
    pub fn train_step(&mut self) -> Result<CnnStepReport> {
        let started = Instant::now();
        let total = self.problems.len();
        let chosen = match self.config.images_per_step {
            Some(k) if k < total => {
                let mut picked = rand::seq::index::sample(&mut self.subset_rng, total, k).into_vec();
                picked.sort_unstable();
                Some(picked)
            }
            _ => None,
        };
        let step = self.trainer.train_step(chosen.as_deref(), self.config.learning_rate)?;
        self.step += 1;
        Ok(CnnStepReport {
            step: self.step,
            loss: step.loss,
            grad_norm: step.grad_norm,
            images: step.images,
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// Trains until `config.steps` from wherever the run stands, checkpoints every
    /// `checkpoint_interval` steps and at the end, and writes the final model to
    /// `out_dir/model`, which it returns.
    pub fn run(&mut self, out_dir: &Path, observer: &mut dyn CnnObserver) -> Result<PathBuf> {
        std::fs::create_dir_all(out_dir).map_err(io_error(out_dir))?;
        write_json_atomic(&out_dir.join(crate::CONFIG_FILE), &self.config)?;
        while self.step < self.config.steps {
            let report = self.train_step()?;
            observer.step(&report, self.config.steps);
            if self.step.is_multiple_of(self.config.checkpoint_interval) || self.step == self.config.steps {
                let dir = self.save_checkpoint(out_dir)?;
                observer.checkpoint(self.step, &dir);
            }
        }
        let model_dir = out_dir.join(crate::MODEL_DIR);
        self.save_model(&model_dir)?;
        Ok(model_dir)
    }

    /// Writes the current model to `dir`.
    pub fn save_model(&self, dir: &Path) -> Result<()> {
        CnnModel::save(self.trainer.network(), &self.predictor, dir)
    }

    /// Writes a checkpoint of the current state under `out_dir/checkpoints`; returns its
    /// directory.
    pub fn save_checkpoint(&self, out_dir: &Path) -> Result<PathBuf> {
        let state = CnnState {
            config: self.config.clone(),
            step: self.step,
            optimiser_steps: self.trainer.optimiser_steps(),
            subset_rng: RngState::of(&self.subset_rng),
            problems: fingerprints(&self.problems),
        };
        checkpoint::commit(out_dir, self.step, std::iter::empty::<&BufferEntry<D>>(), |dir| {
            self.save_model(dir)?;
            self.trainer.save_optimiser(&dir.join(OPTIMISER_FILE))?;
            Ok(write_json_atomic(&dir.join(STATE_FILE), &state)?)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_fem::ExpertHeuristic;
    use amber_graph::FeatureSet;
    use amber_mesh::Mesh3;
    use amber_tasks::poisson::{INITIAL_SIZE, PoissonProblem};

    use amber_tasks::{Column, ProblemError};

    /// Poisson problems with small experts (8 refinement steps).
    fn poisson(seeds: &[u64]) -> Vec<PoissonProblem> {
        seeds
            .iter()
            .map(|&s| PoissonProblem::generate(s, 8, INITIAL_SIZE, &ExpertHeuristic::default()).unwrap())
            .collect()
    }

    fn tiny(steps: u64) -> CnnConfig {
        CnnConfig {
            resolution: 16,
            initial_channels: 4,
            steps,
            checkpoint_interval: 5,
            learning_rate: 3e-3,
            ..CnnConfig::smoke()
        }
    }

    fn single_thread<T: Send>(f: impl FnOnce() -> T + Send) -> T {
        rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(f)
    }

    #[test]
    fn profiles_are_valid_and_round_trip_through_json() {
        for profile in Profile::ALL {
            let config = CnnConfig::profile(profile);
            config.validate().unwrap();
            let json = serde_json::to_string(&config).unwrap();
            assert_eq!(serde_json::from_str::<CnnConfig>(&json).unwrap(), config);
        }
        let partial: CnnConfig = serde_json::from_str(r#"{"resolution": 64, "loss": "softplus_mse"}"#).unwrap();
        assert_eq!(partial, CnnConfig { resolution: 64, loss: CnnLoss::SoftplusMse, ..CnnConfig::quick() });
        assert!(CnnConfig { resolution: 40, ..CnnConfig::quick() }.validate().is_err());
        assert!(CnnConfig { images_per_step: Some(0), ..CnnConfig::quick() }.validate().is_err());
        assert!(
            CnnConfig { loss: CnnLoss::SoftplusMse, normalise_labels: true, ..CnnConfig::quick() }.validate().is_err()
        );
    }

    #[test]
    fn training_lowers_the_loss_resumes_exactly_and_rolls_out_one_step() {
        single_thread(|| {
            let config = tiny(10);
            let mut training = CnnTraining::new(config.clone(), poisson(&[11, 12])).unwrap();
            // Four channels (solution mean and std, load, mask) on 16² pixels.
            assert_eq!(training.predictor().network.in_channels, 4);
            let straight = tempfile::tempdir().unwrap();
            let losses: Vec<f64> = (0..10).map(|_| training.train_step().unwrap().loss).collect();
            assert!(losses[9] < 0.5 * losses[0], "loss {losses:?}");

            // Killed after the checkpoint at step 5 and resumed: the same run.
            let resumed_dir = tempfile::tempdir().unwrap();
            let mut first = CnnTraining::new(CnnConfig { steps: 10, ..config.clone() }, poisson(&[11, 12])).unwrap();
            for _ in 0..5 {
                first.train_step().unwrap();
            }
            first.save_checkpoint(resumed_dir.path()).unwrap();
            drop(first);
            let mut resumed = CnnTraining::open(config.clone(), poisson(&[11, 12]), resumed_dir.path()).unwrap();
            assert_eq!(resumed.step(), 5);
            let model_dir = resumed.run(resumed_dir.path(), &mut ()).unwrap();
            let mut again = CnnTraining::new(config.clone(), poisson(&[11, 12])).unwrap();
            again.run(straight.path(), &mut ()).unwrap();
            let weights = |dir: &Path| std::fs::read(dir.join(CNN_WEIGHTS_FILE)).unwrap();
            assert_eq!(weights(&model_dir), weights(&straight.path().join(crate::MODEL_DIR)));
            assert!(
                CnnTraining::open(CnnConfig { seed: 1, ..config }, poisson(&[11, 12]), resumed_dir.path()).is_err()
            );

            // The saved model predicts like the live network; one step, finite metrics.
            let model = CnnModel::load(&model_dir).unwrap();
            let tests = poisson(&[21]);
            let references = Reference::for_problems(&tests, &model.predictor.limits).unwrap();
            let live = cnn_rollouts(again.network(), again.predictor(), &tests, &references).unwrap();
            let loaded = model.rollouts(&tests, &references).unwrap();
            assert_eq!(loaded.len(), 1);
            assert_eq!(loaded[0].steps.len(), 1);
            assert_eq!(live[0].steps[0].metrics, loaded[0].steps[0].metrics);
            let m = loaded[0].steps[0].metrics;
            assert!(m.dcd.is_finite() && m.normalised_dcd.is_finite() && m.elements > 0, "{m:?}");
        });
    }

    /// The unit cube as n³ cells of 6 tetrahedra each (Kuhn subdivision).
    fn cube(n: usize) -> Mesh3 {
        let index = |i: usize, j: usize, k: usize| ((i * (n + 1) + j) * (n + 1) + k) as u32;
        let h = 1.0 / n as f64;
        let mut vertices = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                for k in 0..=n {
                    vertices.push([i as f64 * h, j as f64 * h, k as f64 * h]);
                }
            }
        }
        let mut cells = Vec::new();
        for (i, j, k) in (0..n).flat_map(|i| (0..n).flat_map(move |j| (0..n).map(move |k| (i, j, k)))) {
            for order in [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]] {
                let mut at = [i, j, k];
                cells.push(index(at[0], at[1], at[2]));
                for axis in order {
                    at[axis] += 1;
                    cells.push(index(at[0], at[1], at[2]));
                }
            }
        }
        Mesh3::new_reoriented(vertices, cells).unwrap()
    }

    /// A 3D problem on the unit cube with no input columns (only the mask, as the Console task):
    /// remeshing makes a uniform cube mesh with the mean requested size.
    struct CubeProblem {
        initial: Mesh3,
        expert: Mesh3,
    }

    impl Problem<3> for CubeProblem {
        fn feature_set(&self) -> FeatureSet {
            FeatureSet::console()
        }

        fn initial_mesh(&self) -> &Mesh3 {
            &self.initial
        }

        fn expert_mesh(&self) -> &Mesh3 {
            &self.expert
        }

        fn columns(&self, _: &Mesh3) -> Result<Vec<Column>, ProblemError> {
            Ok(Vec::new())
        }

        fn remesh(&self, _: &Mesh3, sizes: Vec<f64>, max_elements: usize) -> Result<Mesh3, ProblemError> {
            let mean = sizes.iter().sum::<f64>() / sizes.len() as f64;
            let n = ((1.0 / (6.0 * amber_mesh::volume_from_size::<3>(mean))).cbrt().round() as usize).clamp(1, 12);
            if 6 * n.pow(3) > max_elements {
                return Err(amber_meshgen::MeshgenError::TooManyElements { cap: max_elements }.into());
            }
            Ok(cube(n))
        }
    }

    #[test]
    fn voxel_grids_train_and_roll_out_with_the_same_code() {
        let problems =
            vec![CubeProblem { initial: cube(1), expert: cube(3) }, CubeProblem { initial: cube(1), expert: cube(2) }];
        let mut training = CnnTraining::new(tiny(3), problems).unwrap();
        assert_eq!(training.predictor().network.in_channels, 1);
        assert_eq!(training.predictor().network.spatial_axes, 3);
        for _ in 0..3 {
            assert!(training.train_step().unwrap().loss.is_finite());
        }
        let tests = [CubeProblem { initial: cube(1), expert: cube(3) }];
        let references = Reference::for_problems(&tests, &training.predictor().limits).unwrap();
        let rollouts = cnn_rollouts(training.network(), training.predictor(), &tests, &references).unwrap();
        assert_eq!(rollouts[0].steps.len(), 1);
    }
}
