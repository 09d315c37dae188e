//! The U-Net of the CNN baseline (spec §8, the reference's `unet.py`): `depth` down levels of
//! [conv 3 → BatchNorm → ReLU] × 2 with C, 2C, 4C, … channels and max-pooling 2, a bottleneck
//! with twice the deepest width, up levels of transposed conv 2 → concat skip → the same double
//! conv, and a 1×1 output conv to one channel. Works on images (2 spatial axes) and voxel grids
//! (3) alike.
//!
//! The convolutions before a BatchNorm have no bias (the norm would cancel it). Parameters are
//! `Var`s in a `VarMap`, initialised from a seed as PyTorch does (`U(±1/√fan_in)`); BatchNorm's
//! running statistics live in the same map (they receive no gradient).

use std::collections::HashMap;
use std::path::Path;

use candle_core::{DType, Device, Tensor, Var};
use candle_nn::VarMap;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{CnnError, Result};
use crate::ops::{BatchNormStats, batch_norm_relu, conv, conv_transpose2, max_pool2};

/// Weight of the new batch in the running BatchNorm statistics (PyTorch's momentum).
const RUNNING_MOMENTUM: f64 = 0.1;

/// The shape of a U-Net.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UNetConfig {
    /// Spatial axes: 2 (images) or 3 (voxel grids).
    pub spatial_axes: usize,
    /// Input channels.
    pub in_channels: usize,
    /// Channels of the first level C (the paper's text: 32; its runs: 64).
    pub initial_channels: usize,
    /// Down (and up) levels (the paper: 4).
    pub depth: usize,
}

impl UNetConfig {
    /// Checks ranges; the message names the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(CnnError::InvalidConfig(m.to_owned()));
        if !(2..=3).contains(&self.spatial_axes) {
            return bad("spatial_axes must be 2 or 3");
        }
        if self.in_channels == 0 || self.initial_channels == 0 {
            return bad("in_channels and initial_channels must be positive");
        }
        if !(1..=8).contains(&self.depth) {
            return bad("depth must be in 1..=8");
        }
        Ok(())
    }

    /// Every spatial extent of an input must be a multiple of this (2^depth), so that every
    /// pooled level up-samples back to its skip's shape exactly.
    pub fn size_multiple(&self) -> usize {
        1 << self.depth
    }
}

/// How parameters come into being: drawn from a seeded generator, or taken from a file.
enum Source {
    Seeded(Box<ChaCha8Rng>),
    File { path: std::path::PathBuf, tensors: HashMap<String, Tensor> },
}

/// Creates the named `Var`s of a network in a `VarMap`.
struct Params {
    varmap: VarMap,
    source: Source,
    dtype: DType,
}

impl Params {
    /// A parameter of `shape`: from the file, or `U(±bound)` (`bound = None`: the constant
    /// `fill`).
    fn get(&mut self, name: &str, shape: &[usize], bound: Option<f64>, fill: f64) -> Result<Var> {
        let tensor = match &mut self.source {
            Source::Seeded(rng) => {
                let n = shape.iter().product();
                let values: Vec<f64> = match bound {
                    Some(b) => (0..n).map(|_| rng.random_range(-b..b)).collect(),
                    None => vec![fill; n],
                };
                Tensor::from_vec(values, shape, &Device::Cpu)?
            }
            Source::File { path, tensors } => {
                let t = tensors.remove(name).ok_or_else(|| CnnError::ModelFile {
                    path: path.clone(),
                    message: format!("missing tensor `{name}`"),
                })?;
                if t.dims() != shape {
                    return Err(CnnError::ModelFile {
                        path: path.clone(),
                        message: format!("tensor `{name}` has shape {:?}, the configuration needs {shape:?}", t.dims()),
                    });
                }
                t
            }
        };
        let var = Var::from_tensor(&tensor.to_dtype(self.dtype)?)?;
        self.varmap
            .data()
            .lock()
            .map_err(|_| CnnError::Shape("poisoned variable map".into()))?
            .insert(name.into(), var.clone());
        Ok(var)
    }

    /// Fails on tensors of the file that no parameter took.
    fn finish(self) -> Result<VarMap> {
        if let Source::File { path, tensors } = &self.source
            && let Some(extra) = tensors.keys().next()
        {
            return Err(CnnError::ModelFile { path: path.clone(), message: format!("unexpected tensor `{extra}`") });
        }
        Ok(self.varmap)
    }
}

/// Conv 3 (no bias) → BatchNorm → ReLU.
struct ConvBnRelu {
    weight: Var,
    gamma: Var,
    beta: Var,
    running_mean: Var,
    running_var: Var,
}

