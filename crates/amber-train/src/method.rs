//! A method as one value: the configuration of a run of either method ([`MethodConfig`]) and a
//! trained model of either method ([`TrainedModel`]), so that callers train, load and roll out
//! without knowing which one they hold.

use std::path::Path;

use amber_graph::NodeFeature;
use amber_tasks::{Domain, LOG_SIZE_COLUMN, MeshLimits, Problem};
use serde::{Deserialize, Serialize};

use crate::error::{Result, TrainError};
use crate::rollout::{FinalStep, FinalStepFit, GeneratedStep, fit_final_step, generate};
use crate::{
    AmberModel, CNN_PREDICTOR_FILE, CnnConfig, CnnModel, CnnTraining, DataConfig, Evaluation, MODEL_DIR, Rollout,
    Training, TrainingConfig, TrainingObserver,
};

/// The configuration of one run of either method.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MethodConfig {
    Amber(TrainingConfig),
    Cnn(CnnConfig),
}

impl MethodConfig {
    /// Generation steps of the method's rollouts (the CNN predicts once).
    pub fn inference_steps(&self) -> usize {
        match self {
            MethodConfig::Amber(c) => c.inference_steps,
            MethodConfig::Cnn(_) => 1,
        }
    }

    pub fn seed(&self) -> u64 {
        match self {
            MethodConfig::Amber(c) => c.seed,
            MethodConfig::Cnn(c) => c.seed,
        }
    }

    /// Gradient steps of the run.
    pub fn steps(&self) -> u64 {
        match self {
            MethodConfig::Amber(c) => c.steps,
            MethodConfig::Cnn(c) => c.steps,
        }
    }

    /// How many training and validation problems the run reads.
    pub fn data(&self) -> &DataConfig {
        match self {
            MethodConfig::Amber(c) => &c.data,
            MethodConfig::Cnn(c) => &c.data,
        }
    }

    /// Whether the run reads validation problems (AMBER does, the CNN does not validate).
    pub fn validates(&self) -> bool {
        matches!(self, MethodConfig::Amber(_))
    }

    /// Checks ranges and combinations; the message names the field.
    pub fn validate(&self) -> Result<()> {
        match self {
            MethodConfig::Amber(c) => c.validate(),
            MethodConfig::Cnn(c) => c.validate(),
        }
    }

    /// The config alone, untagged, as its run directory's `config.json` holds it.
    pub fn to_json(&self) -> serde_json::Value {
        let value = match self {
            MethodConfig::Amber(c) => serde_json::to_value(c),
            MethodConfig::Cnn(c) => serde_json::to_value(c),
        };
        value.expect("configs serialise")
    }

    /// Trains into `out_dir` until the config's last step, resuming its newest checkpoint (the
    /// configuration and problems must be those of the checkpointed run); AMBER validates on
    /// `val` as configured. Writes the final model to `out_dir/model`. `ready` is told the
    /// training's step and limits once it stands, before the first step.
    pub fn train<const D: usize, P: Problem<D>, O: TrainingObserver>(
        &self,
        train: Vec<P>,
        val: &[P],
        out_dir: &Path,
        observer: &mut O,
        ready: impl FnOnce(u64, &MeshLimits, &mut O),
    ) -> Result<()> {
        match self {
            MethodConfig::Amber(config) => {
                let mut training = Training::open(config.clone(), train, out_dir)?;
                let validation = Evaluation::new(val, training.limits())?;
                ready(training.step(), training.limits(), observer);
                training.run(out_dir, Some(&validation), observer)
            }
            MethodConfig::Cnn(config) => {
                let mut training = CnnTraining::open(config.clone(), train, out_dir)?;
                ready(training.step(), &training.predictor().limits, observer);
                training.run(out_dir, observer).map(|_| ())
            }
        }
    }
}

/// A trained model of either method, as a directory holds it.
pub enum TrainedModel {
    Amber(AmberModel),
    Cnn(CnnModel),
}

impl TrainedModel {
    /// Loads the model in `dir` (a run's `model/` or a checkpoint directory), of whichever method
    /// wrote it; a run directory is accepted for its `model/`.
    pub fn load(dir: &Path) -> Result<Self> {
        let dir = if dir.join(MODEL_DIR).is_dir() { dir.join(MODEL_DIR) } else { dir.to_owned() };
        if dir.join(CNN_PREDICTOR_FILE).exists() {
            Ok(TrainedModel::Cnn(CnnModel::load(&dir)?))
        } else if dir.join(crate::amber::PREDICTOR_FILE).exists() {
            Ok(TrainedModel::Amber(AmberModel::load(&dir)?))
        } else {
            Err(TrainError::InvalidConfig(format!(
                "{}: not a model directory (no {} or {CNN_PREDICTOR_FILE})",
                dir.display(),
                crate::amber::PREDICTOR_FILE
            )))
        }
    }

