//! The message passing network (MPN) of AMBER in candle: it maps a mesh graph (nodes =
//! elements) to one scalar per node, an element size through the objective
//! (`amber_nn::Objective`, spec §5), and the fused CPU custom ops that make it fast enough to
//! train on CPUs. On another device (`amber_nn::Backend::Cuda`, the `cuda` feature) the same
//! network runs as stock candle ops, the composition the fused ops are tested against.
//!
//! Input is an [`amber_graph::GraphBatch`]; this crate knows nothing of meshes, meshing, labels
//! or the training loop around a step. [`MpnTrainer`] (one training step: forward, loss, Adam
//! from `amber-nn`) and [`Mpn::predict`] / [`Mpn::load`] take and return plain slices, so the
//! training loop never sees a tensor. Only the fused ops in `ops` touch raw tensor storage.
//!
//! ```
//! use amber_mpn::{GraphInput, Mpn, MpnConfig};
//! use amber_nn::Objective;
//! use candle_core::{DType, Device};
//!
//! let config = MpnConfig::small(8, 2);
//! let (model, _vars) = Mpn::init(config, 0, DType::F32, &Device::Cpu)?;
//! let batch = amber_mpn::synthetic::random_graph(10, 15, 4, 1, 0);
//! let z = model.predict(&batch)?;
//! let sizes: Vec<f64> = z.iter().map(|&z| Objective::SoftplusMse.size(f64::from(z), None)).collect();
//! assert_eq!(sizes.len(), 10);
//! assert!(sizes.iter().all(|&h| h > 0.0));
//! # Ok::<(), amber_mpn::MpnError>(())
//! ```

pub mod bench;
mod config;
mod error;
mod graph;
mod kernels;
mod model;
mod ops;
pub mod synthetic;
mod train;

pub use config::{MpnConfig, NetworkConfig};
pub use error::{MpnError, Result};
pub use graph::{GraphInput, Topology};
pub use model::Mpn;
pub use train::{MpnTrainer, StepLoss};
