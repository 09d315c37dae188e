//! The 3D mesh generator: closed CAD-face-labelled surfaces in, tetrahedral meshes out.
//!
//! [`surface`] reads and validates the geometry (STL with CAD face ids, plain STL, OBJ);
//! [`tetgen`] fills a closed surface with tets following a sizing field.

pub mod tetgen;

pub use tetgen::{Optimization, Plc, Quality, TetgenError, TetgenMesh, TetgenSwitches, delaunay, tetrahedralize};
