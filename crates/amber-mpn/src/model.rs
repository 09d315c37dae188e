//! The network of spec §5: linear encoders, L message-passing steps with their own weights, and
//! a tanh MLP decoder to one scalar per node, whose meaning (a size, a log size, a residual) is the
//! trainer's objective (`amber_nn::Objective`).

mod init;
mod naive;

use std::collections::HashMap;
use std::path::Path;

use amber_graph::GraphBatch;
use candle_core::{DType, Device, Tensor};
use candle_nn::{Init, VarBuilder, VarMap};
use rand::Rng;

use crate::config::MpnConfig;
use crate::error::{MpnError, Result};
use crate::graph::GraphInput;
use crate::ops;

/// `y = x·Wᵀ + b`, with candle's `(out, in)` weight layout and PyTorch's default initialisation
/// `U(±1/√in)` for weight and bias.
struct Linear {
    weight: Tensor,
    bias: Tensor,
}

impl Linear {
    fn new(vb: VarBuilder, in_dim: usize, out_dim: usize) -> candle_core::Result<Self> {
        let bound = 1.0 / (in_dim as f64).sqrt();
        let init = Init::Uniform { lo: -bound, up: bound };
        Ok(Self {
            weight: vb.get_with_hints((out_dim, in_dim), "weight", init)?,
            bias: vb.get_with_hints(out_dim, "bias", init)?,
        })
    }

    fn forward(&self, x: &Tensor) -> candle_core::Result<Tensor> {
        x.matmul(&self.weight.t()?)?.broadcast_add(&self.bias)
    }
}

/// Affine parameters of a LayerNorm (γ = 1, β = 0 initially).
struct Norm {
    weight: Tensor,
    bias: Tensor,
}

impl Norm {
    fn new(vb: VarBuilder, d: usize) -> candle_core::Result<Self> {
        Ok(Self {
            weight: vb.get_with_hints(d, "weight", Init::Const(1.0))?,
            bias: vb.get_with_hints(d, "bias", Init::Const(0.0))?,
        })
    }
}

/// A two-layer LeakyReLU MLP followed by residual + LayerNorm: `y = LN(r + MLP(u))`.
struct ResidualMlp {
    layers: [Linear; 2],
    norm: Norm,
}

impl ResidualMlp {
    fn new(vb: VarBuilder, in_dim: usize, d: usize) -> candle_core::Result<Self> {
        let mlp = vb.pp("mlp");
        Ok(Self {
            layers: [Linear::new(mlp.pp(0), in_dim, d)?, Linear::new(mlp.pp(1), d, d)?],
            norm: Norm::new(vb.pp("norm"), d)?,
        })
    }

    /// All parameters as the one flat vector the fused ops take (differentiable: `cat`).
    fn packed(&self) -> candle_core::Result<Tensor> {
        let [l1, l2] = &self.layers;
        Tensor::cat(
            &[
                &l1.weight.flatten_all()?,
                &l1.bias,
                &l2.weight.flatten_all()?,
                &l2.bias,
                &self.norm.weight,
                &self.norm.bias,
            ],
            0,
        )
    }

    fn parameters(&self) -> [&Tensor; 6] {
        let [l1, l2] = &self.layers;
        [&l1.weight, &l1.bias, &l2.weight, &l2.bias, &self.norm.weight, &self.norm.bias]
    }
}

/// One message-passing step: edge update (message), mean aggregation, graph and region
/// contexts if configured, node update.
struct Step {
    edge: ResidualMlp,
    node: ResidualMlp,
    context: Option<Linear>,
    region_context: Option<Linear>,
}

