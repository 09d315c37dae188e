//! The element graph of one mesh with its raw (unnormalised) features (spec §4).

use amber_mesh::{FacetAdjacency, Mesh};

use crate::{EdgeFeature, ElementColumn, FeatureSet, GraphError, NodeFeature};

/// The graph of one mesh: one node per element (same index), two directed edges across every
/// interior facet and one self-loop per node.
///
/// Edges are sorted by `(dst, src)`, so the edges arriving at node `v` are
/// `dst_offsets[v]..dst_offsets[v + 1]` (CSR). Features are raw; normalise batches with
/// [`crate::FeatureNormaliser`].
#[derive(Clone, Debug, PartialEq)]
pub struct MeshGraph {
    node_dim: usize,
    node_features: Vec<f32>,
    edge_dim: usize,
    edge_features: Vec<f32>,
    edge_src: Vec<u32>,
    edge_dst: Vec<u32>,
    dst_offsets: Vec<u32>,
    region_of_node: Vec<u32>,
    num_regions: usize,
}

/// Cubes along the longest side of a graph's bounding box in its partition into regions (see
/// [`MeshGraph::region_of_node`]): at most 4² regions in 2D and 4³ in 3D.
pub const REGIONS_PER_AXIS: usize = 4;

impl MeshGraph {
    /// Builds the graph of `mesh` with the features listed in `features`; `columns` supplies the
    /// non-geometric node features by name (extra columns are ignored).
    ///
    /// ```
    /// use amber_graph::{FeatureSet, MeshGraph};
    /// use amber_mesh::Mesh2;
    /// let square = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
    /// let graph = MeshGraph::new(&square, &FeatureSet::console(), &[]).unwrap();
    /// // One interior edge in both directions plus two self-loops.
    /// assert_eq!((graph.num_nodes(), graph.num_edges()), (2, 4));
    /// ```
    pub fn new<const D: usize>(
        mesh: &Mesh<D>,
        features: &FeatureSet,
        columns: &[ElementColumn<'_>],
    ) -> Result<Self, GraphError> {
        let n = mesh.num_elements();
        let adjacency = FacetAdjacency::new(mesh)?;
        let num_edges = n + 2 * adjacency.num_interior_facets();
        if num_edges > u32::MAX as usize {
            return Err(GraphError::TooLarge { what: "edges", count: num_edges });
        }

        let mut edge_src = Vec::with_capacity(num_edges);
        let mut edge_dst = Vec::with_capacity(num_edges);
        let mut dst_offsets = Vec::with_capacity(n + 1);
        dst_offsets.push(0);
        let mut incoming = Vec::with_capacity(D + 2);
        for v in 0..n {
            incoming.clear();
            incoming.push(v as u32);
            incoming.extend(adjacency.neighbours_of(v).iter().copied().filter(|&u| u != FacetAdjacency::BOUNDARY));
            incoming.sort_unstable();
            edge_src.extend_from_slice(&incoming);
            edge_dst.extend(std::iter::repeat_n(v as u32, incoming.len()));
            dst_offsets.push(edge_src.len() as u32);
        }

        let node_features = node_features(mesh, &features.node, columns)?;
        let midpoints = mesh.midpoints();
        let edge_dim = features.edge_dim(D);
        let mut edge_features = Vec::with_capacity(num_edges * edge_dim);
        for (&s, &d) in edge_src.iter().zip(&edge_dst) {
            let (cs, cd) = (midpoints[s as usize], midpoints[d as usize]);
            let diff: [f64; D] = std::array::from_fn(|k| cd[k] - cs[k]);
            for feature in &features.edge {
                match feature {
                    EdgeFeature::MidpointDistance => {
                        edge_features.push(diff.iter().map(|x| x * x).sum::<f64>().sqrt() as f32);
                    }
                    EdgeFeature::MidpointDifference => edge_features.extend(diff.iter().map(|&x| x as f32)),
                }
            }
        }

        let (region_of_node, num_regions) = regions(&midpoints);
        Ok(Self {
            node_dim: features.node_dim(),
            node_features,
            edge_dim,
            edge_features,
            edge_src,
            edge_dst,
            dst_offsets,
            region_of_node,
            num_regions,
        })
    }

    /// Number of nodes (= elements of the mesh).
    pub fn num_nodes(&self) -> usize {
        self.dst_offsets.len() - 1
    }

    /// Number of directed edges, self-loops included.
    pub fn num_edges(&self) -> usize {
        self.edge_src.len()
    }

    /// Width of a node feature row.
    pub fn node_dim(&self) -> usize {
        self.node_dim
    }

    /// Width of an edge feature row.
    pub fn edge_dim(&self) -> usize {
        self.edge_dim
    }

    /// Raw node features, row-major (`num_nodes × node_dim`).
    pub fn node_features(&self) -> &[f32] {
        &self.node_features
    }

    /// Raw edge features, row-major (`num_edges × edge_dim`), in edge order.
    pub fn edge_features(&self) -> &[f32] {
        &self.edge_features
    }

    /// Source node of every edge.
    pub fn edge_src(&self) -> &[u32] {
        &self.edge_src
    }

    /// Destination node of every edge (ascending).
    pub fn edge_dst(&self) -> &[u32] {
        &self.edge_dst
    }

    /// CSR offsets of the edges by destination (length `num_nodes + 1`).
    pub fn dst_offsets(&self) -> &[u32] {
        &self.dst_offsets
    }

    /// The region of every node: the cell its element's midpoint lies in, of a grid of cubes
    /// over the midpoints' bounding box with [`REGIONS_PER_AXIS`] cubes along its longest side,
    /// the non-empty cells numbered in the grid's order (`0..num_regions`).
    pub fn region_of_node(&self) -> &[u32] {
        &self.region_of_node
    }

    /// Number of regions (non-empty cells), each with at least one node.
    pub fn num_regions(&self) -> usize {
        self.num_regions
    }
}

/// The regions of the elements with midpoints `midpoints` and their count (see
/// [`MeshGraph::region_of_node`]).
fn regions<const D: usize>(midpoints: &[[f64; D]]) -> (Vec<u32>, usize) {
    let Some((low, high)) = amber_mesh::bounding_box(midpoints) else { return (Vec::new(), 0) };
    let longest = (0..D).map(|k| high[k] - low[k]).fold(0.0, f64::max);
    let cube = longest / REGIONS_PER_AXIS as f64;
    let cell = |p: &[f64; D]| {
        (0..D).fold(0, |index, k| {
            let along = if cube > 0.0 { ((p[k] - low[k]) / cube) as usize } else { 0 };
            index * REGIONS_PER_AXIS + along.min(REGIONS_PER_AXIS - 1)
        })
    };
    let cells: Vec<usize> = midpoints.iter().map(cell).collect();
    let mut used = vec![false; REGIONS_PER_AXIS.pow(D as u32)];
    cells.iter().for_each(|&c| used[c] = true);
    let number: Vec<u32> = used
        .iter()
        .scan(0, |next, &u| {
            let n = *next;
            *next += u32::from(u);
            Some(n)
        })
        .collect();
    (cells.iter().map(|&c| number[c]).collect(), used.iter().filter(|&&u| u).count())
}

/// Node feature rows: geometric columns computed here, named columns taken from the caller.
fn node_features<const D: usize>(
    mesh: &Mesh<D>,
    wanted: &[NodeFeature],
    columns: &[ElementColumn<'_>],
) -> Result<Vec<f32>, GraphError> {
    let n = mesh.num_elements();
    let mut sources: Vec<std::borrow::Cow<'_, [f64]>> = Vec::with_capacity(wanted.len());
    for feature in wanted {
        sources.push(match feature {
            NodeFeature::Volume => mesh.volumes().into(),
            NodeFeature::Column(name) => {
                let column = columns
                    .iter()
                    .find(|c| c.name == name)
                    .ok_or_else(|| GraphError::MissingColumn { name: name.clone() })?;
                if column.values.len() != n {
                    return Err(GraphError::ColumnLength { name: name.clone(), len: column.values.len(), expected: n });
                }
                if let Some(element) = column.values.iter().position(|x| !x.is_finite()) {
                    return Err(GraphError::NonFiniteColumn { name: name.clone(), element });
                }
                column.values.into()
            }
        });
    }
    let mut rows = Vec::with_capacity(n * wanted.len());
    for e in 0..n {
        rows.extend(sources.iter().map(|s| s[e] as f32));
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::{Mesh2, Mesh3};

    /// The unit square as a 4-triangle fan around its centre: a 4-cycle of elements.
    fn fan() -> Mesh2 {
        Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]],
            vec![0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4],
        )
        .unwrap()
    }

