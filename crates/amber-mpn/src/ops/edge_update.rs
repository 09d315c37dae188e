//! The message function: `e ← LayerNorm(e + MLP_E([x_src, x_dst, e]))` as one op.
//!
//! The first layer is split, `[x_src, x_dst, e]·W1 = (x·W_src)[src] + (x·W_dst)[dst] + e·W_e`,
//! so the two node-sized products are computed once per node instead of once per edge, and the
//! gather never materialises an edge-sized copy of `x`. Its backward is a segment sum of the
//! edge gradients by source (through the source-sorted index) and by destination.

use std::sync::Arc;

use amber_nn::op::{Fused, SliceOp};
use amber_nn::reduce::ordered_fold;
use candle_core::{Layout, Result, Shape, Tensor, bail};
use rayon::prelude::*;

use super::{Saved, SavedSlot, Scratch};
use crate::graph::Topology;
use crate::kernels::{
    BLOCK_ROWS, MlpGrads, MlpWeights, Real, TailState, ZeroedByChunk, add_assign, add_gathered, matmul, packed_len,
    segment_sum, tail_backward, tail_forward,
};

/// New edge states (E×D) from node states `x` (N×D), edge states `e` (E×D) and the packed edge
/// MLP + LayerNorm parameters `theta` (see [`crate::kernels::packed_len`] with input 3D).
pub(crate) fn edge_update(x: &Tensor, e: &Tensor, theta: &Tensor, topology: &Arc<Topology>) -> Result<Tensor> {
    let (x, e, theta) = (x.contiguous()?, e.contiguous()?, theta.contiguous()?);
    let op = EdgeUpdate {
        topology: topology.clone(),
        d: e.dim(1)?,
        save: x.track_op() || e.track_op() || theta.track_op(),
        saved: SavedSlot::default(),
    };
    x.apply_op3(&e, &theta, Fused(op))
}

struct EdgeUpdate {
    topology: Arc<Topology>,
    d: usize,
    save: bool,
    saved: SavedSlot,
}

impl EdgeUpdate {
    fn check(&self, x: usize, e: usize, theta: usize) -> Result<()> {
        let (n, m, d) = (self.topology.num_nodes(), self.topology.num_edges(), self.d);
        if x != n * d || e != m * d || theta != packed_len(3 * d, d) {
            bail!("edge_update: got {x} node, {e} edge and {theta} parameter values for N={n}, E={m}, D={d}");
        }
        Ok(())
    }
}

impl<T: Real> SliceOp<T, 3> for EdgeUpdate {
    const NAME: &'static str = "amber-edge-update";

