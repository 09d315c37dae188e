//! The results schema every experiment writes (`results.json`): per-problem evaluations are
//! reduced to one [`RunResult`] per (method, variant, difficulty, seed).

use amber_mesh::Mesh;
use amber_stdx::quantile;
use amber_tasks::Problem;
use amber_train::{MeshMetrics, Rollout, StepStatus};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// One test problem's rollout, as cached beside a trained run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProblemEvaluation {
    /// The problem's name ([`Problem::name`]); unknown in evaluations cached before schema 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// SHA-256 of the expert mesh ([`mesh_sha256`]): which data the problem was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expert_sha256: Option<String>,
    /// M⁰ against the expert.
    pub initial: MeshMetrics,
    /// Status and metrics after each generation step (failed steps carry the last mesh).
    pub steps: Vec<StepEvaluation>,
    /// d(M⁰, M*).
    pub initial_dcd: f64,
    /// d(M̂, M*).
    pub reconstruction_dcd: f64,
    /// Elements of the expert mesh.
    pub expert_elements: usize,
}

/// One generation step of a rollout.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepEvaluation {
    pub status: StepStatus,
    pub metrics: MeshMetrics,
}

impl ProblemEvaluation {
    /// The record of `rollout` of `problem`.
    pub fn of<const D: usize>(rollout: &Rollout<D>, problem: &impl Problem<D>) -> Self {
        Self {
            name: Some(problem.name()),
            expert_sha256: Some(mesh_sha256(problem.expert_mesh())),
            initial: rollout.initial,
            steps: rollout
                .steps
                .iter()
                .map(|s| StepEvaluation { status: s.status.clone(), metrics: s.metrics })
                .collect(),
            initial_dcd: rollout.initial_dcd,
            reconstruction_dcd: rollout.reconstruction_dcd,
            expert_elements: problem.expert_mesh().num_elements(),
        }
    }

    /// The metrics after the last step.
    pub fn last(&self) -> &MeshMetrics {
        self.steps.last().map_or(&self.initial, |s| &s.metrics)
    }
}

/// SHA-256 (hex) of a mesh's vertices (little-endian f64) followed by its cells (little-endian
/// u32): equal for the same mesh read from any file format.
pub fn mesh_sha256<const D: usize>(mesh: &Mesh<D>) -> String {
    let mut hasher = Sha256::new();
    for v in mesh.vertices() {
        v.iter().for_each(|c| hasher.update(c.to_le_bytes()));
    }
    mesh.cells().iter().for_each(|c| hasher.update(c.to_le_bytes()));
    hex(&hasher.finalize())
}

/// Lower-case hex of a digest.
fn hex(digest: &[u8]) -> String {
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// One trained and evaluated configuration: the means over the test problems.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    pub method: String,
    pub variant: String,
    pub difficulty: String,
    pub seed: usize,
    /// Test problems evaluated.
    pub test_problems: usize,
    /// SHA-256 of the test problems' expert mesh hashes in order: the same for the same test
    /// data; absent where an evaluation was cached before schema 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub test_data_sha256: Option<String>,
    /// Mean normalised DCD after the last generation step.
    pub ndcd: f64,
    /// 25 % and 75 % quantiles of the per-problem final normalised DCD.
    pub ndcd_quantiles: [f64; 2],
    /// Mean normalised DCD after each generation step.
    pub ndcd_per_step: Vec<f64>,
    /// Mean raw d(Mᵀ, M*).
    pub dcd: f64,
    /// Mean raw d(M⁰, M*).
    pub dcd_initial: f64,
    /// Mean raw d(M̂, M*).
    pub dcd_reconstruction: f64,
    /// Mean volume difference of Mᵀ and M*.
    pub volume_difference: f64,
    /// Mean elements of Mᵀ.
    pub elements: f64,
    /// Mean elements of M*.
    pub expert_elements: f64,
    /// Generation steps that were over budget or failed, over all problems.
    pub failed_steps: usize,
    pub train_seconds: f64,
    pub eval_seconds: f64,
    /// The threads behind those times (absent in runs recorded before they were kept).
    #[serde(default)]
    pub threads: RunThreads,
    /// The commit that trained the model, or each session's where a resumed run's differ
    /// (absent where the run recorded none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trained_by: Option<String>,
    /// Every test problem's rollout: the values the means above reduce.
    pub problems: Vec<ProblemEvaluation>,
}

/// The threads (rayon's pool) a run trained with, in its last session, and was evaluated with:
/// its wall times, and on more than one thread its bits, depend on them. `None` where a run was
/// recorded before runs kept them, or where a cross-validation's folds differ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunThreads {
    pub train: Option<usize>,
    pub eval: Option<usize>,
}

