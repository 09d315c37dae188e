//! Training the network behind plain slices: [`MpnTrainer`] owns the network, its variables and
//! the Adam optimiser, and takes one step (training-mode forward, the objective's mean squared
//! error, backward, clipping, update) on a [`GraphBatch`] and its targets.

use std::path::Path;

use amber_graph::GraphBatch;
use amber_nn::{Adam, Backend, Objective};
use candle_core::{DType, Device, Tensor};
use candle_nn::VarMap;
use rand::Rng;

use crate::error::{MpnError, Result};
use crate::{GraphInput, Mpn, MpnConfig};

/// What one training step measured.
#[derive(Clone, Debug, PartialEq)]
pub struct StepLoss {
    /// Mean squared error of the batch.
    pub loss: f64,
    /// The squared error of every node, in batch order.
    pub squared_errors: Vec<f32>,
    /// Global gradient norm before clipping.
    pub grad_norm: f64,
}

/// A trainable network (f32, on its backend's device) with its variables, objective and
/// optimiser.
pub struct MpnTrainer {
    network: Mpn,
    device: Device,
    varmap: VarMap,
    objective: Objective,
    optimiser: Adam,
}

impl MpnTrainer {
    /// A freshly initialised network (drawn from `seed`, see [`Mpn::init`]) and fresh moments;
    /// trained for `objective` on `backend`; gradients are clipped to a global norm of
    /// `max_grad_norm` if set.
    pub fn new(
        config: MpnConfig,
        objective: Objective,
        seed: u64,
        max_grad_norm: Option<f64>,
        backend: Backend,
    ) -> Result<Self> {
        let device = backend.device()?;
        let (network, varmap) = Mpn::init(config, seed, DType::F32, &device)?;
        let optimiser = Adam::new(&varmap, max_grad_norm)?;
        Ok(Self { network, device, varmap, objective, optimiser })
    }

    /// The network of a checkpoint written by [`Self::save`], on `backend`, with fresh moments.
    pub fn load(weights: &Path, objective: Objective, max_grad_norm: Option<f64>, backend: Backend) -> Result<Self> {
        let device = backend.device()?;
        let (network, varmap) = Mpn::load_trainable(weights, &device)?;
        let optimiser = Adam::new(&varmap, max_grad_norm)?;
        Ok(Self { network, device, varmap, objective, optimiser })
    }

    /// Restores the moments written by [`Self::save_optimiser`] and the count of updates taken.
    pub fn load_optimiser(&mut self, path: &Path, steps: u64) -> Result<()> {
        self.optimiser.load(path, steps).map_err(|e| MpnError::Checkpoint { path: path.into(), message: e.to_string() })
    }

    /// The network (sharing the trained variables).
    pub fn network(&self) -> &Mpn {
        &self.network
    }

    /// Optimiser updates taken so far.
    pub fn optimiser_steps(&self) -> u64 {
        self.optimiser.steps()
    }

    /// One step on `batch` with one target per node: training-mode forward (edge dropout drawn
    /// from `rng`), mean squared error of the objective's activation, backward, clipping, an Adam
    /// update with rate `lr`.
    pub fn train_step<R: Rng + ?Sized>(
        &mut self,
        batch: &GraphBatch,
        targets: &[f32],
        lr: f64,
        rng: &mut R,
    ) -> Result<StepLoss> {
        let input = GraphInput::from_batch(batch, DType::F32, &self.device)?;
        let output = self.objective.activation(&self.network.forward_train(&input, rng)?)?;
        // The mean squared error, kept per node for the caller.
        let squared_errors = (output - Tensor::from_slice(targets, batch.num_nodes, &self.device)?)?.sqr()?;
        let loss = squared_errors.mean_all()?;
        let squared_errors = squared_errors.to_vec1::<f32>()?;
        let loss_value = f64::from(loss.to_scalar::<f32>()?);
        let grad_norm = self.optimiser.step(&loss, lr)?;
        Ok(StepLoss { loss: loss_value, squared_errors, grad_norm })
    }

    /// Saves the network as [`Mpn::save`] does.
    pub fn save(&self, weights: &Path) -> Result<()> {
        self.network.save(&self.varmap, weights)
    }

    /// Writes the optimiser's moments (safetensors); the update count is the caller's to store.
    pub fn save_optimiser(&self, path: &Path) -> Result<()> {
        self.optimiser.save(path).map_err(|e| MpnError::Checkpoint { path: path.into(), message: e.to_string() })
    }
}
