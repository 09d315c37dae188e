//! Loads: anything that answers f(x), and the Gaussian-mixture density of the Poisson task.

use serde::{Deserialize, Serialize};

use crate::FemError;

/// A right-hand side f of −Δu = f, evaluated pointwise (at quadrature points).
pub trait Load<const D: usize>: Sync {
    /// f(x).
    fn value(&self, x: [f64; D]) -> f64;
}

impl<const D: usize, F: Fn([f64; D]) -> f64 + Sync> Load<D> for F {
    fn value(&self, x: [f64; D]) -> f64 {
        self(x)
    }
}

/// The components of a 2D Gaussian mixture as stored in files (reference field names).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaussianMixtureParams {
    /// Component means μ_k.
    pub means: Vec<[f64; 2]>,
    /// Component covariances Σ_k (symmetric positive definite 2×2).
    pub covariances: Vec<[[f64; 2]; 2]>,
    /// Component weights w_k (non-negative, summing to 1).
    pub weights: Vec<f64>,
}

/// The density f(x) = Σ_k w_k N(x; μ_k, Σ_k) of a 2D Gaussian mixture.
///
/// Construction checks every component, so evaluation cannot fail:
/// ```
/// use amber_fem::{GaussianMixture, GaussianMixtureParams, Load};
/// let f = GaussianMixture::new(GaussianMixtureParams {
///     means: vec![[0.5, 0.5]],
///     covariances: vec![[[1e-3, 0.0], [0.0, 1e-3]]],
///     weights: vec![1.0],
/// })?;
/// let peak = 1.0 / (2.0 * std::f64::consts::PI * 1e-3);
/// assert!((f.value([0.5, 0.5]) - peak).abs() < 1e-9 * peak);
/// # Ok::<(), amber_fem::FemError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GaussianMixtureParams", into = "GaussianMixtureParams")]
pub struct GaussianMixture {
    params: GaussianMixtureParams,
    /// Per component: w_k / (2π sqrt(det Σ_k)) and the entries (a, b, c) of Σ_k⁻¹ = [[a, b], [b, c]].
    terms: Vec<(f64, [f64; 3])>,
}

impl GaussianMixture {
    /// Checks the components: at least one, equal counts, finite values, non-negative weights
    /// summing to 1 (to 1e-9), symmetric positive definite covariances.
    pub fn new(params: GaussianMixtureParams) -> Result<Self, FemError> {
        let n = params.means.len();
        let invalid = |component: usize, problem: String| FemError::InvalidMixture { component, problem };
        if params.covariances.len() != n || params.weights.len() != n {
            return Err(invalid(
                0,
                format!(
                    "{n} means, {} covariances and {} weights (counts must match)",
                    params.covariances.len(),
                    params.weights.len()
                ),
            ));
        }
        if n == 0 {
            return Err(invalid(0, "no components: a load needs at least one Gaussian".into()));
        }
        let total: f64 = params.weights.iter().sum();
        if (total - 1.0).abs() > 1e-9 {
            return Err(invalid(0, format!("weights sum to {total}, not 1")));
        }
        let mut terms = Vec::with_capacity(n);
        for k in 0..n {
            let (mu, [[a, b], [b2, c]], w) = (params.means[k], params.covariances[k], params.weights[k]);
            if !(mu.iter().all(|x| x.is_finite()) && w.is_finite() && w >= 0.0) {
                return Err(invalid(k, format!("mean {mu:?} or weight {w} is not finite and non-negative")));
            }
            let det = a * c - b * b;
            let sym = (b - b2).abs() <= 1e-12 * (a.abs() + c.abs());
            if !(sym && a > 0.0 && det > 0.0 && det.is_finite()) {
                return Err(invalid(
                    k,
                    format!("covariance {:?} is not symmetric positive definite", params.covariances[k]),
                ));
            }
            terms.push((w / (2.0 * std::f64::consts::PI * det.sqrt()), [c / det, -b / det, a / det]));
        }
        Ok(Self { params, terms })
    }

    /// The components.
    pub fn params(&self) -> &GaussianMixtureParams {
        &self.params
    }
}

impl Load<2> for GaussianMixture {
    fn value(&self, x: [f64; 2]) -> f64 {
        self.params
            .means
            .iter()
            .zip(&self.terms)
            .map(|(mu, (scale, [a, b, c]))| {
                let (dx, dy) = (x[0] - mu[0], x[1] - mu[1]);
                scale * (-0.5 * (a * dx * dx + 2.0 * b * dx * dy + c * dy * dy)).exp()
            })
            .sum()
    }
}

impl TryFrom<GaussianMixtureParams> for GaussianMixture {
    type Error = FemError;
    fn try_from(params: GaussianMixtureParams) -> Result<Self, FemError> {
        Self::new(params)
    }
}

impl From<GaussianMixture> for GaussianMixtureParams {
    fn from(mixture: GaussianMixture) -> Self {
        mixture.params
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> GaussianMixtureParams {
        GaussianMixtureParams {
            means: vec![[0.3, 0.4], [0.7, 0.2]],
            covariances: vec![[[4e-4, 1e-4], [1e-4, 2e-4]], [[1e-3, 0.0], [0.0, 5e-4]]],
            weights: vec![0.25, 0.75],
        }
    }

    #[test]
    fn density_integrates_to_one() {
        let f = GaussianMixture::new(params()).unwrap();
        let n = 1000;
        let h = 1.0 / n as f64;
        let mut total = 0.0;
        for i in 0..n {
            for j in 0..n {
                total += f.value([(i as f64 + 0.5) * h, (j as f64 + 0.5) * h]) * h * h;
            }
        }
        assert!((total - 1.0).abs() < 1e-6, "{total}");
    }

    #[test]
    fn invalid_components_are_rejected() {
        let mut p = params();
        p.covariances[1] = [[1e-3, 2e-3], [2e-3, 1e-3]];
        let err = GaussianMixture::new(p).unwrap_err();
        assert!(matches!(err, FemError::InvalidMixture { component: 1, .. }), "{err}");
        let mut p = params();
        p.weights = vec![0.5, 0.6];
        assert!(GaussianMixture::new(p).is_err());
        let mut p = params();
        p.covariances[0] = [[1e-3, 1e-4], [0.0, 1e-3]];
        assert!(GaussianMixture::new(p).is_err());
        let empty = GaussianMixtureParams { means: vec![], covariances: vec![], weights: vec![] };
        assert!(GaussianMixture::new(empty).unwrap_err().to_string().contains("at least one Gaussian"));
    }

    #[test]
    fn serde_round_trip_validates() {
        let f = GaussianMixture::new(params()).unwrap();
        let json = serde_json::to_string(&f).unwrap();
        assert!(json.starts_with("{\"means\""));
        assert_eq!(serde_json::from_str::<GaussianMixture>(&json).unwrap(), f);
        let bad = json.replace("0.0005", "-0.0005");
        assert!(serde_json::from_str::<GaussianMixture>(&bad).unwrap_err().to_string().contains("positive definite"));
    }
}
