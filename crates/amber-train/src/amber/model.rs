//! A trained AMBER model: the network plus everything needed to turn meshes into sizing fields
//! (input normaliser, target transform, clip and budget), saved and loaded as one directory.

use std::path::Path;

use amber_graph::{FeatureNormaliser, FeatureSet, GraphBatch};
use amber_mpn::{Mpn, MpnConfig, MpnTrainer};
use amber_stdx::write_json_atomic;
use serde::{Deserialize, Serialize};

use amber_mesh::Mesh;
use amber_tasks::{Domain, MeshLimits, MeshState};
use rayon::prelude::*;

use crate::error::{Result, in_problem, io_error};
use crate::model_file::{check_limits, check_moments, read_checked};
use crate::{PredictedField, SizingModel, TargetTransform};

/// File of the network weights inside a model directory (its config is `model.json`).
pub const WEIGHTS_FILE: &str = "model.safetensors";
/// File of everything but the network inside a model directory.
pub(crate) const PREDICTOR_FILE: &str = "predictor.json";

/// Everything of a model except the network weights.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Predictor {
    /// The graphs' features (must match the task the model is applied to).
    pub features: FeatureSet,
    /// Running input normalisation; `None`: inputs are fed raw (the ablation).
    pub normaliser: Option<FeatureNormaliser>,
    pub target: TargetTransform,
    pub limits: MeshLimits,
}

impl Predictor {
    /// Reads a `predictor.json` written with a network of configuration `network`, checking
    /// that it is one ([`Self::validate`]); the error names the file and the field.
    pub(crate) fn read(path: &Path, network: &MpnConfig) -> Result<Self> {
        read_checked(path, |p: &Self| p.validate(network))
    }

    /// Checks what a file could get wrong: the features (one node column per network input, and
    /// the edge columns of a 2D or a 3D mesh the network takes), the normaliser and the target
    /// moments (finite, non-negative variances, positive counts, one column per network input or
    /// one target) and the limits (positive).
    fn validate(&self, network: &MpnConfig) -> Result<(), String> {
        let (node, edge) = (self.features.node_dim(), [2, 3].map(|dim| self.features.edge_dim(dim)));
        if node != network.node_features {
            return Err(format!("features.node: {node} columns, the network takes {}", network.node_features));
        }
        if !edge.contains(&network.edge_features) {
            return Err(format!(
                "features.edge: {} columns in 2D and {} in 3D, the network takes {}",
                edge[0], edge[1], network.edge_features
            ));
        }
        if let Some(n) = &self.normaliser {
            check_moments("normaliser.node", &n.node, network.node_features)?;
            check_moments("normaliser.edge", &n.edge, network.edge_features)?;
        }
        if let Some(moments) = &self.target.moments {
            check_moments("target.moments", moments, 1)?;
        }
        check_limits(&self.limits)
    }

    /// Predicted element sizes for each state, from one batched forward pass of `network` in
    /// evaluation mode (no dropout, no autograd graph).
    pub fn predict<const D: usize>(&self, network: &Mpn, states: &[&MeshState<D>]) -> Result<Vec<Vec<f64>>> {
        if states.is_empty() {
            return Ok(Vec::new());
        }
        let mut batch = GraphBatch::from_graphs(states.iter().map(|s| &s.graph))?;
        if let Some(normaliser) = &self.normaliser {
            normaliser.normalise(&mut batch)?;
        }
        let z = network.predict(&batch)?;
        Ok(states
            .iter()
            .zip(batch.node_offsets.windows(2))
            .map(|(state, range)| self.target.sizes(&z[range[0] as usize..range[1] as usize], &state.mesh.sizes()))
            .collect())
    }
}

/// Predictions are made in batches of at most this many nodes (a rollout over many large
/// problems would not fit one batch in memory).
const PREDICTION_NODES: usize = 200_000;

/// A network with its predictor, as a [`SizingModel`]: the field of a mesh is the prediction on
/// its graph (columns from the problem), in batches of at most [`PREDICTION_NODES`] nodes.
pub struct AmberSizing<'m> {
    pub network: &'m Mpn,
    pub predictor: &'m Predictor,
}

impl SizingModel for AmberSizing<'_> {
    fn limits(&self) -> &MeshLimits {
        &self.predictor.limits
    }

    fn predict<const D: usize, P: Domain<D>>(
        &self,
        problems: &[&P],
        meshes: &[&Mesh<D>],
    ) -> Result<Vec<PredictedField<D>>> {
        let states: Vec<MeshState<D>> = problems
            .par_iter()
            .zip(meshes)
            .enumerate()
            .map(|(i, (p, m))| MeshState::new(*p, &self.predictor.features, (*m).clone()).map_err(in_problem(i)))
            .collect::<Result<_>>()?;
        let all: Vec<usize> = (0..states.len()).collect();
        let mut fields = Vec::with_capacity(states.len());
        for chunk in node_chunks(&all, |i| states[i].graph.num_nodes()) {
            let batch: Vec<&MeshState<D>> = chunk.iter().map(|&i| &states[i]).collect();
            let sizes = self.predictor.predict(self.network, &batch)?;
            fields.extend(sizes.into_iter().map(|sizes| PredictedField { mesh: None, sizes }));
        }
        Ok(fields)
    }
}

/// Splits `items` into consecutive chunks of at most [`PREDICTION_NODES`] nodes (a larger single
/// item forms a chunk alone).
fn node_chunks(items: &[usize], nodes: impl Fn(usize) -> usize) -> Vec<Vec<usize>> {
    let mut chunks: Vec<Vec<usize>> = Vec::new();
    let mut total = 0;
    for &i in items {
        let n = nodes(i);
        if chunks.is_empty() || total + n > PREDICTION_NODES {
            chunks.push(Vec::new());
            total = 0;
        }
        total += n;
        chunks.last_mut().expect("pushed").push(i);
    }
    chunks
}

/// A trained model ready for inference.
pub struct AmberModel {
    pub network: Mpn,
    pub predictor: Predictor,
}

impl AmberModel {
    /// Writes `model.safetensors`, `model.json` and `predictor.json` into `dir` (created if
    /// missing).
    pub fn save(trainer: &MpnTrainer, predictor: &Predictor, dir: &Path) -> Result<()> {
        std::fs::create_dir_all(dir).map_err(io_error(dir))?;
        trainer.save(&dir.join(WEIGHTS_FILE))?;
        Ok(write_json_atomic(&dir.join(PREDICTOR_FILE), predictor)?)
    }

    /// Loads a model directory written by [`Self::save`] (a training checkpoint directory is
    /// one too) for inference. Weights that are not finite or do not fit the network's
    /// configuration, and a predictor with invalid moments or limits, are errors naming the
    /// file and the tensor or field.
    pub fn load(dir: &Path) -> Result<Self> {
        let network = Mpn::load(&dir.join(WEIGHTS_FILE))?;
        let predictor = Predictor::read(&dir.join(PREDICTOR_FILE), network.config())?;
        Ok(Self { network, predictor })
    }

    /// Predicted element sizes for each state.
    pub fn predict<const D: usize>(&self, states: &[&MeshState<D>]) -> Result<Vec<Vec<f64>>> {
        self.predictor.predict(&self.network, states)
    }

    /// The model as a [`SizingModel`] for rollouts.
    pub fn sizing(&self) -> AmberSizing<'_> {
        AmberSizing { network: &self.network, predictor: &self.predictor }
    }
}