impl ConvBnRelu {
    fn new(p: &mut Params, name: &str, axes: usize, in_c: usize, out_c: usize) -> Result<Self> {
        let kernel: Vec<usize> = [out_c, in_c].into_iter().chain(std::iter::repeat_n(3, axes)).collect();
        let bound = 1.0 / ((in_c * 3usize.pow(axes as u32)) as f64).sqrt();
        Ok(Self {
            weight: p.get(&format!("{name}.weight"), &kernel, Some(bound), 0.0)?,
            gamma: p.get(&format!("{name}.gamma"), &[out_c], None, 1.0)?,
            beta: p.get(&format!("{name}.beta"), &[out_c], None, 0.0)?,
            running_mean: p.get(&format!("{name}.running_mean"), &[out_c], None, 0.0)?,
            running_var: p.get(&format!("{name}.running_var"), &[out_c], None, 1.0)?,
        })
    }

    /// Training: batch statistics (recorded for autograd), running statistics updated.
    fn forward_train(&self, x: &Tensor) -> Result<Tensor> {
        let h = conv(x, &self.weight)?;
        let (y, batch) = batch_norm_relu(&h, &self.gamma, &self.beta, None)?;
        for (var, values) in [(&self.running_mean, &batch.mean), (&self.running_var, &batch.variance)] {
            let blended = ((var.as_tensor().detach() * (1.0 - RUNNING_MOMENTUM))?
                + (Tensor::new(values.as_slice(), &Device::Cpu)?.to_dtype(var.dtype())? * RUNNING_MOMENTUM)?)?;
            var.set(&blended)?;
        }
        Ok(y)
    }

    /// Evaluation: running statistics, nothing recorded.
    fn forward(&self, x: &Tensor) -> Result<Tensor> {
        let h = conv(x, &self.weight.as_tensor().detach())?;
        let values = |v: &Var| v.as_tensor().to_dtype(DType::F64)?.to_vec1::<f64>();
        let running = BatchNormStats { mean: values(&self.running_mean)?, variance: values(&self.running_var)? };
        let gamma = self.gamma.as_tensor().detach();
        Ok(batch_norm_relu(&h, &gamma, &self.beta.as_tensor().detach(), Some(&running))?.0)
    }
}

/// [conv 3 → BatchNorm → ReLU] × 2.
struct DoubleConv([ConvBnRelu; 2]);

impl DoubleConv {
    fn new(p: &mut Params, name: &str, axes: usize, in_c: usize, out_c: usize) -> Result<Self> {
        Ok(Self([
            ConvBnRelu::new(p, &format!("{name}.0"), axes, in_c, out_c)?,
            ConvBnRelu::new(p, &format!("{name}.1"), axes, out_c, out_c)?,
        ]))
    }

    fn forward(&self, x: &Tensor, train: bool) -> Result<Tensor> {
        let [a, b] = &self.0;
        if train { b.forward_train(&a.forward_train(x)?) } else { b.forward(&a.forward(x)?) }
    }
}

/// Transposed conv 2 (with bias), concat with the skip, double conv.
struct Up {
    weight: Var,
    bias: Var,
    block: DoubleConv,
}

/// Parameters as used in a forward pass: the `Var`s themselves (training, recorded) or detached
/// copies (evaluation).
fn param(var: &Var, train: bool) -> Tensor {
    if train { var.as_tensor().clone() } else { var.as_tensor().detach() }
}

/// The U-Net.
pub struct UNet {
    config: UNetConfig,
    varmap: VarMap,
    down: Vec<DoubleConv>,
    bottleneck: DoubleConv,
    up: Vec<Up>,
    out_weight: Var,
    out_bias: Var,
}

