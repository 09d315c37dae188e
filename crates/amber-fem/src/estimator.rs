//! The residual error estimator of the Poisson expert and θ-marking (spec §1).

use rayon::prelude::*;

use crate::{FemError, LoadSamples, P1Space};

impl<const D: usize> P1Space<'_, D> {
    /// η_K = h_K² ∫_K f² + ½ Σ_{interior facets F of K} h_F ∫_F [[∇u·n]]² for every element, with
    /// h_K = (D!·|K|)^(1/D) (2D: √(2|K|)) and h_F = |F|^(1/(D−1)) (2D: the edge length), the
    /// volume term integrated with the quadrature of `samples` (the reference uses degree 2);
    /// boundary facets contribute nothing. ∇u is constant per element, so the facet term is exact.
    pub fn residual_estimator(&self, u: &[f64], samples: &LoadSamples<'_>) -> Result<Vec<f64>, FemError> {
        self.check_solution(u)?;
        let factorial = if D == 2 { 2.0 } else { 6.0 };
        Ok((0..self.mesh.num_elements())
            .into_par_iter()
            .map(|e| {
                let g = &self.geometry[e];
                let h2 = (factorial * g.volume).powf(2.0 / D as f64);
                let f2: f64 = samples.quadrature().iter().zip(samples.element(e)).map(|((_, w), f)| w * f * f).sum();
                let grad = g.gradient(&self.local_values(u, e));
                let jumps: f64 = self
                    .adjacency
                    .neighbours_of(e)
                    .iter()
                    .enumerate()
                    .filter(|&(_, &n)| n != amber_mesh::FacetAdjacency::BOUNDARY)
                    .map(|(i, &n)| {
                        let n = n as usize;
                        let other = self.geometry[n].gradient(&self.local_values(u, n));
                        let normal_len = g.grads[i].iter().map(|x| x * x).sum::<f64>().sqrt();
                        let jump = (0..D).map(|k| (grad[k] - other[k]) * g.grads[i][k]).sum::<f64>() / normal_len;
                        let area = D as f64 * g.volume * normal_len;
                        let h = if D == 2 { area } else { area.sqrt() };
                        h * area * jump * jump
                    })
                    .sum();
                h2 * g.volume * f2 + 0.5 * jumps
            })
            .collect())
    }
}

/// The elements with η_K > θ · max η (scikit-fem `adaptive_theta`), in index order.
pub fn mark_theta(eta: &[f64], theta: f64) -> Vec<usize> {
    let max = eta.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (0..eta.len()).filter(|&k| eta[k] > theta * max).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Quadrature;
    use amber_mesh::Mesh2;

    #[test]
    fn marking_keeps_the_largest() {
        assert_eq!(mark_theta(&[1.0, 0.85, 0.8, 0.1], 0.8), vec![0, 1]);
        assert!(mark_theta(&[], 0.8).is_empty());
    }

    #[test]
    fn estimator_on_two_triangles_by_hand() {
        // Unit square cut along (0,0)-(1,1), u = 1 at (1,0) only: u = x − y on the lower
        // triangle, 0 on the upper; the jump across the diagonal, normal (1,−1)/√2, is √2.
        let m = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
        let space = P1Space::new(&m).unwrap();
        let q = Quadrature::simplex::<2>(2).unwrap();
        let samples = space.sample_load(&|_: [f64; 2]| 3.0, &q).unwrap();
        let eta = space.residual_estimator(&[0.0, 1.0, 0.0, 0.0], &samples).unwrap();
        // Volume term: h² |K| f² = (2·½)·½·9 = 4.5; facet term: ½ · |E|² · 2 = ½ · 2 · 2 = 2.
        for value in eta {
            assert!((value - 6.5).abs() < 1e-12, "{value}");
        }
    }
}