impl Step {
    /// The aggregated messages plus, with a graph context, `tanh(W·mean(x) + b)` of each node's
    /// graph, and with a region context the same of each node's region (stock candle ops: the
    /// group tensors are `(G, D)`, G a handful of graphs or a few dozen regions per graph).
    fn with_context(&self, aggregated: Tensor, x: &Tensor, graph: &GraphInput) -> candle_core::Result<Tensor> {
        let groups = [
            (&self.context, &graph.graph_of_node, &graph.inverse_graph_sizes),
            (&self.region_context, &graph.region_of_node, &graph.inverse_region_sizes),
        ];
        let mut out = aggregated;
        for (linear, group_of_node, inverse_sizes) in groups {
            let Some(linear) = linear else { continue };
            let mean = Tensor::zeros((inverse_sizes.dim(0)?, x.dim(1)?), x.dtype(), x.device())?
                .index_add(group_of_node, x, 0)?
                .broadcast_mul(inverse_sizes)?;
            out = (out + linear.forward(&mean)?.tanh()?.index_select(group_of_node, 0)?)?;
        }
        Ok(out)
    }
}

/// The message passing network. Built from `Var`s ([`Mpn::init`], [`Mpn::load_trainable`]) it
/// records the autograd graph; built from plain tensors ([`Mpn::load`]) it records nothing, which
/// is what inference wants.
pub struct Mpn {
    config: MpnConfig,
    dtype: DType,
    node_encoder: Linear,
    edge_encoder: Linear,
    steps: Vec<Step>,
    decoder: [Linear; 3],
}

impl Mpn {
    /// Builds the network from a `VarBuilder`: parameter names are `node_encoder.weight`,
    /// `steps.{l}.edge.mlp.{0,1}.{weight,bias}`, `steps.{l}.edge.norm.{weight,bias}`, likewise
    /// `node`, `steps.{l}.context.{weight,bias}` with a graph context,
    /// `steps.{l}.region_context.{weight,bias}` with a region context, and `decoder.{0,1,2}.*`.
    pub fn new(config: MpnConfig, vb: VarBuilder) -> Result<Self> {
        config.validate()?;
        let d = config.network.latent_dim;
        let steps = (0..config.network.message_passing_steps)
            .map(|l| {
                let vb = vb.pp("steps").pp(l);
                Ok(Step {
                    edge: ResidualMlp::new(vb.pp("edge"), 3 * d, d)?,
                    node: ResidualMlp::new(vb.pp("node"), 2 * d, d)?,
                    context: config.network.graph_context.then(|| Linear::new(vb.pp("context"), d, d)).transpose()?,
                    region_context: config
                        .network
                        .region_context
                        .then(|| Linear::new(vb.pp("region_context"), d, d))
                        .transpose()?,
                })
            })
            .collect::<candle_core::Result<_>>()?;
        let dec = vb.pp("decoder");
        Ok(Self {
            dtype: vb.dtype(),
            node_encoder: Linear::new(vb.pp("node_encoder"), config.node_features, d)?,
            edge_encoder: Linear::new(vb.pp("edge_encoder"), config.edge_features, d)?,
            steps,
            decoder: [Linear::new(dec.pp(0), d, d)?, Linear::new(dec.pp(1), d, d)?, Linear::new(dec.pp(2), d, 1)?],
            config,
        })
    }

    /// A freshly initialised trainable network (PyTorch's default initialisation, drawn from a
    /// generator seeded with `seed`) and the `VarMap` holding its variables.
    pub fn init(config: MpnConfig, seed: u64, dtype: DType, device: &Device) -> Result<(Self, VarMap)> {
        let varmap = VarMap::new();
        let vb = VarBuilder::from_backend(Box::new(init::SeededInit::new(varmap.clone(), seed)), dtype, device.clone());
        Ok((Self::new(config, vb)?, varmap))
    }

    /// Saves the variables to `path` (safetensors) and the configuration beside it
    /// (`path` with extension `json`).
    pub fn save(&self, varmap: &VarMap, path: &Path) -> Result<()> {
        let json = serde_json::to_string_pretty(&self.config)
            .map_err(|source| MpnError::Json { path: path.with_extension("json"), source })?;
        std::fs::write(path.with_extension("json"), json)
            .map_err(|source| MpnError::Io { path: path.with_extension("json"), source })?;
        varmap.save(path).map_err(|e| MpnError::Checkpoint { path: path.into(), message: e.to_string() })
    }

