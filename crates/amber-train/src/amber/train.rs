//! The training loop (spec §6): gradient steps on least-used batches from the replay buffer, a
//! new generated mesh every `add_interval` steps, checkpoints, a JSON-lines log, validation
//! rollouts, progress through a [`TrainingObserver`].

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_graph::{FeatureNormaliser, FeatureSet, GraphBatch};
use amber_mesh::Mesh;
use amber_mpn::{Mpn, MpnConfig, MpnTrainer};
use amber_stdx::{read_json, write_json_atomic};
use amber_tasks::{
    LOG_SIZE_COLUMN, MeshLimits, MeshState, Problem, ProblemError, SizeBounds, StepOutcome, generation_step, labels,
    with_inputs,
};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::model::WEIGHTS_FILE;
use crate::checkpoint::{
    self, AdditionCounts, EntryRecord, OPTIMISER_FILE, RngState, STATE_FILE, TrainingState, fingerprints, seeded_stream,
};
use crate::error::{Result, TrainError, in_problem, io_error};
use crate::{
    AmberModel, AmberSizing, Evaluation, EvaluationSummary, Predictor, ReplayBuffer, Sample, StepReport,
    TargetTransform, TrainingConfig, TrainingObserver, fit_final_step,
};

/// The final model's sub-directory of the output directory.
pub const MODEL_DIR: &str = "model";
/// The JSON-lines log in the output directory.
pub const LOG_FILE: &str = "train.jsonl";
/// The run's configuration in the output directory.
pub const CONFIG_FILE: &str = "config.json";

/// What became of one attempted buffer addition.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Addition {
    /// A mesh of `depth` with `elements` elements entered the buffer.
    Added { problem: usize, depth: usize, elements: usize },
    /// The predicted field exceeded the element budget; nothing was added.
    OverBudget { problem: usize, depth: usize, estimated_elements: f64 },
    /// The generator failed; nothing was added.
    Failed { problem: usize, depth: usize, reason: String },
}

/// One gradient step (and the addition that followed it, if one was due).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AmberStepReport {
    /// Gradient steps completed, this one included.
    pub step: u64,
    /// Loss of the batch (in the objective's training space).
    pub loss: f64,
    /// The same loss over the batch's nodes of each buffer depth (index = depth; `None`: no
    /// graph of that depth in the batch): where the network still errs.
    pub loss_by_depth: Vec<Option<f64>>,
    pub learning_rate: f64,
    /// Global gradient norm before clipping.
    pub grad_norm: f64,
    pub graphs: usize,
    pub nodes: usize,
    /// Nodes per second of the gradient step (forward, backward, update).
    pub nodes_per_s: f64,
    /// Wall time of the gradient step plus the addition.
    pub seconds: f64,
    pub addition: Option<Addition>,
    pub buffer_size: usize,
    /// Buffer entries per depth (index = depth).
    pub buffer_depths: Vec<usize>,
}

/// A training run: network, optimiser, buffer, normalisers and generators.
pub struct Training<const D: usize, P: Problem<D>> {
    config: TrainingConfig,
    problems: Vec<P>,
    trainer: MpnTrainer,
    predictor: Predictor,
    buffer: ReplayBuffer<D>,
    step: u64,
    dropout_rng: ChaCha8Rng,
    buffer_rng: ChaCha8Rng,
    /// Draws the batch graphs' orientations (`random_orientation`).
    orientation_rng: ChaCha8Rng,
    additions: AdditionCounts,
}

