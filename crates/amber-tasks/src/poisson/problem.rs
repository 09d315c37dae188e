//! The Poisson task as a [`Problem<2>`]: each mesh's columns come from the P1 solution of
//! −Δu = f on it, and every new mesh is made by the 2D generator on the problem's L-shape. A
//! [`PoissonPart`] is the same task on any polygon with holes and without an expert: what a
//! trained Poisson model meshes.

use std::collections::BTreeMap;

use amber_fem::{ExpertHeuristic, GaussianMixture, Load, P1Space, Quadrature, element_stats};
use amber_graph::FeatureSet;
use amber_mesh::{Mesh, Mesh2};
use amber_meshgen::{
    Mesh2dParams, MeshSizing, MeshgenError, PolygonDistance, PolygonDomain, generate_2d, uniform_mesh_2d,
};

use super::{INITIAL_SIZE, PoissonProblem};
use crate::part::{GEOMETRY_INPUTS, PlanarGeometry, polygon_side_tags};
use crate::problem::{Column, Domain, Problem, ProblemError};

/// Name of the optional input ln η_K: the residual error indicator of the current solution, the
/// quantity the expert's refinement loop marks by. An adaptive solver computes it anyway; the
/// network still has to learn where 75 marking rounds end up from one estimate. Not in the paper.
pub const LOG_ERROR_INDICATOR_COLUMN: &str = "log_error_indicator";

/// Name of the optional input sign(f)·ln(1 + |f|) of the load f: the load has peaks of 10²–10³
/// over a background near 0, so after linear normalisation every element off a peak looks alike,
/// yet the expert refines well into the flanks. Not in the paper.
pub const LOG_LOAD_COLUMN: &str = "log_load";

/// The optional inputs of the Poisson task: its own, and the geometry's that every polygon has
/// (the distance to the re-entrant corner and the boundary's turn there among them).
fn optional_inputs() -> Vec<String> {
    [LOG_ERROR_INDICATOR_COLUMN, LOG_LOAD_COLUMN]
        .iter()
        .chain(&GEOMETRY_INPUTS)
        .map(|name| (*name).to_owned())
        .collect()
}

impl PoissonProblem {
    /// The quadrature order of the expert's solver (the default heuristic's when unknown).
    fn quadrature_order(&self) -> usize {
        self.metadata.heuristic.as_ref().map_or(ExpertHeuristic::default().quadrature_order, |h| h.quadrature_order)
    }
}

impl Domain<2> for PoissonProblem {
    fn feature_set(&self) -> FeatureSet {
        FeatureSet::poisson()
    }

    fn optional_inputs(&self) -> Vec<String> {
        optional_inputs()
    }

    fn initial_mesh(&self) -> &Mesh<2> {
        &self.initial_mesh
    }

    fn columns(&self, mesh: &Mesh<2>) -> Result<Vec<Column>, ProblemError> {
        poisson_columns(&PolygonDomain::lshape(self.corner)?, &self.load, self.quadrature_order(), mesh)
    }

    fn remesh(&self, mesh: &Mesh<2>, sizes: Vec<f64>, max_elements: usize) -> Result<Mesh<2>, ProblemError> {
        remesh_polygon(&PolygonDomain::lshape(self.corner)?, mesh, sizes, max_elements)
    }
}

impl Problem<2> for PoissonProblem {
    fn expert_mesh(&self) -> &Mesh<2> {
        &self.expert_mesh
    }

    fn name(&self) -> String {
        self.metadata.seed.map_or_else(|| "a problem without a seed".into(), |seed| format!("seed {seed}"))
    }
}

/// The Poisson task on any polygon with holes, without an expert: −Δu = f with u = 0 on the
/// whole boundary, the inputs a trained Poisson model reads, and M⁰.
#[derive(Clone, Debug)]
pub struct PoissonPart {
    pub domain: PolygonDomain,
    pub load: GaussianMixture,
    /// Quadrature order of the load integrals (the expert heuristic's).
    pub quadrature_order: usize,
    /// M⁰: the given initial mesh, or a uniform mesh of size [`INITIAL_SIZE`].
    pub initial_mesh: Mesh2,
}

impl PoissonPart {
    /// A part on `domain` with load `load`, starting from `initial_mesh` or, when `None`, from a
    /// uniform mesh of size [`INITIAL_SIZE`] (how generated problems make M⁰).
    pub fn new(
        domain: PolygonDomain,
        load: GaussianMixture,
        initial_mesh: Option<Mesh2>,
        quadrature_order: usize,
    ) -> Result<Self, MeshgenError> {
        let initial_mesh = match initial_mesh {
            Some(mesh) => mesh,
            None => uniform_mesh_2d(&domain, INITIAL_SIZE, &Mesh2dParams::default())?,
        };
        Ok(Self { domain, load, quadrature_order, initial_mesh })
    }
}