impl UNet {
    fn build(config: UNetConfig, source: Source, dtype: DType) -> Result<Self> {
        config.validate()?;
        let mut p = Params { varmap: VarMap::new(), source, dtype };
        let axes = config.spatial_axes;
        let widths: Vec<usize> = (0..config.depth).map(|i| config.initial_channels << i).collect();
        let mut down = Vec::new();
        let mut c = config.in_channels;
        for (i, &w) in widths.iter().enumerate() {
            down.push(DoubleConv::new(&mut p, &format!("down.{i}"), axes, c, w)?);
            c = w;
        }
        let bottleneck = DoubleConv::new(&mut p, "bottleneck", axes, c, 2 * c)?;
        let mut up = Vec::new();
        for (i, &w) in widths.iter().enumerate().rev() {
            let kernel: Vec<usize> = [2 * w, w].into_iter().chain(std::iter::repeat_n(2, axes)).collect();
            // PyTorch takes a transposed conv's fan-in from the kernel's second axis.
            let bound = 1.0 / ((w << axes) as f64).sqrt();
            up.push(Up {
                weight: p.get(&format!("up.{i}.transpose.weight"), &kernel, Some(bound), 0.0)?,
                bias: p.get(&format!("up.{i}.transpose.bias"), &[w], Some(bound), 0.0)?,
                block: DoubleConv::new(&mut p, &format!("up.{i}.block"), axes, 2 * w, w)?,
            });
        }
        let out_kernel: Vec<usize> = [1, widths[0]].into_iter().chain(std::iter::repeat_n(1, axes)).collect();
        let bound = 1.0 / (widths[0] as f64).sqrt();
        let out_weight = p.get("out.weight", &out_kernel, Some(bound), 0.0)?;
        let out_bias = p.get("out.bias", &[1], Some(bound), 0.0)?;
        Ok(Self { config, varmap: p.finish()?, down, bottleneck, up, out_weight, out_bias })
    }

    /// A freshly initialised f32 network (parameters drawn from `seed`).
    pub fn init(config: UNetConfig, seed: u64) -> Result<Self> {
        Self::build(config, Source::Seeded(Box::new(ChaCha8Rng::seed_from_u64(seed))), DType::F32)
    }

    /// The f32 network of a weights file written by [`Self::save`], with `config`. A tensor
    /// missing, extra, of the wrong shape for `config` or with a non-finite entry, or a negative
    /// BatchNorm running variance (whose square root would be NaN), is an error naming the file
    /// and the tensor.
    pub fn load(config: UNetConfig, weights: &Path) -> Result<Self> {
        let file_error = |message: String| CnnError::ModelFile { path: weights.into(), message };
        let tensors = candle_core::safetensors::load(weights, &Device::Cpu).map_err(|e| file_error(e.to_string()))?;
        if let Some(name) = amber_nn::first_non_finite(&tensors).map_err(|e| file_error(e.to_string()))? {
            return Err(file_error(format!("tensor `{name}` has a non-finite entry")));
        }
        for (name, t) in tensors.iter().filter(|(name, _)| name.ends_with(".running_var")) {
            let values = t.to_dtype(DType::F64)?.flatten_all()?.to_vec1::<f64>()?;
            if let Some(v) = values.iter().find(|v| **v < 0.0) {
                return Err(file_error(format!("tensor `{name}` has a negative variance {v}")));
            }
        }
        Self::build(config, Source::File { path: weights.into(), tensors }, DType::F32)
    }

    /// Writes every parameter and running statistic to `weights` (safetensors, atomically: a
    /// temporary file, fsynced, then a rename).
    pub fn save(&self, weights: &Path) -> Result<()> {
        amber_stdx::write_atomic_via(weights, |tmp| {
            self.varmap.save(tmp).map_err(|e| CnnError::ModelFile { path: tmp.into(), message: e.to_string() })
        })
    }

    pub fn config(&self) -> &UNetConfig {
        &self.config
    }

    /// All variables (parameters and running statistics), for the optimiser.
    pub fn varmap(&self) -> &VarMap {
        &self.varmap
    }

    /// Trainable parameters (running statistics excluded).
    pub fn parameter_count(&self) -> usize {
        let data = self.varmap.data().lock().expect("variable map lock");
        data.iter().filter(|(name, _)| !name.contains(".running_")).map(|(_, v)| v.elem_count()).sum()
    }

    /// Training forward of `x (N, in_channels, spatial...)` → `(N, 1, spatial...)`: BatchNorm
    /// on batch statistics (whose running averages it updates), autograd recorded.
    pub fn forward_train(&self, x: &Tensor) -> Result<Tensor> {
        self.forward_with(x, true)
    }

    /// Evaluation forward: BatchNorm on running statistics, nothing recorded for autograd.
    pub fn forward(&self, x: &Tensor) -> Result<Tensor> {
        self.forward_with(x, false)
    }

    /// Evaluation forward of channel-major `input` data of `shape` `(N, in_channels,
    /// spatial...)`: the `(N, 1, spatial...)` output, flattened.
    pub fn predict(&self, input: &[f32], shape: &[usize]) -> Result<Vec<f32>> {
        Ok(self.forward(&Tensor::from_slice(input, shape, &Device::Cpu)?)?.flatten_all()?.to_vec1()?)
    }