impl RunThreads {
    /// What the threads of several runs (a cross-validation's folds) have in common.
    pub fn common(all: impl IntoIterator<Item = RunThreads>) -> Self {
        let mut all = all.into_iter();
        let first = all.next().unwrap_or_default();
        all.fold(first, |common, next| RunThreads {
            train: common.train.filter(|_| common.train == next.train),
            eval: common.eval.filter(|_| common.eval == next.eval),
        })
    }
}

/// Where a run result came from, apart from its evaluations.
pub struct RunKey<'a> {
    pub method: &'a str,
    pub variant: &'a str,
    pub difficulty: &'a str,
    pub seed: usize,
    pub train_seconds: f64,
    pub eval_seconds: f64,
    pub threads: RunThreads,
}

impl RunResult {
    /// Reduces per-problem evaluations (at least one) to the run's row.
    pub fn new(key: RunKey<'_>, problems: &[ProblemEvaluation]) -> Self {
        let n = problems.len().max(1) as f64;
        let mean = |f: &dyn Fn(&ProblemEvaluation) -> f64| problems.iter().map(f).sum::<f64>() / n;
        let mut finals: Vec<f64> = problems.iter().map(|p| p.last().normalised_dcd).collect();
        finals.sort_by(f64::total_cmp);
        let steps = problems.iter().map(|p| p.steps.len()).min().unwrap_or(0);
        Self {
            method: key.method.into(),
            variant: key.variant.into(),
            difficulty: key.difficulty.into(),
            seed: key.seed,
            test_problems: problems.len(),
            test_data_sha256: problems
                .iter()
                .map(|p| p.expert_sha256.as_deref())
                .collect::<Option<Vec<_>>>()
                .map(|hashes| hex(&Sha256::digest(hashes.concat().as_bytes()))),
            ndcd: mean(&|p| p.last().normalised_dcd),
            ndcd_quantiles: [quantile(&finals, 0.25), quantile(&finals, 0.75)],
            ndcd_per_step: (0..steps).map(|t| mean(&|p| p.steps[t].metrics.normalised_dcd)).collect(),
            dcd: mean(&|p| p.last().dcd),
            dcd_initial: mean(&|p| p.initial_dcd),
            dcd_reconstruction: mean(&|p| p.reconstruction_dcd),
            volume_difference: mean(&|p| p.last().volume_difference),
            elements: mean(&|p| p.last().elements as f64),
            expert_elements: mean(&|p| p.expert_elements as f64),
            failed_steps: problems
                .iter()
                .flat_map(|p| &p.steps)
                .filter(|s| !matches!(s.status, StepStatus::Meshed))
                .count(),
            train_seconds: key.train_seconds,
            eval_seconds: key.eval_seconds,
            threads: key.threads,
            trained_by: None,
            problems: problems.to_vec(),
        }
    }
}

/// Version of the `results.json` schema: 2 added the per-problem values, the schema and amber
/// versions, and a commit that is always named; 3 the problems' names and data hashes.
pub const RESULTS_SCHEMA: u32 = 3;

/// `results.json`: one experiment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExperimentResults {
    /// Version of this schema ([`RESULTS_SCHEMA`]).
    pub schema: u32,
    /// The amber release that wrote the file.
    pub amber_version: String,
    /// `poisson`, `console` or `ablate`.
    pub experiment: String,
    pub profile: String,
    /// The commit the code was built from (`-dirty` with local changes; see [`crate::commit`]).
    pub commit: String,
    /// CPU, cores, memory, load.
    pub machine: serde_json::Value,
    /// Everything needed to rerun: the experiment's settings and each run's training config.
    pub config: serde_json::Value,
    pub runs: Vec<RunResult>,
}

impl ExperimentResults {
    /// The results of `runs`, stamped with this build's commit, version and machine.
    pub fn new(experiment: &str, profile: &str, config: serde_json::Value, runs: Vec<RunResult>) -> Self {
        Self {
            schema: RESULTS_SCHEMA,
            amber_version: env!("CARGO_PKG_VERSION").into(),
            experiment: experiment.into(),
            profile: profile.into(),
            commit: crate::commit().into(),
            machine: crate::machine(),
            config,
            runs,
        }
    }

    /// The runs trained (in some session) by code with uncommitted changes, each as
    /// "method setting seed r (trained by …)".
    pub fn runs_trained_by_uncommitted_code(&self) -> Vec<String> {
        self.runs
            .iter()
            .filter_map(|r| {
                let commits = r.trained_by.as_deref().filter(|c| c.contains("-dirty"))?;
                Some(format!("{} {} seed {} (trained by {commits})", crate::row_label(r), r.difficulty, r.seed))
            })
            .collect()
    }

