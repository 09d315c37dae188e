//! Progress callbacks of both methods' training loops: binaries draw bars with them, the library
//! never prints.

use std::path::Path;

use crate::{AmberStepReport, CnnStepReport, EvaluationSummary};

/// One gradient step of either method.
#[derive(Clone, Debug, PartialEq)]
pub enum StepReport {
    Amber(AmberStepReport),
    Cnn(CnnStepReport),
}

impl StepReport {
    /// Gradient steps completed, this one included.
    pub fn step(&self) -> u64 {
        match self {
            StepReport::Amber(r) => r.step,
            StepReport::Cnn(r) => r.step,
        }
    }

    /// The loss the step minimised.
    pub fn loss(&self) -> f64 {
        match self {
            StepReport::Amber(r) => r.loss,
            StepReport::Cnn(r) => r.loss,
        }
    }

    /// Wall time of the step (AMBER's includes the buffer addition that followed it).
    pub fn seconds(&self) -> f64 {
        match self {
            StepReport::Amber(r) => r.seconds,
            StepReport::Cnn(r) => r.seconds,
        }
    }
}

/// Progress callbacks of [`Training::run`](crate::Training::run) and
/// [`CnnTraining::run`](crate::CnnTraining::run). Every method has an empty default.
pub trait TrainingObserver {
    /// After every gradient step.
    fn step(&mut self, _report: &StepReport, _total_steps: u64) {}
    /// After every validation rollout (AMBER only: the CNN does not validate).
    fn validation(&mut self, _step: u64, _summary: &EvaluationSummary) {}
    /// After the final step's fit (`calibrate_element_count`), the validation of the model as
    /// saved: what `amber evaluate` gives on the validation problems, where the last
    /// [`validation`](Self::validation) came before the fit.
    fn final_validation(&mut self, _step: u64, _summary: &EvaluationSummary) {}
    /// After every checkpoint.
    fn checkpoint(&mut self, _step: u64, _dir: &Path) {}
}

/// Observes nothing.
impl TrainingObserver for () {}
