//! Training the network behind plain slices: [`MpnTrainer`] owns the network, its variables and
//! the Adam optimiser, and takes one step (training-mode forward, the objective's mean squared
//! error, backward, clipping, update) on a [`GraphBatch`] and its targets. It may also keep a
//! moving average of the weights, the network it then hands to inference.

use std::collections::HashMap;
use std::path::Path;
use std::sync::MutexGuard;

use amber_graph::GraphBatch;
use amber_nn::{Adam, Backend, Objective};
use candle_core::{DType, Device, Tensor, Var};
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
    average: Option<WeightAverage>,
}

/// An exponential moving average of the trained weights (Polyak averaging): after update t,
/// `average ← d·average + (1 − d)·weights` with `d = min(decay, (1 + t) / (10 + t))`, so that the
/// early average follows the fast-moving weights instead of remembering the initialisation.
struct WeightAverage {
    decay: f64,
    network: Mpn,
    varmap: VarMap,
}

impl WeightAverage {
    fn update(&self, weights: &VarMap, step: u64) -> candle_core::Result<()> {
        blend(&self.varmap, weights, self.decay.min((1 + step) as f64 / (10 + step) as f64))
    }
}

/// `average ← decay·average + (1 − decay)·weights`, variable by variable (decay 0 copies).
fn blend(average: &VarMap, weights: &VarMap, decay: f64) -> candle_core::Result<()> {
    fn lock(varmap: &VarMap) -> candle_core::Result<MutexGuard<'_, HashMap<String, Var>>> {
        varmap.data().lock().map_err(|_| candle_core::Error::Msg("poisoned variable map".into()))
    }
    let (average, weights) = (lock(average)?, lock(weights)?);
    for (name, var) in average.iter() {
        let Some(w) = weights.get(name) else { candle_core::bail!("no trained weight `{name}`") };
        var.set(&((var.as_tensor() * decay)? + (w.as_tensor() * (1.0 - decay))?)?)?;
    }
    Ok(())
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
        Ok(Self { network, device, varmap, objective, optimiser, average: None })
    }

    /// The network of a checkpoint written by [`Self::save`], on `backend`, with fresh moments.
    pub fn load(weights: &Path, objective: Objective, max_grad_norm: Option<f64>, backend: Backend) -> Result<Self> {
        let device = backend.device()?;
        let (network, varmap) = Mpn::load_trainable(weights, &device)?;
        let optimiser = Adam::new(&varmap, max_grad_norm)?;
        Ok(Self { network, device, varmap, objective, optimiser, average: None })
    }

    /// Keeps a moving average of the weights with `decay` per update (see `WeightAverage`),
    /// starting from the current weights, or from the average saved at `saved` (by
    /// [`Self::save`], to resume); the average is then the network of [`Self::inference_network`]
    /// and [`Self::save`].
    pub fn with_weight_average(mut self, decay: f64, saved: Option<&Path>) -> Result<Self> {
        if !(0.0..1.0).contains(&decay) {
            return Err(MpnError::InvalidConfig(format!("weight average decay {decay} is not in [0, 1)")));
        }
        let (network, varmap) = match saved {
            Some(path) => {
                let (network, varmap) = Mpn::load_trainable(path, &self.device)?;
                if network.config() != self.network.config() {
                    let message = "a weight average of another network".into();
                    return Err(MpnError::Checkpoint { path: path.into(), message });
                }
                (network, varmap)
            }
            None => {
                let (network, varmap) = Mpn::init(self.network.config().clone(), 0, DType::F32, &self.device)?;
                blend(&varmap, &self.varmap, 0.0)?;
                (network, varmap)
            }
        };
        self.average = Some(WeightAverage { decay, network, varmap });
        Ok(self)
    }

    /// Restores the moments written by [`Self::save_optimiser`] and the count of updates taken.
    pub fn load_optimiser(&mut self, path: &Path, steps: u64) -> Result<()> {
        self.optimiser.load(path, steps).map_err(|e| MpnError::Checkpoint { path: path.into(), message: e.to_string() })
    }

    /// The network (sharing the trained variables).
    pub fn network(&self) -> &Mpn {
        &self.network
    }

    /// The network inference should use: the weight average when the trainer keeps one, else
    /// the trained network.
    pub fn inference_network(&self) -> &Mpn {
        self.average.as_ref().map_or(&self.network, |a| &a.network)
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
        if let Some(average) = &self.average {
            average.update(&self.varmap, self.optimiser.steps())?;
        }
        Ok(StepLoss { loss: loss_value, squared_errors, grad_norm })
    }

    /// Saves the inference network ([`Self::inference_network`]) as [`Mpn::save`] does.
    pub fn save(&self, weights: &Path) -> Result<()> {
        match &self.average {
            Some(average) => average.network.save(&average.varmap, weights),
            None => self.save_trained(weights),
        }
    }

    /// Saves the trained network as [`Mpn::save`] does (with a weight average, what resuming
    /// needs beside [`Self::save`]'s file).
    pub fn save_trained(&self, weights: &Path) -> Result<()> {
        self.network.save(&self.varmap, weights)
    }

    /// Writes the optimiser's moments (safetensors); the update count is the caller's to store.
    pub fn save_optimiser(&self, path: &Path) -> Result<()> {
        self.optimiser.save(path).map_err(|e| MpnError::Checkpoint { path: path.into(), message: e.to_string() })
    }
}
