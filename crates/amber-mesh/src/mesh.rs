//! The simplicial mesh type and its per-element geometry.

use nalgebra::{SVector, Vector3};

use crate::MeshError;

/// A conforming simplicial mesh in `D` dimensions (`D` = 2: triangles, `D` = 3: tetrahedra).
///
/// Invariant: every element references `D + 1` distinct existing vertices and has strictly
/// positive signed volume (positive orientation). The only ways in are [`Mesh::new`] and
/// [`Mesh::new_reoriented`], which check it.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh<const D: usize> {
    vertices: Vec<[f64; D]>,
    /// `D + 1` vertex indices per element, flat.
    cells: Vec<u32>,
}

/// A triangle mesh.
pub type Mesh2 = Mesh<2>;
/// A tetrahedral mesh.
pub type Mesh3 = Mesh<3>;

impl<const D: usize> Mesh<D> {
    /// Vertices per element.
    pub const NODES_PER_ELEMENT: usize = D + 1;

    /// Builds a mesh, checking that every element is valid and positively oriented.
    pub fn new(vertices: Vec<[f64; D]>, cells: Vec<u32>) -> Result<Self, MeshError> {
        Self::build(vertices, cells, false)
    }

    /// Builds a mesh, flipping negatively oriented elements (files from other tools may list
    /// triangles clockwise). Degenerate (zero-volume) elements are still an error.
    pub fn new_reoriented(vertices: Vec<[f64; D]>, cells: Vec<u32>) -> Result<Self, MeshError> {
        Self::build(vertices, cells, true)
    }

    fn build(vertices: Vec<[f64; D]>, mut cells: Vec<u32>, reorient: bool) -> Result<Self, MeshError> {
        const { assert!(D == 2 || D == 3, "meshes are 2D or 3D") };
        let n = D + 1;
        if cells.is_empty() {
            return Err(MeshError::Empty);
        }
        if !cells.len().is_multiple_of(n) {
            return Err(MeshError::Connectivity { len: cells.len(), nodes_per_element: n });
        }
        if let Some(vertex) = vertices.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(MeshError::NonFiniteVertex { vertex });
        }
        let num_vertices = vertices.len();
        for (element, cell) in cells.chunks_exact_mut(n).enumerate() {
            if let Some(&vertex) = cell.iter().find(|&&v| v as usize >= num_vertices) {
                return Err(MeshError::VertexOutOfRange { element, vertex, num_vertices });
            }
            let volume = signed_volume::<D>(&vertices, cell);
            if volume < 0.0 && reorient {
                cell.swap(D - 1, D);
            } else if volume.is_nan() || volume <= 0.0 {
                return Err(MeshError::NonPositiveElement { element, volume });
            }
        }
        Ok(Self { vertices, cells })
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of elements.
    pub fn num_elements(&self) -> usize {
        self.cells.len() / (D + 1)
    }

    /// Vertex coordinates.
    pub fn vertices(&self) -> &[[f64; D]] {
        &self.vertices
    }

    /// Flat connectivity, `D + 1` vertex indices per element.
    pub fn cells(&self) -> &[u32] {
        &self.cells
    }

    /// The vertex indices of one element.
    pub fn element(&self, element: usize) -> &[u32] {
        &self.cells[element * (D + 1)..(element + 1) * (D + 1)]
    }