    /// h_min and the element budget, to read or to change (e.g. to scale fields to the budget).
    pub fn limits_mut(&mut self) -> &mut MeshLimits {
        match self {
            TrainedModel::Amber(m) => &mut m.predictor.limits,
            TrainedModel::Cnn(m) => &mut m.predictor.limits,
        }
    }

    /// Rolls the model out for `steps` generation steps on every problem of `evaluation`.
    pub fn rollouts<const D: usize, P: Problem<D>>(
        &self,
        evaluation: &Evaluation<'_, D, P>,
        steps: usize,
    ) -> Result<Vec<Rollout<D>>> {
        if let Some(problem) = evaluation.problems.first() {
            self.check_inputs(problem)?;
        }
        match self {
            TrainedModel::Amber(m) => Ok(evaluation.run(&m.sizing(), steps)?.0),
            TrainedModel::Cnn(m) => Ok(evaluation.run(&m.sizing(), steps)?.0),
        }
    }

    /// Meshes `domain` (no expert needed): `steps` generation steps from its M⁰, the last one as
    /// `last` asks (see [`generate`]).
    pub fn generate<const D: usize, P: Domain<D>>(
        &self,
        domain: &P,
        steps: usize,
        last: FinalStep,
    ) -> Result<Vec<GeneratedStep<D>>> {
        self.check_inputs(domain)?;
        match self {
            TrainedModel::Amber(m) => generate(&m.sizing(), domain, steps, last),
            TrainedModel::Cnn(m) => generate(&m.sizing(), domain, steps, last),
        }
    }

    /// Fits the model's final step scale to the element counts of the experts of `problems`
    /// after `steps` generation steps ([`fit_final_step`]), replacing any earlier one, and its
    /// count regression if it has one or `count_regression` asks for one; returns the fit.
    pub fn calibrate<const D: usize, P: Problem<D>>(
        &mut self,
        problems: &[P],
        steps: usize,
        count_regression: bool,
    ) -> Result<FinalStepFit> {
        self.limits_mut().final_step_scale = 1.0;
        let had_count = self.limits_mut().final_count.take().is_some();
        let fit = match self {
            TrainedModel::Amber(m) => fit_final_step(&m.sizing(), problems, steps)?,
            TrainedModel::Cnn(m) => fit_final_step(&m.sizing(), problems, steps)?,
        };
        self.limits_mut().final_step_scale = fit.scale;
        self.limits_mut().final_count = (had_count || count_regression).then_some(fit.count);
        Ok(fit)
    }

    /// Writes everything but the weights (normalisers, limits) into the model directory `dir`,
    /// which must hold this model's weights.
    pub fn write_predictor(&self, dir: &Path) -> Result<()> {
        let (file, json) = match self {
            TrainedModel::Amber(m) => (crate::amber::PREDICTOR_FILE, serde_json::to_value(&m.predictor)),
            TrainedModel::Cnn(m) => (CNN_PREDICTOR_FILE, serde_json::to_value(&m.predictor)),
        };
        let path = dir.join(file);
        let json = json.map_err(|source| TrainError::Json { path: path.clone(), source })?;
        Ok(amber_stdx::write_json_atomic(&path, &json)?)
    }

    /// Whether `domain` offers every per-element column the model reads beyond the geometric
    /// features and log h(K) (the CNN reads none).
    pub fn check_inputs<const D: usize, P: Domain<D>>(&self, domain: &P) -> Result<()> {
        let TrainedModel::Amber(m) = self else { return Ok(()) };
        let (own, offered) = (domain.feature_set(), domain.optional_inputs());
        let missing: Vec<String> = m
            .predictor
            .features
            .node
            .iter()
            .filter(|&f| !own.node.contains(f))
            .filter_map(|f| match f {
                NodeFeature::Column(name) if name != LOG_SIZE_COLUMN && !offered.contains(name) => Some(name.clone()),
                _ => None,
            })
            .collect();
        if missing.is_empty() { Ok(()) } else { Err(TrainError::MissingInputs(missing)) }
    }

    /// h_min and the element budget.
    pub fn limits(&self) -> &MeshLimits {
        match self {
            TrainedModel::Amber(m) => &m.predictor.limits,
            TrainedModel::Cnn(m) => &m.predictor.limits,
        }
    }
}
