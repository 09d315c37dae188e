//! Test helpers: a small graph with every corner case, packed parameters, the stock-candle
//! residual MLP the fused ops must match, and (re-exported) `amber_nn`'s finite-difference check.

use std::sync::Arc;

pub use amber_nn::gradcheck::{
    assert_same_at_any_thread_count, autograd, check_finite_differences, probe_loss, random, values,
};
use candle_core::Tensor;

use crate::graph::Topology;

/// Six nodes: node 2 has no incoming edge, node 0 several, node 3 several outgoing ones, and
/// not every node has its self-loop.
pub fn corner_case_graph() -> Arc<Topology> {
    let src = vec![0, 2, 3, 5, 0, 1, 3, 0, 4, 2, 3, 1];
    let dst = vec![0, 0, 0, 0, 1, 1, 3, 3, 4, 4, 4, 5];
    Arc::new(Topology::new(6, src, dst, vec![0, 4, 6, 6, 8, 11, 12]).unwrap())
}

/// A random graph larger than one row block, to exercise block boundaries.
pub fn multi_block_graph() -> Arc<Topology> {
    let b = crate::synthetic::random_graph(700, 1000, 1, 1, 5);
    Arc::new(Topology::new(b.num_nodes, b.edge_src, b.edge_dst, b.dst_offsets).unwrap())
}

/// Asserts two gradient sets agree to `tol` (relative to the largest entry).
pub fn assert_close(a: &[Vec<f64>], b: &[Vec<f64>], tol: f64) {
    for (i, (ga, gb)) in a.iter().zip(b).enumerate() {
        let scale = ga.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        for (j, (x, y)) in ga.iter().zip(gb).enumerate() {
            assert!((x - y).abs() <= tol * scale, "input {i} entry {j}: {x} vs {y}");
        }
    }
}

/// `LayerNorm(residual + MLP(input))` from stock candle ops, with the parameters unpacked from
/// the flat vector the fused ops take.
pub fn composed_residual_mlp(input: &Tensor, residual: &Tensor, theta: &Tensor) -> candle_core::Result<Tensor> {
    use candle_nn::ops::{layer_norm_slow, leaky_relu};
    let (in_dim, d) = (input.dim(1)?, residual.dim(1)?);
    let mut offset = 0;
    let mut take = |len: usize| {
        let t = theta.narrow(0, offset, len);
        offset += len;
        t
    };
    let w1 = take(d * in_dim)?.reshape((d, in_dim))?;
    let b1 = take(d)?;
    let w2 = take(d * d)?.reshape((d, d))?;
    let (b2, gamma, beta) = (take(d)?, take(d)?, take(d)?);
    let h = leaky_relu(&input.matmul(&w1.t()?)?.broadcast_add(&b1)?, 0.01)?;
    let h = leaky_relu(&h.matmul(&w2.t()?)?.broadcast_add(&b2)?, 0.01)?;
    layer_norm_slow(&(residual + h)?, &gamma, &beta, 1e-5)
}

/// The tensors in f32, the training dtype (whose rounding shows any change of summation order).
pub fn f32s(t: &[Tensor]) -> Vec<Tensor> {
    t.iter().map(|t| t.to_dtype(candle_core::DType::F32).unwrap()).collect()
}

pub fn random_theta(in_dim: usize, d: usize, seed: u64) -> Tensor {
    random((1, crate::kernels::packed_len(in_dim, d)), seed).flatten_all().unwrap()
}