    /// Loads a checkpoint written by [`Mpn::save`] as plain f32 tensors on the CPU, for
    /// inference. A tensor missing, extra, of the wrong shape for the configuration or with a
    /// non-finite entry is an error naming the file and the tensor.
    pub fn load(path: &Path) -> Result<Self> {
        let (dtype, device) = (DType::F32, Device::Cpu);
        let config = read_config(path)?;
        let checkpoint_err = |e: candle_core::Error| MpnError::Checkpoint { path: path.into(), message: e.to_string() };
        let tensors = read_tensors(path)?;
        let stored = tensors.len();
        let model = match Self::new(config, VarBuilder::from_tensors(tensors, dtype, &device)) {
            Err(MpnError::Candle(e)) => return Err(checkpoint_err(e)),
            other => other?,
        };
        model.check_tensor_count(path, stored)?;
        Ok(model)
    }

    /// Loads a checkpoint written by [`Mpn::save`] into new f32 variables on `device`, to resume
    /// training; checked as in [`Mpn::load`].
    pub fn load_trainable(path: &Path, device: &Device) -> Result<(Self, VarMap)> {
        let (model, mut varmap) = Self::init(read_config(path)?, 0, DType::F32, device)?;
        let stored = read_tensors(path)?.len();
        // `VarMap::load` overwrites the variables the model created (shape-checked); it would
        // load nothing into an empty map.
        varmap.load(path).map_err(|e| MpnError::Checkpoint { path: path.into(), message: e.to_string() })?;
        model.check_tensor_count(path, stored)?;
        Ok((model, varmap))
    }

    fn check_tensor_count(&self, path: &Path, stored: usize) -> Result<()> {
        let expected = self.parameters().len();
        if stored != expected {
            return Err(MpnError::Checkpoint {
                path: path.into(),
                message: format!("{stored} tensors, the configuration has {expected}"),
            });
        }
        Ok(())
    }

    /// The same network on plain tensors (sharing the variables' storage, so it sees later
    /// optimiser updates): its forward records no autograd graph, for evaluation during training.
    pub fn for_inference(&self) -> Self {
        let linear = |l: &Linear| Linear { weight: l.weight.detach(), bias: l.bias.detach() };
        let mlp = |m: &ResidualMlp| ResidualMlp {
            layers: [linear(&m.layers[0]), linear(&m.layers[1])],
            norm: Norm { weight: m.norm.weight.detach(), bias: m.norm.bias.detach() },
        };
        Self {
            config: self.config.clone(),
            dtype: self.dtype,
            node_encoder: linear(&self.node_encoder),
            edge_encoder: linear(&self.edge_encoder),
            steps: self
                .steps
                .iter()
                .map(|s| Step {
                    edge: mlp(&s.edge),
                    node: mlp(&s.node),
                    context: s.context.as_ref().map(linear),
                    region_context: s.region_context.as_ref().map(linear),
                })
                .collect(),
            decoder: [linear(&self.decoder[0]), linear(&self.decoder[1]), linear(&self.decoder[2])],
        }
    }

    pub fn config(&self) -> &MpnConfig {
        &self.config
    }

    pub fn dtype(&self) -> DType {
        self.dtype
    }

    /// Every parameter tensor (for gradient checks and counting).
    pub fn parameters(&self) -> Vec<&Tensor> {
        let mut p = vec![
            &self.node_encoder.weight,
            &self.node_encoder.bias,
            &self.edge_encoder.weight,
            &self.edge_encoder.bias,
        ];
        for s in &self.steps {
            p.extend(s.edge.parameters());
            p.extend(s.node.parameters());
            p.extend(s.context.iter().chain(&s.region_context).flat_map(|l| [&l.weight, &l.bias]));
        }
        for l in &self.decoder {
            p.extend([&l.weight, &l.bias]);
        }
        p
    }