    fn forward_with(&self, x: &Tensor, train: bool) -> Result<Tensor> {
        let dims = x.dims();
        let multiple = self.config.size_multiple();
        if dims.len() != self.config.spatial_axes + 2
            || dims[1] != self.config.in_channels
            || dims[2..].iter().any(|s| s % multiple != 0 || *s == 0)
        {
            return Err(CnnError::Shape(format!(
                "the U-Net takes (N, {}, {} spatial axes, each a positive multiple of {multiple}), got {dims:?}",
                self.config.in_channels, self.config.spatial_axes
            )));
        }
        let mut skips = Vec::with_capacity(self.down.len());
        let mut h = x.clone();
        for block in &self.down {
            let out = block.forward(&h, train)?;
            h = max_pool2(&out)?;
            skips.push(out);
        }
        h = self.bottleneck.forward(&h, train)?;
        for (up, skip) in self.up.iter().zip(skips.iter().rev()) {
            let upsampled = conv_transpose2(&h, &param(&up.weight, train), &param(&up.bias, train))?;
            h = up.block.forward(&Tensor::cat(&[&upsampled, skip], 1)?, train)?;
        }
        let out = conv(&h, &param(&self.out_weight, train))?;
        let bias_shape: Vec<usize> = vec![1; out.rank()];
        Ok(out.broadcast_add(&param(&self.out_bias, train).reshape(bias_shape)?)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(spatial_axes: usize) -> UNetConfig {
        UNetConfig { spatial_axes, in_channels: 2, initial_channels: 4, depth: 2 }
    }

    fn input(dims: &[usize], seed: u64) -> Tensor {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let v: Vec<f32> = (0..dims.iter().product()).map(|_| rng.random_range(-1.0..1.0)).collect();
        Tensor::from_vec(v, dims, &Device::Cpu).unwrap()
    }

    #[test]
    fn every_parameter_gets_a_gradient_in_2d_and_3d() {
        for (axes, dims) in [(2, vec![2, 2, 8, 12]), (3, vec![1, 2, 4, 8, 4])] {
            let net = UNet::init(config(axes), 0).unwrap();
            let y = net.forward_train(&input(&dims, 1)).unwrap();
            assert_eq!(y.dims()[1..], [&[1], &dims[2..]].concat()[..]);
            let grads = y.sqr().unwrap().sum_all().unwrap().backward().unwrap();
            for (name, var) in net.varmap().data().lock().unwrap().iter() {
                let has = grads.get(var).is_some();
                assert_eq!(has, !name.contains(".running_"), "{name}: gradient present = {has}");
            }
        }
    }

    #[test]
    fn parameter_count_matches_the_reference_layout() {
        // PyTorch's 2D U-Net with 32 channels, depth 4, 4 inputs has 7,766,273 parameters; it
        // has a bias in each of the 18 convolutions followed by BatchNorm, which this one omits.
        let net =
            UNet::init(UNetConfig { spatial_axes: 2, in_channels: 4, initial_channels: 32, depth: 4 }, 0).unwrap();
        let biases: usize =
            [32, 32, 64, 64, 128, 128, 256, 256, 512, 512, 256, 256, 128, 128, 64, 64, 32, 32].iter().sum();
        assert_eq!(net.parameter_count() + biases, 7_766_273);
    }

    #[test]
    fn running_statistics_move_towards_the_batch_and_round_trip_through_a_file() {
        let net = UNet::init(config(2), 3).unwrap();
        let x = input(&[2, 2, 8, 8], 4);
        let before = net.forward(&x).unwrap();
        net.forward_train(&x).unwrap();
        let after = net.forward(&x).unwrap();
        assert!((before - &after).unwrap().abs().unwrap().sum_all().unwrap().to_scalar::<f32>().unwrap() > 0.0);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("unet.safetensors");
        net.save(&path).unwrap();
        let loaded = UNet::load(config(2), &path).unwrap();
        let again = loaded.forward(&x).unwrap();
        assert_eq!(
            again.flatten_all().unwrap().to_vec1::<f32>().unwrap(),
            after.flatten_all().unwrap().to_vec1::<f32>().unwrap()
        );
        let other = UNetConfig { initial_channels: 8, ..config(2) };
        assert!(matches!(UNet::load(other, &path), Err(CnnError::ModelFile { .. })));
    }

    #[test]
    fn inputs_of_the_wrong_shape_are_errors() {
        let net = UNet::init(config(2), 0).unwrap();
        assert!(matches!(net.forward(&input(&[1, 2, 6, 8], 0)), Err(CnnError::Shape(_))));
        assert!(matches!(net.forward(&input(&[1, 3, 8, 8], 0)), Err(CnnError::Shape(_))));
        assert!(UNet::init(UNetConfig { spatial_axes: 4, ..config(2) }, 0).is_err());
    }
}
