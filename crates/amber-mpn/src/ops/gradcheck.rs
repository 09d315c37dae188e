//! Test helpers: a small graph with every corner case, random inputs, and a finite-difference
//! gradient check in f64.

use std::sync::Arc;

use candle_core::{DType, Device, Tensor, Var};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

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

pub fn random(shape: (usize, usize), seed: u64) -> Tensor {
    let mut rng = StdRng::seed_from_u64(seed);
    let v: Vec<f64> = (0..shape.0 * shape.1).map(|_| rng.random_range(-1.0..1.0)).collect();
    Tensor::from_vec(v, shape, &Device::Cpu).unwrap()
}

pub fn values(t: &Tensor) -> Vec<f64> {
    t.to_dtype(DType::F64).unwrap().flatten_all().unwrap().to_vec1().unwrap()
}

/// Weighted sum of the output, so that every output entry gets a distinct gradient.
pub fn probe_loss(out: &Tensor, seed: u64) -> candle_core::Result<Tensor> {
    let w = random(out.dims2()?, seed).to_dtype(out.dtype())?;
    (out * w)?.sum_all()
}

/// Gradients of `loss(inputs)` with respect to every input, via autograd.
pub fn autograd(inputs: &[Tensor], loss: &dyn Fn(&[Tensor]) -> candle_core::Result<Tensor>) -> Vec<Vec<f64>> {
    let vars: Vec<Var> = inputs.iter().map(|t| Var::from_tensor(t).unwrap()).collect();
    let tensors: Vec<Tensor> = vars.iter().map(|v| v.as_tensor().clone()).collect();
    let grads = loss(&tensors).unwrap().backward().unwrap();
    vars.iter().map(|v| values(grads.get(v).expect("every input gets a gradient"))).collect()
}

/// Compares autograd with central differences (step 1e-6) on up to 40 entries per input.
pub fn check_finite_differences(inputs: &[Tensor], loss: &dyn Fn(&[Tensor]) -> candle_core::Result<Tensor>) {
    let analytic = autograd(inputs, loss);
    let eval = |i: usize, idx: usize, delta: f64| {
        let mut v = values(&inputs[i]);
        v[idx] += delta;
        let mut perturbed = inputs.to_vec();
        perturbed[i] = Tensor::from_vec(v, inputs[i].shape(), &Device::Cpu).unwrap();
        loss(&perturbed).unwrap().to_scalar::<f64>().unwrap()
    };
    let eps = 1e-6;
    for (i, grad) in analytic.iter().enumerate() {
        let step = grad.len().div_ceil(40);
        for idx in (0..grad.len()).step_by(step) {
            let fd = (eval(i, idx, eps) - eval(i, idx, -eps)) / (2.0 * eps);
            let err = (fd - grad[idx]).abs() / fd.abs().max(grad[idx].abs()).max(1.0);
            assert!(err < 1e-6, "input {i} entry {idx}: finite difference {fd}, autograd {}", grad[idx]);
        }
    }
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

pub fn random_theta(in_dim: usize, d: usize, seed: u64) -> Tensor {
    random((1, crate::kernels::packed_len(in_dim, d)), seed).flatten_all().unwrap()
}
