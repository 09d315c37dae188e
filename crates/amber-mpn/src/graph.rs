//! The graph as the network sees it: feature tensors plus the edge index in the two sorted
//! orders the fused ops need.

use std::sync::Arc;

use amber_graph::GraphBatch;
use amber_stdx::{Buckets, offsets_of};
use candle_core::{DType, Device, Tensor};
use rand::Rng;

use crate::error::{MpnError, Result};

/// Directed edges (self-loops included) of a graph, sorted by destination, with the CSR index of
/// both endpoints: edges into `v` are `dst_offsets[v]..dst_offsets[v + 1]`, edges out of `v` are
/// `by_src[src_offsets[v]..src_offsets[v + 1]]`.
#[derive(Debug)]
pub struct Topology {
    num_nodes: usize,
    src: Vec<u32>,
    dst: Vec<u32>,
    dst_offsets: Vec<u32>,
    by_src: Vec<u32>,
    src_offsets: Vec<u32>,
}

impl Topology {
    /// Checks that `dst` is sorted, `dst_offsets` is its CSR index and every endpoint exists.
    pub fn new(num_nodes: usize, src: Vec<u32>, dst: Vec<u32>, dst_offsets: Vec<u32>) -> Result<Self> {
        let bad = |m: String| Err(MpnError::InvalidGraph(m));
        if num_nodes > u32::MAX as usize || src.len() > u32::MAX as usize {
            return bad("more than 2^32 nodes or edges".into());
        }
        if src.len() != dst.len() {
            return bad(format!("{} edge sources but {} destinations", src.len(), dst.len()));
        }
        if dst_offsets.len() != num_nodes + 1 || dst_offsets[0] != 0 || dst_offsets[num_nodes] as usize != dst.len() {
            return bad(format!("dst_offsets must have {} entries from 0 to {}", num_nodes + 1, dst.len()));
        }
        for v in 0..num_nodes {
            let (lo, hi) = (dst_offsets[v] as usize, dst_offsets[v + 1] as usize);
            if lo > hi {
                return bad(format!("dst_offsets decreases at node {v}"));
            }
            if let Some(k) = (lo..hi).find(|&k| dst[k] as usize != v) {
                return bad(format!("edge {k} ends at node {} but lies in the segment of node {v}", dst[k]));
            }
        }
        if let Some(k) = src.iter().position(|&s| s as usize >= num_nodes) {
            return bad(format!("edge {k} starts at node {} of {num_nodes}", src[k]));
        }
        Ok(Self::from_sorted(num_nodes, src, dst, dst_offsets))
    }

    /// Builds the source-sorted index (a stable counting sort) of an already valid edge list.
    fn from_sorted(num_nodes: usize, src: Vec<u32>, dst: Vec<u32>, dst_offsets: Vec<u32>) -> Self {
        let Buckets { offsets: src_offsets, items: by_src } =
            Buckets::new(num_nodes, src.len(), |k| src[k], |k| k as u32);
        Self { num_nodes, src, dst, dst_offsets, by_src, src_offsets }
    }

    pub fn num_nodes(&self) -> usize {
        self.num_nodes
    }
    pub fn num_edges(&self) -> usize {
        self.src.len()
    }
    pub fn src(&self) -> &[u32] {
        &self.src
    }
    pub fn dst(&self) -> &[u32] {
        &self.dst
    }
    pub fn dst_offsets(&self) -> &[u32] {
        &self.dst_offsets
    }
    /// Edge ids sorted by source node.
    pub fn by_src(&self) -> &[u32] {
        &self.by_src
    }
    pub fn src_offsets(&self) -> &[u32] {
        &self.src_offsets
    }

    /// Drops every directed edge (self-loops included) independently with probability `p`
    /// (none for `p ≤ 0`, all for `p ≥ 1`); returns the remaining graph and the ids of the kept
    /// edges.
    pub fn drop_edges<R: Rng + ?Sized>(&self, p: f64, rng: &mut R) -> (Self, Vec<u32>) {
        let kept: Vec<u32> = (0..self.num_edges() as u32).filter(|_| rng.random::<f64>() >= p).collect();
        let src = kept.iter().map(|&k| self.src[k as usize]).collect();
        let dst: Vec<u32> = kept.iter().map(|&k| self.dst[k as usize]).collect();
        let dst_offsets = offsets_of(self.num_nodes, dst.iter().copied());
        (Self::from_sorted(self.num_nodes, src, dst, dst_offsets), kept)
    }
}

/// Input of one forward pass: normalised node and edge features (rows in the order of the
/// topology) on the network's device and dtype, and which graph of the batch each node is in.
#[derive(Clone, Debug)]
pub struct GraphInput {
    pub node_features: Tensor,
    pub edge_features: Tensor,
    pub topology: Arc<Topology>,
    /// The graph index of every node (u32, `(N)`).
    pub graph_of_node: Tensor,
    /// One over the node count of every graph (`(G, 1)`, the network's dtype).
    pub inverse_graph_sizes: Tensor,
    /// The region index of every node (u32, `(N)`; see `amber_graph::GraphBatch`).
    pub region_of_node: Tensor,
    /// One over the node count of every region (`(R, 1)`, the network's dtype).
    pub inverse_region_sizes: Tensor,
}