    /// The problems the runs were evaluated on, for captions: the test problems, the split a
    /// task without a test split fell back to (`config.test_split`), or the training parts of a
    /// cross-validation (`config.experiment.folds`).
    pub fn evaluated_on(&self) -> String {
        if let Some(folds) = self.config["experiment"]["folds"].as_u64() {
            return format!(
                "the training parts of a {folds}-fold cross-validation, each scored by the model that did not train on it"
            );
        }
        match self.config["test_split"].as_str() {
            Some(split) if split != "test" => format!("the {split} problems (no test split)"),
            _ => "the test problems".into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metrics(ndcd: f64) -> MeshMetrics {
        MeshMetrics { dcd: ndcd, normalised_dcd: ndcd, chamfer: 0.0, volume_difference: 0.0, elements: 10 }
    }

    fn evaluation(per_step: &[f64], failed_last: bool) -> ProblemEvaluation {
        let steps = per_step
            .iter()
            .enumerate()
            .map(|(t, &v)| StepEvaluation {
                status: if failed_last && t + 1 == per_step.len() {
                    StepStatus::OverBudget { estimated_elements: 1e6 }
                } else {
                    StepStatus::Meshed
                },
                metrics: metrics(v),
            })
            .collect();
        ProblemEvaluation {
            name: None,
            expert_sha256: None,
            initial: metrics(1.0),
            steps,
            initial_dcd: 0.5,
            reconstruction_dcd: 0.2,
            expert_elements: 20,
        }
    }

    #[test]
    fn runs_reduce_to_means_quantiles_and_failure_counts() {
        let problems = [evaluation(&[0.8, 0.4], false), evaluation(&[0.6, 0.2], true), evaluation(&[0.7, 0.3], false)];
        let key = RunKey {
            method: "m",
            variant: "v",
            difficulty: "hard",
            seed: 0,
            train_seconds: 1.0,
            eval_seconds: 2.0,
            threads: RunThreads::default(),
        };
        let run = RunResult::new(key, &problems);
        assert!((run.ndcd - 0.3).abs() < 1e-12);
        assert!((run.ndcd_per_step[0] - 0.7).abs() < 1e-12 && (run.ndcd_per_step[1] - 0.3).abs() < 1e-12);
        assert!((run.ndcd_quantiles[0] - 0.25).abs() < 1e-12 && (run.ndcd_quantiles[1] - 0.35).abs() < 1e-12);
        assert_eq!(run.failed_steps, 1);
        assert_eq!((run.test_problems, run.expert_elements), (3, 20.0));
    }

    #[test]
    fn folds_share_the_threads_they_agree_on() {
        let threads = |train, eval| RunThreads { train: Some(train), eval: Some(eval) };
        let common = RunThreads::common([threads(1, 2), threads(1, 1), threads(1, 2)]);
        assert_eq!(common, RunThreads { train: Some(1), eval: None });
        assert_eq!(RunThreads::common([]), RunThreads::default());
    }

    /// Quick Console results of commit `0123abc` with `config` and `runs`.
    fn console_results(config: serde_json::Value, runs: Vec<RunResult>) -> ExperimentResults {
        ExperimentResults {
            schema: RESULTS_SCHEMA,
            amber_version: "0.1.0".into(),
            experiment: "console".into(),
            profile: "quick".into(),
            commit: "0123abc".into(),
            machine: serde_json::json!({}),
            config,
            runs,
        }
    }

    #[test]
    fn runs_trained_by_uncommitted_code_are_named() {
        let key = |seed| RunKey {
            method: "amber-mean",
            variant: "default",
            difficulty: "console",
            seed,
            train_seconds: 1.0,
            eval_seconds: 1.0,
            threads: RunThreads::default(),
        };
        let run = |seed, trained_by: Option<&str>| RunResult {
            trained_by: trained_by.map(String::from),
            ..RunResult::new(key(seed), &[evaluation(&[0.5], false)])
        };
        let runs = vec![
            run(0, Some("0123abc")),
            run(1, Some("0123abc (from step 0), 4567def-dirty (from step 500)")),
            run(2, None),
        ];
        let results = console_results(serde_json::json!({}), runs);
        assert_eq!(
            results.runs_trained_by_uncommitted_code(),
            ["amber-mean console seed 1 (trained by 0123abc (from step 0), 4567def-dirty (from step 500))"]
        );
    }

    #[test]
    fn captions_name_the_split_that_was_evaluated() {
        let results = |config| console_results(config, Vec::new());
        assert_eq!(
            results(serde_json::json!({ "test_split": "val" })).evaluated_on(),
            "the val problems (no test split)"
        );
        assert_eq!(results(serde_json::json!({ "test_split": "test" })).evaluated_on(), "the test problems");
        assert_eq!(results(serde_json::json!({})).evaluated_on(), "the test problems");
        let cv = results(serde_json::json!({ "test_split": "cross-validation", "experiment": { "folds": 4 } }));
        assert!(cv.evaluated_on().starts_with("the training parts of a 4-fold cross-validation, each"));
    }
}
