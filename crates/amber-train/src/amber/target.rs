//! The map between element sizes and what the network regresses: the objective's targets and
//! sizes (`amber_nn::Objective`), with the optional running normalisation of the targets.

use amber_graph::RunningMoments;
use amber_nn::Objective;
use serde::{Deserialize, Serialize};

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

    /// Un-normalised targets of one graph ([`Objective::target`]) for the current element sizes.
    pub fn raw_targets(&self, labels: &[f64], current_sizes: &[f64]) -> Vec<f64> {
        labels.iter().zip(current_sizes).map(|(&y, &h)| self.objective.target(y, Some(h))).collect()
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
        z.iter().zip(current_sizes).map(|(&z, &h)| self.objective.size(f64::from(z) * scale + shift, Some(h))).collect()
    }
}

#[cfg(test)]
mod tests {
    use amber_nn::softplus_inverse;

    use super::*;

    #[test]
    fn perfect_outputs_map_back_to_the_labels() {
        let labels = [0.01, 0.2, 0.5];
        let current = [0.9, 0.1, 0.5];
        for objective in [
            Objective::SoftplusMse,
            Objective::Mse,
            Objective::LogMse,
            Objective::SoftplusResidual,
            Objective::LogResidual,
        ] {
            let mut t = TargetTransform::new(objective, true);
            let raw = t.raw_targets(&labels, &current);
            t.update(&raw);
            // The outputs whose activation is the training target.
            let z: Vec<f32> = t
                .training_targets(&raw)
                .into_iter()
                .map(|z| if objective == Objective::SoftplusMse { softplus_inverse(f64::from(z)) as f32 } else { z })
                .collect();
            let sizes = t.sizes(&z, &current);
            for (s, y) in sizes.iter().zip(labels) {
                assert!((s - y).abs() < 1e-5 * y.max(0.1), "{objective:?}: {s} vs {y}");
            }
        }
    }
}
