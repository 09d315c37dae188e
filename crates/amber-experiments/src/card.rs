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
    /// The commit of the code that trained it (`-dirty`: with uncommitted changes), or, for a
    /// run resumed by other code, each session's with the step it started from.
    pub commit: String,
    /// Wall time of the training, seconds.
    pub training_seconds: f64,
    /// Scores on held-out problems, when the command evaluated it (and no calibration has
    /// changed its predictor since).
    pub evaluation: Option<CardEvaluation>,
    /// The last re-fit of its final step by `amber calibrate`, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<CardCalibration>,
}

/// How `amber calibrate` re-fitted a model's final step on a folder of expert meshes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CardCalibration {
    /// The command, as it was run.
    pub command: String,
    /// The expert meshes it was fitted on.
    pub data: String,
    /// The commit of the code that fitted it.
    pub commit: String,
    /// Generation steps the fit was made for.
    pub steps: usize,
    pub final_step_scale: f64,
    /// The count regression's slope, when the model has one.
    pub count_regression_slope: Option<f64>,
    /// The scores the card held before, those of the predictor the calibration replaced.
    pub evaluation_before: Option<CardEvaluation>,
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
    /// Reads the card of the model directory `dir`: at least one and at most
    /// `TrainingConfig::MAX_INFERENCE_STEPS` generation steps and a positive M⁰ size, or an error
    /// naming the card (`amber mesh` takes both from it).
    pub fn read(dir: &Path) -> anyhow::Result<Self> {
        let path = dir.join(CARD_FILE);
        let card: Self = read_json(&path).with_context(|| {
            format!("{}: the model has no readable card (models trained before cards existed need one)", path.display())
        })?;
        card.validate().map_err(|message| anyhow::anyhow!("{}: {message}", path.display()))?;
        Ok(card)
    }

    /// What a card could get wrong that the model's use would only meet far from the file.
    fn validate(&self) -> Result<(), String> {
        let max_steps = amber_train::TrainingConfig::MAX_INFERENCE_STEPS;
        if !(1..=max_steps).contains(&self.inference_steps) {
            return Err(format!("inference_steps is {}, not in 1..={max_steps}", self.inference_steps));
        }
        if !(self.initial_size.is_finite() && self.initial_size > 0.0) {
            return Err(format!("initial_size is {}, not a positive size", self.initial_size));
        }
        Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    fn card() -> ModelCard {
        ModelCard {
            task: Task::Poisson,
            method: "amber-mean".into(),
            inference_steps: 5,
            initial_size: 0.94667,
            command: "amber train".into(),
            data: "data/poisson".into(),
            commit: "5952202".into(),
            training_seconds: 1.0,
            evaluation: None,
            calibration: None,
        }
    }

    #[test]
    fn cards_without_a_step_or_a_positive_initial_size_are_rejected_naming_the_card() {
        // The fuzz inputs fuzz/corpus/model_dir/crash-card-*: `amber mesh` blamed a card with 0
        // steps on `--steps`, and a negative M⁰ size on the geometry.
        let dir = tempfile::tempdir().unwrap();
        card().write(dir.path()).unwrap();
        assert_eq!(ModelCard::read(dir.path()).unwrap(), card());
        let path = dir.path().join(CARD_FILE).display().to_string();
        let bad = [
            (ModelCard { inference_steps: 0, ..card() }, "inference_steps is 0"),
            (ModelCard { inference_steps: 10_001, ..card() }, "inference_steps is 10001"),
            (ModelCard { initial_size: -1.0, ..card() }, "initial_size is -1"),
            (ModelCard { initial_size: 0.0, ..card() }, "initial_size is 0"),
        ];
        for (card, needle) in bad {
            card.write(dir.path()).unwrap();
            let message = format!("{:#}", ModelCard::read(dir.path()).unwrap_err());
            assert!(message.contains(&path) && message.contains(needle), "{message}");
        }
    }
}
