//! Everything that makes a mesh: sizing fields, geometry descriptions, the 2D sizing-field mesh
//! generator on spade, the 3D generator, red-green-blue refinement and smoothing.
//!
//! Every mesh that leaves this crate is conforming, positively oriented and covers its geometry.
//! This crate knows nothing of FEM, graphs or learning.

mod domain;
mod error;
mod mesh2d;
mod predicates;
mod quality;
mod ray;
mod sizing;

pub use domain::{PolygonDistance, PolygonDomain};
pub use error::MeshgenError;
pub use mesh2d::{Mesh2dParams, generate_2d, uniform_mesh_2d};
pub use quality::QualityReport;
pub use sizing::{
    ClampedSize, ConstantSize, FnSize, MeshSizing, PixelGridSizing, SizingField, estimated_element_count,
};

pub mod mesh3d;
pub mod rgb;