impl<const D: usize, P: Problem<D>> Training<D, P> {
    /// A fresh run on `problems`: h_min and the element budget from their experts, one
    /// protected buffer entry per problem (which also seed the normalisers), a freshly
    /// initialised network.
    pub fn new(config: TrainingConfig, problems: Vec<P>) -> Result<Self> {
        config.validate()?;
        let first = problems.first().ok_or(TrainError::NoProblems)?;
        for (k, problem) in problems.iter().enumerate() {
            let offered = problem.optional_inputs();
            if let Some(unknown) = config.inputs.iter().find(|i| *i != LOG_SIZE_COLUMN && !offered.contains(i)) {
                return Err(TrainError::InvalidConfig(format!(
                    "inputs: training problem {k} offers no input `{unknown}` (it offers {LOG_SIZE_COLUMN}{})",
                    offered.iter().map(|o| format!(", {o}")).collect::<String>()
                )));
            }
        }
        let mut features = with_inputs(first.feature_set(), &config.inputs);
        if let Some(edge) = &config.edge_features {
            features.edge.clone_from(edge);
        }
        if config.random_orientation && !features.has_edge_vectors() {
            return Err(TrainError::InvalidConfig(
                "random_orientation turns the edge vectors, but the edge features have none (add \"midpoint_difference\" to edge_features)".into(),
            ));
        }
        let limits = MeshLimits::from_experts(
            problems.iter().map(|p| p.expert_mesh()),
            config.budget_factor,
            config.min_size_quantile,
        );
        let normaliser =
            config.normalise_inputs.then(|| FeatureNormaliser::new(features.node_dim(), features.edge_dim(D)));
        let target = TargetTransform::new(config.objective, config.normalise_labels);
        let network_config = MpnConfig {
            node_features: features.node_dim(),
            edge_features: features.edge_dim(D),
            network: config.network.clone(),
        };
        let mut trainer =
            MpnTrainer::new(network_config, config.objective, config.seed, config.max_grad_norm, config.device)?;
        if let Some(decay) = config.weight_average_decay {
            trainer = trainer.with_weight_average(decay, None)?;
        }
        let mut training = Self {
            buffer: ReplayBuffer::new(config.buffer_capacity),
            dropout_rng: seeded_stream(config.seed, 1),
            buffer_rng: seeded_stream(config.seed, 2),
            orientation_rng: seeded_stream(config.seed, ORIENTATION_STREAM),
            config,
            trainer,
            predictor: Predictor { features, normaliser, target, limits },
            step: 0,
            additions: AdditionCounts::default(),
            problems: Vec::new(),
        };
        let samples: Vec<Sample<D>> = problems
            .par_iter()
            .enumerate()
            .map(|(i, p)| training.sample(p, p.initial_mesh().clone()).map_err(in_problem(i)))
            .collect::<Result<_>>()?;
        for (i, sample) in samples.into_iter().enumerate() {
            training.observe(&sample)?;
            training.buffer.push_protected(i, sample);
        }
        training.problems = problems;
        Ok(training)
    }

    /// Resumes the newest checkpoint under `out_dir` if there is one (the configuration and
    /// problems must be those of the checkpointed run), else starts afresh.
    pub fn open(config: TrainingConfig, problems: Vec<P>, out_dir: &Path) -> Result<Self> {
        match checkpoint::latest_checkpoint(out_dir)? {
            Some(dir) => Self::resume(config, problems, &dir),
            None => Self::new(config, problems),
        }
    }

    /// Restores the run checkpointed in `dir`.
    pub fn resume(config: TrainingConfig, problems: Vec<P>, dir: &Path) -> Result<Self> {
        let fail = |message: String| TrainError::Checkpoint { path: dir.into(), message };
        let state: TrainingState = read_json(&dir.join(STATE_FILE))?;
        if state.config != config {
            return Err(fail("the configuration differs from the checkpointed run's".into()));
        }
        if state.problems != fingerprints(&problems) {
            return Err(fail("the training problems differ from the checkpointed run's".into()));
        }
        state.check(problems.len()).map_err(fail)?;
        // With a weight average the model's weights are the average, the trained ones beside.
        let trained = if config.weight_average_decay.is_some() { TRAINED_WEIGHTS_FILE } else { WEIGHTS_FILE };
        let mut trainer = MpnTrainer::load(&dir.join(trained), config.objective, config.max_grad_norm, config.device)?;
        if let Some(decay) = config.weight_average_decay {
            trainer = trainer.with_weight_average(decay, Some(&dir.join(WEIGHTS_FILE)))?;
        }
        let predictor = Predictor::read(&dir.join(super::model::PREDICTOR_FILE), trainer.network().config())?;
        trainer.load_optimiser(&dir.join(OPTIMISER_FILE), state.optimiser_steps)?;
        let load = |records: &[EntryRecord]| -> Result<Vec<_>> {
            records.par_iter().map(|r| checkpoint::load_entry(dir, r, &predictor.features, &predictor.target)).collect()
        };
        let buffer = ReplayBuffer::restore(
            config.buffer_capacity,
            state.next_entry_id,
            load(&state.protected)?,
            load(&state.generated)?,
        );
        Ok(Self {
            dropout_rng: state.dropout_rng.restore(dir)?,
            buffer_rng: state.buffer_rng.restore(dir)?,
            orientation_rng: match &state.orientation_rng {
                Some(rng) => rng.restore(dir)?,
                None => seeded_stream(config.seed, ORIENTATION_STREAM),
            },
            config,
            problems,
            trainer,
            predictor,
            buffer,
            step: state.step,
            additions: state.additions,
        })
    }

