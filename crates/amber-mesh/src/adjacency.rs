//! Facet adjacency: which element lies across each facet.

use amber_stdx::Buckets;

use crate::{Mesh, MeshError};

/// The elements around each vertex, in element order (compressed rows, built by a counting sort).
#[derive(Clone, Debug)]
pub struct VertexElements(Buckets<u32>);

impl VertexElements {
    /// The table of `cells` (`nodes_per_element` vertex indices each, all below `num_vertices`).
    pub fn new(num_vertices: usize, cells: &[u32], nodes_per_element: usize) -> Self {
        Self(Buckets::new(num_vertices, cells.len(), |k| cells[k], |k| (k / nodes_per_element) as u32))
    }

    /// The table of a mesh's elements.
    pub fn of_mesh<const D: usize>(mesh: &Mesh<D>) -> Self {
        Self::new(mesh.num_vertices(), mesh.cells(), D + 1)
    }

    /// The elements containing `vertex`, ascending.
    pub fn around(&self, vertex: usize) -> &[u32] {
        self.0.bucket(vertex)
    }
}

/// For every element and local facet (the facet opposite local vertex `i`), the neighbouring
/// element across it, or none on the boundary.
#[derive(Clone, Debug)]
pub struct FacetAdjacency {
    nodes_per_element: usize,
    /// `neighbours[e * (D + 1) + i]`: element across the facet opposite vertex `i` of `e`, or
    /// [`Self::BOUNDARY`].
    neighbours: Vec<u32>,
}

impl FacetAdjacency {
    /// Marker for a facet on the boundary.
    pub const BOUNDARY: u32 = u32::MAX;

    /// Builds the adjacency by sorting facet keys (deterministic): bucketed by their smallest
    /// vertex (a counting sort), then each vertex's few facets sorted.
    ///
    /// Fails if a facet is shared by more than two elements, or by two that lie on the same side
    /// of it (overlapping elements, such as a listed twice): a conforming mesh has neither.
    pub fn new<const D: usize>(mesh: &Mesh<D>) -> Result<Self, MeshError> {
        let n = D + 1;
        // (sorted vertices, whether sorting the outward listing took an odd permutation, slot).
        let key_of = |slot: usize| {
            let (cell, local) = (mesh.element(slot / n), outward_facets::<D>()[slot % n]);
            let mut key = [u32::MAX; 3];
            for (k, &j) in local.iter().enumerate() {
                key[k] = cell[j];
            }
            let odd = sort_parity(&mut key[..D]);
            (key, odd, slot as u32)
        };
        // A facet's smallest vertex, its key's first, needs no sort.
        let smallest = |slot: usize| {
            let cell = mesh.element(slot / n);
            outward_facets::<D>()[slot % n].iter().map(|&j| cell[j]).min().unwrap_or(0)
        };
        let mut buckets = Buckets::new(mesh.num_vertices(), mesh.cells().len(), smallest, key_of);
        for v in 0..mesh.num_vertices() {
            buckets.bucket_mut(v).sort_unstable();
        }
        let facets = buckets.items;
        let mut neighbours = vec![Self::BOUNDARY; facets.len()];
        let mut i = 0;
        while i < facets.len() {
            let mut j = i + 1;
            while j < facets.len() && facets[j].0 == facets[i].0 {
                j += 1;
            }
            match j - i {
                1 => {}
                2 => {
                    let (a, b) = (facets[i].2 as usize, facets[i + 1].2 as usize);
                    // Elements on opposite sides list their shared facet in opposite orientations.
                    if facets[i].1 == facets[i + 1].1 {
                        return Err(MeshError::OverlappingElements { elements: [a / n, b / n] });
                    }
                    neighbours[a] = (b / n) as u32;
                    neighbours[b] = (a / n) as u32;
                }
                _ => return Err(MeshError::NonManifoldFacet { facet: facets[i].0[..D].to_vec() }),
            }
            i = j;
        }
        Ok(Self { nodes_per_element: n, neighbours })
    }

    /// The element across the facet opposite local vertex `local` of `element`, if any.
    pub fn neighbour(&self, element: usize, local: usize) -> Option<usize> {
        let n = self.neighbours[element * self.nodes_per_element + local];
        (n != Self::BOUNDARY).then_some(n as usize)
    }

    /// Neighbours of `element` per local facet ([`Self::BOUNDARY`] on the boundary).
    pub fn neighbours_of(&self, element: usize) -> &[u32] {
        &self.neighbours[element * self.nodes_per_element..(element + 1) * self.nodes_per_element]
    }

    /// All `(element, local facet)` pairs on the boundary, in element order.
    pub fn boundary_facets(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.neighbours
            .iter()
            .enumerate()
            .filter(|(_, n)| **n == Self::BOUNDARY)
            .map(|(k, _)| (k / self.nodes_per_element, k % self.nodes_per_element))
    }

    /// The boundary facets as vertex lists oriented outwards (2D: edges with the domain on their
    /// left, so outer rings run counter-clockwise and holes clockwise; 3D: triangles whose
    /// right-hand normal points out of the solid), in element order. Assumes positively oriented
    /// elements, as every [`Mesh`] has.
    pub fn oriented_boundary_facets<const D: usize>(&self, mesh: &Mesh<D>) -> Vec<[u32; D]> {
        let local = outward_facets::<D>();
        self.boundary_facets()
            .map(|(e, opposite)| {
                let cell = mesh.element(e);
                std::array::from_fn(|k| cell[local[opposite][k]])
            })
            .collect()
    }