impl Domain<2> for PoissonPart {
    fn feature_set(&self) -> FeatureSet {
        FeatureSet::poisson()
    }

    fn optional_inputs(&self) -> Vec<String> {
        optional_inputs()
    }

    fn initial_mesh(&self) -> &Mesh<2> {
        &self.initial_mesh
    }

    fn columns(&self, mesh: &Mesh<2>) -> Result<Vec<Column>, ProblemError> {
        poisson_columns(&self.domain, &self.load, self.quadrature_order, mesh)
    }

    fn remesh(&self, mesh: &Mesh<2>, sizes: Vec<f64>, max_elements: usize) -> Result<Mesh<2>, ProblemError> {
        remesh_polygon(&self.domain, mesh, sizes, max_elements)
    }

    fn boundary_tags(&self, mesh: &Mesh<2>) -> BTreeMap<Vec<u32>, i32> {
        polygon_side_tags(&PolygonDistance::new(&self.domain), mesh)
    }
}

/// Solves −Δu = f (P1) on `mesh`, a mesh of `domain`: `solution_mean`, `solution_std` of u over
/// each element's vertices, `load` = f at the element midpoint, and the optional inputs ln η_K,
/// the log-scaled load and the geometry's.
fn poisson_columns(
    domain: &PolygonDomain,
    load: &GaussianMixture,
    quadrature_order: usize,
    mesh: &Mesh2,
) -> Result<Vec<Column>, ProblemError> {
    let space = P1Space::new(mesh)?;
    let quadrature = Quadrature::simplex::<2>(quadrature_order)?;
    let samples = space.sample_load(load, &quadrature)?;
    let solution = space.solve_poisson(&samples)?;
    let stats = element_stats(mesh, &solution.u)?;
    let indicator = space.residual_estimator(&solution.u, &samples)?;
    let midpoints = mesh.midpoints();
    let values: Vec<f64> = midpoints.iter().map(|&x| Load::value(load, x)).collect();
    let log_load = values.iter().map(|f| f.signum() * f.abs().ln_1p()).collect();
    let geometry = PlanarGeometry::new(domain).columns(&midpoints);
    let mut columns = vec![
        Column { name: "solution_mean".into(), values: stats.iter().map(|s| s.mean).collect() },
        Column { name: "solution_std".into(), values: stats.iter().map(|s| s.std).collect() },
        Column { name: "load".into(), values },
        Column {
            name: LOG_ERROR_INDICATOR_COLUMN.into(),
            values: indicator.iter().map(|eta| eta.max(f64::MIN_POSITIVE).ln()).collect(),
        },
        Column { name: LOG_LOAD_COLUMN.into(), values: log_load },
    ];
    columns.extend(geometry);
    Ok(columns)
}

/// A new mesh of `domain` from the piecewise-constant field `sizes` on `mesh`.
fn remesh_polygon(
    domain: &PolygonDomain,
    mesh: &Mesh2,
    sizes: Vec<f64>,
    max_elements: usize,
) -> Result<Mesh2, ProblemError> {
    let params = Mesh2dParams::default().with_max_elements(max_elements);
    Ok(generate_2d(domain, &MeshSizing::new(mesh, sizes), &params)?)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::FRAC_PI_2;

    use super::*;
    use crate::poisson::ProblemSample;

    /// A Poisson part offers every column it names, one value per element, and its geometry
    /// columns see the L-shape's re-entrant corner: where the expert's refinement starts.
    #[test]
    fn poisson_columns_include_the_geometry_inputs() {
        let sample = ProblemSample::draw(3).unwrap();
        let part = PoissonPart::new(PolygonDomain::lshape(sample.corner).unwrap(), sample.load, None, 2).unwrap();
        let mesh = part.initial_mesh();
        let columns = part.columns(mesh).unwrap();
        for name in part.optional_inputs() {
            let column = columns.iter().find(|c| c.name == name).unwrap_or_else(|| panic!("no column {name}"));
            assert_eq!(column.values.len(), mesh.num_elements());
            assert!(column.values.iter().all(|v| v.is_finite()), "{name}");
        }
        let values = |name: &str| &columns.iter().find(|c| c.name == name).unwrap().values;
        let to_corner = |e: usize| {
            let [x, y] = mesh.midpoint(e);
            (x - sample.corner[0]).hypot(y - sample.corner[1])
        };
        let nearest = (0..mesh.num_elements()).min_by(|&a, &b| to_corner(a).total_cmp(&to_corner(b))).unwrap();
        assert!((values("feature_turn")[nearest] + FRAC_PI_2).abs() < 1e-12);
        assert!((values("log_feature_distance")[nearest] - to_corner(nearest).ln()).abs() < 1e-12);
    }
}