    /// Iterates over the vertex indices of every element.
    pub fn elements(&self) -> std::slice::ChunksExact<'_, u32> {
        self.cells.chunks_exact(D + 1)
    }

    /// Position of the `corner`-th vertex of `element`.
    pub fn corner(&self, element: usize, corner: usize) -> [f64; D] {
        self.vertices[self.cells[element * (D + 1) + corner] as usize]
    }

    /// Volume (area in 2D) of one element.
    pub fn volume(&self, element: usize) -> f64 {
        signed_volume::<D>(&self.vertices, self.element(element))
    }

    /// Volumes of all elements.
    pub fn volumes(&self) -> Vec<f64> {
        self.elements().map(|cell| signed_volume::<D>(&self.vertices, cell)).collect()
    }

    /// Vertex centroid ("midpoint") of one element.
    pub fn midpoint(&self, element: usize) -> [f64; D] {
        centroid::<D>(&self.vertices, self.element(element))
    }

    /// Midpoints of all elements.
    pub fn midpoints(&self) -> Vec<[f64; D]> {
        self.elements().map(|cell| centroid::<D>(&self.vertices, cell)).collect()
    }

    /// Element size h(K): edge length of the regular simplex of equal volume (spec §0).
    pub fn size(&self, element: usize) -> f64 {
        size_from_volume::<D>(self.volume(element))
    }

    /// Sizes of all elements.
    pub fn sizes(&self) -> Vec<f64> {
        self.elements().map(|cell| size_from_volume::<D>(signed_volume::<D>(&self.vertices, cell))).collect()
    }

    /// Sum of all element volumes.
    pub fn total_volume(&self) -> f64 {
        self.elements().map(|cell| signed_volume::<D>(&self.vertices, cell)).sum()
    }

    /// Axis-aligned bounding box `(min, max)` of the vertices; `None` for an empty mesh.
    pub fn bounding_box(&self) -> Option<([f64; D], [f64; D])> {
        bounding_box(&self.vertices)
    }

    /// Minimum interior angle of each triangle in degrees (2D), or minimum dihedral angle of
    /// each tetrahedron in degrees (3D).
    pub fn min_angles(&self) -> Vec<f64> {
        (0..self.num_elements())
            .map(|e| {
                let p: Vec<[f64; D]> = self.element(e).iter().map(|&v| self.vertices[v as usize]).collect();
                if D == 2 { min_triangle_angle(&p) } else { min_dihedral_angle(&p) }
            })
            .collect()
    }
}

