//! Everything that makes a mesh: sizing fields, geometry descriptions, the 2D sizing-field mesh
//! generator on spade, the 3D generator, red-green-blue refinement and smoothing.
//!
//! Every mesh that leaves this crate is conforming, positively oriented and covers its geometry.
//! This crate knows nothing of FEM, graphs or learning.
