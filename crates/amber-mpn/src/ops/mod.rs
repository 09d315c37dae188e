//! Fused candle custom ops of one message-passing step, each with a hand-written backward:
//! [`edge_update`] (message), [`segment_mean`] (aggregate) and [`node_update`] (update); and a
//! vectorised [`tanh`] for the decoder.
//!
//! Forward and backward are plain slice loops, parallel over blocks of rows with rayon, made
//! candle ops by `amber_nn::op::Fused`; the weight gradients are summed over the blocks by
//! `amber_nn::reduce::ordered_fold`, so they are the same bits at any thread count. The ops keep the few intermediates their backward needs inside the op object, and only when an input
//! is tracked by autograd, so inference with plain tensors stores nothing.

mod edge_update;
mod node_update;
mod segment_mean;
mod tanh;

use std::sync::Mutex;

use candle_core::{CpuStorage, Result, bail};

pub(crate) use edge_update::edge_update;
pub(crate) use node_update::node_update;
pub(crate) use segment_mean::segment_mean;
pub(crate) use tanh::tanh;

use crate::kernels::Real;

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
