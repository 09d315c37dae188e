//! What a network's scalar output means (spec §5, §8, §11): both networks regress one scalar
//! per node or pixel with a mean squared error, and [`Objective`] is the one map between that
//! scalar and an element size: the target a label size becomes, the transform the loss applies
//! to the output, and the size an output stands for.

use candle_core::Tensor;
use serde::{Deserialize, Serialize};

/// softplus(x) = log(1 + eˣ), overflow-free.
pub fn softplus(x: f64) -> f64 {
    x.max(0.0) + (-x.abs()).exp().ln_1p()
}

/// softplus⁻¹(y) = y + log(1 − e⁻ʸ) for y > 0.
pub fn softplus_inverse(y: f64) -> f64 {
    y + (-(-y).exp_m1()).ln()
}

/// How the network's scalar output `z` becomes an element size and what it is trained against.
/// `z` is the output after undoing any label standardisation. The names are the CNN's
/// configuration spelling; AMBER's earlier names are read as aliases.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// size = exp(z); MSE of z against log sizes (the paper's CNN).
    #[serde(alias = "log")]
    LogMse,
    /// size = softplus(z); MSE of the size against the label (the paper's AMBER).
    #[serde(alias = "softplus")]
    SoftplusMse,
    /// size = z; MSE against the label (the "no softplus" ablations; non-positive sizes are
    /// clipped at h_min downstream).
    #[serde(alias = "linear")]
    Mse,
    /// The later version (§11.3): size = softplus(z + softplus⁻¹(h)), h the element's current
    /// size; MSE of z against the residual softplus⁻¹(y) − softplus⁻¹(h). Needs a current mesh.
    SoftplusResidual,
    /// size = h·exp(z), h the element's current size; MSE of z against ln(y/h). The residual
    /// in log space: unlike the softplus residual, which is logarithmic only for sizes well
    /// below 1 (Poisson's unit square) and nearly linear for sizes of several units (Console's
    /// millimetres), it weighs a size's relative error alike at every scale and in every unit.
    LogResidual,
}

impl Objective {
    /// Whether [`Self::target`] and [`Self::size`] read the element's current size.
    pub fn needs_current_size(self) -> bool {
        matches!(self, Objective::SoftplusResidual | Objective::LogResidual)
    }

    /// Whether the loss compares the output itself with the targets, so that the targets may
    /// be standardised and the output de-standardised: everything but a softplus in the loss,
    /// whose bend sits at a fixed scale.
    pub fn supports_label_normalisation(self) -> bool {
        self != Objective::SoftplusMse
    }

    /// The regression target of a label size `y` on an element of current size `current`.
    ///
    /// # Panics
    /// If the objective [needs the current size](Self::needs_current_size) and none is given:
    /// configurations without a current mesh refuse such an objective.
    pub fn target(self, y: f64, current: Option<f64>) -> f64 {
        match self {
            Objective::LogMse => y.ln(),
            Objective::SoftplusMse | Objective::Mse => y,
            Objective::SoftplusResidual => softplus_inverse(y) - softplus_inverse(residual_base(current)),
            Objective::LogResidual => (y / residual_base(current)).ln(),
        }
    }

    /// The size an output `z` stands for on an element of current size `current` (panics as
    /// [`Self::target`] does).
    pub fn size(self, z: f64, current: Option<f64>) -> f64 {
        match self {
            Objective::LogMse => z.exp(),
            Objective::SoftplusMse => softplus(z),
            Objective::Mse => z,
            Objective::SoftplusResidual => softplus(z + softplus_inverse(residual_base(current))),
            Objective::LogResidual => residual_base(current) * z.exp(),
        }
    }

    /// What the loss compares with the targets: softplus of the raw output for
    /// [`Self::SoftplusMse`], the output itself otherwise. Inside the autograd graph, so the
    /// gradient flows through it.
    pub fn activation(self, z: &Tensor) -> candle_core::Result<Tensor> {
        match self {
            // relu(z) + log(1 + exp(-|z|)): exact and overflow-free for any z.
            Objective::SoftplusMse => z.relu()? + (z.abs()?.neg()?.exp()? + 1.0)?.log()?,
            Objective::LogMse | Objective::Mse | Objective::SoftplusResidual | Objective::LogResidual => Ok(z.clone()),
        }
    }
}

fn residual_base(current: Option<f64>) -> f64 {
    current.expect("a residual objective needs the element's current size")
}

#[cfg(test)]
mod tests {
    use candle_core::Device;

    use super::*;

    const ALL: [Objective; 5] = [
        Objective::LogMse,
        Objective::SoftplusMse,
        Objective::Mse,
        Objective::SoftplusResidual,
        Objective::LogResidual,
    ];

    #[test]
    fn softplus_inverse_inverts_softplus_over_the_size_range() {
        for y in [1e-6, 1e-3, 0.05, 0.9, 3.0, 40.0] {
            assert!((softplus(softplus_inverse(y)) - y).abs() <= 1e-12 * y.max(1.0), "{y}");
        }
    }

    #[test]
    fn a_perfect_output_maps_back_to_the_label() {
        for objective in ALL {
            for (y, h) in [(0.37, 0.9), (0.01, 0.1), (2.0, 0.5)] {
                let target = objective.target(y, Some(h));
                // The output whose activation equals the target.
                let z = if objective == Objective::SoftplusMse { softplus_inverse(target) } else { target };
                assert!((objective.size(z, Some(h)) - y).abs() < 1e-12 * y.max(1.0), "{objective:?}: {y}");
            }
        }
    }

    #[test]
    fn the_log_residual_does_not_depend_on_the_unit() {
        // The same refinement, 4.4 → 0.4, in millimetres and in metres: one target.
        let target = |scale: f64| Objective::LogResidual.target(0.4 * scale, Some(4.4 * scale));
        assert!((target(1.0) - target(1e-3)).abs() < 1e-12);
        // The softplus residual's target differs by a factor of about 2 between the two units.
        let softplus = |scale: f64| Objective::SoftplusResidual.target(0.4 * scale, Some(4.4 * scale));
        assert!(softplus(1.0) / softplus(1e-3) > 1.5);
    }

    #[test]
    fn the_activation_is_the_size_map_of_the_softplus_loss() {
        let z = [-30.0, -1.5, 0.0, 0.7, 40.0];
        let tensor = Tensor::new(&z, &Device::Cpu).unwrap();
        for objective in ALL {
            let out = objective.activation(&tensor).unwrap().to_vec1::<f64>().unwrap();
            for (o, z) in out.iter().zip(z) {
                let expected = if objective == Objective::SoftplusMse { softplus(z) } else { z };
                assert!((o - expected).abs() <= 1e-12 * expected.abs().max(1.0), "{objective:?}: {o} vs {expected}");
            }
        }
    }

    #[test]
    fn earlier_spellings_still_read() {
        let read = |s: &str| serde_json::from_str::<Objective>(&format!("\"{s}\"")).unwrap();
        for (old, new) in [("log", "log_mse"), ("softplus", "softplus_mse"), ("linear", "mse")] {
            assert_eq!(read(old), read(new));
        }
        for objective in ALL {
            assert_eq!(read(serde_json::to_value(objective).unwrap().as_str().unwrap()), objective);
        }
        assert_eq!(serde_json::to_string(&Objective::SoftplusResidual).unwrap(), "\"softplus_residual\"");
    }
}
