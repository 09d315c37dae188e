//! Adam with global gradient-norm clipping whose moments can be saved and restored, so that a
//! resumed run continues exactly (candle's `AdamW` keeps its state private). The update is
//! candle's `AdamW` with zero weight decay.

use std::collections::HashMap;
use std::path::Path;

use candle_core::backprop::GradStore;
use candle_core::{DType, Device, Result, Tensor, Var, bail};
use candle_nn::VarMap;

const BETA1: f64 = 0.9;
const BETA2: f64 = 0.999;
const EPSILON: f64 = 1e-8;

/// Adam over every variable of a `VarMap`, in name order (so that the gradient norm sums in a
/// fixed order). Variables without a gradient (e.g. running statistics) are left alone.
pub struct Adam {
    names: Vec<String>,
    vars: Vec<Var>,
    first: Vec<Tensor>,
    second: Vec<Tensor>,
    steps: u64,
    max_grad_norm: Option<f64>,
}

impl Adam {
    /// Fresh moments (zero) for the variables of `varmap`; gradients are clipped to a global
    /// norm of `max_grad_norm` if set.
    pub fn new(varmap: &VarMap, max_grad_norm: Option<f64>) -> Result<Self> {
        let mut named: Vec<(String, Var)> = match varmap.data().lock() {
            Ok(data) => data.iter().map(|(k, v)| (k.clone(), v.clone())).collect(),
            Err(_) => bail!("poisoned variable map"),
        };
        named.sort_by(|a, b| a.0.cmp(&b.0));
        let (names, vars): (Vec<String>, Vec<Var>) = named.into_iter().unzip();
        let zeros = |v: &Var| v.as_tensor().zeros_like();
        let first = vars.iter().map(zeros).collect::<Result<_>>()?;
        let second = vars.iter().map(zeros).collect::<Result<_>>()?;
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
            None => grad_norm(&grads, &self.vars)?,
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
    }

    /// Restores moments written by [`Self::save`] and the step count.
    pub fn load(&mut self, path: &Path, steps: u64) -> Result<()> {
        let mut tensors = candle_core::safetensors::load(path, &Device::Cpu)?;
        for (i, name) in self.names.iter().enumerate() {
            for (prefix, slot) in [("m", &mut self.first[i]), ("v", &mut self.second[i])] {
                let key = format!("{prefix}.{name}");
                let Some(t) = tensors.remove(&key) else { bail!("missing optimiser moment `{key}`") };
                if t.shape() != slot.shape() || t.dtype() != slot.dtype() {
                    bail!("optimiser moment `{key}` has shape {:?}", t.shape());
                }
                *slot = t.to_device(slot.device())?;
            }
        }
        if let Some(extra) = tensors.keys().next() {
            bail!("unexpected optimiser moment `{extra}`");
        }
        self.steps = steps;
        Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    /// One variable `w`, loss Σ w²: gradient 2w.
    fn quadratic(values: &[f32]) -> (VarMap, Var) {
        let varmap = VarMap::new();
        let var = Var::from_tensor(&Tensor::new(values, &Device::Cpu).unwrap()).unwrap();
        varmap.data().lock().unwrap().insert("w".into(), var.clone());
        (varmap, var)
    }

    #[test]
    fn clipping_scales_the_update_and_reports_the_norm_before() {
        let (varmap, var) = quadratic(&[3.0, 4.0]);
        let mut adam = Adam::new(&varmap, Some(0.5)).unwrap();
        let norm = adam.step(&var.as_tensor().sqr().unwrap().sum_all().unwrap(), 0.1).unwrap();
        assert!((norm - 10.0).abs() < 1e-6);
        // Adam's first step moves every entry by about lr, whatever the gradient's scale.
        let w = var.as_tensor().to_vec1::<f32>().unwrap();
        assert!((w[0] - 2.9).abs() < 1e-5 && (w[1] - 3.9).abs() < 1e-5, "{w:?}");
        assert_eq!(adam.steps(), 1);
    }

    #[test]
    fn saved_moments_resume_exactly() {
        let run = |split: bool| {
            let (varmap, var) = quadratic(&[1.0, -2.0, 0.5]);
            let mut adam = Adam::new(&varmap, None).unwrap();
            let loss = |v: &Var| v.as_tensor().sqr().unwrap().sum_all().unwrap();
            for _ in 0..3 {
                adam.step(&loss(&var), 0.05).unwrap();
            }
            if split {
                let dir = std::env::temp_dir().join(format!("amber-nn-adam-{}", std::process::id()));
                std::fs::create_dir_all(&dir).unwrap();
                let path = dir.join("optimiser.safetensors");
                adam.save(&path).unwrap();
                adam = Adam::new(&varmap, None).unwrap();
                adam.load(&path, 3).unwrap();
                std::fs::remove_dir_all(dir).unwrap();
            }
            for _ in 0..3 {
                adam.step(&loss(&var), 0.05).unwrap();
            }
            var.as_tensor().to_vec1::<f32>().unwrap()
        };
        assert_eq!(run(false), run(true));
    }
}
