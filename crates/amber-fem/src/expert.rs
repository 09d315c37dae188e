//! The expert refinement heuristic that produces the Poisson expert meshes M* (spec §1).

use amber_mesh::Mesh2;
use amber_meshgen::rgb::{refine_rgb, smooth_laplacian};
use serde::{Deserialize, Serialize};

use crate::{FemError, Load, P1Space, Quadrature, mark_theta};

/// Settings of the expert heuristic; the defaults are the reference's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ExpertHeuristic {
    /// Marking threshold θ: refine every element with η_K > θ · max η.
    pub theta: f64,
    /// Quadrature degree for the load vector and the volume term of the estimator.
    pub quadrature_order: usize,
    /// One Jacobi Laplacian sweep after every refinement.
    pub smoothing: bool,
}

impl Default for ExpertHeuristic {
    fn default() -> Self {
        Self { theta: 0.8, quadrature_order: 2, smoothing: true }
    }
}

impl ExpertHeuristic {
    /// Starting from `initial`, repeats `steps` times: solve −Δu = f → estimate η → mark
    /// η_K > θ·max η → red-green-blue refinement → (optionally) one smoothing sweep.
    pub fn run(&self, initial: &Mesh2, load: &impl Load<2>, steps: usize) -> Result<Mesh2, FemError> {
        let quadrature = Quadrature::simplex::<2>(self.quadrature_order)?;
        let mut mesh = initial.clone();
        for step in 1..=steps {
            let space = P1Space::new(&mesh)?;
            let samples = space.sample_load(load, &quadrature)?;
            let solution = space.solve_poisson(&samples)?;
            let eta = space.residual_estimator(&solution.u, &samples)?;
            let marked = mark_theta(&eta, self.theta);
            let expert_step = |source| FemError::Expert { step, source };
            mesh = refine_rgb(&mesh, &marked).map_err(expert_step)?;
            if self.smoothing {
                mesh = smooth_laplacian(&mesh).map_err(expert_step)?;
            }
        }
        Ok(mesh)
    }
}
