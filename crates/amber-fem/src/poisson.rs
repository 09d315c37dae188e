//! Assembly of −Δu = f in P1 (stiffness matrix and load vector) and its sparse Cholesky solve.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;

use crate::space::{NESTED_DISSECTION_MIN_DOFS, NO_DOF, parallel_lists};
use crate::{FemError, Load, P1Space, Quadrature};

/// The upper triangle (diagonal included) of the symmetric stiffness matrix on the degrees of
/// freedom, in compressed sparse column form with sorted rows.
#[derive(Clone, Debug)]
pub struct StiffnessMatrix {
    dofs: usize,
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
    ordering: Elimination,
}

/// The order in which the Cholesky factorisation eliminates the degrees of freedom.
#[derive(Clone, Copy, Debug)]
enum Elimination {
    /// Approximate minimum degree (faer's).
    Amd,
    /// Their numbering: the space numbered them in nested-dissection order.
    AsNumbered,
}

/// The load f at every quadrature point of every element: the load vector and the error
/// estimator share it (evaluating f dominates both).
#[derive(Clone, Debug)]
pub struct LoadSamples<'q> {
    quadrature: &'q Quadrature,
    per_element: usize,
    /// f at point q of element e at `e * per_element + q`.
    values: Vec<f64>,
}

impl LoadSamples<'_> {
    /// The rule the samples belong to.
    pub fn quadrature(&self) -> &Quadrature {
        self.quadrature
    }

    /// f at the quadrature points of `element`.
    pub fn element(&self, element: usize) -> &[f64] {
        &self.values[element * self.per_element..(element + 1) * self.per_element]
    }
}

/// A solved Poisson problem.
#[derive(Clone, Debug)]
pub struct PoissonSolution {
    /// u at every vertex (0 on the boundary).
    pub u: Vec<f64>,
    /// ‖K u − F‖ / ‖F‖ over the degrees of freedom (0 when there are none or F = 0).
    pub relative_residual: f64,
}

impl<const D: usize> P1Space<'_, D> {
    /// Assembles K_ij = ∫ ∇φ_i·∇φ_j over the degrees of freedom.
    ///
    /// Columns are assembled in parallel, each from the elements around its vertex; every entry
    /// sums its elements' contributions in element order, so the matrix is the same whatever the
    /// thread count.
    pub fn stiffness(&self) -> StiffnessMatrix {
        let (col_ptr, column_entries) = parallel_lists(&self.vertex_of, |c, v, column: &mut Vec<(u32, f64)>| {
            let c = c as u32;
            let first = column.len();
            for &e in self.around.around(v as usize) {
                let cell = self.mesh.element(e as usize);
                let g = &self.geometry[e as usize];
                let a = cell.iter().position(|&w| w == v).expect("the element is around its vertex");
                for (b, &w) in cell.iter().enumerate() {
                    let row = self.dof[w as usize];
                    // Column c holds the rows r ≤ c of the upper triangle.
                    if row == NO_DOF || row > c {
                        continue;
                    }
                    let (i, j) = (a.min(b), a.max(b));
                    let k_ij = g.volume * (0..D).map(|d| g.grads[i][d] * g.grads[j][d]).sum::<f64>();
                    match column[first..].iter_mut().find(|(r, _)| *r == row) {
                        Some((_, sum)) => *sum += k_ij,
                        None => column.push((row, k_ij)),
                    }
                }
            }
            column[first..].sort_unstable_by_key(|&(row, _)| row);
        });
        let (row_idx, values) = column_entries.into_iter().unzip();
        // The space numbers large systems in nested-dissection order, which the factor keeps.
        let dofs = self.num_dofs();
        let ordering = if dofs >= NESTED_DISSECTION_MIN_DOFS { Elimination::AsNumbered } else { Elimination::Amd };
        StiffnessMatrix { dofs, col_ptr, row_idx, values, ordering }
    }

    /// Evaluates f at the points of `quadrature` in every element (the reference uses degree 2).
    pub fn sample_load<'q>(
        &self,
        load: &impl Load<D>,
        quadrature: &'q Quadrature,
    ) -> Result<LoadSamples<'q>, FemError> {
        let per_element = quadrature.iter().count();
        let mut values = vec![0.0; self.mesh.num_elements() * per_element];
        values.par_chunks_mut(per_element).enumerate().for_each(|(e, f)| {
            for (fq, (lambda, _)) in f.iter_mut().zip(quadrature.iter()) {
                *fq = load.value(self.point(e, lambda));
            }
        });
        match values.iter().position(|x| !x.is_finite()) {
            Some(k) => Err(FemError::NonFiniteLoad { element: k / per_element }),
            None => Ok(LoadSamples { quadrature, per_element, values }),
        }
    }

    /// Assembles F_i = ∫ f φ_i over the degrees of freedom.
    pub fn load_vector(&self, samples: &LoadSamples<'_>) -> Vec<f64> {
        let mut rhs = vec![0.0; self.num_dofs()];
        for (e, cell) in self.mesh.elements().enumerate() {
            for ((lambda, w), fq) in samples.quadrature.iter().zip(samples.element(e)) {
                let scaled = self.geometry[e].volume * w * fq;
                for (i, &v) in cell.iter().enumerate() {
                    let d = self.dof[v as usize];
                    if d != NO_DOF {
                        rhs[d as usize] += scaled * lambda[i];
                    }
                }
            }
        }
        rhs
    }

    /// Solves −Δu = f, u = 0 on the boundary.
    pub fn solve_poisson(&self, samples: &LoadSamples<'_>) -> Result<PoissonSolution, FemError> {
        let rhs = self.load_vector(samples);
        let stiffness = self.stiffness();
        let x = stiffness.solve(&rhs)?;
        let relative_residual = stiffness.relative_residual(&x, &rhs);
        let u = self.dof.iter().map(|&d| if d == NO_DOF { 0.0 } else { x[d as usize] }).collect();
        Ok(PoissonSolution { u, relative_residual })
    }

    /// The physical point with barycentric coordinates `lambda` in `element`.
    pub(crate) fn point(&self, element: usize, lambda: &[f64; 4]) -> [f64; D] {
        let mut x = [0.0; D];
        for (i, &v) in self.mesh.element(element).iter().enumerate() {
            let p = self.mesh.vertices()[v as usize];
            for k in 0..D {
                x[k] += lambda[i] * p[k];
            }
        }
        x
    }
}

