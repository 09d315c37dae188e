//! Random graphs with the shape of mesh graphs, for benchmarks and tests.

use amber_graph::GraphBatch;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// A single graph of `num_nodes` nodes with `undirected_edges` random node pairs, each as two
/// directed edges, plus a self-loop per node (so about `2·undirected_edges/num_nodes` neighbours
/// per node), sorted by destination, in four regions. Node and edge features are uniform in
/// [-1, 1].
pub fn random_graph(
    num_nodes: usize,
    undirected_edges: usize,
    node_dim: usize,
    edge_dim: usize,
    seed: u64,
) -> GraphBatch {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut pairs: Vec<(u32, u32)> = (0..num_nodes as u32).map(|v| (v, v)).collect();
    if num_nodes > 1 {
        for _ in 0..undirected_edges {
            let a = rng.random_range(0..num_nodes as u32);
            let b = (a + rng.random_range(1..num_nodes as u32)) % num_nodes as u32;
            pairs.extend([(a, b), (b, a)]);
        }
    }
    pairs.sort_unstable_by_key(|&(s, d)| (d, s));
    let dst_offsets = amber_stdx::offsets_of(num_nodes, pairs.iter().map(|&(_, d)| d));
    let num_edges = pairs.len();
    // Four regions of consecutive nodes (one per node in a graph of fewer).
    let regions = num_nodes.min(4);
    let mut uniform = |n: usize| (0..n).map(|_| rng.random_range(-1.0f32..1.0)).collect::<Vec<_>>();
    GraphBatch {
        num_nodes,
        node_dim,
        node_features: uniform(num_nodes * node_dim),
        num_edges,
        edge_dim,
        edge_features: uniform(num_edges * edge_dim),
        edge_src: pairs.iter().map(|p| p.0).collect(),
        edge_dst: pairs.iter().map(|p| p.1).collect(),
        dst_offsets,
        graph_of_node: vec![0; num_nodes],
        node_offsets: vec![0, num_nodes as u32],
        region_of_node: (0..num_nodes).map(|v| (v * regions / num_nodes) as u32).collect(),
        num_regions: regions,
    }
}