impl GraphInput {
    /// Validates a batch and uploads it with the given dtype.
    pub fn from_batch(batch: &GraphBatch, dtype: DType, device: &Device) -> Result<Self> {
        let n = batch.num_nodes;
        let e = batch.num_edges;
        batch.validate().map_err(|error| MpnError::InvalidGraph(error.to_string()))?;
        let offsets = &batch.node_offsets;
        if let Some(g) = offsets.windows(2).position(|w| w[0] == w[1]) {
            // Its mean node state would be 0/0, and a NaN reaches every context weight's gradient.
            return Err(MpnError::InvalidGraph(format!("graph {g} of the batch has no nodes")));
        }
        let inverse_graph_sizes: Vec<f32> = offsets.windows(2).map(|w| 1.0 / (w[1] - w[0]) as f32).collect();
        let inverse_graph_sizes =
            Tensor::from_vec(inverse_graph_sizes, (offsets.len() - 1, 1), device)?.to_dtype(dtype)?;
        // `validate` checked that every region has a node.
        let inverse_region_sizes: Vec<f32> = batch.region_sizes().into_iter().map(|n| 1.0 / n as f32).collect();
        let inverse_region_sizes =
            Tensor::from_vec(inverse_region_sizes, (batch.num_regions, 1), device)?.to_dtype(dtype)?;
        let topology = Topology::new(n, batch.edge_src.clone(), batch.edge_dst.clone(), batch.dst_offsets.clone())?;
        let node_features = Tensor::from_slice(&batch.node_features, (n, batch.node_dim), device)?.to_dtype(dtype)?;
        let edge_features = Tensor::from_slice(&batch.edge_features, (e, batch.edge_dim), device)?.to_dtype(dtype)?;
        Ok(Self {
            node_features,
            edge_features,
            topology: Arc::new(topology),
            graph_of_node: Tensor::from_slice(&batch.graph_of_node, n, device)?,
            inverse_graph_sizes,
            region_of_node: Tensor::from_slice(&batch.region_of_node, n, device)?,
            inverse_region_sizes,
        })
    }

    pub fn num_nodes(&self) -> usize {
        self.topology.num_nodes()
    }

    pub fn num_graphs(&self) -> usize {
        self.inverse_graph_sizes.dims()[0]
    }

    /// The same graph with each directed edge dropped independently with probability `p`
    /// (training-mode edge dropout; nodes are kept).
    pub fn drop_edges<R: Rng + ?Sized>(&self, p: f64, rng: &mut R) -> Result<Self> {
        let (topology, kept) = self.topology.drop_edges(p, rng);
        let kept = Tensor::from_vec(kept, topology.num_edges(), self.edge_features.device())?;
        Ok(Self {
            node_features: self.node_features.clone(),
            edge_features: self.edge_features.index_select(&kept, 0)?,
            topology: Arc::new(topology),
            graph_of_node: self.graph_of_node.clone(),
            inverse_graph_sizes: self.inverse_graph_sizes.clone(),
            region_of_node: self.region_of_node.clone(),
            inverse_region_sizes: self.inverse_region_sizes.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;

    /// 3 nodes, edges 1→0, 2→0, and self-loops.
    fn small() -> Topology {
        Topology::new(3, vec![0, 1, 2, 1, 2], vec![0, 0, 0, 1, 2], vec![0, 3, 4, 5]).unwrap()
    }

    #[test]
    fn source_index_lists_outgoing_edges() {
        let t = small();
        assert_eq!(t.src_offsets(), &[0, 1, 3, 5]);
        assert_eq!(t.by_src(), &[0, 1, 3, 2, 4]);
    }

    #[test]
    fn rejects_unsorted_or_out_of_range_edges() {
        assert!(Topology::new(2, vec![0, 1], vec![1, 0], vec![0, 1, 2]).is_err());
        assert!(Topology::new(2, vec![0, 5], vec![0, 1], vec![0, 1, 2]).is_err());
        assert!(Topology::new(2, vec![0, 1], vec![0, 1], vec![0, 2]).is_err());
        assert!(Topology::new(2, vec![0], vec![0, 1], vec![0, 1, 2]).is_err());
    }

    #[test]
    fn dropout_keeps_order_and_offsets() {
        let t = small();
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let (none, kept) = t.drop_edges(0.0, &mut rng);
        assert_eq!(kept, vec![0, 1, 2, 3, 4]);
        assert_eq!(none.dst_offsets(), t.dst_offsets());
        let (half, kept) = t.drop_edges(0.5, &mut rng);
        let again = Topology::new(3, half.src().to_vec(), half.dst().to_vec(), half.dst_offsets().to_vec());
        assert!(again.is_ok());
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
    }
}
