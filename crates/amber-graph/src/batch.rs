//! A batch of graphs flattened into one graph, in the layout the network consumes.

/// One or more graphs concatenated into a single graph (nodes of graph `g` are
/// `node_offsets[g]..node_offsets[g + 1]`).
///
/// Invariants (checked by the constructors of this crate):
/// - `node_features.len() == num_nodes * node_dim`, `edge_features.len() == num_edges * edge_dim`
///   (row-major);
/// - `edge_dst` is sorted ascending and `dst_offsets` (length `num_nodes + 1`) is its CSR index:
///   the edges arriving at node `v` are `dst_offsets[v]..dst_offsets[v + 1]`, so aggregation is
///   a segment operation;
/// - every node has a self-loop among its incoming edges;
/// - `graph_of_node[v]` is the graph index of node `v`.
#[derive(Clone, Debug, PartialEq)]
pub struct GraphBatch {
    pub num_nodes: usize,
    pub node_dim: usize,
    pub node_features: Vec<f32>,
    pub num_edges: usize,
    pub edge_dim: usize,
    pub edge_features: Vec<f32>,
    pub edge_src: Vec<u32>,
    pub edge_dst: Vec<u32>,
    pub dst_offsets: Vec<u32>,
    pub graph_of_node: Vec<u32>,
    pub node_offsets: Vec<u32>,
}
