//! The network's configuration (serde): widths, depth, dropout; the paper's values as defaults.

use serde::{Deserialize, Serialize};

use crate::error::{MpnError, Result};

/// The network's size apart from its input widths, which the task's features fix: what a
/// training configuration chooses (spec §5). The defaults are the paper's Poisson network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NetworkConfig {
    /// Latent width D of every node and edge state (Poisson 64, Console 128).
    pub latent_dim: usize,
    /// Message-passing steps L, each with its own weights (`steps` in model files written
    /// before the training configuration shared this type).
    #[serde(alias = "steps")]
    pub message_passing_steps: usize,
    /// Probability of dropping each directed edge (self-loops included) in training mode.
    pub edge_dropout: f64,
    /// Graph context (off in the paper): every step adds `tanh(W·mean(x) + b)`, the mean node
    /// state of each graph transformed, to its nodes' aggregated messages. Ten steps of message
    /// passing reach ten elements; this gives every element a view of its whole mesh (spec §11's
    /// coarse graph level, reduced to one node per graph). Omitted from the JSON when off, so
    /// configurations without it keep their hashes.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub graph_context: bool,
    /// Region context (off in the paper): every step also adds `tanh(W·mean_R(x) + b)`, the mean
    /// node state of each node's region transformed (the graph's cell of a grid of about
    /// `amber_graph::REGIONS_PER_AXIS` cubes along its longest side): a coarse level between
    /// the element and the whole mesh, so a step sees a region of the part, not ten elements.
    /// Omitted from the JSON when off.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub region_context: bool,
}

impl Default for NetworkConfig {
    fn default() -> Self {
        Self {
            latent_dim: 64,
            message_passing_steps: 10,
            edge_dropout: 0.1,
            graph_context: false,
            region_context: false,
        }
    }
}

/// The whole network: its input widths and its size. Fields a model file holds beyond these
/// are ignored: files written before the output transform moved to the trainer's objective
/// (`amber_nn::Objective`) still carry it as `output`, and the objective beside them says the
/// same.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MpnConfig {
    /// Input features per node (Poisson: area, mean u, std u, f).
    pub node_features: usize,
    /// Input features per directed edge (Poisson: midpoint distance).
    pub edge_features: usize,
    #[serde(flatten)]
    pub network: NetworkConfig,
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
        Self { node_features: 4, edge_features: 1, network: NetworkConfig::default() }
    }

    /// The reference code's Console network: 1 node feature, 3 edge features, D = 128.
    pub fn console() -> Self {
        Self {
            node_features: 1,
            edge_features: 3,
            network: NetworkConfig { latent_dim: 128, ..NetworkConfig::default() },
        }
    }

    /// The paper's Poisson network made `latent_dim` wide and `message_passing_steps` deep
    /// (small networks for tests and benchmarks).
    pub fn small(latent_dim: usize, message_passing_steps: usize) -> Self {
        Self {
            network: NetworkConfig { latent_dim, message_passing_steps, ..NetworkConfig::default() },
            ..Self::poisson()
        }
    }

    pub fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(MpnError::InvalidConfig(m.to_owned()));
        if self.node_features == 0 || self.edge_features == 0 || self.network.latent_dim == 0 {
            return bad("feature counts and latent_dim must be positive");
        }
        if !(0.0..1.0).contains(&self.network.edge_dropout) {
            return bad("edge_dropout must be in [0, 1)");
        }
        Ok(())
    }

    /// Number of trainable scalars: encoders, L × (edge MLP 3D→D→D, node MLP 2D→D→D, two
    /// affine LayerNorms, the graph and region contexts' D→D if on), decoder D→D→D→1.
    pub fn num_parameters(&self) -> usize {
        let d = self.network.latent_dim;
        let linear = |i: usize, o: usize| i * o + o;
        let context = [self.network.graph_context, self.network.region_context]
            .into_iter()
            .map(|on| if on { linear(d, d) } else { 0 })
            .sum::<usize>();
        let step = linear(3 * d, d) + linear(d, d) + linear(2 * d, d) + linear(d, d) + 2 * 2 * d + context;
        linear(self.node_features, d)
            + linear(self.edge_features, d)
            + self.network.message_passing_steps * step
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
        let mut with_context = MpnConfig::poisson();
        with_context.network.graph_context = true;
        assert_eq!(with_context.num_parameters(), 300_673 + 10 * (64 * 64 + 64));
        with_context.network.region_context = true;
        assert_eq!(with_context.num_parameters(), 300_673 + 20 * (64 * 64 + 64));
    }

    #[test]
    fn json_round_trip_and_defaults() {
        let c = MpnConfig::console();
        let back: MpnConfig = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
        assert_eq!(back, c);
        assert!(!serde_json::to_string(&c).unwrap().contains("graph_context"));
        assert!(!serde_json::to_string(&c).unwrap().contains("region_context"));
        let mut on = c;
        on.network.graph_context = true;
        assert_eq!(serde_json::from_str::<MpnConfig>(&serde_json::to_string(&on).unwrap()).unwrap(), on);
        // Earlier model files name the output transform and call L `steps`.
        let earlier: MpnConfig = serde_json::from_str(r#"{"latent_dim": 32, "steps": 3, "output": "none"}"#).unwrap();
        assert_eq!(earlier, MpnConfig::small(32, 3));
        let mut dropout = MpnConfig::poisson();
        dropout.network.edge_dropout = 1.0;
        assert!(dropout.validate().is_err());
    }

    #[test]
    fn a_training_configuration_names_only_the_networks_fields() {
        let network: NetworkConfig = serde_json::from_str(r#"{"latent_dim": 128}"#).unwrap();
        assert_eq!(network, MpnConfig::console().network);
        assert!(serde_json::from_str::<NetworkConfig>(r#"{"latnet_dim": 128}"#).is_err());
    }
}
