//! Training the U-Net behind plain slices: [`TrainingImages`] holds a run's stacked images as
//! tensors, built from `Vec<f32>`s; [`CnnTrainer`] owns the network, the images and the Adam
//! optimiser and takes one step (training forward, the objective's mean squared error over the
//! pixels inside the geometry, backward, clipping, update) on all images or a subset.

use std::path::Path;

use amber_nn::{Adam, Objective};
use candle_core::{Device, Tensor};

use crate::UNet;
use crate::error::{CnnError, Result};

/// A run's training images, stacked: inputs `(N, C, spatial...)`, targets and masks
/// `(N, 1, spatial...)` (mask 1 inside the geometry, 0 outside).
pub struct TrainingImages {
    inputs: Tensor,
    targets: Tensor,
    masks: Tensor,
}

impl TrainingImages {
    /// The images from channel-major data: `inputs` holds `images × channels` planes of the
    /// `spatial` shape, image after image; `targets` and `masks` one plane per image.
    pub fn new(
        inputs: Vec<f32>,
        targets: Vec<f32>,
        masks: Vec<f32>,
        images: usize,
        channels: usize,
        spatial: &[usize],
    ) -> Result<Self> {
        let shape = |c: usize| -> Vec<usize> { [images, c].into_iter().chain(spatial.iter().copied()).collect() };
        Ok(Self {
            inputs: Tensor::from_vec(inputs, shape(channels), &Device::Cpu)?,
            targets: Tensor::from_vec(targets, shape(1), &Device::Cpu)?,
            masks: Tensor::from_vec(masks, shape(1), &Device::Cpu)?,
        })
    }
}

/// What one training step measured.
#[derive(Clone, Debug, PartialEq)]
pub struct CnnStep {
    /// Masked loss of the step's images.
    pub loss: f64,
    /// Global gradient norm before clipping.
    pub grad_norm: f64,
    /// Images the step trained on.
    pub images: usize,
}

/// A trainable U-Net with its training images, objective and optimiser.
pub struct CnnTrainer {
    network: UNet,
    images: TrainingImages,
    objective: Objective,
    optimiser: Adam,
}

impl CnnTrainer {
    /// Trains `network` for `objective` (whose targets `images` hold), with fresh moments for
    /// every variable; gradients are clipped to a global norm of `max_grad_norm` if set.
    pub fn new(
        network: UNet,
        images: TrainingImages,
        objective: Objective,
        max_grad_norm: Option<f64>,
    ) -> Result<Self> {
        let optimiser = Adam::new(network.varmap(), max_grad_norm)?;
        Ok(Self { network, images, objective, optimiser })
    }

    /// Restores the moments written by [`Self::save_optimiser`] and the count of updates taken.
    pub fn load_optimiser(&mut self, path: &Path, steps: u64) -> Result<()> {
        self.optimiser.load(path, steps).map_err(|e| CnnError::ModelFile { path: path.into(), message: e.to_string() })
    }

    /// Writes the optimiser's moments (safetensors); the update count is the caller's to store.
    pub fn save_optimiser(&self, path: &Path) -> Result<()> {
        self.optimiser.save(path).map_err(|e| CnnError::ModelFile { path: path.into(), message: e.to_string() })
    }

    /// Optimiser updates taken so far.
    pub fn optimiser_steps(&self) -> u64 {
        self.optimiser.steps()
    }

    /// The network (sharing the trained variables).
    pub fn network(&self) -> &UNet {
        &self.network
    }

    /// One step with learning rate `lr` on the images of `subset` (indices in increasing
    /// order), or on all of them.
    pub fn train_step(&mut self, subset: Option<&[usize]>, lr: f64) -> Result<CnnStep> {
        let index = subset
            .map(|s| Tensor::from_vec(s.iter().map(|&i| i as u32).collect::<Vec<_>>(), s.len(), &Device::Cpu))
            .transpose()?;
        let pick = |t: &Tensor| match &index {
            Some(index) => t.index_select(index, 0),
            None => Ok(t.clone()),
        };
        let images = &self.images;
        let (inputs, targets, masks) = (pick(&images.inputs)?, pick(&images.targets)?, pick(&images.masks)?);
        let output = self.network.forward_train(&inputs)?;
        let loss = masked_mse(&self.objective.activation(&output)?, &targets, &masks)?;
        let loss_value = f64::from(loss.to_scalar::<f32>()?);
        let grad_norm = self.optimiser.step(&loss, lr)?;
        Ok(CnnStep { loss: loss_value, grad_norm, images: inputs.dim(0)? })
    }
}

/// Mean over the pixels where `mask` is 1 (0 elsewhere) of the squared difference between
/// `prediction` and `targets`; all three tensors have the same shape.
pub(crate) fn masked_mse(prediction: &Tensor, targets: &Tensor, mask: &Tensor) -> Result<Tensor> {
    let squared = ((prediction - targets)?.sqr()? * mask)?;
    let inside = mask.sum_all()?.maximum(1.0)?;
    Ok(squared.sum_all()?.div(&inside)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_loss_averages_over_inside_pixels_only() {
        let dev = Device::Cpu;
        let out = Tensor::new(&[[0.0f32, 1.0, 5.0]], &dev).unwrap();
        let targets = Tensor::new(&[[1.0f32, 1.0, -7.0]], &dev).unwrap();
        let mask = Tensor::new(&[[1.0f32, 1.0, 0.0]], &dev).unwrap();
        let loss = |objective: Objective| {
            let prediction = objective.activation(&out).unwrap();
            masked_mse(&prediction, &targets, &mask).unwrap().to_scalar::<f32>().unwrap()
        };
        assert_eq!(loss(Objective::LogMse), 0.5);
        let expected = ((2f64.ln() - 1.0).powi(2) + (1.0 + (-1f64).exp().ln_1p() - 1.0).powi(2)) / 2.0;
        assert!((f64::from(loss(Objective::SoftplusMse)) - expected).abs() < 1e-6);
    }
}