    #[test]
    fn edges_are_bidirectional_dst_sorted_with_self_loops() {
        let g = MeshGraph::new(&fan(), &FeatureSet::console(), &[]).unwrap();
        assert_eq!(g.num_nodes(), 4);
        assert_eq!(g.num_edges(), 4 + 2 * 4);
        assert_eq!(g.dst_offsets(), &[0, 3, 6, 9, 12]);
        assert_eq!(g.edge_dst(), &[0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3]);
        assert_eq!(g.edge_src(), &[0, 1, 3, 0, 1, 2, 1, 2, 3, 0, 2, 3]);
    }

    #[test]
    fn poisson_features_combine_geometry_and_caller_columns() {
        let mean = [1.0, 2.0, 3.0, 4.0];
        let std = [0.0; 4];
        let load = [5.0, 6.0, 7.0, 8.0];
        let columns = [
            ElementColumn { name: "load", values: &load },
            ElementColumn { name: "solution_mean", values: &mean },
            ElementColumn { name: "solution_std", values: &std },
        ];
        let g = MeshGraph::new(&fan(), &FeatureSet::poisson(), &columns).unwrap();
        assert_eq!((g.node_dim(), g.edge_dim()), (4, 1));
        assert_eq!(&g.node_features()[4..8], &[0.25, 2.0, 0.0, 6.0]);
        // Edge 1 → 0: midpoints (5/6, 1/2) and (1/2, 1/6); self-loop 0 → 0 has distance 0.
        assert_eq!(g.edge_features()[0], 0.0);
        assert!((g.edge_features()[1] - (2.0f32 / 9.0).sqrt()).abs() < 1e-7);
    }