impl StiffnessMatrix {
    /// Number of rows (degrees of freedom).
    pub fn dofs(&self) -> usize {
        self.dofs
    }

    /// Stored entries of the upper triangle.
    pub fn nnz_upper(&self) -> usize {
        self.values.len()
    }

    /// Solves K x = rhs by sparse Cholesky (faer; nested dissection or AMD ordering; sequential:
    /// callers parallelise across problems, and faer's parallel factorisation was slower here).
    pub fn solve(&self, rhs: &[f64]) -> Result<Vec<f64>, FemError> {
        let n = self.dofs;
        let mut x = rhs.to_vec();
        if n == 0 {
            return Ok(x);
        }
        let failed = |message: String| FemError::Factorisation { dofs: n, message };
        let par = Par::Seq;
        let pattern = self.pattern();
        let symbolic = self.symbolic()?;
        let mut factor = vec![0.0; symbolic.len_val()];
        let mut buffer = MemBuffer::try_new(StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]))
        .map_err(|e| failed(format!("{e:?}")))?;
        let stack = MemStack::new(&mut buffer);
        let llt = symbolic
            .factorize_numeric_llt(
                &mut factor,
                SparseColMatRef::new(pattern, &self.values),
                Side::Upper,
                LltRegularization::default(),
                par,
                stack,
                Default::default(),
            )
            .map_err(|e| failed(format!("{e:?}")))?;
        llt.solve_in_place_with_conj(Conj::No, MatMut::from_column_major_slice_mut(&mut x, n, 1), par, stack);
        Ok(x)
    }

    fn pattern(&self) -> SymbolicSparseColMatRef<'_, u32> {
        SymbolicSparseColMatRef::new_checked(self.dofs, self.dofs, &self.col_ptr, None, &self.row_idx)
    }

    /// The factor's structure (its elimination order and fill).
    fn symbolic(&self) -> Result<SymbolicCholesky<u32>, FemError> {
        let ordering = match self.ordering {
            Elimination::Amd => SymmetricOrdering::Amd,
            Elimination::AsNumbered => SymmetricOrdering::Identity,
        };
        factorize_symbolic_cholesky(self.pattern(), Side::Upper, ordering, CholeskySymbolicParams::default())
            .map_err(|e| FemError::Factorisation { dofs: self.dofs, message: format!("{e:?}") })
    }

    /// y = K x, using the symmetry of the stored upper triangle.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.dofs];
        for col in 0..self.dofs {
            for k in self.col_ptr[col] as usize..self.col_ptr[col + 1] as usize {
                let (row, a) = (self.row_idx[k] as usize, self.values[k]);
                y[row] += a * x[col];
                if row != col {
                    y[col] += a * x[row];
                }
            }
        }
        y
    }

    /// ‖K x − rhs‖ / ‖rhs‖ (0 for a zero right-hand side).
    pub fn relative_residual(&self, x: &[f64], rhs: &[f64]) -> f64 {
        let r: f64 = self.apply(x).iter().zip(rhs).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        let norm = rhs.iter().map(|b| b * b).sum::<f64>().sqrt();
        if norm > 0.0 { r / norm } else { r }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::{Mesh2, Mesh3};
    use std::f64::consts::PI;

    /// An `n × n` grid of the unit square, each cell cut along a diagonal.
    fn grid(n: usize) -> Mesh2 {
        let v = (0..=n).flat_map(|j| (0..=n).map(move |i| [i as f64 / n as f64, j as f64 / n as f64])).collect();
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let c = (0..n)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .flat_map(|(i, j)| [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)])
            .collect();
        Mesh2::new(v, c).unwrap()
    }

    /// (L2 error, H1-seminorm error) of the P1 solution for u = sin(πx) sin(πy).
    fn errors(n: usize) -> (f64, f64) {
        let exact = |p: [f64; 2]| (PI * p[0]).sin() * (PI * p[1]).sin();
        let grad =
            |p: [f64; 2]| [PI * (PI * p[0]).cos() * (PI * p[1]).sin(), PI * (PI * p[0]).sin() * (PI * p[1]).cos()];
        let f = move |p: [f64; 2]| 2.0 * PI * PI * exact(p);
        let mesh = grid(n);
        let space = P1Space::new(&mesh).unwrap();
        let q = Quadrature::simplex::<2>(2).unwrap();
        let solution = space.solve_poisson(&space.sample_load(&f, &q).unwrap()).unwrap();
        assert!(solution.relative_residual < 1e-10, "{}", solution.relative_residual);
        let fine = Quadrature::simplex::<2>(5).unwrap();
        let (mut l2, mut h1) = (0.0, 0.0);
        for (e, g) in space.geometry().iter().enumerate() {
            let local = space.local_values(&solution.u, e);
            let grad_h = g.gradient(&local);
            for (lambda, w) in fine.iter() {
                let x = space.point(e, lambda);
                let uh: f64 = (0..3).map(|i| lambda[i] * local[i]).sum();
                let du = grad(x);
                l2 += g.volume * w * (exact(x) - uh).powi(2);
                h1 += g.volume * w * ((du[0] - grad_h[0]).powi(2) + (du[1] - grad_h[1]).powi(2));
            }
        }
        (l2.sqrt(), h1.sqrt())
    }

    #[test]
    fn manufactured_solution_converges_at_the_optimal_rates() {
        let levels: Vec<(f64, f64)> = [8, 16, 32, 64].into_iter().map(errors).collect();
        for pair in levels.windows(2) {
            let (l2_rate, h1_rate) = ((pair[0].0 / pair[1].0).log2(), (pair[0].1 / pair[1].1).log2());
            assert!((l2_rate - 2.0).abs() < 0.15, "L2 rate {l2_rate}");
            assert!((h1_rate - 1.0).abs() < 0.1, "H1 rate {h1_rate}");
        }
    }

    #[test]
    fn stiffness_matches_the_five_point_stencil_on_a_grid() {
        // On this criss-cross-free grid, P1 gives the 5-point Laplacian: 4 on the diagonal.
        let mesh = grid(4);
        let space = P1Space::new(&mesh).unwrap();
        let k = space.stiffness();
        assert_eq!(k.dofs(), 9);
        let ones = k.apply(&[1.0; 9]);
        // Row sums: 4 − (number of interior neighbours).
        assert_eq!(ones, vec![2.0, 1.0, 2.0, 1.0, 0.0, 1.0, 2.0, 1.0, 2.0]);
    }

    #[test]
    fn entries_sum_their_elements_in_element_order() {
        // The same sums, bit for bit, as adding each element's entries in element order.
        let mut mesh = grid(9);
        let jiggle = |p: [f64; 2]| [p[0] + 0.013 * (7.0 * p[1]).sin(), p[1] + 0.011 * (5.0 * p[0]).cos()];
        mesh = Mesh2::new(mesh.vertices().iter().map(|&p| jiggle(p)).collect(), mesh.cells().to_vec()).unwrap();
        let space = P1Space::new(&mesh).unwrap();
        let mut expected = std::collections::BTreeMap::new();
        for (e, cell) in mesh.elements().enumerate() {
            let g = &space.geometry()[e];
            for i in 0..3 {
                for j in i..3 {
                    let (a, b) = (space.dof[cell[i] as usize], space.dof[cell[j] as usize]);
                    if a != NO_DOF && b != NO_DOF {
                        let value = g.volume * (0..2).map(|d| g.grads[i][d] * g.grads[j][d]).sum::<f64>();
                        *expected.entry((a.max(b), a.min(b))).or_insert(-0.0) += value;
                    }
                }
            }
        }
        let k = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(|| space.stiffness());
        let mut got = Vec::new();
        for col in 0..k.dofs() {
            for at in k.col_ptr[col] as usize..k.col_ptr[col + 1] as usize {
                got.push(((col as u32, k.row_idx[at]), k.values[at].to_bits()));
            }
        }
        let expected: Vec<_> = expected.into_iter().map(|(key, v)| (key, v.to_bits())).collect();
        assert_eq!(got, expected);
    }

    #[test]
    fn large_systems_solve_in_nested_dissection_order() {
        let mesh = grid(320);
        let space = P1Space::new(&mesh).unwrap();
        let q = Quadrature::simplex::<2>(2).unwrap();
        let rhs = space.load_vector(&space.sample_load(&|p: [f64; 2]| 1.0 + p[0] * p[1], &q).unwrap());
        let k = space.stiffness();
        assert!(k.dofs() >= NESTED_DISSECTION_MIN_DOFS && matches!(k.ordering, Elimination::AsNumbered));
        let x = k.solve(&rhs).unwrap();
        assert!(k.relative_residual(&x, &rhs) < 1e-10);
        let amd_ordered = StiffnessMatrix { ordering: Elimination::Amd, ..k.clone() };
        // The nested-dissection numbering leaves less fill than AMD at this size.
        let (fill, amd_fill) = (k.symbolic().unwrap().len_val(), amd_ordered.symbolic().unwrap().len_val());
        assert!(fill < amd_fill, "{fill} entries in the factor against AMD's {amd_fill}");
        let amd = amd_ordered.solve(&rhs).unwrap();
        let scale = amd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let gap = x.iter().zip(&amd).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(gap < 1e-10 * scale, "{gap} against {scale}");
    }

    #[test]
    fn tetrahedral_assembly_is_consistent() {
        // A cube split into 12 tets, two per face, all sharing its centre: one interior dof.
        let mut v: Vec<[f64; 3]> =
            (0..8).map(|k| [(k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64]).collect();
        v.push([0.5, 0.5, 0.5]);
        let faces = [[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4], [2, 3, 7, 6], [0, 2, 6, 4], [1, 3, 7, 5]];
        let cells: Vec<u32> = faces.iter().flat_map(|f| [f[0], f[1], f[2], 8, f[0], f[2], f[3], 8]).collect();
        let mesh = Mesh3::new_reoriented(v, cells).unwrap();
        let space = P1Space::new(&mesh).unwrap();
        assert_eq!(space.num_dofs(), 1);
        // ∫ φ_centre = (1/4)·Σ|K| = 1/4 for f = 1; the quadrature of degree 2 is exact.
        let one = |_: [f64; 3]| 1.0;
        let q2 = Quadrature::simplex::<3>(2).unwrap();
        let rhs = space.load_vector(&space.sample_load(&one, &q2).unwrap());
        assert!((rhs[0] - 0.25).abs() < 1e-15);
        let q1 = Quadrature::simplex::<3>(1).unwrap();
        let solution = space.solve_poisson(&space.sample_load(&one, &q1).unwrap()).unwrap();
        assert!(solution.u[8] > 0.0 && solution.relative_residual < 1e-14);
    }

    #[test]
    fn meshes_without_interior_vertices_give_zero() {
        let mesh = grid(1);
        let space = P1Space::new(&mesh).unwrap();
        let q = Quadrature::simplex::<2>(2).unwrap();
        let solution = space.solve_poisson(&space.sample_load(&|_: [f64; 2]| 1.0, &q).unwrap()).unwrap();
        assert_eq!(solution.u, vec![0.0; 4]);
    }
}
