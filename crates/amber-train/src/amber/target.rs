//! The map between element sizes and what the network regresses: training targets from labels,
//! sizes from network outputs, with the optional running normalisation of the targets.

use amber_graph::RunningMoments;
use amber_mpn::OutputTransform;
use serde::{Deserialize, Serialize};

use crate::Objective;

/// softplus(x) = log(1 + eˣ), overflow-free.
pub fn softplus(x: f64) -> f64 {
    x.max(0.0) + (-x.abs()).exp().ln_1p()
}

/// softplus⁻¹(y) = y + log(1 − e⁻ʸ) for y > 0.
pub fn softplus_inverse(y: f64) -> f64 {
    y + (-(-y).exp_m1()).ln()
}

/// The objective plus the running moments of its targets (when labels are normalised).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetTransform {
    pub objective: Objective,
    /// Running mean/variance of the raw targets; `None`: targets are not normalised.
    pub moments: Option<RunningMoments>,
}

impl TargetTransform {
    /// A transform for `objective`, normalising targets if `normalise` (and the objective allows
    /// it).
    pub fn new(objective: Objective, normalise: bool) -> Self {
        let normalise = normalise && objective.supports_label_normalisation();
        Self { objective, moments: normalise.then(|| RunningMoments::new(1)) }
    }

    /// The output transform the network itself applies.
    pub fn network_output(&self) -> OutputTransform {
        match self.objective {
            Objective::Softplus => OutputTransform::Softplus,
            Objective::Linear | Objective::Log | Objective::SoftplusResidual => OutputTransform::None,
        }
    }

    /// Un-normalised targets of one graph: labels y, log y, or softplus⁻¹(y) − softplus⁻¹(h)
    /// for the current element sizes h.
    pub fn raw_targets(&self, labels: &[f64], current_sizes: &[f64]) -> Vec<f64> {
        match self.objective {
            Objective::Softplus | Objective::Linear => labels.to_vec(),
            Objective::Log => labels.iter().map(|y| y.ln()).collect(),
            Objective::SoftplusResidual => {
                labels.iter().zip(current_sizes).map(|(&y, &h)| softplus_inverse(y) - softplus_inverse(h)).collect()
            }
        }
    }

    /// Merges one graph's raw targets into the running moments (a no-op without normalisation).
    pub fn update(&mut self, raw_targets: &[f64]) {
        if let Some(moments) = &mut self.moments {
            let rows: Vec<f32> = raw_targets.iter().map(|&t| t as f32).collect();
            moments.update(&rows).expect("one column, any number of rows");
        }
    }

    /// What the network output is trained against: the raw targets, normalised if enabled.
    pub fn training_targets(&self, raw_targets: &[f64]) -> Vec<f32> {
        let mut rows: Vec<f32> = raw_targets.iter().map(|&t| t as f32).collect();
        if let Some(moments) = &self.moments {
            moments.normalise(&mut rows).expect("one column, any number of rows");
        }
        rows
    }

    /// Element sizes from network outputs `z` on a mesh whose current element sizes are
    /// `current_sizes`.
    pub fn sizes(&self, z: &[f32], current_sizes: &[f64]) -> Vec<f64> {
        let (shift, scale) = match &self.moments {
            Some(m) => (m.mean()[0], (m.variance()[0] + amber_graph::VARIANCE_EPSILON).sqrt()),
            None => (0.0, 1.0),
        };
        let denormalised = z.iter().map(|&z| f64::from(z) * scale + shift);
        match self.objective {
            // The network already applied softplus, or nothing.
            Objective::Softplus | Objective::Linear => denormalised.collect(),
            Objective::Log => denormalised.map(f64::exp).collect(),
            Objective::SoftplusResidual => {
                denormalised.zip(current_sizes).map(|(r, &h)| softplus(r + softplus_inverse(h))).collect()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn softplus_inverse_inverts_softplus_over_the_size_range() {
        for y in [1e-6, 1e-3, 0.05, 0.9, 3.0, 40.0] {
            assert!((softplus(softplus_inverse(y)) - y).abs() <= 1e-12 * y.max(1.0), "{y}");
        }
    }

    #[test]
    fn perfect_targets_map_back_to_the_labels() {
        let labels = [0.01, 0.2, 0.5];
        let current = [0.9, 0.1, 0.5];
        for objective in [Objective::Softplus, Objective::Linear, Objective::Log, Objective::SoftplusResidual] {
            let mut t = TargetTransform::new(objective, true);
            let raw = t.raw_targets(&labels, &current);
            t.update(&raw);
            let z = t.training_targets(&raw);
            let sizes = t.sizes(&z, &current);
            for (s, y) in sizes.iter().zip(labels) {
                assert!((s - y).abs() < 1e-5 * y.max(0.1), "{objective:?}: {s} vs {y}");
            }
        }
    }
}
