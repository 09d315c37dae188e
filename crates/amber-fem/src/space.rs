//! The P1 Lagrange space on a simplicial mesh with homogeneous Dirichlet conditions on the whole
//! boundary: element geometry, degrees of freedom, and per-element statistics of a solution.

use amber_mesh::{FacetAdjacency, Mesh, VertexElements};
use rayon::prelude::*;

use crate::FemError;
use crate::ordering::nested_dissection;

/// Geometry of one simplex: its volume and the gradients of its barycentric coordinates (the P1
/// shape functions), `grads[i]` for local vertex `i ≤ D`.
#[derive(Clone, Copy, Debug)]
pub struct ElementGeometry<const D: usize> {
    /// |K|.
    pub volume: f64,
    /// ∇λ_i, constant on the element.
    pub grads: [[f64; D]; 4],
}

impl<const D: usize> ElementGeometry<D> {
    fn new(mesh: &Mesh<D>, element: usize) -> Self {
        let p0 = mesh.corner(element, 0);
        let e: [[f64; D]; 3] = std::array::from_fn(|i| {
            if i < D { std::array::from_fn(|k| mesh.corner(element, i + 1)[k] - p0[k]) } else { [0.0; D] }
        });
        // Rows of J⁻¹ (J has the edge vectors e_i as columns) are ∇λ_1..∇λ_D: rows of the
        // cofactor matrix divided by det J.
        let mut grads = [[0.0; D]; 4];
        let det = match D {
            2 => {
                let det = e[0][0] * e[1][1] - e[0][1] * e[1][0];
                grads[1][0] = e[1][1] / det;
                grads[1][1] = -e[1][0] / det;
                grads[2][0] = -e[0][1] / det;
                grads[2][1] = e[0][0] / det;
                det
            }
            3 => {
                let cross = |a: [f64; D], b: [f64; D]| {
                    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
                };
                let det = (0..3).map(|k| e[0][k] * cross(e[1], e[2])[k]).sum::<f64>();
                for (i, (a, b)) in [(1, 2), (2, 0), (0, 1)].into_iter().enumerate() {
                    let c = cross(e[a], e[b]);
                    for k in 0..D {
                        grads[i + 1][k] = c[k] / det;
                    }
                }
                det
            }
            _ => unreachable!("meshes are 2D or 3D"),
        };
        grads[0] = std::array::from_fn(|k| -(1..=D).map(|i| grads[i][k]).sum::<f64>());
        let factorial = if D == 2 { 2.0 } else { 6.0 };
        Self { volume: det / factorial, grads }
    }

    /// Gradient of the P1 function with vertex values `values` (local order).
    pub fn gradient(&self, values: &[f64]) -> [f64; D] {
        std::array::from_fn(|k| (0..=D).map(|i| values[i] * self.grads[i][k]).sum())
    }
}

/// Marker for a vertex without a degree of freedom (on the Dirichlet boundary).
pub(crate) const NO_DOF: u32 = u32::MAX;

/// From this many degrees of freedom on, they are numbered in nested-dissection order, which
/// leaves less fill than AMD on mesh graphs and costs less to compute (docs/PROFILES.md).
pub(crate) const NESTED_DISSECTION_MIN_DOFS: usize = 100_000;

/// Vertices (or columns) handled by one parallel task.
const VERTICES_PER_TASK: usize = 4096;

/// P1 Lagrange elements on `mesh` with u = 0 on the whole boundary.
pub struct P1Space<'m, const D: usize> {
    pub(crate) mesh: &'m Mesh<D>,
    pub(crate) adjacency: FacetAdjacency,
    pub(crate) geometry: Vec<ElementGeometry<D>>,
    /// Degree of freedom of each vertex, or [`NO_DOF`] on the boundary.
    pub(crate) dof: Vec<u32>,
    /// The vertex of each degree of freedom.
    pub(crate) vertex_of: Vec<u32>,
    /// The elements around each vertex.
    pub(crate) around: VertexElements,
}

impl<'m, const D: usize> P1Space<'m, D> {
    /// Builds the space: adjacency (fails on a non-conforming mesh), element geometry, and one
    /// degree of freedom per interior vertex, numbered in vertex order, or in nested-dissection
    /// order from [`NESTED_DISSECTION_MIN_DOFS`] on (the sparse factorisation keeps it).
    pub fn new(mesh: &'m Mesh<D>) -> Result<Self, FemError> {
        let adjacency = FacetAdjacency::new(mesh)?;
        let boundary = adjacency.boundary_vertices(mesh);
        let around = VertexElements::of_mesh(mesh);
        let mut vertex_of: Vec<u32> = (0..mesh.num_vertices() as u32).filter(|&v| !boundary[v as usize]).collect();
        let mut dof = vec![NO_DOF; mesh.num_vertices()];
        for (d, &v) in vertex_of.iter().enumerate() {
            dof[v as usize] = d as u32;
        }
        if vertex_of.len() >= NESTED_DISSECTION_MIN_DOFS {
            let (neighbours_start, neighbours) = parallel_lists(&vertex_of, |_, v, out| {
                let first = out.len();
                for &e in around.around(v as usize) {
                    for &w in mesh.element(e as usize) {
                        let d = dof[w as usize];
                        if w != v && d != NO_DOF && !out[first..].contains(&d) {
                            out.push(d);
                        }
                    }
                }
            });
            let points: Vec<[f64; D]> = vertex_of.iter().map(|&v| mesh.vertices()[v as usize]).collect();
            let order = nested_dissection(&points, &neighbours_start, &neighbours);
            vertex_of = order.iter().map(|&d| vertex_of[d as usize]).collect();
            for (d, &v) in vertex_of.iter().enumerate() {
                dof[v as usize] = d as u32;
            }
        }
        let geometry = (0..mesh.num_elements()).into_par_iter().map(|e| ElementGeometry::new(mesh, e)).collect();
        Ok(Self { mesh, adjacency, geometry, dof, vertex_of, around })
    }