    /// Flags every vertex that lies on a boundary facet.
    pub fn boundary_vertices<const D: usize>(&self, mesh: &Mesh<D>) -> Vec<bool> {
        let mut on_boundary = vec![false; mesh.num_vertices()];
        for (e, local) in self.boundary_facets() {
            for (j, &v) in mesh.element(e).iter().enumerate() {
                if j != local {
                    on_boundary[v as usize] = true;
                }
            }
        }
        on_boundary
    }

    /// Number of interior facets (each counted once).
    pub fn num_interior_facets(&self) -> usize {
        self.neighbours.iter().filter(|&&n| n != Self::BOUNDARY).count() / 2
    }
}

/// The facet opposite each local vertex `i`, listed so that it is outward for a positive simplex.
fn outward_facets<const D: usize>() -> &'static [&'static [usize]] {
    match D {
        2 => &[&[1, 2], &[2, 0], &[0, 1]],
        3 => &[&[1, 2, 3], &[0, 3, 2], &[0, 1, 3], &[0, 2, 1]],
        _ => unreachable!("meshes are 2D or 3D"),
    }
}

/// Sorts `values` (at most 3) and says whether that took an odd permutation.
fn sort_parity(values: &mut [u32]) -> bool {
    let mut odd = false;
    for end in (1..values.len()).rev() {
        for k in 0..end {
            if values[k] > values[k + 1] {
                values.swap(k, k + 1);
                odd = !odd;
            }
        }
    }
    odd
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Mesh2, Mesh3};

    #[test]
    fn two_triangles_share_one_edge() {
        let m = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
        let adj = FacetAdjacency::new(&m).unwrap();
        // Facet opposite vertex 1 of element 0 is edge (0, 2), shared with element 1.
        assert_eq!(adj.neighbour(0, 1), Some(1));
        assert_eq!(adj.neighbour(1, 2), Some(0));
        assert_eq!(adj.boundary_facets().count(), 4);
        assert_eq!(adj.num_interior_facets(), 1);
        assert!(adj.boundary_vertices(&m).iter().all(|&b| b));
    }

    /// Outward facets enclose the mesh: the shoelace sum over the boundary edges (2D) and the
    /// divergence-theorem sum over the boundary triangles (3D) give the total volume.
    #[test]
    fn oriented_boundary_facets_enclose_the_mesh() {
        let m = Mesh2::new(vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
        let edges = FacetAdjacency::new(&m).unwrap().oriented_boundary_facets(&m);
        let v = m.vertices();
        let area: f64 = edges
            .iter()
            .map(|&[a, b]| v[a as usize][0] * v[b as usize][1] - v[b as usize][0] * v[a as usize][1])
            .sum::<f64>()
            / 2.0;
        assert_eq!((edges.len(), area), (4, 2.0));
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -2.0]];
        let m = Mesh3::new_reoriented(v, vec![0, 1, 2, 3, 0, 2, 1, 4]).unwrap();
        let faces = FacetAdjacency::new(&m).unwrap().oriented_boundary_facets(&m);
        let p = |i: u32| nalgebra::Vector3::from(m.vertices()[i as usize]);
        let volume: f64 = faces.iter().map(|&[a, b, c]| p(a).dot(&p(b).cross(&p(c))) / 6.0).sum();
        assert_eq!(faces.len(), 6);
        assert!((volume - m.total_volume()).abs() < 1e-15, "{volume} vs {}", m.total_volume());
    }

    #[test]
    fn two_tets_share_one_face() {
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
        let m = Mesh3::new_reoriented(v, vec![0, 1, 2, 3, 0, 1, 2, 4]).unwrap();
        let adj = FacetAdjacency::new(&m).unwrap();
        assert_eq!(adj.num_interior_facets(), 1);
        assert_eq!(adj.boundary_facets().count(), 6);
    }

    #[test]
    fn non_manifold_edge_is_an_error() {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0], [0.5, -1.0], [0.5, 2.0]];
        let m = Mesh2::new_reoriented(v, vec![0, 1, 2, 0, 1, 3, 0, 1, 4]).unwrap();
        assert!(matches!(FacetAdjacency::new(&m), Err(MeshError::NonManifoldFacet { .. })));
    }

    #[test]
    fn overlapping_elements_are_an_error() {
        let square = || (vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]);
        let (v, mut cells) = square();
        cells.extend([0, 1, 2]);
        let twice = Mesh2::new(v, cells).unwrap();
        assert!(matches!(FacetAdjacency::new(&twice), Err(MeshError::OverlappingElements { .. })));
        // A triangle on edge (0, 1) whose apex lies inside triangle 0 overlaps it.
        let (mut v, mut cells) = square();
        v.push([0.6, 0.3]);
        cells.extend([0, 1, 4]);
        let inside = Mesh2::new(v, cells).unwrap();
        assert!(matches!(FacetAdjacency::new(&inside), Err(MeshError::OverlappingElements { elements: [0, 2] })));
        // In 3D: a tet and its copy with two vertices swapped back to positive orientation.
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.1, 0.1, 0.5]];
        let m = Mesh3::new_reoriented(v, vec![0, 1, 2, 3, 0, 1, 2, 4]).unwrap();
        assert!(matches!(FacetAdjacency::new(&m), Err(MeshError::OverlappingElements { .. })));
    }
}