/// Axis-aligned bounding box `(min, max)` of `points`; `None` when there are none.
pub fn bounding_box<const D: usize>(points: &[[f64; D]]) -> Option<([f64; D], [f64; D])> {
    let first = *points.first()?;
    Some(points.iter().fold((first, first), |(mut lo, mut hi), p| {
        for k in 0..D {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
        (lo, hi)
    }))
}

/// Signed volume of the simplex formed by `cell` (positive for positive orientation).
pub fn signed_volume<const D: usize>(vertices: &[[f64; D]], cell: &[u32]) -> f64 {
    let a = vertices[cell[0] as usize];
    let d = |i: usize, k: usize| vertices[cell[i] as usize][k] - a[k];
    match D {
        2 => 0.5 * (d(1, 0) * d(2, 1) - d(1, 1) * d(2, 0)),
        3 => {
            let det = d(1, 0) * (d(2, 1) * d(3, 2) - d(2, 2) * d(3, 1))
                - d(1, 1) * (d(2, 0) * d(3, 2) - d(2, 2) * d(3, 0))
                + d(1, 2) * (d(2, 0) * d(3, 1) - d(2, 1) * d(3, 0));
            det / 6.0
        }
        _ => unreachable!("meshes are 2D or 3D"),
    }
}

/// Vertex centroid of `cell`.
pub fn centroid<const D: usize>(vertices: &[[f64; D]], cell: &[u32]) -> [f64; D] {
    let mut c = [0.0; D];
    for &v in cell {
        for k in 0..D {
            c[k] += vertices[v as usize][k];
        }
    }
    c.map(|x| x / cell.len() as f64)
}

/// Edge length of the regular simplex with the given volume: 2D √(4V/√3), 3D (6√2·V)^(1/3).
pub fn size_from_volume<const D: usize>(volume: f64) -> f64 {
    match D {
        2 => (4.0 * volume / 3f64.sqrt()).sqrt(),
        3 => (6.0 * 2f64.sqrt() * volume).cbrt(),
        _ => unreachable!("meshes are 2D or 3D"),
    }
}

/// Volume of the regular simplex with edge length `size`: 2D h²√3/4, 3D h³√2/12.
pub fn volume_from_size<const D: usize>(size: f64) -> f64 {
    match D {
        2 => size * size * 3f64.sqrt() / 4.0,
        3 => size * size * size * 2f64.sqrt() / 12.0,
        _ => unreachable!("meshes are 2D or 3D"),
    }
}

fn angle_between<const D: usize>(a: SVector<f64, D>, b: SVector<f64, D>) -> f64 {
    let c = a.dot(&b) / (a.dot(&a) * b.dot(&b)).sqrt();
    c.clamp(-1.0, 1.0).acos().to_degrees()
}

fn min_triangle_angle<const D: usize>(p: &[[f64; D]]) -> f64 {
    let v = |i: usize| SVector::<f64, D>::from(p[i % 3]);
    (0..3).map(|i| angle_between(v(i + 1) - v(i), v(i + 2) - v(i))).fold(f64::INFINITY, f64::min)
}

fn min_dihedral_angle<const D: usize>(p: &[[f64; D]]) -> f64 {
    let v = |i: usize| Vector3::new(p[i][0], p[i][1], p[i][2]);
    let mut min = f64::INFINITY;
    // The dihedral angle at edge (i, j) equals the angle between e×(p_k−p_i) and e×(p_l−p_i).
    for (i, j, k, l) in [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2), (1, 2, 0, 3), (1, 3, 0, 2), (2, 3, 0, 1)] {
        let e = v(j) - v(i);
        let nk = e.cross(&(v(k) - v(i)));
        let nl = e.cross(&(v(l) - v(i)));
        min = min.min(angle_between(nk, nl));
    }
    min
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_square() -> Mesh2 {
        Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap()
    }

    #[test]
    fn square_geometry() {
        let m = unit_square();
        assert_eq!(m.num_elements(), 2);
        assert!((m.total_volume() - 1.0).abs() < 1e-15);
        let mid = m.midpoint(0);
        assert!((mid[0] - 2.0 / 3.0).abs() < 1e-15 && (mid[1] - 1.0 / 3.0).abs() < 1e-15);
        assert!((m.min_angles()[0] - 45.0).abs() < 1e-9);
    }

    #[test]
    fn size_and_volume_are_inverse_and_exact_for_regular_simplices() {
        let eq = Mesh2::new(vec![[0.0, 0.0], [2.0, 0.0], [1.0, 3f64.sqrt()]], vec![0, 1, 2]).unwrap();
        assert!((eq.size(0) - 2.0).abs() < 1e-12);
        let s = 2f64.sqrt();
        let tet = Mesh3::new(vec![[0.0, 0.0, 0.0], [s, s, 0.0], [s, 0.0, s], [0.0, s, s]], vec![0, 2, 1, 3]).unwrap();
        assert!((tet.size(0) - 2.0).abs() < 1e-12);
        assert!((tet.min_angles()[0] - 70.528_779_365_509_3).abs() < 1e-9);
        for h in [0.01, 0.5, 3.0] {
            assert!((size_from_volume::<2>(volume_from_size::<2>(h)) - h).abs() < 1e-12 * h);
            assert!((size_from_volume::<3>(volume_from_size::<3>(h)) - h).abs() < 1e-12 * h);
        }
    }

    #[test]
    fn clockwise_triangles_are_rejected_or_reoriented() {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(matches!(Mesh2::new(v.clone(), vec![0, 2, 1]), Err(MeshError::NonPositiveElement { element: 0, .. })));
        let m = Mesh2::new_reoriented(v, vec![0, 2, 1]).unwrap();
        assert!(m.volume(0) > 0.0);
    }

    #[test]
    fn bad_connectivity_is_an_error() {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(matches!(Mesh2::new(v.clone(), vec![0, 1]), Err(MeshError::Connectivity { .. })));
        assert!(matches!(Mesh2::new(v.clone(), vec![0, 1, 7]), Err(MeshError::VertexOutOfRange { vertex: 7, .. })));
        assert!(matches!(Mesh2::new(v, vec![0, 1, 1]), Err(MeshError::NonPositiveElement { .. })));
        let nan = vec![[f64::NAN, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(matches!(Mesh2::new(nan, vec![0, 1, 2]), Err(MeshError::NonFiniteVertex { vertex: 0 })));
        assert!(matches!(Mesh2::new(vec![[0.0, 0.0]], vec![]), Err(MeshError::Empty)));
        assert!(matches!(Mesh3::new(Vec::new(), Vec::new()), Err(MeshError::Empty)));
    }
}
