//! A trained AMBER model: the network plus everything needed to turn meshes into sizing fields
//! (input normaliser, target transform, clip and budget), saved and loaded as one directory.

use std::path::Path;

use amber_graph::{FeatureNormaliser, FeatureSet, GraphBatch};
use amber_mpn::{Mpn, MpnTrainer};
use amber_stdx::{read_json, write_json_atomic};
use serde::{Deserialize, Serialize};

use crate::error::{Result, io_error};
use amber_tasks::{MeshLimits, MeshState};

use crate::TargetTransform;

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
    /// one too) for inference.
    pub fn load(dir: &Path) -> Result<Self> {
        let network = Mpn::load(&dir.join(WEIGHTS_FILE))?;
        let predictor = read_json(&dir.join(PREDICTOR_FILE))?;
        Ok(Self { network, predictor })
    }

    /// Predicted element sizes for each state.
    pub fn predict<const D: usize>(&self, states: &[&MeshState<D>]) -> Result<Vec<Vec<f64>>> {
        self.predictor.predict(&self.network, states)
    }
}
