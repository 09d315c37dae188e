//! The U-Net's CPU ops that candle lacks or gets wrong, each a custom op with a hand-written
//! backward and generic over the number of spatial axes (2D images, 3D voxel grids):
//! [`conv`] (odd kernel, "same" padding), [`conv_transpose2`] (kernel 2, stride 2),
//! [`max_pool2`] (candle's `max_pool2d` backward is wrong) and [`batch_norm_relu`] (candle-nn's
//! norms are not all differentiable, and fusing the ReLU saves two passes).
//!
//! Each is a slice-loop kernel made a candle op by `amber_nn::op::Fused`. Tensors are
//! channel-major, `(N, C, spatial...)`. The convolutions are tiled im2col + gemm:
//! each work item unfolds a block of rows of one image into a small scratch matrix and
//! multiplies it straight into the output, so no image-sized unfolded copy ever exists.

mod batch_norm;
mod conv;
mod conv_transpose;
mod gemm;
mod pool;

pub use batch_norm::{BatchNormStats, batch_norm_relu};
pub use conv::conv;
pub use conv_transpose::conv_transpose2;
pub use pool::max_pool2;

use std::mem::MaybeUninit;

use candle_core::{Result, WithDType, bail};
use rayon::prelude::*;

/// The float types the ops run on: f32 for training, f64 for gradient checks.
pub(crate) trait Float: WithDType {}

impl Float for f32 {}
impl Float for f64 {}

/// `(N, C, spatial...)` of a channel-major tensor with `spatial_axes` spatial axes.
fn image_dims(op: &str, dims: &[usize], spatial_axes: usize) -> Result<(usize, usize, Vec<usize>)> {
    if dims.len() != spatial_axes + 2 || spatial_axes == 0 || dims[2..].contains(&0) {
        bail!("{op}: expected a (N, C, {spatial_axes} non-empty spatial axes) tensor, got shape {dims:?}");
    }
    Ok((dims[0], dims[1], dims[2..].to_vec()))
}

/// A vector of `len` values built plane by plane in parallel: `fill(i, plane)` must write every
/// slot of plane `i` (`len` is a multiple of `plane`). Saves the zero fill of `vec![0; len]`.
fn build_by_planes<T: Float>(len: usize, plane: usize, fill: impl Fn(usize, &mut [MaybeUninit<T>]) + Sync) -> Vec<T> {
    let mut out: Vec<T> = Vec::with_capacity(len);
    out.spare_capacity_mut()[..len].par_chunks_mut(plane.max(1)).enumerate().for_each(|(i, p)| fill(i, p));
    // SAFETY: every caller's `fill` writes every slot of its plane, and the planes cover `len`.
    unsafe { out.set_len(len) };
    out
}

/// A raw pointer that work items running in parallel write through, each into its own disjoint
/// part of the buffer.
#[derive(Clone, Copy)]
struct SharedMut<T>(*mut T);

// SAFETY: every user writes disjoint index ranges from different threads (checked at each use).
unsafe impl<T: Send> Send for SharedMut<T> {}
unsafe impl<T: Send> Sync for SharedMut<T> {}

impl<T> SharedMut<T> {
    /// The pointer (a method, so that closures capture the `Sync` wrapper, not the raw field).
    fn ptr(self) -> *mut T {
        self.0
    }
}

#[cfg(test)]
pub(crate) mod testing;
