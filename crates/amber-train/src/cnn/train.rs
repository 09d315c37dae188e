//! Training the U-Net CNN baseline (spec §8, reference notes §8) on any [`Problem`]: an auxiliary uniform mesh of the problem's geometry with about two elements per
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

use amber_cnn::{CnnTrainer, TrainingImages, UNet};
use amber_graph::RunningMoments;
use amber_stdx::{read_json, write_json_atomic};
use amber_tasks::{MeshLimits, Problem, labels};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::model::{CNN_PREDICTOR_FILE, CNN_WEIGHTS_FILE, CnnModel, CnnPredictor, Rasterised, rasterise, transpose};
use crate::checkpoint::{self, OPTIMISER_FILE, ProblemFingerprint, RngState, STATE_FILE, fingerprints, seeded_stream};
use crate::error::{Result, TrainError, in_problem, io_error};
use crate::{BufferEntry, CnnConfig, StepReport, TrainingObserver};

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
                sample.raster.owners.iter().flatten().map(|&e| config.objective.target(labels[e as usize], None) as f32)
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
            objective: config.objective,
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
        let trainer = CnnTrainer::new(network, images, config.objective, config.max_grad_norm)?;
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
        let saved = CnnPredictor::read(&dir.join(CNN_PREDICTOR_FILE))?;
        let (network, predictor, images) =
            Self::prepare(&config, &problems, |p| Ok(UNet::load(p.network.clone(), &dir.join(CNN_WEIGHTS_FILE))?))?;
        if saved != predictor {
            return Err(fail("the rasterised problems give another normaliser or limits than the checkpointed run's"));
        }
        let mut trainer = CnnTrainer::new(network, images, config.objective, config.max_grad_norm)?;
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
    pub fn run(&mut self, out_dir: &Path, observer: &mut dyn TrainingObserver) -> Result<PathBuf> {
        std::fs::create_dir_all(out_dir).map_err(io_error(out_dir))?;
        write_json_atomic(&out_dir.join(crate::CONFIG_FILE), &self.config)?;
        while self.step < self.config.steps {
            let report = self.train_step()?;
            observer.step(&StepReport::Cnn(report), self.config.steps);
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
    use crate::{CnnSizing, Reference, rollouts};
    use amber_fem::ExpertHeuristic;
    use amber_graph::FeatureSet;
    use amber_mesh::Mesh3;
    use amber_tasks::poisson::{INITIAL_SIZE, PoissonProblem};

    use amber_tasks::{Column, Domain, ProblemError};

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
            let live_model = CnnSizing { network: again.network(), predictor: again.predictor() };
            let live = rollouts(&live_model, &tests, &references, 1).unwrap();
            let loaded = rollouts(&model.sizing(), &tests, &references, 1).unwrap();
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
        fn expert_mesh(&self) -> &Mesh3 {
            &self.expert
        }

        fn name(&self) -> String {
            "cube".into()
        }
    }

    impl Domain<3> for CubeProblem {
        fn feature_set(&self) -> FeatureSet {
            FeatureSet::console()
        }

        fn initial_mesh(&self) -> &Mesh3 {
            &self.initial
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
        let sizing = CnnSizing { network: training.network(), predictor: training.predictor() };
        let rollouts = rollouts(&sizing, &tests, &references, 1).unwrap();
        assert_eq!(rollouts[0].steps.len(), 1);
    }
}
