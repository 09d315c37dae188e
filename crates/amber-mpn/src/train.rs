//! One optimisation step as in the reference: backward, global gradient-norm clipping, Adam.

use candle_core::backprop::GradStore;
use candle_core::{DType, Tensor, Var};
use candle_nn::{AdamW, Optimizer, ParamsAdamW, VarMap};
use serde::{Deserialize, Serialize};

use crate::error::Result;

/// Optimiser settings (spec §5: Adam, lr 3e-4, clip 0.5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrainConfig {
    pub learning_rate: f64,
    /// Global L2 norm the gradients are scaled down to, if set.
    pub max_grad_norm: Option<f64>,
}

impl Default for TrainConfig {
    fn default() -> Self {
        Self { learning_rate: 3e-4, max_grad_norm: Some(0.5) }
    }
}

/// Adam (no weight decay) over every variable of a `VarMap`, with gradient clipping.
pub struct Trainer {
    vars: Vec<Var>,
    optimizer: AdamW,
    max_grad_norm: Option<f64>,
}

impl Trainer {
    pub fn new(varmap: &VarMap, config: &TrainConfig) -> Result<Self> {
        let vars = varmap.all_vars();
        // candle's AdamW with zero weight decay is Adam (its default decay is 0.01).
        let params = ParamsAdamW { lr: config.learning_rate, weight_decay: 0.0, ..Default::default() };
        let optimizer = AdamW::new(vars.clone(), params)?;
        Ok(Self { vars, optimizer, max_grad_norm: config.max_grad_norm })
    }

    pub fn set_learning_rate(&mut self, lr: f64) {
        self.optimizer.set_learning_rate(lr);
    }

    /// Backpropagates `loss`, clips and applies one Adam update; returns the gradient norm
    /// before clipping.
    pub fn step(&mut self, loss: &Tensor) -> Result<f64> {
        let mut grads = loss.backward()?;
        let norm = match self.max_grad_norm {
            Some(max) => clip_grad_norm(&mut grads, &self.vars, max)?,
            None => grad_norm(&grads, &self.vars)?,
        };
        self.optimizer.step(&grads)?;
        Ok(norm)
    }
}

/// Global L2 norm of the gradients of `vars` (missing gradients count as zero).
pub fn grad_norm(grads: &GradStore, vars: &[Var]) -> Result<f64> {
    let mut sum = 0.0;
    for var in vars {
        if let Some(g) = grads.get(var) {
            sum += g.to_dtype(DType::F64)?.sqr()?.sum_all()?.to_scalar::<f64>()?;
        }
    }
    Ok(sum.sqrt())
}

/// Scales all gradients by `max_norm / (norm + 1e-6)` when their global norm exceeds `max_norm`
/// (PyTorch's `clip_grad_norm_`); returns the norm before clipping.
pub fn clip_grad_norm(grads: &mut GradStore, vars: &[Var], max_norm: f64) -> Result<f64> {
    let norm = grad_norm(grads, vars)?;
    let scale = max_norm / (norm + 1e-6);
    if scale < 1.0 {
        for var in vars {
            if let Some(g) = grads.remove(var) {
                grads.insert(var, (g * scale)?);
            }
        }
    }
    Ok(norm)
}

/// Mean squared error between predictions and targets of the same shape.
pub fn mse(prediction: &Tensor, target: &Tensor) -> Result<Tensor> {
    Ok(candle_nn::loss::mse(prediction, target)?)
}
