//! What `cargo xtask bench mpn` times, built here so that the benchmark sees no tensor: a random
//! mesh-like graph ([`random_graph`]), sizing-field-like targets, a freshly initialised network
//! with the Adam that trains it, and one unit of timed work ([`BenchStep`]). The caller times and
//! reports.

use amber_nn::{Adam, Objective};
use candle_core::{DType, Device, Tensor};
use candle_nn::loss::mse;
use rand::SeedableRng;
use rand::rngs::StdRng;

use crate::synthetic::random_graph;
use crate::{GraphInput, Mpn, MpnConfig, Result};

/// One unit of timed work: an inference forward of a plain-tensor model, or a training step
/// (forward, the objective's MSE, backward, clipping, an Adam update).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchStep {
    /// Inference in stock candle ops (`Mpn::forward_naive`).
    NaiveInfer,
    /// Inference with the fused ops.
    FastInfer,
    /// A training step in stock candle ops.
    NaiveTrain,
    /// A training step with the fused ops, without edge dropout.
    FastTrain,
    /// A training step with the fused ops and the configured edge dropout.
    FastDropoutTrain,
}

/// A network, its optimiser and one random graph with targets.
pub struct BenchCase {
    graph: GraphInput,
    targets: Tensor,
    model: Mpn,
    frozen: Mpn,
    adam: Adam,
    objective: Objective,
    learning_rate: f64,
    rng: StdRng,
}

impl BenchCase {
    /// A graph of `nodes` nodes and `undirected_edges` random node pairs with `config`'s feature
    /// widths, targets in [0.01, 0.06), and a network of `config` (seed 0) trained for
    /// `objective` by Adam with rate `learning_rate` and clip `max_grad_norm`.
    pub fn new(
        config: &MpnConfig,
        objective: Objective,
        nodes: usize,
        undirected_edges: usize,
        learning_rate: f64,
        max_grad_norm: Option<f64>,
    ) -> Result<Self> {
        let dev = Device::Cpu;
        let batch = random_graph(nodes, undirected_edges, config.node_features, config.edge_features, 0);
        let graph = GraphInput::from_batch(&batch, DType::F32, &dev)?;
        let targets: Vec<f32> = (0..nodes).map(|i| 0.01 + 0.05 * ((i as f32 * 0.618_034) % 1.0)).collect();
        let targets = Tensor::from_vec(targets, nodes, &dev)?;
        let (model, varmap) = Mpn::init(config.clone(), 0, DType::F32, &dev)?;
        let adam = Adam::new(&varmap, max_grad_norm)?;
        let frozen = model.for_inference();
        Ok(Self { graph, targets, model, frozen, adam, objective, learning_rate, rng: StdRng::seed_from_u64(0) })
    }

    /// Directed edges of the graph, self-loops included.
    pub fn num_edges(&self) -> usize {
        self.graph.topology.num_edges()
    }

    /// Does `step` once.
    pub fn run(&mut self, step: BenchStep) -> Result<()> {
        let output = match step {
            BenchStep::NaiveInfer => self.frozen.forward_naive(&self.graph)?,
            BenchStep::FastInfer => self.frozen.forward(&self.graph)?,
            BenchStep::NaiveTrain => self.model.forward_naive(&self.graph)?,
            BenchStep::FastTrain => self.model.forward(&self.graph)?,
            BenchStep::FastDropoutTrain => self.model.forward_train(&self.graph, &mut self.rng)?,
        };
        let output = self.objective.activation(&output)?;
        if matches!(step, BenchStep::NaiveTrain | BenchStep::FastTrain | BenchStep::FastDropoutTrain) {
            self.adam.step(&mse(&output, &self.targets)?, self.learning_rate)?;
        }
        Ok(())
    }
}

/// Threads of candle's own kernels (the benchmark records them beside rayon's).
pub fn candle_threads() -> usize {
    candle_core::utils::get_num_threads()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_step_runs_on_a_small_case() {
        let config = MpnConfig::small(8, 2);
        let mut case = BenchCase::new(&config, Objective::SoftplusMse, 20, 30, 1e-3, Some(0.5)).unwrap();
        assert_eq!(case.num_edges(), 20 + 60);
        for step in [
            BenchStep::NaiveInfer,
            BenchStep::FastInfer,
            BenchStep::NaiveTrain,
            BenchStep::FastTrain,
            BenchStep::FastDropoutTrain,
        ] {
            case.run(step).unwrap();
        }
    }
}
