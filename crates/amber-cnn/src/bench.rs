//! What `cargo xtask bench cnn` times, built here so that the benchmark sees no tensor: a random
//! input image and labels in [0, 1) with every pixel inside, a freshly initialised U-Net with the
//! Adam that trains it, a training step, its backward pass alone and an inference forward. The
//! caller times and reports.

use std::time::Instant;

use amber_nn::{Adam, Objective};
use candle_core::{DType, Device, Tensor};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use crate::train::masked_mse;
use crate::{Result, UNet, UNetConfig};

/// A U-Net, its optimiser and one random image with labels.
pub struct BenchCase {
    network: UNet,
    input: Tensor,
    labels: Tensor,
    mask: Tensor,
    adam: Adam,
    objective: Objective,
    learning_rate: f64,
}

impl BenchCase {
    /// One image of `resolution` pixels per axis for a U-Net of `config` (seed 0), trained for
    /// `objective` by Adam with rate `learning_rate` and clip `max_grad_norm`.
    pub fn new(
        config: UNetConfig,
        resolution: usize,
        objective: Objective,
        learning_rate: f64,
        max_grad_norm: Option<f64>,
    ) -> Result<Self> {
        let spatial = vec![resolution; config.spatial_axes];
        let input_shape: Vec<usize> = [1, config.in_channels].into_iter().chain(spatial.iter().copied()).collect();
        let label_shape: Vec<usize> = [1, 1].into_iter().chain(spatial).collect();
        let network = UNet::init(config, 0)?;
        let mut rng = StdRng::seed_from_u64(0);
        let mut random = |shape: &[usize], lo: f32, hi: f32| {
            let v: Vec<f32> = (0..shape.iter().product()).map(|_| rng.random_range(lo..hi)).collect();
            Tensor::from_vec(v, shape, &Device::Cpu)
        };
        let input = random(&input_shape, -1.0, 1.0)?;
        let labels = random(&label_shape, 0.0, 1.0)?;
        let mask = Tensor::ones(label_shape.as_slice(), DType::F32, &Device::Cpu)?;
        let adam = Adam::new(network.varmap(), max_grad_norm)?;
        Ok(Self { network, input, labels, mask, adam, objective, learning_rate })
    }

    /// `(1, in_channels, spatial...)`.
    pub fn input_shape(&self) -> &[usize] {
        self.input.dims()
    }

    /// Trainable parameters of the network.
    pub fn parameter_count(&self) -> usize {
        self.network.parameter_count()
    }

    /// The training forward (batch statistics) and the objective's masked MSE.
    fn loss(&self) -> Result<Tensor> {
        let output = self.objective.activation(&self.network.forward_train(&self.input)?)?;
        masked_mse(&output, &self.labels, &self.mask)
    }

    /// One training step: forward, loss, backward, clipping, an Adam update. Returns the seconds
    /// of the forward pass and loss.
    pub fn train_step(&mut self) -> Result<f64> {
        let started = Instant::now();
        let loss = self.loss()?;
        let forward_s = started.elapsed().as_secs_f64();
        self.adam.step(&loss, self.learning_rate)?;
        Ok(forward_s)
    }

    /// Forward, loss and backward without the optimiser. Returns the seconds of the backward
    /// pass.
    pub fn backward(&self) -> Result<f64> {
        let loss = self.loss()?;
        let started = Instant::now();
        drop(loss.backward()?);
        Ok(started.elapsed().as_secs_f64())
    }

    /// An evaluation forward (running statistics).
    pub fn infer(&self) -> Result<()> {
        drop(self.network.forward(&self.input)?);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_of_work_runs_on_a_small_case() {
        let config = UNetConfig { spatial_axes: 2, in_channels: 2, initial_channels: 2, depth: 1 };
        let mut case = BenchCase::new(config, 8, Objective::Mse, 1e-3, Some(0.5)).unwrap();
        assert_eq!(case.input_shape(), [1, 2, 8, 8]);
        assert!(case.parameter_count() > 0);
        assert!(case.train_step().unwrap() >= 0.0);
        assert!(case.backward().unwrap() >= 0.0);
        case.infer().unwrap();
    }
}
