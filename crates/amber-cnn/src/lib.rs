//! The U-Net CNN baseline of AMBER (spec §8): per-element features of an auxiliary mesh and an
//! inside/outside mask rasterised onto a pixel (2D) or voxel (3D) grid over the geometry's
//! bounding box ([`PixelGrid`]), a candle U-Net for both dimensions ([`UNet`]) built on this
//! crate's own convolution, transposed convolution, max-pooling and fused BatchNorm+ReLU ops
//! (candle has no 3D ops, a wrong `max_pool2d` backward and norms that drop gradients), model
//! files (safetensors + JSON), and a training handle ([`CnnTrainer`]: the images, the network,
//! the masked MSE of an `amber_nn::Objective` and `amber-nn`'s Adam) that, like
//! [`UNet::predict`], takes and returns plain slices.
//!
//! This crate sees meshes only to rasterise them and knows nothing of FEM, mesh generation, the
//! training loop or metrics: those live in `amber-train`, which drives it.

pub mod bench;
mod error;
pub mod ops;
mod raster;
mod train;
mod unet;

pub use error::{CnnError, Result};
pub use raster::{PixelGrid, Raster};
pub use train::{CnnStep, CnnTrainer, TrainingImages};
pub use unet::{UNet, UNetConfig};