    /// The mesh.
    pub fn mesh(&self) -> &'m Mesh<D> {
        self.mesh
    }

    /// Facet adjacency of the mesh.
    pub fn adjacency(&self) -> &FacetAdjacency {
        &self.adjacency
    }

    /// Geometry of every element.
    pub fn geometry(&self) -> &[ElementGeometry<D>] {
        &self.geometry
    }

    /// Number of degrees of freedom (interior vertices).
    pub fn num_dofs(&self) -> usize {
        self.vertex_of.len()
    }

    /// The vertex values of `u` on `element`, in local order.
    pub(crate) fn local_values(&self, u: &[f64], element: usize) -> [f64; 4] {
        let mut local = [0.0; 4];
        for (i, &v) in self.mesh.element(element).iter().enumerate() {
            local[i] = u[v as usize];
        }
        local
    }

    pub(crate) fn check_solution(&self, u: &[f64]) -> Result<(), FemError> {
        if u.len() == self.mesh.num_vertices() {
            Ok(())
        } else {
            Err(FemError::SolutionLength { len: u.len(), num_vertices: self.mesh.num_vertices() })
        }
    }
}

/// Compressed lists, one per item, built in parallel: `list(i, item, out)` appends item i's
/// entries to `out` (which holds earlier items' entries before them). Returns (start, entries), list i at `entries[start[i]..start[i + 1]]`.
pub(crate) fn parallel_lists<T: Send>(
    items: &[u32],
    list: impl Fn(usize, u32, &mut Vec<T>) + Sync,
) -> (Vec<u32>, Vec<T>) {
    let chunks: Vec<(Vec<u32>, Vec<T>)> = items
        .par_chunks(VERTICES_PER_TASK)
        .enumerate()
        .map(|(chunk, items)| {
            let (mut lengths, mut entries) = (Vec::with_capacity(items.len()), Vec::new());
            for (k, &item) in items.iter().enumerate() {
                let before = entries.len();
                list(chunk * VERTICES_PER_TASK + k, item, &mut entries);
                lengths.push((entries.len() - before) as u32);
            }
            (lengths, entries)
        })
        .collect();
    let mut start = Vec::with_capacity(items.len() + 1);
    start.push(0u32);
    let mut all = Vec::with_capacity(chunks.iter().map(|(_, e)| e.len()).sum());
    for (lengths, entries) in chunks {
        for length in lengths {
            start.push(start.last().copied().unwrap_or(0) + length);
        }
        all.extend(entries);
    }
    (start, all)
}

/// Mean and population standard deviation of a vertex function over one element's vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementStats {
    /// Mean of the vertex values.
    pub mean: f64,
    /// Population standard deviation of the vertex values.
    pub std: f64,
}

/// Per-element [`ElementStats`] of the vertex values `u` (features of spec §4).
pub fn element_stats<const D: usize>(mesh: &Mesh<D>, u: &[f64]) -> Result<Vec<ElementStats>, FemError> {
    if u.len() != mesh.num_vertices() {
        return Err(FemError::SolutionLength { len: u.len(), num_vertices: mesh.num_vertices() });
    }
    let n = (D + 1) as f64;
    Ok(mesh
        .elements()
        .map(|cell| {
            let mean = cell.iter().map(|&v| u[v as usize]).sum::<f64>() / n;
            let var = cell.iter().map(|&v| (u[v as usize] - mean).powi(2)).sum::<f64>() / n;
            ElementStats { mean, std: var.sqrt() }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::{Mesh2, Mesh3};

    #[test]
    fn barycentric_gradients_reproduce_linear_functions() {
        let m2 = Mesh2::new(vec![[0.1, 0.2], [1.3, 0.1], [0.4, 0.9]], vec![0, 1, 2]).unwrap();
        let g = ElementGeometry::new(&m2, 0);
        assert!((g.volume - m2.volume(0)).abs() < 1e-15);
        let lin = |p: [f64; 2]| 2.0 * p[0] - 3.0 * p[1];
        let vals: Vec<f64> = (0..3).map(|i| lin(m2.corner(0, i))).collect();
        let grad = g.gradient(&vals);
        assert!((grad[0] - 2.0).abs() < 1e-13 && (grad[1] + 3.0).abs() < 1e-13);

        let m3 = Mesh3::new_reoriented(
            vec![[0.0, 0.0, 0.0], [1.0, 0.1, 0.0], [0.2, 1.0, 0.1], [0.1, 0.3, 1.2]],
            vec![0, 1, 2, 3],
        )
        .unwrap();
        let g = ElementGeometry::new(&m3, 0);
        assert!((g.volume - m3.volume(0)).abs() < 1e-15);
        let lin = |p: [f64; 3]| p[0] + 2.0 * p[1] - p[2];
        let vals: Vec<f64> = (0..4).map(|i| lin(m3.corner(0, i))).collect();
        let grad = g.gradient(&vals);
        for (k, want) in [1.0, 2.0, -1.0].into_iter().enumerate() {
            assert!((grad[k] - want).abs() < 1e-13);
        }
    }

    #[test]
    fn stats_are_population_moments() {
        let m = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap();
        let s = element_stats(&m, &[0.0, 3.0, 6.0]).unwrap();
        assert_eq!(s[0].mean, 3.0);
        assert!((s[0].std - 6f64.sqrt()).abs() < 1e-15);
        assert!(matches!(element_stats(&m, &[0.0]), Err(FemError::SolutionLength { len: 1, .. })));
    }
}
