//! The same network written with stock candle ops only (concat → Linear, index_select gathers,
//! `index_add` scatter-mean, `layer_norm_slow`, candle's LeakyReLU): the oracle the fused ops are
//! tested against and the baseline of the benchmark.

use candle_core::Tensor;
use candle_nn::ops::{layer_norm_slow, leaky_relu};

use super::{Mpn, ResidualMlp};
use crate::error::Result;
use crate::graph::GraphInput;
use crate::kernels::{LAYER_NORM_EPS, NEGATIVE_SLOPE};

impl ResidualMlp {
    fn forward_naive(&self, input: &Tensor, residual: &Tensor) -> candle_core::Result<Tensor> {
        let [l1, l2] = &self.layers;
        let h = leaky_relu(&l2.forward(&leaky_relu(&l1.forward(input)?, NEGATIVE_SLOPE)?)?, NEGATIVE_SLOPE)?;
        layer_norm_slow(&(residual + h)?, &self.norm.weight, &self.norm.bias, LAYER_NORM_EPS as f32)
    }
}

impl Mpn {
    /// [`Mpn::forward`] composed of stock candle ops (slow; for tests and benchmarks).
    pub fn forward_naive(&self, graph: &GraphInput) -> Result<Tensor> {
        let topo = &graph.topology;
        let dev = graph.node_features.device();
        let src = Tensor::from_slice(topo.src(), topo.num_edges(), dev)?;
        let dst = Tensor::from_slice(topo.dst(), topo.num_edges(), dev)?;
        let inv_degree: Vec<f64> =
            topo.dst_offsets().windows(2).map(|w| if w[1] > w[0] { 1.0 / (w[1] - w[0]) as f64 } else { 0.0 }).collect();
        let inv_degree = Tensor::from_vec(inv_degree, (topo.num_nodes(), 1), dev)?.to_dtype(self.dtype)?;
        let (mut x, mut e) = self.encode(graph)?;
        for step in &self.steps {
            let message = Tensor::cat(&[&x.index_select(&src, 0)?, &x.index_select(&dst, 0)?, &e], 1)?;
            e = step.edge.forward_naive(&message, &e)?;
            let a = x.zeros_like()?.index_add(&dst, &e, 0)?.broadcast_mul(&inv_degree)?;
            let a = step.with_context(a, &x, graph)?;
            x = step.node.forward_naive(&Tensor::cat(&[&x, &a], 1)?, &x)?;
        }
        self.decode(&x, Tensor::tanh)
    }
}
