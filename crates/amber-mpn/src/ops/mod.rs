//! Fused candle custom ops of one message-passing step, each with a hand-written backward:
//! [`edge_update`] (message), [`segment_mean`] (aggregate) and [`node_update`] (update); and a
//! vectorised [`tanh`] for the decoder.
//!
//! Forward and backward are plain slice loops, parallel over blocks of rows with rayon. The ops
//! keep the few intermediates their backward needs inside the op object, and only when an input
//! is tracked by autograd, so inference with plain tensors stores nothing.

mod edge_update;
mod node_update;
mod segment_mean;
mod tanh;

use std::sync::Mutex;

use candle_core::backend::BackendStorage;
use candle_core::{CpuStorage, CustomOp3, DType, Layout, Result, Shape, Storage, Tensor, bail};

pub(crate) use edge_update::edge_update;
pub(crate) use node_update::node_update;
pub(crate) use segment_mean::segment_mean;
pub(crate) use tanh::tanh;

use crate::kernels::Real;

/// The contiguous data of a CPU storage.
fn cpu_slice<'a, T: Real>(s: &'a CpuStorage, l: &Layout) -> Result<&'a [T]> {
    match l.contiguous_offsets() {
        Some((start, end)) => Ok(&s.as_slice::<T>()?[start..end]),
        None => bail!("amber-mpn ops need contiguous inputs"),
    }
}

/// The contiguous data of a tensor, borrowed from its storage guard.
fn tensor_slice<'a, T: Real>(storage: &'a Storage, l: &Layout) -> Result<&'a [T]> {
    match storage {
        Storage::Cpu(s) => cpu_slice(s, l),
        _ => bail!("amber-mpn ops run on the CPU only"),
    }
}

fn float_dtype(op: &str, dtypes: &[DType]) -> Result<DType> {
    match dtypes {
        [first, rest @ ..] if matches!(first, DType::F32 | DType::F64) && rest.iter().all(|d| d == first) => Ok(*first),
        _ => bail!("{op}: inputs must be all f32 or all f64, got {dtypes:?}"),
    }
}

fn tensor_of<T: Real>(data: Vec<T>, shape: (usize, usize), like: &Tensor) -> Result<Tensor> {
    Tensor::from_vec(data, shape, like.device())
}

/// A fused residual-MLP op of three inputs (states, second states, packed parameters) with a
/// hand-written backward, in f32 or f64; [`Fused`] makes it a candle op.
trait FusedMlpOp: Send + Sync {
    const NAME: &'static str;
    /// Rows and columns of the output.
    fn output_shape(&self) -> (usize, usize);
    fn forward<T: Real>(&self, a: &[T], b: &[T], theta: &[T]) -> Result<Vec<T>>;
    /// The gradients of `a`, `b` and `theta`, each laid out as its input.
    fn backward<T: Real>(&self, a: &[T], b: &[T], theta: &[T], grad: &[T]) -> Result<[Vec<T>; 3]>;
}

/// The candle `CustomOp3` of a [`FusedMlpOp`]: dtype dispatch and storage access in one place.
struct Fused<Op>(Op);

impl<Op: FusedMlpOp> CustomOp3 for Fused<Op> {
    fn name(&self) -> &'static str {
        Op::NAME
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
        s3: &CpuStorage,
        l3: &Layout,
    ) -> Result<(CpuStorage, Shape)> {
        let op = &self.0;
        let storage = match float_dtype(Op::NAME, &[s1.dtype(), s2.dtype(), s3.dtype()])? {
            DType::F32 => CpuStorage::F32(op.forward(cpu_slice(s1, l1)?, cpu_slice(s2, l2)?, cpu_slice(s3, l3)?)?),
            _ => CpuStorage::F64(op.forward(cpu_slice(s1, l1)?, cpu_slice(s2, l2)?, cpu_slice(s3, l3)?)?),
        };
        Ok((storage, Shape::from(op.output_shape())))
    }

    fn bwd(
        &self,
        a: &Tensor,
        b: &Tensor,
        theta: &Tensor,
        _res: &Tensor,
        grad: &Tensor,
    ) -> Result<(Option<Tensor>, Option<Tensor>, Option<Tensor>)> {
        let grad = grad.contiguous()?;
        let [da, db, dtheta] = match float_dtype(Op::NAME, &[a.dtype(), b.dtype(), theta.dtype(), grad.dtype()])? {
            DType::F32 => self.backward::<f32>(a, b, theta, &grad)?,
            _ => self.backward::<f64>(a, b, theta, &grad)?,
        };
        Ok((Some(da), Some(db), Some(dtheta)))
    }
}

impl<Op: FusedMlpOp> Fused<Op> {
    /// Borrows the inputs' data, runs the op's backward and shapes each gradient as its input.
    fn backward<T: Real>(&self, a: &Tensor, b: &Tensor, theta: &Tensor, grad: &Tensor) -> Result<[Tensor; 3]> {
        let [sa, sb, st, sg] = [a, b, theta, grad].map(|t| t.storage_and_layout());
        let [da, db, dtheta] = self.0.backward::<T>(
            tensor_slice(&sa.0, sa.1)?,
            tensor_slice(&sb.0, sb.1)?,
            tensor_slice(&st.0, st.1)?,
            tensor_slice(&sg.0, sg.1)?,
        )?;
        let like = |data: Vec<T>, t: &Tensor| Tensor::from_vec(data, t.shape(), t.device());
        Ok([like(da, a)?, like(db, b)?, like(dtheta, theta)?])
    }
}

/// First-layer activations, second-layer activations and LayerNorm statistics of a residual MLP
/// block, saved by the forward for the backward.
struct Saved {
    h1: CpuStorage,
    h2: CpuStorage,
    mean: CpuStorage,
    rstd: CpuStorage,
}

/// Holder of [`Saved`]; the backward takes it out, so each graph can be differentiated once.
#[derive(Default)]
struct SavedSlot(Mutex<Option<Saved>>);

impl SavedSlot {
    fn put(&self, saved: Saved) -> Result<()> {
        match self.0.lock() {
            Ok(mut slot) => {
                *slot = Some(saved);
                Ok(())
            }
            Err(_) => bail!("poisoned op state"),
        }
    }

    fn take(&self, op: &str) -> Result<Saved> {
        match self.0.lock().map(|mut slot| slot.take()) {
            Ok(Some(saved)) => Ok(saved),
            Ok(None) => {
                bail!("{op}: backward called twice or on a graph built without gradient tracking")
            }
            Err(_) => bail!("poisoned op state"),
        }
    }
}

/// Zeroed per-block buffers for the inference path, which saves nothing.
struct Scratch<T> {
    h1: Vec<T>,
    h2: Vec<T>,
    mean: Vec<T>,
    rstd: Vec<T>,
}

impl<T: Real> Scratch<T> {
    fn new(rows: usize, d: usize) -> Self {
        let z = |n| vec![T::from_f64(0.0); n];
        Self { h1: z(rows * d), h2: z(rows * d), mean: z(rows), rstd: z(rows) }
    }

    fn state(&mut self, rows: usize, d: usize) -> crate::kernels::TailState<'_, T> {
        crate::kernels::TailState {
            h1: &mut self.h1[..rows * d],
            h2: &mut self.h2[..rows * d],
            mean: &mut self.mean[..rows],
            rstd: &mut self.rstd[..rows],
        }
    }
}

#[cfg(test)]
pub(crate) mod gradcheck;
