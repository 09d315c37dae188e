//! Adam with global gradient-norm clipping whose moments can be saved and restored, so that a
//! resumed run continues exactly (candle's `AdamW` keeps its state private). The update is
//! candle's `AdamW` with zero weight decay; on the CPU it overwrites the weights and moments in
//! place instead of allocating a tensor per operation, with the same rounding.

use std::collections::HashMap;
use std::path::Path;

use candle_core::backprop::GradStore;
use candle_core::{CpuStorage, DType, Device, InplaceOp2, InplaceOp3, Layout, Result, Tensor, Var, WithDType, bail};
use candle_nn::VarMap;
use rayon::prelude::*;

use crate::op::with_slice;

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
        let norm = grad_norm(&grads, &self.vars)?;
        let clip = self.max_grad_norm.map(|max| max / (norm + 1e-6)).filter(|&scale| scale < 1.0);
        self.steps += 1;
        let t = self.steps as i32;
        let update = Update { clip, scale_m: 1.0 / (1.0 - BETA1.powi(t)), scale_v: 1.0 / (1.0 - BETA2.powi(t)), lr };
        for ((var, m), v) in self.vars.iter().zip(&mut self.first).zip(&mut self.second) {
            let Some(g) = grads.remove(var) else { continue };
            if g.device().is_cpu() {
                update.in_place(var.as_tensor(), &g, m, v)?;
            } else {
                let (next_w, next_m, next_v) = update.with_tensor_ops(var.as_tensor(), &g, m, v)?;
                var.set(&next_w)?;
                (*m, *v) = (next_m, next_v);
            }
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

/// Global L2 norm of the gradients of `vars` (missing gradients count as zero), summed in f64
/// one variable and one entry after the other.
fn grad_norm(grads: &GradStore, vars: &[Var]) -> Result<f64> {
    let mut sum = 0.0;
    for var in vars {
        if let Some(g) = grads.get(var) {
            sum += match g.dtype() {
                DType::F32 if g.device().is_cpu() => with_slice::<f32, _>(g, |g| Ok(squares(g)))?,
                DType::F64 if g.device().is_cpu() => with_slice::<f64, _>(g, |g| Ok(squares(g)))?,
                _ => g.to_dtype(DType::F64)?.sqr()?.sum_all()?.to_scalar::<f64>()?,
            };
        }
    }
    Ok(sum.sqrt())
}

/// Σ x² in f64, in order (what candle's `to_dtype(F64)?.sqr()?.sum_all()` computes).
fn squares<T: WithDType>(g: &[T]) -> f64 {
    g.iter().fold(0.0, |sum, &x| {
        let x = x.to_f64();
        sum + x * x
    })
}

/// One Adam update's coefficients: the clipping factor (if the norm exceeded its bound), the
/// moments' bias corrections and the learning rate.
struct Update {
    clip: Option<f64>,
    scale_m: f64,
    scale_v: f64,
    lr: f64,
}

impl Update {
    /// New weights and moments from candle's tensor ops (candle's `AdamW` without weight decay):
    /// every device.
    fn with_tensor_ops(&self, w: &Tensor, g: &Tensor, m: &Tensor, v: &Tensor) -> Result<(Tensor, Tensor, Tensor)> {
        let g = match self.clip {
            Some(scale) => (g * scale)?,
            None => g.clone(),
        };
        let next_m = ((m * BETA1)? + (&g * (1.0 - BETA1))?)?.detach();
        let next_v = ((v * BETA2)? + (g.sqr()? * (1.0 - BETA2))?)?.detach();
        let update = ((&next_m * self.scale_m)? / ((&next_v * self.scale_v)?.sqrt()? + EPSILON)?)?;
        Ok(((w - (update * self.lr)?)?.detach(), next_m, next_v))
    }

    /// The same on CPU tensors, overwriting `w`, `m` and `v` in three passes without a temporary
    /// tensor. Each value rounds as in [`Self::with_tensor_ops`]: `tensor * c` is candle's affine
    /// `x·c + 0`, `tensor + c` its `x·1 + c`.
    fn in_place(&self, w: &Tensor, g: &Tensor, m: &Tensor, v: &Tensor) -> Result<()> {
        m.inplace_op2(g, &InPlace { update: self, pass: Pass::FirstMoment })?;
        v.inplace_op2(g, &InPlace { update: self, pass: Pass::SecondMoment })?;
        w.inplace_op3(m, v, &InPlace { update: self, pass: Pass::Weights })
    }
}

/// One pass of [`Update::in_place`]: what it overwrites, from what.
#[derive(Clone, Copy)]
enum Pass {
    /// m ← β₁·m + (1 − β₁)·g, reading g.
    FirstMoment,
    /// v ← β₂·v + (1 − β₂)·g², reading g.
    SecondMoment,
    /// w ← w − lr·m̂ / (√v̂ + ε), reading the new m and v.
    Weights,
}

struct InPlace<'a> {
    update: &'a Update,
    pass: Pass,
}

/// The float types of the update: `sqrt` besides candle's arithmetic.
trait AdamFloat: WithDType {
    fn sqrt(self) -> Self;
}

impl AdamFloat for f32 {
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
}

impl AdamFloat for f64 {
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
}