    /// The run's configuration.
    pub fn config(&self) -> &TrainingConfig {
        &self.config
    }

    /// Gradient steps completed.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// h_min and the element budget of this run (validation and inference use them too).
    pub fn limits(&self) -> &MeshLimits {
        &self.predictor.limits
    }

    /// The replay buffer.
    pub fn buffer(&self) -> &ReplayBuffer<D> {
        &self.buffer
    }

    /// Buffer additions so far, by outcome.
    pub fn additions(&self) -> AdditionCounts {
        self.additions
    }

    /// The network the run rolls out and writes: the weight average if the run keeps one, else
    /// the trained network (sharing its variables).
    pub fn network(&self) -> &Mpn {
        self.trainer.inference_network()
    }

    /// Normalisers, target transform and limits.
    pub fn predictor(&self) -> &Predictor {
        &self.predictor
    }

    /// The training problems.
    pub fn problems(&self) -> &[P] {
        &self.problems
    }

    /// Features and labels of `mesh`, a mesh of `problem`'s domain.
    fn sample(&self, problem: &P, mesh: Mesh<D>) -> Result<Sample<D>, ProblemError> {
        let state = MeshState::new(problem, &self.predictor.features, mesh)?;
        let labels = labels(problem, &state.mesh, self.config.aggregation)?;
        let targets = self.predictor.target.raw_targets(&labels, &state.mesh.sizes());
        Ok(Sample { state, labels, targets })
    }

    /// Merges a graph entering the buffer into the running normalisers.
    fn observe(&mut self, sample: &Sample<D>) -> Result<()> {
        if let Some(normaliser) = &mut self.predictor.normaliser {
            let graph = &sample.state.graph;
            if self.config.random_orientation {
                normaliser.update_all_axes_alike::<D>(graph, &self.predictor.features)?;
            } else {
                normaliser.update(graph)?;
            }
        }
        self.predictor.target.update(&sample.targets);
        Ok(())
    }

    /// One gradient step on the next least-used batch, then a buffer addition if one is due.
    pub fn train_step(&mut self) -> Result<AmberStepReport> {
        let started = Instant::now();
        let lr = self.config.lr_schedule.rate(self.config.learning_rate, self.step, self.config.steps);
        let chosen = self.buffer.next_batch(self.config.batch_nodes);
        let entries: Vec<_> = chosen.iter().map(|&i| self.buffer.get(i)).collect();
        let mut batch = GraphBatch::from_graphs(entries.iter().map(|e| &e.sample.state.graph))?;
        if self.config.random_orientation {
            turn_at_random::<D>(&mut batch, &self.predictor.features, &mut self.orientation_rng);
        }
        if let Some(normaliser) = &self.predictor.normaliser {
            normaliser.normalise(&mut batch)?;
        }
        let targets: Vec<f32> =
            entries.iter().flat_map(|e| self.predictor.target.training_targets(&e.sample.targets)).collect();
        let nodes = batch.num_nodes;
        let step = self.trainer.train_step(&batch, &targets, lr, &mut self.dropout_rng)?;
        let loss_by_depth =
            loss_by_depth(&step.squared_errors, entries.iter().map(|e| (e.depth, e.sample.state.graph.num_nodes())));
        let step_seconds = started.elapsed().as_secs_f64();
        let addition =
            if self.step.is_multiple_of(self.config.add_interval) { Some(self.add_generated()?) } else { None };
        self.step += 1;
        Ok(AmberStepReport {
            step: self.step,
            loss: step.loss,
            loss_by_depth,
            learning_rate: lr,
            grad_norm: step.grad_norm,
            graphs: chosen.len(),
            nodes,
            nodes_per_s: nodes as f64 / step_seconds,
            seconds: started.elapsed().as_secs_f64(),
            addition,
            buffer_size: self.buffer.len(),
            buffer_depths: self.buffer.depth_histogram(),
        })
    }

