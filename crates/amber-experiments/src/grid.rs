//! An experiment as a grid of independent runs (method × variant × setting × seed), so that a
//! scheduler can run them apart: each run writes only its own directory, is found again by its
//! key, and the outputs are collected from the runs' caches once all are done.

use std::path::PathBuf;

use amber_train::MethodConfig;
use anyhow::bail;
use serde::Serialize;

use crate::method::MethodSpec;
use crate::run::Run;

/// One run of an experiment, as a scheduler sees it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedRun {
    /// The run's directory under the runs root (`<task>/<setting>/<method>/seed<r>-<hash>`):
    /// what `run_one` takes.
    pub key: String,
    /// The run's directory: everything the run writes.
    pub dir: PathBuf,
    /// Method, setting and seed, for people.
    pub label: String,
}

/// What an experiment does with the runs it finds cached.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CachePolicy {
    /// Reuse finished runs and their evaluations; train and evaluate the rest (killed runs
    /// resume).
    #[default]
    Reuse,
    /// Delete the runs' directories first: every run is trained and evaluated afresh.
    Retrain,
    /// Train nothing: every run must have its evaluation cached (the runs of a plan are done),
    /// else the experiment fails naming those that have none.
    Require,
}

impl CachePolicy {
    /// Readies `runs` for the policy: deletes them for `Retrain`, checks them for `Require`.
    pub(crate) fn prepare<'a>(self, runs: impl IntoIterator<Item = &'a GridRun>) -> anyhow::Result<()> {
        match self {
            CachePolicy::Reuse => Ok(()),
            CachePolicy::Retrain => runs.into_iter().try_for_each(|r| r.run.clear()),
            CachePolicy::Require => {
                let runs: Vec<&GridRun> = runs.into_iter().collect();
                let missing: Vec<String> = runs
                    .iter()
                    .filter(|r| !r.run.is_evaluated())
                    .map(|r| format!("  {}: {}", r.run.label, r.run.dir.display()))
                    .collect();
                if !missing.is_empty() {
                    bail!(
                        "{} of the {} runs have no cached evaluation (run their lines of the plan, or run \
                         without --collect to train them here):\n{}",
                        missing.len(),
                        runs.len(),
                        missing.join("\n")
                    );
                }
                Ok(())
            }
        }
    }
}

/// A cell of an experiment's grid: the method, its seed and config, and the run directory they
/// key.
pub(crate) struct GridRun {
    pub spec: MethodSpec,
    pub seed: usize,
    pub config: MethodConfig,
    pub run: Run,
}

impl GridRun {
    /// Whether `key` names this run (a trailing `/` allowed: shells complete directories so).
    pub fn has_key(&self, key: &str) -> bool {
        self.run.key == key.trim_end_matches('/')
    }

    /// The run as a plan lists it.
    pub fn planned(&self) -> PlannedRun {
        PlannedRun { key: self.run.key.clone(), dir: self.run.dir.clone(), label: self.run.label.clone() }
    }
}

/// The error for a key that names none of `runs`: it lists the keys there are (a plan written
/// with other options or by other code names runs this experiment does not have).
pub(crate) fn unknown_run<'a>(key: &str, runs: impl IntoIterator<Item = &'a GridRun>) -> anyhow::Error {
    let keys: Vec<&str> = runs.into_iter().map(|r| r.run.key.as_str()).collect();
    anyhow::anyhow!(
        "no run of this experiment has the key `{key}` (was the plan written with other options or by other code?); \
         its runs: {}",
        keys.join(", ")
    )
}
