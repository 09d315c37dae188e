//! How well a mesh realises a sizing field, and how well shaped its elements are.

use amber_mesh::Mesh;
use amber_stdx::quantile;
use rayon::prelude::*;
use serde::Serialize;

use crate::SizingField;

/// Size fidelity and shape statistics of a mesh against the field it was made from.
#[derive(Clone, Debug, Serialize)]
pub struct QualityReport {
    pub elements: usize,
    /// Quantiles of h(K) / h_target(midpoint of K).
    pub size_ratio_median: f64,
    pub size_ratio_p10: f64,
    pub size_ratio_p90: f64,
    /// Smallest angle (2D) or dihedral angle (3D) over the mesh, degrees.
    pub min_angle: f64,
    /// Mean over elements of their smallest angle, degrees.
    pub mean_min_angle: f64,
}

impl QualityReport {
    /// Measures `mesh` against `field`.
    pub fn measure<const D: usize, F: SizingField<D> + ?Sized>(mesh: &Mesh<D>, field: &F) -> Self {
        let mut ratios: Vec<f64> =
            (0..mesh.num_elements()).into_par_iter().map(|e| mesh.size(e) / field.size_at(mesh.midpoint(e))).collect();
        ratios.sort_unstable_by(f64::total_cmp);
        let angles = mesh.min_angles();
        Self {
            elements: mesh.num_elements(),
            size_ratio_median: quantile(&ratios, 0.5),
            size_ratio_p10: quantile(&ratios, 0.1),
            size_ratio_p90: quantile(&ratios, 0.9),
            min_angle: angles.iter().copied().fold(f64::INFINITY, f64::min),
            mean_min_angle: angles.iter().sum::<f64>() / angles.len().max(1) as f64,
        }
    }
}
