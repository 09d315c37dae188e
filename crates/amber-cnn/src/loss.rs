//! What the U-Net's output means and how it is trained (spec §8, reference notes §8): MSE on log
//! sizes (the paper's Poisson runs), MSE after a softplus (the Console runs and an ablation) and
//! plain MSE on raw sizes (an ablation); always averaged over the pixels inside the geometry.

use candle_core::Tensor;
use serde::{Deserialize, Serialize};

use crate::error::Result;

/// The output transform and loss of the U-Net.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CnnLoss {
    /// size = exp(z); MSE of z against log sizes (default).
    #[default]
    LogMse,
    /// size = softplus(z); MSE of the size against the label.
    SoftplusMse,
    /// size = z; MSE against the label (non-positive sizes are clipped at h_min downstream).
    Mse,
}

impl CnnLoss {
    /// The regression target of a label size.
    pub fn target(self, size: f64) -> f64 {
        match self {
            CnnLoss::LogMse => size.ln(),
            CnnLoss::SoftplusMse | CnnLoss::Mse => size,
        }
    }

    /// The size an output value stands for.
    pub fn size(self, z: f64) -> f64 {
        match self {
            CnnLoss::LogMse => z.exp(),
            CnnLoss::SoftplusMse => z.max(0.0) + (-z.abs()).exp().ln_1p(),
            CnnLoss::Mse => z,
        }
    }

    /// Mean over the pixels where `mask` is 1 (0 elsewhere) of the squared difference between
    /// the (transformed) `output` and `targets` ([`Self::target`] of the labels); all three
    /// tensors have the same shape.
    pub fn loss(self, output: &Tensor, targets: &Tensor, mask: &Tensor) -> Result<Tensor> {
        let prediction = match self {
            CnnLoss::LogMse | CnnLoss::Mse => output.clone(),
            // softplus(z) = relu(z) + log(1 + e^−|z|), overflow-free.
            CnnLoss::SoftplusMse => (output.relu()? + (output.abs()?.neg()?.exp()? + 1.0)?.log()?)?,
        };
        let squared = ((prediction - targets)?.sqr()? * mask)?;
        let inside = mask.sum_all()?.maximum(1.0)?;
        Ok(squared.sum_all()?.div(&inside)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;

    #[test]
    fn targets_and_sizes_invert_each_other() {
        for loss in [CnnLoss::LogMse, CnnLoss::SoftplusMse, CnnLoss::Mse] {
            let y: f64 = 0.37;
            let z = match loss {
                CnnLoss::SoftplusMse => y + (-(-y).exp_m1()).ln(),
                _ => loss.target(y),
            };
            assert!((loss.size(z) - y).abs() < 1e-12, "{loss:?}");
        }
    }

    #[test]
    fn loss_averages_over_inside_pixels_only() {
        let dev = Device::Cpu;
        let out = Tensor::new(&[[0.0f32, 1.0, 5.0]], &dev).unwrap();
        let targets = Tensor::new(&[[1.0f32, 1.0, -7.0]], &dev).unwrap();
        let mask = Tensor::new(&[[1.0f32, 1.0, 0.0]], &dev).unwrap();
        let mse = CnnLoss::LogMse.loss(&out, &targets, &mask).unwrap().to_scalar::<f32>().unwrap();
        assert_eq!(mse, 0.5);
        let softplus = CnnLoss::SoftplusMse.loss(&out, &targets, &mask).unwrap().to_scalar::<f32>().unwrap();
        let expected = ((2f64.ln() - 1.0).powi(2) + (1.0 + (-1f64).exp().ln_1p() - 1.0).powi(2)) / 2.0;
        assert!((f64::from(softplus) - expected).abs() < 1e-6);
    }
}
