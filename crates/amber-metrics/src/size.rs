//! Where a generated mesh is coarser or finer than the expert's: each generated element's size
//! against the expert's element at its midpoint. The DCD says how far two meshes are apart; this
//! says where and in which direction, as a field to look at and as quantiles to compare parts by.

use amber_mesh::{Mesh, PointLocator};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// ln(h(K) / h_E(m_K)) for every element K of `generated`, in its order: h(K) its size, h_E(m_K)
/// the size of the expert element containing its midpoint (of the expert element with the nearest
/// midpoint where the midpoint lies outside the expert mesh). Positive where the generated mesh
/// is coarser, negative where it is finer.
///
/// ```
/// use amber_mesh::Mesh2;
/// let square = |s: f64| Mesh2::new(vec![[0.0, 0.0], [s, 0.0], [s, s], [0.0, s]], vec![0, 1, 2, 0, 2, 3]).unwrap();
/// let ratios = amber_metrics::log_size_ratios(&square(2.0), &square(1.0));
/// assert!(ratios.iter().all(|r| (r - 2f64.ln()).abs() < 1e-12));
/// ```
pub fn log_size_ratios<const D: usize>(generated: &Mesh<D>, expert: &Mesh<D>) -> Vec<f64> {
    let locator = PointLocator::new(expert);
    let expert_sizes = expert.sizes();
    (generated.midpoints().par_iter().zip(generated.sizes()))
        .map(|(m, h)| (h / expert_sizes[locator.locate_or_nearest(*m).element()]).ln())
        .collect()
}

/// The generated elements' sizes over the expert's where they lie, as factors: the median and the
/// 10th and 90th percentiles of exp([`log_size_ratios`]) over the generated elements.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SizeRatios {
    pub p10: f64,
    pub median: f64,
    pub p90: f64,
}

impl SizeRatios {
    /// The quantiles of `log_ratios` ([`log_size_ratios`]), as factors; NaN for none.
    pub fn of(log_ratios: &[f64]) -> Self {
        let mut sorted = log_ratios.to_vec();
        sorted.sort_by(f64::total_cmp);
        let factor = |q| amber_stdx::quantile(&sorted, q).exp();
        Self { p10: factor(0.1), median: factor(0.5), p90: factor(0.9) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::Mesh2;

    /// The unit square cut into 2·n² triangles.
    fn grid(n: usize) -> Mesh2 {
        let h = 1.0 / n as f64;
        let vertices = (0..=n).flat_map(|j| (0..=n).map(move |i| [i as f64 * h, j as f64 * h])).collect();
        let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let cells = (0..n)
            .flat_map(|j| {
                (0..n).flat_map(move |i| {
                    [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)]
                })
            })
            .collect();
        Mesh2::new(vertices, cells).unwrap()
    }

    #[test]
    fn a_mesh_twice_as_coarse_as_the_expert_is_twice_as_large_everywhere() {
        let ratios = log_size_ratios(&grid(4), &grid(8));
        assert_eq!(ratios.len(), 32);
        assert!(ratios.iter().all(|r| (r - 2f64.ln()).abs() < 1e-12), "{ratios:?}");
        let summary = SizeRatios::of(&ratios);
        assert!([summary.p10, summary.median, summary.p90].iter().all(|f| (f - 2.0).abs() < 1e-12));
        let inverse = SizeRatios::of(&log_size_ratios(&grid(8), &grid(4)));
        assert!((inverse.median - 0.5).abs() < 1e-12);
    }

    #[test]
    fn the_quantiles_are_those_of_the_factors() {
        let logs: Vec<f64> = (0..=10).map(|i| f64::from(i) * 0.1).collect();
        let s = SizeRatios::of(&logs);
        assert!((s.p10 - 0.1f64.exp()).abs() < 1e-12 && (s.median - 0.5f64.exp()).abs() < 1e-12);
        assert!((s.p90 - 0.9f64.exp()).abs() < 1e-12);
        assert!(SizeRatios::of(&[]).median.is_nan());
    }
}
