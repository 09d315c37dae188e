//! The aggregation: mean of the incoming edge states of every node, over the destination-sorted
//! CSR segments (a node without incoming edges gets zeros).

use std::sync::Arc;

use amber_nn::op::{Fused, SliceOp};
use candle_core::{Layout, Result, Shape, Tensor, bail};
use rayon::prelude::*;

use crate::graph::Topology;
use crate::kernels::{BLOCK_ROWS, Real, ZeroedByChunk, segment_sum};

/// Mean of the rows of `e` (E×D) over each node's incoming edges: N×D.
pub(crate) fn segment_mean(e: &Tensor, topology: &Arc<Topology>) -> Result<Tensor> {
    let e = e.contiguous()?;
    let d = e.dim(1)?;
    e.apply_op1(Fused(SegmentMean { topology: topology.clone(), d }))
}

struct SegmentMean {
    topology: Arc<Topology>,
    d: usize,
}

impl SegmentMean {
    /// `1 / in-degree`, or 0 for a node without incoming edges.
    fn inv_count<T: Real>(&self, v: usize) -> (usize, usize, T) {
        let offsets = self.topology.dst_offsets();
        let (lo, hi) = (offsets[v] as usize, offsets[v + 1] as usize);
        let inv = if hi > lo { T::from_f64(1.0 / (hi - lo) as f64) } else { T::from_f64(0.0) };
        (lo, hi, inv)
    }

    fn mean_rows<T: Real>(&self, e: &[T]) -> Vec<T> {
        let d = self.d;
        let mut out = ZeroedByChunk::new(self.topology.num_nodes() * d);
        out.par_chunks_mut(BLOCK_ROWS * d).enumerate().for_each(|(b, out)| {
            segment_sum(out, e, self.topology.dst_offsets(), None, b * BLOCK_ROWS, d);
            for (i, o) in out.chunks_exact_mut(d).enumerate() {
                let (.., inv) = self.inv_count::<T>(b * BLOCK_ROWS + i);
                o.iter_mut().for_each(|v| *v *= inv);
            }
        });
        out.into_vec()
    }

    fn spread_rows<T: Real>(&self, grad: &[T]) -> Vec<T> {
        let d = self.d;
        let offsets = self.topology.dst_offsets();
        let mut de = vec![T::from_f64(0.0); self.topology.num_edges() * d];
        // Split the edge rows at node boundaries so each work item owns whole segments.
        let n = self.topology.num_nodes();
        let mut parts = Vec::with_capacity(n.div_ceil(BLOCK_ROWS));
        let mut rest = de.as_mut_slice();
        for first in (0..n).step_by(BLOCK_ROWS) {
            let last = (first + BLOCK_ROWS).min(n);
            let len = (offsets[last] - offsets[first]) as usize * d;
            let (part, tail) = rest.split_at_mut(len);
            parts.push((first..last, part));
            rest = tail;
        }
        parts.into_par_iter().for_each(|(nodes, part)| {
            let base = offsets[nodes.start] as usize;
            for v in nodes {
                let (lo, hi, inv) = self.inv_count::<T>(v);
                let g = &grad[v * d..(v + 1) * d];
                for k in lo..hi {
                    let row = &mut part[(k - base) * d..(k - base + 1) * d];
                    for (r, &gv) in row.iter_mut().zip(g) {
                        *r = gv * inv;
                    }
                }
            }
        });
        de
    }
}

impl<T: Real> SliceOp<T, 1> for SegmentMean {
    const NAME: &'static str = "amber-segment-mean";

    fn forward(&self, [e]: [&[T]; 1], [l]: [&Layout; 1]) -> Result<(Vec<T>, Shape)> {
        let (m, d) = (self.topology.num_edges(), self.d);
        if l.shape().elem_count() != m * d {
            bail!("segment_mean: {} values for E={m}, D={d}", l.shape().elem_count());
        }
        Ok((self.mean_rows(e), Shape::from((self.topology.num_nodes(), d))))
    }

    fn backward(
        &self,
        _: [&[T]; 1],
        _: [&Layout; 1],
        _: &[T],
        grad: &[T],
        _: [bool; 1],
    ) -> Result<[Option<Vec<T>>; 1]> {
        Ok([Some(self.spread_rows(grad))])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::gradcheck::*;

    fn fused(topo: &Arc<Topology>) -> impl Fn(&[Tensor]) -> Result<Tensor> + '_ {
        move |t: &[Tensor]| probe_loss(&segment_mean(&t[0], topo)?, 7)
    }

    /// `index_add` scatter, then division by the in-degree (0 for isolated nodes).
    fn composed(topo: &Arc<Topology>) -> impl Fn(&[Tensor]) -> Result<Tensor> + '_ {
        move |t: &[Tensor]| {
            let dst = Tensor::from_slice(topo.dst(), topo.num_edges(), t[0].device())?;
            let inv: Vec<f64> = topo
                .dst_offsets()
                .windows(2)
                .map(|w| if w[1] > w[0] { 1.0 / (w[1] - w[0]) as f64 } else { 0.0 })
                .collect();
            let inv = Tensor::from_vec(inv, (topo.num_nodes(), 1), t[0].device())?;
            let sum = Tensor::zeros((topo.num_nodes(), t[0].dim(1)?), t[0].dtype(), t[0].device())?
                .index_add(&dst, &t[0], 0)?;
            probe_loss(&sum.broadcast_mul(&inv)?, 7)
        }
    }

    #[test]
    fn gradients_match_finite_differences_and_composition() {
        for topo in [corner_case_graph(), multi_block_graph()] {
            let t = [random((topo.num_edges(), 3), 1)];
            check_finite_differences(&t, &fused(&topo));
            assert_close(&autograd(&t, &fused(&topo)), &autograd(&t, &composed(&topo)), 1e-12);
        }
    }

    #[test]
    fn gradients_are_the_same_at_any_thread_count() {
        let topo = multi_block_graph();
        let t = f32s(&[random((topo.num_edges(), 8), 1)]);
        assert_same_at_any_thread_count(|| autograd(&t, &fused(&topo)));
    }

    #[test]
    fn isolated_nodes_get_zero() {
        let topo = corner_case_graph();
        let out = segment_mean(&random((topo.num_edges(), 3), 1), &topo).unwrap();
        assert_eq!(values(&out.get(2).unwrap()), vec![0.0; 3]);
    }
}
