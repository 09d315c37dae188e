//! A batch of graphs flattened into one graph, in the layout the network consumes.

use crate::{GraphError, MeshGraph};

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
/// - `graph_of_node[v]` is the graph index of node `v`;
/// - `region_of_node[v] < num_regions` is the region of node `v` ([`MeshGraph::region_of_node`],
///   numbered on from the previous graph's), and every region has a node.
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
    pub region_of_node: Vec<u32>,
    pub num_regions: usize,
}

impl GraphBatch {
    /// Concatenates graphs into one batch: node and edge indices of each graph are shifted by the
    /// number of nodes before it, so edges stay sorted by destination. Features stay raw; apply
    /// [`crate::FeatureNormaliser::normalise`] afterwards.
    pub fn from_graphs<'a>(graphs: impl IntoIterator<Item = &'a MeshGraph>) -> Result<Self, GraphError> {
        let graphs: Vec<&MeshGraph> = graphs.into_iter().collect();
        let first = graphs.first().ok_or(GraphError::EmptyBatch)?;
        let (node_dim, edge_dim) = (first.node_dim(), first.edge_dim());
        for g in &graphs {
            if g.node_dim() != node_dim {
                return Err(GraphError::DimensionMismatch {
                    what: "node features",
                    expected: node_dim,
                    found: g.node_dim(),
                });
            }
            if g.edge_dim() != edge_dim {
                return Err(GraphError::DimensionMismatch {
                    what: "edge features",
                    expected: edge_dim,
                    found: g.edge_dim(),
                });
            }
        }
        let num_nodes: usize = graphs.iter().map(|g| g.num_nodes()).sum();
        let num_edges: usize = graphs.iter().map(|g| g.num_edges()).sum();
        // dst_offsets holds edge counts and graph_of_node graph indices: all must fit in u32.
        for (what, count) in [("nodes", num_nodes), ("edges", num_edges)] {
            if count > u32::MAX as usize {
                return Err(GraphError::TooLarge { what, count });
            }
        }

        let mut batch = GraphBatch {
            num_nodes,
            node_dim,
            node_features: Vec::with_capacity(num_nodes * node_dim),
            num_edges,
            edge_dim,
            edge_features: Vec::with_capacity(num_edges * edge_dim),
            edge_src: Vec::with_capacity(num_edges),
            edge_dst: Vec::with_capacity(num_edges),
            dst_offsets: Vec::with_capacity(num_nodes + 1),
            graph_of_node: Vec::with_capacity(num_nodes),
            node_offsets: Vec::with_capacity(graphs.len() + 1),
            region_of_node: Vec::with_capacity(num_nodes),
            num_regions: 0,
        };
        batch.dst_offsets.push(0);
        batch.node_offsets.push(0);
        let (mut node_base, mut edge_base) = (0u32, 0u32);
        for (index, g) in graphs.iter().enumerate() {
            batch.node_features.extend_from_slice(g.node_features());
            batch.edge_features.extend_from_slice(g.edge_features());
            batch.edge_src.extend(g.edge_src().iter().map(|&s| s + node_base));
            batch.edge_dst.extend(g.edge_dst().iter().map(|&d| d + node_base));
            batch.dst_offsets.extend(g.dst_offsets()[1..].iter().map(|&o| o + edge_base));
            batch.graph_of_node.extend(std::iter::repeat_n(index as u32, g.num_nodes()));
            batch.region_of_node.extend(g.region_of_node().iter().map(|&r| r + batch.num_regions as u32));
            batch.num_regions += g.num_regions();
            node_base += g.num_nodes() as u32;
            edge_base += g.num_edges() as u32;
            batch.node_offsets.push(node_base);
        }
        Ok(batch)
    }

    /// Number of graphs in the batch.
    pub fn num_graphs(&self) -> usize {
        self.node_offsets.len().saturating_sub(1)
    }

    /// The node count of every region.
    pub fn region_sizes(&self) -> Vec<usize> {
        let mut sizes = vec![0; self.num_regions];
        for &r in &self.region_of_node {
            if let Some(n) = sizes.get_mut(r as usize) {
                *n += 1;
            }
        }
        sizes
    }

    /// Checks every invariant listed on [`GraphBatch`] (for batches assembled by hand).
    pub fn validate(&self) -> Result<(), GraphError> {
        let fail = |reason: String| Err(GraphError::InvalidBatch { reason });
        let (n, m) = (self.num_nodes, self.num_edges);
        if self.node_features.len() != n * self.node_dim || self.edge_features.len() != m * self.edge_dim {
            return fail("feature lengths do not match num_nodes × node_dim and num_edges × edge_dim".into());
        }
        if self.edge_src.len() != m || self.edge_dst.len() != m || self.dst_offsets.len() != n + 1 {
            return fail("edge_src, edge_dst or dst_offsets has the wrong length".into());
        }
        if self.graph_of_node.len() != n
            || self.node_offsets.first() != Some(&0)
            || self.node_offsets.last() != Some(&(n as u32))
        {
            return fail("graph_of_node or node_offsets does not cover the nodes".into());
        }
        if let Some(&bad) = self.edge_src.iter().chain(&self.edge_dst).find(|&&v| v as usize >= n) {
            return fail(format!("edge endpoint {bad} is not a node"));
        }
        if self.dst_offsets[0] != 0 || self.dst_offsets[n] as usize != m {
            return fail("dst_offsets must start at 0 and end at num_edges".into());
        }
        for v in 0..n {
            let (start, end) = (self.dst_offsets[v] as usize, self.dst_offsets[v + 1] as usize);
            if start > end || end > m {
                return fail(format!("dst_offsets is not monotone at node {v}"));
            }
            if self.edge_dst[start..end].iter().any(|&d| d as usize != v) {
                return fail(format!("edges {start}..{end} do not all arrive at node {v}"));
            }
            if !self.edge_src[start..end].contains(&(v as u32)) {
                return fail(format!("node {v} has no self-loop"));
            }
        }
        for (g, w) in self.node_offsets.windows(2).enumerate() {
            if w[0] > w[1]
                || w[1] as usize > n
                || self.graph_of_node[w[0] as usize..w[1] as usize].iter().any(|&x| x as usize != g)
            {
                return fail(format!("graph_of_node disagrees with node_offsets for graph {g}"));
            }
        }
        if self.region_of_node.len() != n || self.region_of_node.iter().any(|&r| r as usize >= self.num_regions) {
            return fail(format!("region_of_node must give every node a region below {}", self.num_regions));
        }
        if let Some(r) = self.region_sizes().iter().position(|&size| size == 0) {
            return fail(format!("region {r} has no nodes"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FeatureSet;
    use amber_mesh::Mesh2;

    fn graph(extra_triangle: bool) -> MeshGraph {
        let mut v = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let mut cells = vec![0, 1, 2, 0, 2, 3];
        if extra_triangle {
            v.push([2.0, 0.0]);
            cells.extend([1, 4, 2]);
        }
        MeshGraph::new(&Mesh2::new(v, cells).unwrap(), &FeatureSet::console(), &[]).unwrap()
    }

    #[test]
    fn batching_shifts_indices_and_keeps_edges_dst_sorted() {
        let (a, b) = (graph(false), graph(true));
        let batch = GraphBatch::from_graphs([&a, &b]).unwrap();
        batch.validate().unwrap();
        assert_eq!((batch.num_graphs(), batch.num_nodes, batch.num_edges), (2, 5, a.num_edges() + b.num_edges()));
        assert_eq!(batch.node_offsets, vec![0, 2, 5]);
        assert_eq!(batch.graph_of_node, vec![0, 0, 1, 1, 1]);
        assert!(batch.edge_dst.is_sorted());
        assert_eq!(&batch.edge_src[a.num_edges()..], &b.edge_src().iter().map(|s| s + 2).collect::<Vec<_>>()[..]);
        assert_eq!(batch.dst_offsets[2] as usize, a.num_edges());
        assert_eq!(&batch.edge_features[..a.edge_features().len()], a.edge_features());
        // Regions in the grid's order, x major: a's midpoints lie in cells (3, 0) and (0, 3) of
        // cubes a quarter of 1/3 wide; b's in (1, 0), (0, 1) and (3, 0) of cubes 1/4 wide.
        assert_eq!((a.region_of_node(), b.region_of_node()), (&[1, 0][..], &[1, 0, 2][..]));
        assert_eq!((batch.region_of_node.clone(), batch.num_regions), (vec![1, 0, 3, 2, 4], 5));
    }

    /// Regions are cubes, a quarter of the longest side wide: an 8 × 8 grid of split squares has
    /// 16 regions of 2 × 2 squares, an 8 × 2 grid 4 (its short side fits in one cube).
    #[test]
    fn regions_are_cubes_of_a_quarter_of_the_longest_side() {
        for ((nx, ny), regions) in [((8, 8), 16), ((8, 2), 4)] {
            let graph = MeshGraph::new(&grid(nx, ny), &FeatureSet::console(), &[]).unwrap();
            let batch = GraphBatch::from_graphs([&graph]).unwrap();
            assert_eq!(batch.num_regions, regions);
            assert_eq!(batch.region_sizes(), vec![2 * nx * ny / regions; regions]);
        }
    }

    /// An `nx × ny` grid of unit squares, each split into two triangles.
    fn grid(nx: usize, ny: usize) -> Mesh2 {
        let vertices = (0..=ny).flat_map(|j| (0..=nx).map(move |i| [i as f64, j as f64])).collect();
        let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
        let cells = (0..ny)
            .flat_map(|j| (0..nx).map(move |i| (i, j)))
            .flat_map(|(i, j)| [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)])
            .collect();
        Mesh2::new(vertices, cells).unwrap()
    }

    proptest::proptest! {
        #[test]
        fn batches_of_grid_graphs_keep_every_invariant(sizes in proptest::collection::vec((1..6usize, 1..6usize), 1..5)) {
            let graphs: Vec<MeshGraph> = sizes
                .iter()
                .map(|&(nx, ny)| MeshGraph::new(&grid(nx, ny), &FeatureSet::console(), &[]).unwrap())
                .collect();
            let batch = GraphBatch::from_graphs(&graphs).unwrap();
            batch.validate().unwrap();
            // Interior edges of an nx × ny grid of split squares: 3·nx·ny − nx − ny.
            let edges: usize = sizes.iter().map(|&(nx, ny)| 2 * nx * ny + 2 * (3 * nx * ny - nx - ny)).sum();
            proptest::prop_assert_eq!(batch.num_edges, edges);
            proptest::prop_assert_eq!(batch.num_graphs(), sizes.len());
        }
    }

    #[test]
    fn mismatched_or_empty_batches_are_errors() {
        assert!(matches!(GraphBatch::from_graphs([]), Err(GraphError::EmptyBatch)));
        let m = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap();
        let poisson_like = FeatureSet { node: vec![crate::NodeFeature::Volume; 2], edge: vec![] };
        let other = MeshGraph::new(&m, &poisson_like, &[]).unwrap();
        assert!(matches!(GraphBatch::from_graphs([&graph(false), &other]), Err(GraphError::DimensionMismatch { .. })));
    }

    #[test]
    fn validation_catches_a_missing_self_loop() {
        let mut batch = GraphBatch::from_graphs([&graph(false)]).unwrap();
        // Node 0 receives (0 → 0, 1 → 0); redirect the self-loop's source.
        batch.edge_src[0] = 1;
        assert!(matches!(batch.validate(), Err(GraphError::InvalidBatch { .. })));
    }

    #[test]
    fn validation_catches_an_empty_or_unknown_region() {
        let batch = GraphBatch::from_graphs([&graph(false)]).unwrap();
        let mut empty = batch.clone();
        empty.region_of_node = vec![0, 0];
        let mut unknown = batch;
        unknown.region_of_node[1] = 2;
        for bad in [empty, unknown] {
            assert!(matches!(bad.validate(), Err(GraphError::InvalidBatch { .. })));
        }
    }
}