    /// Generates one mesh from a buffer entry chosen by the configured strategy and stores it
    /// (spec §6): predict (evaluation mode), clip, guard, remesh, features, labels.
    pub fn add_generated(&mut self) -> Result<Addition> {
        let source = self
            .buffer
            .choose_source(self.config.max_source_depth, self.config.source_selection, &mut self.buffer_rng)
            .expect("protected depth-0 entries are always eligible");
        let entry = self.buffer.get(source);
        let (problem, depth) = (entry.problem, entry.depth + 1);
        let sizes = self.predictor.predict(self.network(), &[&entry.sample.state])?.pop().expect("one state");
        let outcome = generation_step(
            &self.problems[problem],
            &entry.sample.state.mesh,
            sizes,
            &self.predictor.limits,
            &SizeBounds::default(),
        );
        Ok(match outcome {
            StepOutcome::Meshed(mesh) => {
                let sample = self.sample(&self.problems[problem], mesh).map_err(in_problem(problem))?;
                let elements = sample.state.mesh.num_elements();
                self.observe(&sample)?;
                self.buffer.push_generated(problem, depth, sample);
                self.additions.added += 1;
                Addition::Added { problem, depth, elements }
            }
            StepOutcome::OverBudget { estimated_elements } => {
                self.additions.over_budget += 1;
                Addition::OverBudget { problem, depth, estimated_elements }
            }
            StepOutcome::Failed { reason } => {
                self.additions.failed += 1;
                Addition::Failed { problem, depth, reason }
            }
        })
    }

    /// Trains until `config.steps`, from wherever the run stands: logs every step to
    /// `out_dir/train.jsonl`, validates on `validation` every `validation_interval` steps and at
    /// the end, checkpoints every `checkpoint_interval` steps and at the end, fits the final
    /// step (with `calibrate_element_count`, then validating the fitted model once more), and
    /// writes the final model to `out_dir/model`.
    pub fn run(
        &mut self,
        out_dir: &Path,
        validation: Option<&Evaluation<'_, D, P>>,
        observer: &mut dyn TrainingObserver,
    ) -> Result<()> {
        std::fs::create_dir_all(out_dir).map_err(io_error(out_dir))?;
        write_json_atomic(&out_dir.join(CONFIG_FILE), &self.config)?;
        let mut log = TrainingLog::open(&out_dir.join(LOG_FILE), self.step)?;
        let (total, interval) = (self.config.steps, self.config.validation_interval);
        // An interval of 0 turns validation off.
        let validation = validation.filter(|_| interval > 0);
        while self.step < total {
            let report = self.train_step()?;
            log.write(&LogRecord::Step(&report))?;
            observer.step(&StepReport::Amber(report), total);
            let (step, last) = (self.step, self.step == total);
            if let Some(validation) = validation
                && (step.is_multiple_of(interval) || last)
            {
                let summary = self.validate(validation)?;
                log.write(&LogRecord::Validation { step, summary: &summary })?;
                observer.validation(step, &summary);
            }
            if step.is_multiple_of(self.config.checkpoint_interval) || last {
                let dir = self.save_checkpoint(out_dir)?;
                observer.checkpoint(step, &dir);
            }
        }
        if self.config.calibrate_element_count {
            let sizing = AmberSizing { network: self.network(), predictor: &self.predictor };
            let fit = fit_final_step(&sizing, &self.problems, self.config.inference_steps)?;
            self.predictor.limits.final_step_scale = fit.scale;
            self.predictor.limits.final_count = self.config.count_regression.then_some(fit.count);
            if let Some(validation) = validation {
                let summary = self.validate(validation)?;
                log.write(&LogRecord::FinalValidation { step: self.step, summary: &summary })?;
                observer.final_validation(self.step, &summary);
            }
        }
        self.save_model(&out_dir.join(MODEL_DIR))
    }

