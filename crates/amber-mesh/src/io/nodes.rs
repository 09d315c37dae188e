//! The nodes and elements a writer writes: a mesh's own vertices and simplices (first order), or
//! with one more node at the midpoint of every edge (second order: `triangle6`, `tetra10`).

use std::collections::HashMap;

use crate::Mesh;

/// The order of the elements a writer writes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ElementOrder {
    /// The mesh's simplices: 3-node triangles, 4-node tetrahedra.
    #[default]
    Linear,
    /// One more node on each edge, at its midpoint (straight-sided, as TetGen's `-o2` makes them):
    /// 6-node triangles, 10-node tetrahedra, for solvers whose linear simplices are too stiff.
    Quadratic,
}

/// The local edges of a simplex in VTK's order (also Abaqus's and NASTRAN's): a triangle's
/// 0-1, 1-2, 2-0; a tetrahedron's three more 0-3, 1-3, 2-3.
const EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];

/// A mesh's nodes and elements as written.
pub(super) struct Nodes<'m, const D: usize> {
    mesh: &'m Mesh<D>,
    /// The edge nodes of a second-order mesh, numbered after the vertices in the order the
    /// elements first name their edges, keyed by their sorted end vertices.
    edge_node: HashMap<[u32; 2], u32>,
    /// The edges of `edge_node` in the order of their numbers.
    edges: Vec<[u32; 2]>,
}

impl<'m, const D: usize> Nodes<'m, D> {
    pub(super) fn new(mesh: &'m Mesh<D>, order: ElementOrder) -> Self {
        let mut nodes = Self { mesh, edge_node: HashMap::new(), edges: Vec::new() };
        if order == ElementOrder::Quadratic {
            for cell in mesh.elements() {
                for [a, b] in &EDGES[..Self::edges_per_element()] {
                    let key = sorted(cell[*a], cell[*b]);
                    let next = (mesh.num_vertices() + nodes.edges.len()) as u32;
                    nodes.edge_node.entry(key).or_insert_with(|| {
                        nodes.edges.push(key);
                        next
                    });
                }
            }
        }
        nodes
    }

    pub(super) fn mesh(&self) -> &'m Mesh<D> {
        self.mesh
    }

    pub(super) fn is_quadratic(&self) -> bool {
        !self.edges.is_empty()
    }

    fn edges_per_element() -> usize {
        D * (D + 1) / 2
    }

    /// Vertices, then the edge nodes.
    pub(super) fn num_points(&self) -> usize {
        self.mesh.num_vertices() + self.edges.len()
    }

    /// The coordinates of every node: the vertices, then each edge's midpoint.
    pub(super) fn points(&self) -> impl Iterator<Item = [f64; D]> + '_ {
        let v = self.mesh.vertices();
        let midpoint = |[a, b]: [u32; 2]| std::array::from_fn(|k| 0.5 * (v[a as usize][k] + v[b as usize][k]));
        v.iter().copied().chain(self.edges.iter().map(move |&e| midpoint(e)))
    }

    pub(super) fn nodes_per_element(&self) -> usize {
        if self.is_quadratic() { D + 1 + Self::edges_per_element() } else { D + 1 }
    }

    /// The nodes of each element: its corners, then (second order) its edge nodes in [`EDGES`]'
    /// order.
    pub(super) fn elements(&self) -> impl ExactSizeIterator<Item = Vec<u32>> + '_ {
        self.mesh.elements().map(|cell| self.with_edge_nodes(cell, &EDGES[..Self::edges_per_element()]))
    }

    /// The nodes of a facet given by its corners: the corners, then (second order) the edge
    /// nodes of a triangle's 0-1, 1-2, 2-0 or the midpoint of a segment.
    pub(super) fn facet(&self, corners: &[u32]) -> Vec<u32> {
        let edges: &[[usize; 2]] = if D == 3 { &EDGES[..3] } else { &EDGES[..1] };
        self.with_edge_nodes(corners, edges)
    }

    fn with_edge_nodes(&self, corners: &[u32], edges: &[[usize; 2]]) -> Vec<u32> {
        let mut nodes = corners.to_vec();
        if self.is_quadratic() {
            nodes.extend(edges.iter().map(|&[a, b]| self.edge_node[&sorted(corners[a], corners[b])]));
        }
        nodes
    }

    /// A per-vertex field on every node: an edge node takes the mean of its ends, the value of
    /// the field's linear interpolation there.
    pub(super) fn point_field(&self, values: &[f64]) -> Vec<f64> {
        let mean = |[a, b]: [u32; 2]| 0.5 * (values[a as usize] + values[b as usize]);
        values.iter().copied().chain(self.edges.iter().map(|&e| mean(e))).collect()
    }
}

fn sorted(a: u32, b: u32) -> [u32; 2] {
    if a < b { [a, b] } else { [b, a] }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Mesh2, Mesh3};

    /// Two triangles sharing an edge: five edges, each node once, at its edge's midpoint.
    #[test]
    fn edge_nodes_are_shared_and_at_midpoints() {
        let mesh = Mesh2::new(vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
        let nodes = Nodes::new(&mesh, ElementOrder::Quadratic);
        assert_eq!((nodes.num_points(), nodes.nodes_per_element()), (9, 6));
        let points: Vec<[f64; 2]> = nodes.points().collect();
        let elements: Vec<Vec<u32>> = nodes.elements().collect();
        for cell in &elements {
            for (k, [a, b]) in EDGES[..3].iter().enumerate() {
                let (pa, pb, m) = (points[cell[*a] as usize], points[cell[*b] as usize], points[cell[3 + k] as usize]);
                assert_eq!(m, [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])]);
            }
        }
        // The diagonal 0-2 is the first triangle's edge 2-0 and the second's 0-1.
        assert_eq!(elements[0][5], elements[1][3]);
        assert_eq!(nodes.facet(&[2, 0]), vec![2, 0, elements[0][5]]);
        assert_eq!(nodes.point_field(&[1.0, 3.0, 5.0, 7.0])[4..], [2.0, 4.0, 3.0, 6.0, 4.0]);
        let linear = Nodes::new(&mesh, ElementOrder::Linear);
        assert_eq!((linear.num_points(), linear.nodes_per_element(), linear.facet(&[2, 0])), (4, 3, vec![2, 0]));
    }

    /// Two tetrahedra on a common face: 9 edges; a face's edge nodes are its elements' own.
    #[test]
    fn a_tetrahedron_has_six_edge_nodes_in_vtk_order() {
        let vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]];
        let mesh = Mesh3::new_reoriented(vertices, vec![0, 1, 2, 3, 1, 2, 3, 4]).unwrap();
        let nodes = Nodes::new(&mesh, ElementOrder::Quadratic);
        assert_eq!((nodes.num_points(), nodes.nodes_per_element()), (14, 10));
        let points: Vec<[f64; 3]> = nodes.points().collect();
        for cell in nodes.elements() {
            for (k, [a, b]) in EDGES.iter().enumerate() {
                let mid: [f64; 3] =
                    std::array::from_fn(|i| 0.5 * (points[cell[*a] as usize][i] + points[cell[*b] as usize][i]));
                assert_eq!(points[cell[4 + k] as usize], mid);
            }
            let face = nodes.facet(&cell[1..4]);
            assert_eq!(face.len(), 6);
            assert!(face[3..].iter().all(|n| cell[4..].contains(n)));
        }
    }
}
