//! Mesh graphs for the message passing network: one node per element, edges across interior
//! facets in both directions plus self-loops, node and edge features, a running input
//! normaliser, batching, and the projection of an expert mesh's sizing field onto a mesh
//! (the training labels).
//!
//! Plain `Vec`s and slices only: this crate never sees a candle tensor.

mod batch;

pub use batch::GraphBatch;