    /// The output z, one per node (evaluation mode: no edge dropout). With `Var` parameters the
    /// result can be differentiated once (the fused ops hand their saved activations to the first
    /// backward pass).
    pub fn forward(&self, graph: &GraphInput) -> Result<Tensor> {
        // The fused ops are CPU kernels; elsewhere candle's own ops compute the same function.
        if !graph.node_features.device().is_cpu() {
            return self.forward_naive(graph);
        }
        let (mut x, mut e) = self.encode(graph)?;
        for step in &self.steps {
            e = ops::edge_update(&x, &e, &step.edge.packed()?, &graph.topology)?;
            let a = step.with_context(ops::segment_mean(&e, &graph.topology)?, &x, graph)?;
            x = ops::node_update(&x, &a, &step.node.packed()?)?;
        }
        self.decode(&x, ops::tanh)
    }

    /// Training-mode forward: edge dropout with the configured rate, one dropped graph for all
    /// steps, drawn from `rng`.
    pub fn forward_train<R: Rng + ?Sized>(&self, graph: &GraphInput, rng: &mut R) -> Result<Tensor> {
        if self.config.network.edge_dropout > 0.0 {
            self.forward(&graph.drop_edges(self.config.network.edge_dropout, rng)?)
        } else {
            self.forward(graph)
        }
    }

    /// Evaluation-mode outputs z for a batch, one per node (on plain tensors: no autograd graph
    /// is recorded, even for a network of variables).
    pub fn predict(&self, batch: &GraphBatch) -> Result<Vec<f32>> {
        let graph = GraphInput::from_batch(batch, self.dtype, self.node_encoder.weight.device())?;
        Ok(self.for_inference().forward(&graph)?.to_dtype(DType::F32)?.to_vec1()?)
    }

    fn encode(&self, g: &GraphInput) -> Result<(Tensor, Tensor)> {
        let check = |what, t: &Tensor, rows: usize, expected: usize| -> Result<()> {
            let (r, c) = t.dims2()?;
            if c != expected {
                return Err(MpnError::FeatureDim { what, expected, got: c });
            }
            if r != rows {
                return Err(MpnError::InvalidGraph(format!("{r} rows of {what} for {rows} graph items")));
            }
            if t.dtype() != self.dtype {
                return Err(MpnError::InvalidGraph(format!(
                    "{what} are {:?}, the network is {:?}",
                    t.dtype(),
                    self.dtype
                )));
            }
            Ok(())
        };
        check("node features", &g.node_features, g.topology.num_nodes(), self.config.node_features)?;
        check("edge features", &g.edge_features, g.topology.num_edges(), self.config.edge_features)?;
        Ok((self.node_encoder.forward(&g.node_features)?, self.edge_encoder.forward(&g.edge_features)?))
    }

    /// The decoder MLP, with the given `tanh` (fused or candle's).
    fn decode(&self, x: &Tensor, tanh: impl Fn(&Tensor) -> candle_core::Result<Tensor>) -> Result<Tensor> {
        let [l1, l2, l3] = &self.decoder;
        Ok(l3.forward(&tanh(&l2.forward(&tanh(&l1.forward(x)?)?)?)?)?.squeeze(1)?)
    }
}

fn read_config(path: &Path) -> Result<MpnConfig> {
    let json_path = path.with_extension("json");
    let text =
        std::fs::read_to_string(&json_path).map_err(|source| MpnError::Io { path: json_path.clone(), source })?;
    let config: MpnConfig =
        serde_json::from_str(&text).map_err(|source| MpnError::Json { path: json_path.clone(), source })?;
    config.validate().map_err(|e| MpnError::Checkpoint { path: json_path, message: e.to_string() })?;
    Ok(config)
}

/// The tensors of a checkpoint, every entry finite.
fn read_tensors(path: &Path) -> Result<HashMap<String, Tensor>> {
    let checkpoint_err = |message: String| MpnError::Checkpoint { path: path.into(), message };
    let tensors = candle_core::safetensors::load(path, &Device::Cpu).map_err(|e| checkpoint_err(e.to_string()))?;
    if let Some(name) = amber_nn::first_non_finite(&tensors).map_err(|e| checkpoint_err(e.to_string()))? {
        return Err(checkpoint_err(format!("tensor `{name}` has a non-finite entry")));
    }
    Ok(tensors)
}