impl InPlace<'_> {
    /// Overwrites `dst` from `a` (and, in the weights' pass, `b`: the second moment).
    fn run<T: AdamFloat>(&self, dst: &mut [T], a: &[T], b: &[T]) {
        const CHUNK: usize = 1 << 14;
        let c = T::from_f64;
        let Update { clip, scale_m, scale_v, lr } = *self.update;
        let (zero, one, clip) = (c(0.0), c(1.0), clip.map(c));
        let clipped = |g: T| match clip {
            Some(scale) => g * scale + zero,
            None => g,
        };
        let (beta1, rest1, beta2, rest2) = (c(BETA1), c(1.0 - BETA1), c(BETA2), c(1.0 - BETA2));
        let (scale_m, scale_v, epsilon, lr) = (c(scale_m), c(scale_v), c(EPSILON), c(lr));
        dst.par_chunks_mut(CHUNK).enumerate().for_each(|(chunk, dst)| {
            let span = chunk * CHUNK..chunk * CHUNK + dst.len();
            match self.pass {
                Pass::FirstMoment => {
                    for (m, &g) in dst.iter_mut().zip(&a[span]) {
                        *m = (*m * beta1 + zero) + (clipped(g) * rest1 + zero);
                    }
                }
                Pass::SecondMoment => {
                    for (v, &g) in dst.iter_mut().zip(&a[span]) {
                        let g = clipped(g);
                        *v = (*v * beta2 + zero) + ((g * g) * rest2 + zero);
                    }
                }
                Pass::Weights => {
                    for ((w, &m), &v) in dst.iter_mut().zip(&a[span.clone()]).zip(&b[span]) {
                        let step = (m * scale_m + zero) / ((v * scale_v + zero).sqrt() * one + epsilon);
                        *w -= step * lr + zero;
                    }
                }
            }
        });
    }

    fn apply(
        &self,
        dst: &mut CpuStorage,
        dl: &Layout,
        a: &CpuStorage,
        al: &Layout,
        b: Option<(&CpuStorage, &Layout)>,
    ) -> Result<()> {
        let span = |l: &Layout| match l.contiguous_offsets() {
            Some((start, end)) if end - start == dl.shape().elem_count() => Ok(start..end),
            _ => bail!("Adam: the weights, gradients and moments must be contiguous and of one shape"),
        };
        let (d, sa) = (span(dl)?, span(al)?);
        let sb = match b {
            Some((_, l)) => span(l)?,
            None => 0..0,
        };
        match (dst, a, b.map(|(s, _)| s)) {
            (CpuStorage::F32(dst), CpuStorage::F32(a), None) => self.run(&mut dst[d], &a[sa], &[]),
            (CpuStorage::F32(dst), CpuStorage::F32(a), Some(CpuStorage::F32(b))) => {
                self.run(&mut dst[d], &a[sa], &b[sb])
            }
            (CpuStorage::F64(dst), CpuStorage::F64(a), None) => self.run(&mut dst[d], &a[sa], &[]),
            (CpuStorage::F64(dst), CpuStorage::F64(a), Some(CpuStorage::F64(b))) => {
                self.run(&mut dst[d], &a[sa], &b[sb])
            }
            _ => bail!("Adam: the weights, gradients and moments must all be f32 or all f64"),
        }
        Ok(())
    }
}

impl InplaceOp2 for InPlace<'_> {
    fn name(&self) -> &'static str {
        "amber-adam"
    }

    fn cpu_fwd(&self, dst: &mut CpuStorage, dl: &Layout, a: &CpuStorage, al: &Layout) -> Result<()> {
        self.apply(dst, dl, a, al, None)
    }
}

impl InplaceOp3 for InPlace<'_> {
    fn name(&self) -> &'static str {
        "amber-adam"
    }

    fn cpu_fwd(
        &self,
        dst: &mut CpuStorage,
        dl: &Layout,
        a: &CpuStorage,
        al: &Layout,
        b: &CpuStorage,
        bl: &Layout,
    ) -> Result<()> {
        self.apply(dst, dl, a, al, Some((b, bl)))
    }
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
    fn the_update_in_place_rounds_as_the_tensor_ops_do() {
        // Over twice the passes' chunk, with zeros among the entries, clipped and not.
        let len = 40_000;
        let random = |seed: u64| {
            let t = crate::gradcheck::random(len, seed).to_dtype(DType::F32).unwrap();
            let zeros = Tensor::zeros(len, DType::F32, &Device::Cpu).unwrap();
            let mask = crate::gradcheck::random(len, seed + 7).ge(0.8).unwrap();
            mask.where_cond(&zeros, &t).unwrap()
        };
        let (w, g) = (random(1), (random(2) * 30.0).unwrap());
        let (m, v) = (random(3), random(4).sqr().unwrap());
        for (step, clip) in [(1, Some(0.05)), (2, None), (3, Some(0.5))] {
            let update = Update {
                clip,
                scale_m: 1.0 / (1.0 - BETA1.powi(step)),
                scale_v: 1.0 / (1.0 - BETA2.powi(step)),
                lr: 1e-3,
            };
            let reference = update.with_tensor_ops(&w, &g, &m, &v).unwrap();
            update.in_place(&w, &g, &m, &v).unwrap();
            for (a, b) in [(&w, &reference.0), (&m, &reference.1), (&v, &reference.2)] {
                let (a, b) = (a.to_vec1::<f32>().unwrap(), b.to_vec1::<f32>().unwrap());
                assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()), "step {step}");
            }
        }
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
