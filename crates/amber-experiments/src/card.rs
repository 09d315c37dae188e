//! Model cards: what a trained model is for and where it came from, in `card.json` beside its
//! weights. `amber mesh --model` reads the task (which fixes how a geometry becomes a domain),
//! the initial size of M⁰ and the default number of generation steps from it; a reader of a
//! shipped model finds the command, data, commit, training time and scores that made it.

use std::path::{Path, PathBuf};

use amber_stdx::read_json;
use anyhow::Context;
use serde::{Deserialize, Serialize};

use crate::Task;
use crate::results::RunResult;

/// The card's file inside a model directory.
pub const CARD_FILE: &str = "card.json";

/// What a model is for and where it came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelCard {
    /// The task the model was trained on.
    pub task: Task,
    /// `amber-mean`, `amber-max`, `cnn-32`, ...
    pub method: String,
    /// Generation steps T the model was trained to take (its default at inference).
    pub inference_steps: usize,
    /// Edge length of the uniform M⁰ a new geometry starts from, in the training data's units.
    pub initial_size: f64,
    /// The command that trained it, run from the repository root.
    pub command: String,
    /// The training data.
    pub data: String,
    /// The commit of the code that trained it (`-dirty`: with uncommitted changes).
    pub commit: String,
    /// Wall time of the training, seconds.
    pub training_seconds: f64,
    /// Scores on held-out problems, when the command evaluated it.
    pub evaluation: Option<CardEvaluation>,
}

/// A model's scores on the problems it was evaluated on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CardEvaluation {
    /// Which problems, e.g. `console val (2 parts)`.
    pub problems: String,
    /// Mean normalised DCD after the last step.
    pub normalised_dcd: f64,
    /// Mean normalised DCD after each generation step.
    pub normalised_dcd_per_step: Vec<f64>,
    /// Mean elements of the final meshes and of the experts'.
    pub elements: f64,
    pub expert_elements: f64,
}

impl CardEvaluation {
    /// The scores of a run's row on the problems named `problems`.
    pub fn of(problems: &str, result: &RunResult) -> Self {
        Self {
            problems: problems.to_owned(),
            normalised_dcd: result.ndcd,
            normalised_dcd_per_step: result.ndcd_per_step.clone(),
            elements: result.elements,
            expert_elements: result.expert_elements,
        }
    }
}

impl ModelCard {
    /// Reads the card of the model directory `dir`.
    pub fn read(dir: &Path) -> anyhow::Result<Self> {
        let path = dir.join(CARD_FILE);
        read_json(&path).with_context(|| {
            format!("{}: the model has no readable card (models trained before cards existed need one)", path.display())
        })
    }

    /// Writes the card into the model directory `dir`.
    pub fn write(&self, dir: &Path) -> anyhow::Result<()> {
        crate::write_json(&dir.join(CARD_FILE), self)
    }
}

/// The model directory `model` names: an existing directory (a model, or a run whose `model/`
/// is taken), else the name of a model shipped in `shipped`.
pub fn resolve_model(model: &str, shipped: &Path) -> anyhow::Result<PathBuf> {
    let path = Path::new(model);
    if path.is_dir() {
        let inner = path.join(amber_train::MODEL_DIR);
        return Ok(if inner.is_dir() { inner } else { path.to_owned() });
    }
    let candidate = shipped.join(model);
    if !model.contains(['/', '\\']) && candidate.is_dir() {
        return Ok(candidate);
    }
    let mut names: Vec<String> = std::fs::read_dir(shipped)
        .map(|entries| entries.filter_map(|e| Some(e.ok()?.file_name().to_string_lossy().into_owned())).collect())
        .unwrap_or_default();
    names.sort();
    anyhow::bail!(
        "{model}: neither a model directory nor a shipped model (shipped, in {}: {})",
        shipped.display(),
        if names.is_empty() { "none".to_owned() } else { names.join(", ") }
    )
}