    #[test]
    fn difference_vectors_point_from_source_to_destination() {
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
        let m = Mesh3::new_reoriented(v, vec![0, 1, 2, 3, 0, 1, 2, 4]).unwrap();
        let g = MeshGraph::new(&m, &FeatureSet::console(), &[]).unwrap();
        assert_eq!(g.edge_src(), &[0, 1, 0, 1]);
        assert_eq!(g.edge_dim(), 3);
        // Edge 1 → 0: c_0 − c_1 = (0, 0, 1/4 − (−1/4)).
        assert_eq!(&g.edge_features()[3..6], &[0.0, 0.0, 0.5]);
        assert_eq!(&g.edge_features()[0..3], &[0.0, 0.0, 0.0]);
    }

    #[test]
    fn bad_columns_are_typed_errors() {
        let set = FeatureSet { node: vec![NodeFeature::Column("u".into())], edge: vec![] };
        let m = fan();
        assert!(matches!(MeshGraph::new(&m, &set, &[]), Err(GraphError::MissingColumn { .. })));
        let short = [1.0; 3];
        let columns = [ElementColumn { name: "u", values: &short }];
        assert!(matches!(
            MeshGraph::new(&m, &set, &columns),
            Err(GraphError::ColumnLength { len: 3, expected: 4, .. })
        ));
        let nan = [1.0, f64::NAN, 0.0, 0.0];
        let columns = [ElementColumn { name: "u", values: &nan }];
        assert!(matches!(MeshGraph::new(&m, &set, &columns), Err(GraphError::NonFiniteColumn { element: 1, .. })));
    }
}
