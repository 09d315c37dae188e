//! The update function: `x ← LayerNorm(x + MLP_V([x, a]))` as one op, with the concatenation
//! split into `x·W_x + a·W_a`.

use amber_nn::op::{Fused, SliceOp};
use amber_nn::reduce::ordered_fold;
use candle_core::{Layout, Result, Shape, Tensor, bail};
use rayon::prelude::*;

use super::{Saved, SavedSlot, Scratch};
use crate::kernels::{
    BLOCK_ROWS, MlpGrads, MlpWeights, Real, TailState, ZeroedByChunk, matmul, packed_len, tail_backward, tail_forward,
};

/// New node states (N×D) from node states `x` and aggregated messages `a` (both N×D) and the
/// packed node MLP + LayerNorm parameters `theta` (input 2D).
pub(crate) fn node_update(x: &Tensor, a: &Tensor, theta: &Tensor) -> Result<Tensor> {
    let (x, a, theta) = (x.contiguous()?, a.contiguous()?, theta.contiguous()?);
    let op = NodeUpdate {
        rows: x.dim(0)?,
        d: x.dim(1)?,
        save: x.track_op() || a.track_op() || theta.track_op(),
        saved: SavedSlot::default(),
    };
    x.apply_op3(&a, &theta, Fused(op))
}

struct NodeUpdate {
    rows: usize,
    d: usize,
    save: bool,
    saved: SavedSlot,
}

impl NodeUpdate {
    fn check(&self, x: usize, a: usize, theta: usize) -> Result<()> {
        let (n, d) = (self.rows, self.d);
        if x != n * d || a != n * d || theta != packed_len(2 * d, d) {
            bail!("node_update: got {x} node, {a} aggregate and {theta} parameter values for N={n}, D={d}");
        }
        Ok(())
    }
}

impl<T: Real> SliceOp<T, 3> for NodeUpdate {
    const NAME: &'static str = "amber-node-update";

