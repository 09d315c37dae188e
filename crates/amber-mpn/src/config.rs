//! The network's configuration (serde): widths, depth, dropout; the paper's values as defaults.

use serde::{Deserialize, Serialize};

use crate::error::{MpnError, Result};

/// Hyper-parameters of the message passing network (spec §5). The defaults are the paper's
/// Poisson configuration. Unknown fields are ignored: model files written before the output
/// transform moved to the trainer's objective (`amber_nn::Objective`) still carry it as
/// `output`, and the objective beside them says the same.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MpnConfig {
    /// Input features per node (Poisson: area, mean u, std u, f).
    pub node_features: usize,
    /// Input features per directed edge (Poisson: midpoint distance).
    pub edge_features: usize,
    /// Latent width D of every node and edge state.
    pub latent_dim: usize,
    /// Message-passing steps L, each with its own weights.
    pub steps: usize,
    /// Probability of dropping each directed edge (self-loops included) in training mode.
    pub edge_dropout: f64,
    /// Graph context (off in the paper): every step adds `tanh(W·mean(x) + b)`, the mean node
    /// state of each graph transformed, to its nodes' aggregated messages. Ten steps of message
    /// passing reach ten elements; this gives every element a view of its whole mesh (spec §11's
    /// coarse graph level, reduced to one node per graph). Omitted from the JSON when off, so
    /// configurations without it keep their hashes.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub graph_context: bool,
}

impl Default for MpnConfig {
    fn default() -> Self {
        Self::poisson()
    }
}

impl MpnConfig {
    /// The paper's Poisson network: 4 node features, 1 edge feature, D = 64, L = 10
    /// (300,673 parameters).
    pub fn poisson() -> Self {
        Self { node_features: 4, edge_features: 1, latent_dim: 64, steps: 10, edge_dropout: 0.1, graph_context: false }
    }

    /// The reference code's Console network: 1 node feature, 3 edge features, D = 128.
    pub fn console() -> Self {
        Self { node_features: 1, edge_features: 3, latent_dim: 128, ..Self::poisson() }
    }

    pub fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(MpnError::InvalidConfig(m.to_owned()));
        if self.node_features == 0 || self.edge_features == 0 || self.latent_dim == 0 {
            return bad("feature counts and latent_dim must be positive");
        }
        if !(0.0..1.0).contains(&self.edge_dropout) {
            return bad("edge_dropout must be in [0, 1)");
        }
        Ok(())
    }

    /// Number of trainable scalars: encoders, L × (edge MLP 3D→D→D, node MLP 2D→D→D, two
    /// affine LayerNorms, the graph context's D→D if on), decoder D→D→D→1.
    pub fn num_parameters(&self) -> usize {
        let d = self.latent_dim;
        let linear = |i: usize, o: usize| i * o + o;
        let context = if self.graph_context { linear(d, d) } else { 0 };
        let step = linear(3 * d, d) + linear(d, d) + linear(2 * d, d) + linear(d, d) + 2 * 2 * d + context;
        linear(self.node_features, d)
            + linear(self.edge_features, d)
            + self.steps * step
            + linear(d, d)
            + linear(d, d)
            + linear(d, 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_parameter_counts() {
        assert_eq!(MpnConfig::poisson().num_parameters(), 300_673);
        assert_eq!(MpnConfig::console().num_parameters(), 1_191_041);
        let with_context = MpnConfig { graph_context: true, ..MpnConfig::poisson() };
        assert_eq!(with_context.num_parameters(), 300_673 + 10 * (64 * 64 + 64));
    }

    #[test]
    fn json_round_trip_and_defaults() {
        let c = MpnConfig::console();
        let back: MpnConfig = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
        assert_eq!(back, c);
        assert!(!serde_json::to_string(&c).unwrap().contains("graph_context"));
        let on = MpnConfig { graph_context: true, ..c };
        assert_eq!(serde_json::from_str::<MpnConfig>(&serde_json::to_string(&on).unwrap()).unwrap(), on);
        // Earlier model files name the output transform.
        let partial: MpnConfig = serde_json::from_str(r#"{"latent_dim": 32, "output": "none"}"#).unwrap();
        assert_eq!(partial, MpnConfig { latent_dim: 32, ..MpnConfig::poisson() });
        assert!(MpnConfig { edge_dropout: 1.0, ..MpnConfig::poisson() }.validate().is_err());
    }
}
