//! Mesh graphs for the message passing network: one node per element, edges across interior
//! facets in both directions plus self-loops, node and edge features, a running input
//! normaliser, batching, and the projection of an expert mesh's sizing field onto a mesh
//! (the training labels).
//!
//! Plain `Vec`s and slices only: this crate never sees a candle tensor, and knows nothing of
//! training or mesh generation.

mod batch;
mod error;
mod features;
mod graph;
mod normaliser;
mod projection;

pub use batch::GraphBatch;
pub use error::GraphError;
pub use features::{EdgeFeature, ElementColumn, FeatureSet, NodeFeature};
pub use graph::MeshGraph;
pub use normaliser::{CLIP, FeatureNormaliser, INITIAL_COUNT, RunningMoments, VARIANCE_EPSILON};
pub use projection::{Aggregation, project_expert_sizing};
