//! Adam with global gradient-norm clipping whose moments can be saved and restored, so that a
//! resumed run continues exactly (`amber_mpn::Trainer` keeps candle's `AdamW`, whose state is
//! private). The update is candle's `AdamW` with zero weight decay.

use std::collections::HashMap;
use std::path::Path;

use amber_mpn::clip_grad_norm;
use candle_core::{Device, Tensor, Var};
use candle_nn::VarMap;

use crate::error::{Result, TrainError};

const BETA1: f64 = 0.9;
const BETA2: f64 = 0.999;
const EPSILON: f64 = 1e-8;

/// Adam over every variable of a `VarMap`, in name order (so that the gradient norm sums in a
/// fixed order).
pub struct Adam {
    names: Vec<String>,
    vars: Vec<Var>,
    first: Vec<Tensor>,
    second: Vec<Tensor>,
    steps: u64,
    max_grad_norm: Option<f64>,
}

impl Adam {
    /// Fresh moments (zero) for the variables of `varmap`.
    pub fn new(varmap: &VarMap, max_grad_norm: Option<f64>) -> Result<Self> {
        let mut named: Vec<(String, Var)> =
            varmap.data().lock().expect("var map lock").iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        named.sort_by(|a, b| a.0.cmp(&b.0));
        let (names, vars): (Vec<String>, Vec<Var>) = named.into_iter().unzip();
        let zeros = |v: &Var| v.as_tensor().zeros_like();
        let first = vars.iter().map(zeros).collect::<candle_core::Result<_>>()?;
        let second = vars.iter().map(zeros).collect::<candle_core::Result<_>>()?;
        Ok(Self { names, vars, first, second, steps: 0, max_grad_norm })
    }

    /// Updates taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Backpropagates `loss`, clips the global gradient norm and applies one update with
    /// learning rate `lr`; returns the gradient norm before clipping.
    pub fn step(&mut self, loss: &Tensor, lr: f64) -> Result<f64> {
        let mut grads = loss.backward()?;
        let norm = match self.max_grad_norm {
            Some(max) => clip_grad_norm(&mut grads, &self.vars, max)?,
            None => amber_mpn::grad_norm(&grads, &self.vars)?,
        };
        self.steps += 1;
        let t = self.steps as i32;
        let (scale_m, scale_v) = (1.0 / (1.0 - BETA1.powi(t)), 1.0 / (1.0 - BETA2.powi(t)));
        for ((var, m), v) in self.vars.iter().zip(&mut self.first).zip(&mut self.second) {
            let Some(g) = grads.get(var) else { continue };
            let next_m = ((&*m * BETA1)? + (g * (1.0 - BETA1))?)?.detach();
            let next_v = ((&*v * BETA2)? + (g.sqr()? * (1.0 - BETA2))?)?.detach();
            let update = ((&next_m * scale_m)? / ((&next_v * scale_v)?.sqrt()? + EPSILON)?)?;
            var.set(&(var.as_tensor() - (update * lr)?)?)?;
            *m = next_m;
            *v = next_v;
        }
        Ok(norm)
    }

    /// Writes the moments to `path` (safetensors, `m.<name>` and `v.<name>`); the step count is
    /// the caller's to store.
    pub fn save(&self, path: &Path) -> Result<()> {
        let mut tensors = HashMap::new();
        for ((name, m), v) in self.names.iter().zip(&self.first).zip(&self.second) {
            tensors.insert(format!("m.{name}"), m.clone());
            tensors.insert(format!("v.{name}"), v.clone());
        }
        candle_core::safetensors::save(&tensors, path)
            .map_err(|e| TrainError::Checkpoint { path: path.into(), message: e.to_string() })
    }

    /// Restores moments written by [`Self::save`] and the step count.
    pub fn load(&mut self, path: &Path, steps: u64) -> Result<()> {
        let fail = |message: String| TrainError::Checkpoint { path: path.into(), message };
        let mut tensors = candle_core::safetensors::load(path, &Device::Cpu).map_err(|e| fail(e.to_string()))?;
        for (i, name) in self.names.iter().enumerate() {
            for (prefix, slot) in [("m", &mut self.first[i]), ("v", &mut self.second[i])] {
                let key = format!("{prefix}.{name}");
                let t = tensors.remove(&key).ok_or_else(|| fail(format!("missing optimiser moment `{key}`")))?;
                if t.shape() != slot.shape() || t.dtype() != slot.dtype() {
                    return Err(fail(format!("optimiser moment `{key}` has shape {:?}", t.shape())));
                }
                *slot = t;
            }
        }
        if let Some(extra) = tensors.keys().next() {
            return Err(fail(format!("unexpected optimiser moment `{extra}`")));
        }
        self.steps = steps;
        Ok(())
    }
}