    /// Rolls out the current model on `validation` (evaluation mode) and summarises; a field
    /// over the budget is scaled to it, as `amber evaluate` does, rather than skipped (a skipped
    /// first step would score as M⁰ and hide what the model does).
    pub fn validate(&self, validation: &Evaluation<'_, D, P>) -> Result<EvaluationSummary> {
        let mut predictor = self.predictor.clone();
        predictor.limits.scale_to_budget = true;
        let sizing = AmberSizing { network: self.network(), predictor: &predictor };
        Ok(validation.run(&sizing, self.config.inference_steps)?.1)
    }

    /// Writes the current model (network, normalisers, target transform, limits) to `dir`.
    pub fn save_model(&self, dir: &Path) -> Result<()> {
        AmberModel::save(&self.trainer, &self.predictor, dir)
    }

    /// Writes a checkpoint of the current state under `out_dir/checkpoints`; returns its
    /// directory.
    pub fn save_checkpoint(&self, out_dir: &Path) -> Result<PathBuf> {
        let records =
            |entries: &mut dyn Iterator<Item = &crate::BufferEntry<D>>| entries.map(EntryRecord::of).collect();
        let state = TrainingState {
            config: self.config.clone(),
            step: self.step,
            optimiser_steps: self.trainer.optimiser_steps(),
            dropout_rng: RngState::of(&self.dropout_rng),
            buffer_rng: RngState::of(&self.buffer_rng),
            orientation_rng: self.config.random_orientation.then(|| RngState::of(&self.orientation_rng)),
            problems: fingerprints(&self.problems),
            next_entry_id: self.buffer.next_id(),
            protected: records(&mut self.buffer.protected().iter()),
            generated: records(&mut self.buffer.generated()),
            additions: self.additions,
        };
        checkpoint::commit(out_dir, self.step, self.buffer.entries(), |dir| {
            self.save_model(dir)?;
            if self.config.weight_average_decay.is_some() {
                self.trainer.save_trained(&dir.join(TRAINED_WEIGHTS_FILE))?;
            }
            self.trainer.save_optimiser(&dir.join(OPTIMISER_FILE))?;
            Ok(write_json_atomic(&dir.join(STATE_FILE), &state)?)
        })
    }
}

/// The trained weights in a checkpoint of a run that keeps a weight average (whose
/// [`WEIGHTS_FILE`] holds the average, the model).
const TRAINED_WEIGHTS_FILE: &str = "trained.safetensors";

/// The random stream of the batch graphs' orientations (after edge dropout's 1 and the buffer's 2).
const ORIENTATION_STREAM: u64 = 3;

/// Turns each graph of `batch` by its own random orthogonal matrix (uniform over rotations and
/// reflections).
fn turn_at_random<const D: usize>(batch: &mut GraphBatch, features: &FeatureSet, rng: &mut ChaCha8Rng) {
    let width = batch.edge_dim;
    for graph in 0..batch.num_graphs() {
        let q = random_orthogonal::<D>(rng);
        let [first, last] = [graph, graph + 1].map(|g| batch.dst_offsets[batch.node_offsets[g] as usize] as usize);
        features.transform_edge_vectors(&mut batch.edge_features[first * width..last * width], &q);
    }
}

/// A random orthogonal matrix, uniform (Haar) over the rotations and reflections of `D`
/// dimensions: Gram–Schmidt on `D` standard normal vectors.
fn random_orthogonal<const D: usize>(rng: &mut ChaCha8Rng) -> [[f64; D]; D] {
    let mut q = [[0.0; D]; D];
    let mut i = 0;
    while i < D {
        let mut v: [f64; D] = std::array::from_fn(|_| rng.sample(StandardNormal));
        // Twice, so that the rows are orthogonal to rounding even when the draw nearly lies in
        // their span ("twice is enough").
        for row in q[..i].iter().chain(&q[..i]) {
            let along: f64 = row.iter().zip(&v).map(|(a, b)| a * b).sum();
            v.iter_mut().zip(row).for_each(|(x, a)| *x -= along * a);
        }
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        // A draw (almost) in the span of the rows so far is drawn again.
        if norm > 1e-6 {
            q[i] = v.map(|x| x / norm);
            i += 1;
        }
    }
    q
}