    fn forward(&self, [x, e, theta]: [&[T]; 3], _: [&Layout; 3]) -> Result<(Vec<T>, Shape)> {
        self.check(x.len(), e.len(), theta.len())?;
        let d = self.d;
        let (n, m) = (self.topology.num_nodes(), self.topology.num_edges());
        let w = MlpWeights::unpack(theta, 3 * d, d);
        let (mut p, mut q) = (ZeroedByChunk::new(n * d), ZeroedByChunk::new(n * d));
        (p.par_chunks_mut(BLOCK_ROWS * d), q.par_chunks_mut(BLOCK_ROWS * d), x.par_chunks(BLOCK_ROWS * d))
            .into_par_iter()
            .for_each(|(p, q, x)| {
                let rows = x.len() / d;
                matmul(rows, d, d, x, false, w.w1_rows(0..d), false, p, false);
                matmul(rows, d, d, x, false, w.w1_rows(d..2 * d), false, q, false);
            });
        let (p, q) = (p.into_vec(), q.into_vec());
        let block = |b: usize, e: &[T], st: TailState<'_, T>, out: &mut [T]| {
            let rows = e.len() / d;
            matmul(rows, d, d, e, false, w.w1_rows(2 * d..3 * d), false, st.h1, false);
            let edges = b * BLOCK_ROWS..b * BLOCK_ROWS + rows;
            add_gathered(st.h1, &p, &q, &self.topology.src()[edges.clone()], &self.topology.dst()[edges], d);
            tail_forward(&w, e, st, out);
        };
        let mut out = ZeroedByChunk::new(m * d);
        let chunk = BLOCK_ROWS * d;
        if self.save {
            let (mut h1, mut h2, mut mean, mut rstd) =
                (ZeroedByChunk::new(m * d), ZeroedByChunk::new(m * d), ZeroedByChunk::new(m), ZeroedByChunk::new(m));
            (
                out.par_chunks_mut(chunk),
                e.par_chunks(chunk),
                h1.par_chunks_mut(chunk),
                h2.par_chunks_mut(chunk),
                mean.par_chunks_mut(BLOCK_ROWS),
                rstd.par_chunks_mut(BLOCK_ROWS),
            )
                .into_par_iter()
                .enumerate()
                .for_each(|(b, (out, e, h1, h2, mean, rstd))| block(b, e, TailState { h1, h2, mean, rstd }, out));
            self.saved.put(Saved {
                h1: T::to_cpu_storage_owned(h1.into_vec()),
                h2: T::to_cpu_storage_owned(h2.into_vec()),
                mean: T::to_cpu_storage_owned(mean.into_vec()),
                rstd: T::to_cpu_storage_owned(rstd.into_vec()),
            })?;
        } else {
            (out.par_chunks_mut(chunk), e.par_chunks(chunk)).into_par_iter().enumerate().for_each_init(
                || Scratch::new(BLOCK_ROWS, d),
                |scratch, (b, (out, e))| block(b, e, scratch.state(e.len() / d, d), out),
            );
        }
        Ok((out.into_vec(), Shape::from((m, d))))
    }

    fn backward(
        &self,
        [xv, ev, tv]: [&[T]; 3],
        _: [&Layout; 3],
        _: &[T],
        gv: &[T],
        _: [bool; 3],
    ) -> Result<[Option<Vec<T>>; 3]> {
        self.check(xv.len(), ev.len(), tv.len())?;
        let saved = self.saved.take(<Self as SliceOp<T, 3>>::NAME)?;
        // The backward overwrites the saved activations with gradients: h1 becomes d(first-layer
        // pre-activation), h2 becomes d(e), saving two edge-sized allocations.
        let (mut dpre1, mut de) = (T::cpu_storage_data(saved.h1)?, T::cpu_storage_data(saved.h2)?);
        let (mean, rstd) = (saved.mean.as_slice::<T>()?, saved.rstd.as_slice::<T>()?);
        let d = self.d;
        let (n, m) = (self.topology.num_nodes(), self.topology.num_edges());
        let w = MlpWeights::unpack(tv, 3 * d, d);
        let zero = T::from_f64(0.0);
        let chunk = BLOCK_ROWS * d;
        if dpre1.len() != m * d || de.len() != m * d {
            bail!("edge_update: saved activations do not match the graph");
        }

        let blocks = (
            de.par_chunks_mut(chunk),
            dpre1.par_chunks_mut(chunk),
            gv.par_chunks(chunk),
            ev.par_chunks(chunk),
            mean.par_chunks(BLOCK_ROWS),
            rstd.par_chunks(BLOCK_ROWS),
        );
        let (mut g, _) = ordered_fold(
            blocks.into_par_iter(),
            || (MlpGrads::zeros(3 * d, d), vec![zero; 2 * chunk]),
            |(mut g, mut scratch), (de, dpre1, gr, e, mean, rstd)| {
                let rows = e.len() / d;
                tail_backward(&w, gr, e, dpre1, de, mean, rstd, &mut scratch[..2 * rows * d], &mut g);
                matmul(rows, d, d, dpre1, false, w.w1_rows(2 * d..3 * d), true, de, true);
                matmul(d, rows, d, e, true, dpre1, false, &mut g.w1[2 * d * d..], true);
                (g, scratch)
            },
            |(a, scratch), (b, _)| (a.merge(b), scratch),
        );

        // Gradients of the gathered node products: segment sums by source and by destination.
        let (mut dp, mut dq) = (ZeroedByChunk::new(n * d), ZeroedByChunk::new(n * d));
        let topo = &self.topology;
        (dp.par_chunks_mut(chunk), dq.par_chunks_mut(chunk)).into_par_iter().enumerate().for_each(|(b, (dp, dq))| {
            segment_sum(dp, &dpre1, topo.src_offsets(), Some(topo.by_src()), b * BLOCK_ROWS, d);
            segment_sum(dq, &dpre1, topo.dst_offsets(), None, b * BLOCK_ROWS, d);
        });
        let (dp, dq) = (dp.into_vec(), dq.into_vec());
        let mut dx = ZeroedByChunk::new(n * d);
        let blocks = (dx.par_chunks_mut(chunk), dp.par_chunks(chunk), dq.par_chunks(chunk), xv.par_chunks(chunk));
        let dw_nodes = ordered_fold(
            blocks.into_par_iter(),
            || vec![zero; 2 * d * d],
            |mut acc, (dx, dp, dq, x)| {
                let rows = x.len() / d;
                matmul(rows, d, d, dp, false, w.w1_rows(0..d), true, dx, false);
                matmul(rows, d, d, dq, false, w.w1_rows(d..2 * d), true, dx, true);
                let (acc_src, acc_dst) = acc.split_at_mut(d * d);
                matmul(d, rows, d, x, true, dp, false, acc_src, true);
                matmul(d, rows, d, x, true, dq, false, acc_dst, true);
                acc
            },
            |mut a, b| {
                add_assign(&mut a, &b);
                a
            },
        );
        add_assign(&mut g.w1[..2 * d * d], &dw_nodes);
        Ok([Some(dx.into_vec()), Some(de), Some(g.pack(3 * d, d))])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::gradcheck::*;

    fn fused(topo: &Arc<Topology>) -> impl Fn(&[Tensor]) -> Result<Tensor> + '_ {
        move |t: &[Tensor]| probe_loss(&edge_update(&t[0], &t[1], &t[2], topo)?, 7)
    }

    fn composed(topo: &Arc<Topology>) -> impl Fn(&[Tensor]) -> Result<Tensor> + '_ {
        move |t: &[Tensor]| {
            let dev = t[0].device();
            let src = Tensor::from_slice(topo.src(), topo.num_edges(), dev)?;
            let dst = Tensor::from_slice(topo.dst(), topo.num_edges(), dev)?;
            let message = Tensor::cat(&[&t[0].index_select(&src, 0)?, &t[0].index_select(&dst, 0)?, &t[1]], 1)?;
            probe_loss(&composed_residual_mlp(&message, &t[1], &t[2])?, 7)
        }
    }

    fn inputs(topo: &Topology, d: usize) -> Vec<Tensor> {
        vec![random((topo.num_nodes(), d), 1), random((topo.num_edges(), d), 2), random_theta(3 * d, d, 3)]
    }

    #[test]
    fn gradients_match_finite_differences() {
        let topo = corner_case_graph();
        check_finite_differences(&inputs(&topo, 3), &fused(&topo));
    }

    #[test]
    fn matches_the_candle_composition_across_blocks() {
        for topo in [corner_case_graph(), multi_block_graph()] {
            let t = inputs(&topo, 4);
            let (f, c) = (fused(&topo), composed(&topo));
            let (lf, lc) = (f(&t).unwrap().to_scalar::<f64>().unwrap(), c(&t).unwrap().to_scalar::<f64>().unwrap());
            assert!((lf - lc).abs() < 1e-9 * lc.abs().max(1.0), "{lf} vs {lc}");
            assert_close(&autograd(&t, &f), &autograd(&t, &c), 1e-10);
        }
    }

    #[test]
    fn gradients_are_the_same_at_any_thread_count() {
        let topo = multi_block_graph();
        let t = f32s(&inputs(&topo, 8));
        assert_same_at_any_thread_count(|| autograd(&t, &fused(&topo)));
    }

    #[test]
    fn inference_path_equals_training_path() {
        let topo = multi_block_graph();
        let t = f32s(&inputs(&topo, 4));
        let plain = edge_update(&t[0], &t[1], &t[2], &topo).unwrap();
        let var = candle_core::Var::from_tensor(&t[1]).unwrap();
        let tracked = edge_update(&t[0], var.as_tensor(), &t[2], &topo).unwrap();
        assert_eq!(values(&plain), values(&tracked));
    }

    #[test]
    fn wrong_sizes_are_errors() {
        let topo = corner_case_graph();
        let t = inputs(&topo, 3);
        assert!(edge_update(&t[0], &t[1], &random_theta(6, 3, 1), &topo).is_err());
        assert!(edge_update(&t[0].narrow(0, 0, 5).unwrap(), &t[1], &t[2], &topo).is_err());
    }
}
