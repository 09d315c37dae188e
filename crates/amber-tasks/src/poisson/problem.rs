//! The Poisson task as a [`Problem<2>`]: each mesh's columns come from the P1 solution of
//! −Δu = f on it, and every new mesh is made by the 2D generator on the problem's L-shape.

use amber_fem::{ExpertHeuristic, Load, P1Space, Quadrature, element_stats};
use amber_graph::FeatureSet;
use amber_mesh::Mesh;
use amber_meshgen::{Mesh2dParams, MeshSizing, PolygonDomain, generate_2d};

use super::PoissonProblem;
use crate::problem::{Column, Problem, ProblemError};

/// Name of the optional input ln η_K: the residual error indicator of the current solution, the
/// quantity the expert's refinement loop marks by. An adaptive solver computes it anyway; the
/// network still has to learn where 75 marking rounds end up from one estimate. Not in the paper.
pub const LOG_ERROR_INDICATOR_COLUMN: &str = "log_error_indicator";

/// Name of the optional input sign(f)·ln(1 + |f|) of the load f: the load has peaks of 10²–10³
/// over a background near 0, so after linear normalisation every element off a peak looks alike,
/// yet the expert refines well into the flanks. Not in the paper.
pub const LOG_LOAD_COLUMN: &str = "log_load";

impl Problem<2> for PoissonProblem {
    fn feature_set(&self) -> FeatureSet {
        FeatureSet::poisson()
    }

    fn optional_inputs(&self) -> &'static [&'static str] {
        &[LOG_ERROR_INDICATOR_COLUMN, LOG_LOAD_COLUMN]
    }

    fn initial_mesh(&self) -> &Mesh<2> {
        &self.initial_mesh
    }

    fn expert_mesh(&self) -> &Mesh<2> {
        &self.expert_mesh
    }

    /// Solves −Δu = f (P1) on `mesh`: `solution_mean`, `solution_std` of u over each element's
    /// vertices, `load` = f at the element midpoint, and the optional inputs ln η_K and the
    /// log-scaled load.
    fn columns(&self, mesh: &Mesh<2>) -> Result<Vec<Column>, ProblemError> {
        let order = self
            .metadata
            .heuristic
            .as_ref()
            .map_or(ExpertHeuristic::default().quadrature_order, |h| h.quadrature_order);
        let space = P1Space::new(mesh)?;
        let quadrature = Quadrature::simplex::<2>(order)?;
        let samples = space.sample_load(&self.load, &quadrature)?;
        let solution = space.solve_poisson(&samples)?;
        let stats = element_stats(mesh, &solution.u)?;
        let indicator = space.residual_estimator(&solution.u, &samples)?;
        let load: Vec<f64> = mesh.midpoints().into_iter().map(|x| Load::value(&self.load, x)).collect();
        let log_load = load.iter().map(|f| f.signum() * f.abs().ln_1p()).collect();
        Ok(vec![
            Column { name: "solution_mean".into(), values: stats.iter().map(|s| s.mean).collect() },
            Column { name: "solution_std".into(), values: stats.iter().map(|s| s.std).collect() },
            Column { name: "load".into(), values: load },
            Column {
                name: LOG_ERROR_INDICATOR_COLUMN.into(),
                values: indicator.iter().map(|eta| eta.max(f64::MIN_POSITIVE).ln()).collect(),
            },
            Column { name: LOG_LOAD_COLUMN.into(), values: log_load },
        ])
    }

    fn remesh(&self, mesh: &Mesh<2>, sizes: Vec<f64>, max_elements: usize) -> Result<Mesh<2>, ProblemError> {
        let domain = PolygonDomain::lshape(self.corner)?;
        let params = Mesh2dParams::default().with_max_elements(max_elements);
        Ok(generate_2d(&domain, &MeshSizing::new(mesh, sizes), &params)?)
    }
}