    fn forward(&self, [x, a, theta]: [&[T]; 3], _: [&Layout; 3]) -> Result<(Vec<T>, Shape)> {
        self.check(x.len(), a.len(), theta.len())?;
        let (n, d) = (self.rows, self.d);
        let w = MlpWeights::unpack(theta, 2 * d, d);
        let block = |x: &[T], a: &[T], st: TailState<'_, T>, out: &mut [T]| {
            let rows = x.len() / d;
            matmul(rows, d, d, x, false, w.w1_rows(0..d), false, st.h1, false);
            matmul(rows, d, d, a, false, w.w1_rows(d..2 * d), false, st.h1, true);
            tail_forward(&w, x, st, out);
        };
        let chunk = BLOCK_ROWS * d;
        let mut out = ZeroedByChunk::new(n * d);
        if self.save {
            let (mut h1, mut h2, mut mean, mut rstd) =
                (ZeroedByChunk::new(n * d), ZeroedByChunk::new(n * d), ZeroedByChunk::new(n), ZeroedByChunk::new(n));
            (
                out.par_chunks_mut(chunk),
                x.par_chunks(chunk),
                a.par_chunks(chunk),
                h1.par_chunks_mut(chunk),
                h2.par_chunks_mut(chunk),
                mean.par_chunks_mut(BLOCK_ROWS),
                rstd.par_chunks_mut(BLOCK_ROWS),
            )
                .into_par_iter()
                .for_each(|(out, x, a, h1, h2, mean, rstd)| block(x, a, TailState { h1, h2, mean, rstd }, out));
            self.saved.put(Saved {
                h1: T::to_cpu_storage_owned(h1.into_vec()),
                h2: T::to_cpu_storage_owned(h2.into_vec()),
                mean: T::to_cpu_storage_owned(mean.into_vec()),
                rstd: T::to_cpu_storage_owned(rstd.into_vec()),
            })?;
        } else {
            (out.par_chunks_mut(chunk), x.par_chunks(chunk), a.par_chunks(chunk)).into_par_iter().for_each_init(
                || Scratch::new(BLOCK_ROWS, d),
                |scratch, (out, x, a)| block(x, a, scratch.state(x.len() / d, d), out),
            );
        }
        Ok((out.into_vec(), Shape::from((n, d))))
    }

    fn backward(
        &self,
        [xv, av, tv]: [&[T]; 3],
        _: [&Layout; 3],
        _: &[T],
        gv: &[T],
        _: [bool; 3],
    ) -> Result<[Option<Vec<T>>; 3]> {
        self.check(xv.len(), av.len(), tv.len())?;
        let saved = self.saved.take(<Self as SliceOp<T, 3>>::NAME)?;
        // As in the edge update, the saved activations are overwritten with gradients: h2 becomes
        // d(x), h1 the first-layer pre-activation gradient.
        let (mut h1, mut dx) = (T::cpu_storage_data(saved.h1)?, T::cpu_storage_data(saved.h2)?);
        let (mean, rstd) = (saved.mean.as_slice::<T>()?, saved.rstd.as_slice::<T>()?);
        let (n, d) = (self.rows, self.d);
        if h1.len() != n * d || dx.len() != n * d {
            bail!("node_update: saved activations do not match the input");
        }
        let w = MlpWeights::unpack(tv, 2 * d, d);
        let zero = T::from_f64(0.0);
        let chunk = BLOCK_ROWS * d;
        let mut da = ZeroedByChunk::new(n * d);
        let blocks = (
            dx.par_chunks_mut(chunk),
            da.par_chunks_mut(chunk),
            h1.par_chunks_mut(chunk),
            gv.par_chunks(chunk),
            xv.par_chunks(chunk),
            av.par_chunks(chunk),
            mean.par_chunks(BLOCK_ROWS),
            rstd.par_chunks(BLOCK_ROWS),
        );
        let (g, _) = ordered_fold(
            blocks.into_par_iter(),
            || (MlpGrads::zeros(2 * d, d), vec![zero; 2 * chunk]),
            |(mut g, mut scratch), (dx, da, dpre1, gr, x, a, mean, rstd)| {
                let rows = x.len() / d;
                tail_backward(&w, gr, x, dpre1, dx, mean, rstd, &mut scratch[..2 * rows * d], &mut g);
                matmul(rows, d, d, dpre1, false, w.w1_rows(0..d), true, dx, true);
                matmul(rows, d, d, dpre1, false, w.w1_rows(d..2 * d), true, da, false);
                let (w1x, w1a) = g.w1.split_at_mut(d * d);
                matmul(d, rows, d, x, true, dpre1, false, w1x, true);
                matmul(d, rows, d, a, true, dpre1, false, w1a, true);
                (g, scratch)
            },
            |(a, scratch), (b, _)| (a.merge(b), scratch),
        );
        Ok([Some(dx), Some(da.into_vec()), Some(g.pack(2 * d, d))])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::gradcheck::*;

    fn fused(t: &[Tensor]) -> Result<Tensor> {
        probe_loss(&node_update(&t[0], &t[1], &t[2])?, 7)
    }

    fn composed(t: &[Tensor]) -> Result<Tensor> {
        probe_loss(&composed_residual_mlp(&Tensor::cat(&[&t[0], &t[1]], 1)?, &t[0], &t[2])?, 7)
    }

    #[test]
    fn gradients_match_finite_differences() {
        let t = [random((5, 3), 1), random((5, 3), 2), random_theta(6, 3, 3)];
        check_finite_differences(&t, &fused);
    }

    #[test]
    fn matches_the_candle_composition_across_blocks() {
        for n in [5, 600] {
            let t = [random((n, 4), 1), random((n, 4), 2), random_theta(8, 4, 3)];
            assert!(
                (fused(&t).unwrap().to_scalar::<f64>().unwrap() - composed(&t).unwrap().to_scalar::<f64>().unwrap())
                    .abs()
                    < 1e-9
            );
            assert_close(&autograd(&t, &fused), &autograd(&t, &composed), 1e-10);
        }
    }

    #[test]
    fn gradients_are_the_same_at_any_thread_count() {
        let t = f32s(&[random((2_000, 8), 1), random((2_000, 8), 2), random_theta(16, 8, 3)]);
        assert_same_at_any_thread_count(|| autograd(&t, &fused));
    }
}