/// One line of the training log.
#[derive(Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
enum LogRecord<'a> {
    Step(&'a AmberStepReport),
    Validation {
        step: u64,
        summary: &'a EvaluationSummary,
    },
    /// The model as saved, after the final step's fit.
    FinalValidation {
        step: u64,
        summary: &'a EvaluationSummary,
    },
}

/// The JSON-lines log, appended to; on resume, records after the checkpoint are dropped first
/// (they belong to the killed run's lost steps and will be redone), and so is the final
/// validation, which every run to the end redoes.
struct TrainingLog {
    file: std::fs::File,
    path: PathBuf,
}

impl TrainingLog {
    fn open(path: &Path, completed_steps: u64) -> Result<Self> {
        let kept: String = match std::fs::read_to_string(path) {
            Ok(text) => text
                .lines()
                .filter(|line| {
                    serde_json::from_str::<serde_json::Value>(line).ok().is_some_and(|v| {
                        v["kind"] != "final_validation" && v["step"].as_u64().is_some_and(|s| s <= completed_steps)
                    })
                })
                .map(|line| format!("{line}\n"))
                .collect(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => return Err(io_error(path)(e)),
        };
        amber_stdx::write_atomic(path, kept.as_bytes())?;
        let file = std::fs::OpenOptions::new().append(true).open(path).map_err(io_error(path))?;
        Ok(Self { file, path: path.into() })
    }

    fn write(&mut self, record: &LogRecord<'_>) -> Result<()> {
        let mut line =
            serde_json::to_vec(record).map_err(|source| TrainError::Json { path: self.path.clone(), source })?;
        line.push(b'\n');
        self.file.write_all(&line).map_err(io_error(&self.path))
    }
}

/// The mean of the per-node squared errors over the nodes of each depth, for a batch of graphs
/// given in order as (depth, nodes).
fn loss_by_depth(squared_errors: &[f32], graphs: impl Iterator<Item = (usize, usize)>) -> Vec<Option<f64>> {
    let mut sums: Vec<(f64, usize)> = Vec::new();
    let mut start = 0;
    for (depth, nodes) in graphs {
        if sums.len() <= depth {
            sums.resize(depth + 1, (0.0, 0));
        }
        sums[depth].0 += squared_errors[start..start + nodes].iter().map(|&e| f64::from(e)).sum::<f64>();
        sums[depth].1 += nodes;
        start += nodes;
    }
    sums.into_iter().map(|(sum, n)| (n > 0).then(|| sum / n as f64)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_orthogonal_matrices_are_orthogonal_and_unbiased() {
        let mut rng = seeded_stream(7, ORIENTATION_STREAM);
        let (mut mean, mut reflections) = ([[0.0; 3]; 3], 0);
        let draws = 4000;
        for _ in 0..draws {
            let q = random_orthogonal::<3>(&mut rng);
            for i in 0..3 {
                for j in 0..3 {
                    let dot: f64 = (0..3).map(|k| q[i][k] * q[j][k]).sum();
                    assert!((dot - f64::from(i == j)).abs() < 1e-12);
                    mean[i][j] += q[i][j] / f64::from(draws);
                }
            }
            let det = q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1])
                - q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0])
                + q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0]);
            reflections += usize::from(det < 0.0);
        }
        // Every entry of a Haar matrix has mean 0 (standard deviation 1/√3 here); half are reflections.
        assert!(mean.iter().flatten().all(|m| m.abs() < 0.05), "{mean:?}");
        assert!((1800..2200).contains(&reflections), "{reflections}");
    }

    #[test]
    fn the_loss_by_depth_averages_over_the_nodes_of_each_depth() {
        // Graphs in batch order: depth 2 (1 node), depth 0 (2 nodes), depth 2 (1 node).
        let by_depth = loss_by_depth(&[1.0, 4.0, 9.0, 25.0], [(2, 1), (0, 2), (2, 1)].into_iter());
        assert_eq!(by_depth, vec![Some(6.5), None, Some(13.0)]);
    }
}
