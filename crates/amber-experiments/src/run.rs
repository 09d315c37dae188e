//! One trained and evaluated configuration, for any task: its directory (named by a hash of
//! everything that determines it), training that resumes and is never repeated once finished,
//! evaluation on test problems cached beside it, and the test meshes kept for galleries.

use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_mesh::{Mesh, MeshData, read_mesh, write_mesh};
use amber_stdx::read_json;
use amber_tasks::MeshLimits;
use amber_tasks::Problem;
use amber_train::{
    CONFIG_FILE, Evaluation, EvaluationSummary, MODEL_DIR, MethodConfig, Rollout, StepReport, TrainedModel,
    TrainingObserver,
};
use anyhow::{Context, bail};
use serde::{Deserialize, Serialize};

use crate::card::{CardEvaluation, ModelCard};
use crate::method::MethodSpec;
use crate::profiles::Task;
use crate::progress::TrainingProgress;
use crate::report::{commit, config_hash, write_json};
use crate::results::{ProblemEvaluation, RunKey, RunResult, RunThreads};

/// Test problems whose rollouts are kept as meshes (`.vtu`) and drawn in the gallery.
pub(crate) const GALLERY_PROBLEMS: usize = 2;

/// Where a run directory records its training wall time.
const TIME_FILE: &str = "training_time.json";

/// The name an evaluation is cached under: the test set's, and how over-budget fields are
/// treated when they are scaled.
pub(crate) fn evaluation_name(test_name: String, scale_to_budget: bool) -> String {
    if scale_to_budget { format!("{test_name}, fields scaled to the budget") } else { test_name }
}

/// A run's evaluation on a test set, as cached in its directory.
#[derive(Serialize, Deserialize)]
pub(crate) struct CachedEvaluation {
    pub test_set: String,
    pub train_seconds: f64,
    pub eval_seconds: f64,
    #[serde(default)]
    pub threads: RunThreads,
    pub problems: Vec<ProblemEvaluation>,
    /// The commits that trained the model, read from its run directory's record (not cached:
    /// runs evaluated before it was kept have it too).
    #[serde(skip)]
    pub trained_by: Option<String>,
}

impl CachedEvaluation {
    /// The evaluations of a cross-validation's folds (at least one) as one: every fold's
    /// problems in fold order, the folds' summed training and evaluation times.
    pub fn pooled(folds: Vec<CachedEvaluation>) -> Self {
        Self {
            test_set: folds.iter().map(|f| f.test_set.as_str()).collect::<Vec<_>>().join("; "),
            train_seconds: folds.iter().map(|f| f.train_seconds).sum(),
            eval_seconds: folds.iter().map(|f| f.eval_seconds).sum(),
            threads: RunThreads::common(folds.iter().map(|f| f.threads)),
            trained_by: distinct_commits(folds.iter().map(|f| f.trained_by.as_deref())),
            problems: folds.into_iter().flat_map(|f| f.problems).collect(),
        }
    }

    /// The run's row of `results.json`.
    pub fn result(&self, spec: &MethodSpec, setting: &str, seed: usize) -> RunResult {
        let key = RunKey {
            method: &spec.method.name(),
            variant: &spec.variant.name,
            difficulty: setting,
            seed,
            train_seconds: self.train_seconds,
            eval_seconds: self.eval_seconds,
            threads: self.threads,
        };
        RunResult { trained_by: self.trained_by.clone(), ..RunResult::new(key, &self.problems) }
    }
}

/// The distinct commits of `commits` in order of appearance, comma-separated (`None` if any is
/// unknown).
fn distinct_commits<'a>(commits: impl IntoIterator<Item = Option<&'a str>>) -> Option<String> {
    let mut distinct: Vec<&str> = Vec::new();
    for commit in commits {
        let commit = commit?;
        if !distinct.contains(&commit) {
            distinct.push(commit);
        }
    }
    Some(distinct.join(", "))
}

/// What the model card of an experiment's runs says about their task and data.
pub(crate) struct RunOrigin {
    pub task: Task,
    /// Edge length of M⁰.
    pub initial_size: f64,
    /// The training data, for people.
    pub data: String,
}

/// A run directory: `<runs>/<task>/<setting>/<method>[-<variant>]/seed<r>-<hash>`, where the
/// hash covers the config and `data` (what identifies the training data).
pub(crate) struct Run {
    /// The directory's path under the runs root: the run's name in a plan.
    pub key: String,
    pub dir: PathBuf,
    pub label: String,
    test_name: String,
    eval_dir: PathBuf,
    /// The model's card, short of what training and evaluation fill in.
    card: ModelCard,
}

impl Run {
    pub fn new(
        runs_root: &Path,
        origin: &RunOrigin,
        setting: &str,
        spec: &MethodSpec,
        config: &MethodConfig,
        data: serde_json::Value,
        test_name: &str,
    ) -> Self {
        let name = match spec.variant.name.as_str() {
            "default" => spec.method.name(),
            variant => format!("{}-{variant}", spec.method.name()),
        };
        let hashed = serde_json::json!({ "config": config.to_json(), "data": data });
        let key = format!("{}/{setting}/{name}/seed{}-{}", origin.task.name(), config.seed(), config_hash(&hashed));
        let dir = runs_root.join(&key);
        // Evaluations are keyed by the test set and how it is evaluated.
        let eval_dir = dir.join(format!("eval-{}", config_hash(&serde_json::json!(test_name))));
        let label = format!("{} {setting} seed {}", spec.label(), config.seed());
        let card = ModelCard {
            task: origin.task,
            method: name,
            inference_steps: config.inference_steps(),
            initial_size: origin.initial_size,
            command: String::new(),
            data: format!("{}, seed {}", origin.data, config.seed()),
            commit: String::new(),
            training_seconds: 0.0,
            evaluation: None,
            calibration: None,
        };
        Self { key, dir, label, test_name: test_name.into(), eval_dir, card }
    }

    fn evaluation_path(&self) -> PathBuf {
        self.eval_dir.join("evaluation.json")
    }

    /// Whether the run's evaluation on its test set is cached (the run is done).
    pub fn is_evaluated(&self) -> bool {
        self.evaluation_path().exists()
    }

    /// Deletes what the run directory holds, so that the run is trained and evaluated afresh.
    pub fn clear(&self) -> anyhow::Result<()> {
        if self.dir.exists() {
            std::fs::remove_dir_all(&self.dir)
                .with_context(|| format!("{}: cannot remove for --force", self.dir.display()))?;
        }
        Ok(())
    }

    /// Trains the run with `train` (which must resume or reuse what `dir` holds; it returns the
    /// training time), then evaluates the model on `test`, scaling fields over the element
    /// budget to it if `scale_to_budget` (spec §11) instead of skipping the step; a cached
    /// evaluation skips both.
    pub fn train_and_evaluate<const D: usize, P: Problem<D>>(
        &self,
        config: &MethodConfig,
        test: &[P],
        scale_to_budget: bool,
        train: impl FnOnce(&Path, &str) -> anyhow::Result<f64>,
    ) -> anyhow::Result<CachedEvaluation> {
        let cache = self.evaluation_path();
        if cache.exists() {
            let cached: CachedEvaluation = read_json(&cache)?;
            println!("{}: reusing the evaluation in {}", self.label, cache.display());
            self.write_card(&cached)?;
            return Ok(CachedEvaluation { trained_by: self.training_record()?.commits(), ..cached });
        }
        let train_seconds = train(&self.dir, &self.label)?;
        let started = Instant::now();
        let mut model = TrainedModel::load(&self.dir.join(MODEL_DIR))?;
        model.limits_mut().scale_to_budget = scale_to_budget;
        let evaluation = Evaluation::new(test, model.limits())?;
        let rollouts = model.rollouts(&evaluation, config.inference_steps())?;
        let eval_seconds = started.elapsed().as_secs_f64();
        let problems: Vec<ProblemEvaluation> =
            rollouts.iter().zip(test).map(|(r, p)| ProblemEvaluation::of(r, p)).collect();
        self.save_gallery_meshes(&rollouts)?;
        let summary = EvaluationSummary::new(test, &rollouts);
        println!(
            "{}: test normalised DCD {:.3} after {} steps ({} problems, {:.0} s)",
            self.label,
            summary.final_normalised_dcd().unwrap_or(f64::NAN),
            config.inference_steps(),
            test.len(),
            eval_seconds
        );
        let record = self.training_record()?;
        let threads = RunThreads { train: record.threads, eval: Some(rayon::current_num_threads()) };
        let evaluated = CachedEvaluation {
            test_set: self.test_name.clone(),
            train_seconds,
            eval_seconds,
            threads,
            problems,
            trained_by: record.commits(),
        };
        write_json(&cache, &evaluated)?;
        self.write_card(&evaluated)?;
        Ok(evaluated)
    }

    /// Writes the model's card, with the command and commit that trained it and its scores on
    /// the test set, so that `amber mesh` and `amber evaluate` take the run's model as they take
    /// a shipped one.
    fn write_card(&self, evaluated: &CachedEvaluation) -> anyhow::Result<()> {
        let model = self.dir.join(MODEL_DIR);
        if !model.is_dir() {
            return Ok(());
        }
        let record = self.training_record()?;
        let key = RunKey {
            method: &self.card.method,
            variant: "",
            difficulty: "",
            seed: 0,
            train_seconds: evaluated.train_seconds,
            eval_seconds: evaluated.eval_seconds,
            threads: evaluated.threads,
        };
        let result = RunResult::new(key, &evaluated.problems);
        let commit = record.commits();
        let card = ModelCard {
            command: record.command.unwrap_or_else(|| "unknown (trained before runs recorded it)".into()),
            commit: commit.unwrap_or_else(|| "unknown (trained before runs recorded it)".into()),
            training_seconds: evaluated.train_seconds,
            evaluation: Some(CardEvaluation::of(&evaluated.test_set, &result)),
            ..self.card.clone()
        };
        card.write(&model)
    }

    /// What the run directory records of its training (nothing before it trained).
    fn training_record(&self) -> anyhow::Result<TrainingRecord> {
        TrainingRecord::read(&self.dir)
    }

    fn gallery_path(&self, problem: usize, step: usize) -> PathBuf {
        self.eval_dir.join(format!("problem{problem:03}-step{}.vtu", step + 1))
    }

    /// Keeps every step's mesh of the first test problems as `.vtu` (ParaView) for the gallery.
    fn save_gallery_meshes<const D: usize>(&self, rollouts: &[Rollout<D>]) -> anyhow::Result<()> {
        std::fs::create_dir_all(&self.eval_dir)
            .with_context(|| format!("{}: cannot create directory", self.eval_dir.display()))?;
        for (k, rollout) in rollouts.iter().take(GALLERY_PROBLEMS).enumerate() {
            for (t, step) in rollout.steps.iter().enumerate() {
                let mut data = MeshData::default();
                data.cell.insert("size".into(), step.mesh.sizes());
                write_mesh(&step.mesh, self.gallery_path(k, t), &data)?;
            }
        }
        Ok(())
    }

    /// The saved gallery meshes, per problem, every step.
    pub fn gallery_meshes<const D: usize>(&self, steps: usize) -> anyhow::Result<Vec<Vec<Mesh<D>>>> {
        let mut meshes = Vec::new();
        for k in 0..GALLERY_PROBLEMS {
            let paths: Vec<PathBuf> = (0..steps).map(|t| self.gallery_path(k, t)).collect();
            if !paths.iter().all(|p| p.exists()) {
                break;
            }
            meshes.push(paths.iter().map(read_mesh).collect::<Result<_, _>>()?);
        }
        Ok(meshes)
    }
}

/// Trains the run of `config` into `dir` until its last step: resumes from the newest checkpoint
/// in `dir`, validates (AMBER) on the validation problems as configured, writes the model to
/// `dir/model`. A finished run of the same config is not retrained (and `problems` is not
/// called). Returns the training wall time, summed over resumed sessions; `label` names the run
/// in progress lines. `problems` gives the training and, when the method validates, the
/// validation problems (it is told whether to load them).
pub fn train_run<const D: usize, P: Problem<D>>(
    config: &MethodConfig,
    problems: impl FnOnce(bool) -> anyhow::Result<(Vec<P>, Vec<P>)>,
    dir: &Path,
    label: &str,
) -> anyhow::Result<f64> {
    if let Some(seconds) = finished_run(dir, config)? {
        return Ok(seconds);
    }
    let (train, val) = problems(config.validates())?;
    let mut progress = TimedProgress::start(dir, label, config.steps())?;
    let announce = |step: u64, limits: &MeshLimits, progress: &mut TimedProgress| {
        progress.resume_at(step);
        progress.inner.println(&format!(
            "{} at step {step} in {}: h_min {:.3e}, budget {} elements",
            if step > 0 { "resumed" } else { "training" },
            dir.display(),
            limits.min_size,
            limits.max_elements
        ));
    };
    config.train(train, &val, dir, &mut progress, announce)?;
    progress.finish()
}

/// The commits that trained the run in `dir`, as a model card names them: one commit, or each
/// session's with the step it started at when a resumed run's sessions ran different code
/// (`None` if the directory holds no record of them).
pub fn training_commits(dir: &Path) -> anyhow::Result<Option<String>> {
    Ok(TrainingRecord::read(dir)?.commits())
}

/// Training wall time, accumulated over resumed sessions, the command, commit and threads of the
/// last session, and the commit of every session.
#[derive(Default, Serialize, Deserialize)]
struct TrainingRecord {
    seconds: f64,
    finished: bool,
    /// Absent in runs trained before they were recorded.
    #[serde(default)]
    command: Option<String>,
    #[serde(default)]
    commit: Option<String>,
    /// The threads of the last session (absent in runs trained before they were recorded).
    #[serde(default)]
    threads: Option<usize>,
    /// Every session, first to last (empty in runs trained before they were recorded).
    #[serde(default)]
    sessions: Vec<TrainingSession>,
}

/// One session of a run's training: the code that ran it, from which step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct TrainingSession {
    commit: String,
    first_step: u64,
}

impl TrainingRecord {
    fn read(dir: &Path) -> anyhow::Result<Self> {
        let path = dir.join(TIME_FILE);
        Ok(if path.exists() { read_json(&path)? } else { Self::default() })
    }

    fn now(seconds: f64, finished: bool, sessions: Vec<TrainingSession>) -> Self {
        Self {
            seconds,
            finished,
            command: Some(std::env::args().collect::<Vec<_>>().join(" ")),
            commit: Some(commit().to_owned()),
            threads: Some(rayon::current_num_threads()),
            sessions,
        }
    }

    /// See [`training_commits`].
    fn commits(&self) -> Option<String> {
        let mut runs: Vec<&TrainingSession> = Vec::new();
        for session in &self.sessions {
            if runs.last().is_none_or(|last| last.commit != session.commit) {
                runs.push(session);
            }
        }
        match runs.as_slice() {
            [] => self.commit.clone(),
            [only] => Some(only.commit.clone()),
            _ => Some(
                runs.iter()
                    .map(|s| format!("{} (from step {})", s.commit, s.first_step))
                    .collect::<Vec<_>>()
                    .join(", "),
            ),
        }
    }
}

/// The training time of `dir` if it holds a finished run of `config`; an error if it holds a
/// finished run of another configuration.
fn finished_run(dir: &Path, config: &MethodConfig) -> anyhow::Result<Option<f64>> {
    let time_path = dir.join(TIME_FILE);
    let time: TrainingRecord = if time_path.exists() { read_json(&time_path)? } else { TrainingRecord::default() };
    if !(time.finished && dir.join(MODEL_DIR).exists()) {
        return Ok(None);
    }
    if read_json::<serde_json::Value>(&dir.join(CONFIG_FILE))? != config.to_json() {
        bail!(
            "{}: holds a finished run with another configuration; train into a new directory or delete it",
            dir.display()
        );
    }
    Ok(Some(time.seconds))
}

/// The progress bar plus a record of the training wall time at every checkpoint, so the time
/// of a resumed run counts its earlier sessions.
struct TimedProgress {
    inner: TrainingProgress,
    time_path: PathBuf,
    before: f64,
    started: Instant,
    /// The earlier sessions' and this one's (last).
    sessions: Vec<TrainingSession>,
}

impl TimedProgress {
    /// Progress of the run in `dir` of `total` steps, its clock continuing from the time
    /// recorded there.
    fn start(dir: &Path, label: &str, total: u64) -> anyhow::Result<Self> {
        let record = TrainingRecord::read(dir)?;
        let mut sessions = record.sessions;
        if sessions.is_empty() && record.seconds > 0.0 {
            // A run recorded before its sessions were: its last session's commit from step 0.
            let commit = record.commit.unwrap_or_else(|| "unknown".into());
            sessions.push(TrainingSession { commit, first_step: 0 });
        }
        sessions.push(TrainingSession { commit: commit().to_owned(), first_step: 0 });
        Ok(Self {
            inner: TrainingProgress::new(label, 0, total),
            time_path: dir.join(TIME_FILE),
            before: record.seconds,
            started: Instant::now(),
            sessions,
        })
    }

    /// The run stands at step `done` (it resumed there).
    fn resume_at(&mut self, done: u64) {
        self.inner.set_position(done);
        if let Some(session) = self.sessions.last_mut() {
            session.first_step = done;
        }
    }

    fn seconds(&self) -> f64 {
        self.before + self.started.elapsed().as_secs_f64()
    }

    /// Records the run as finished; returns its total training time.
    fn finish(self) -> anyhow::Result<f64> {
        self.inner.finish();
        let time = TrainingRecord::now(self.seconds(), true, self.sessions.clone());
        write_json(&self.time_path, &time)?;
        Ok(time.seconds)
    }

    fn record(&mut self) {
        let time = TrainingRecord::now(self.seconds(), false, self.sessions.clone());
        if let Err(e) = write_json(&self.time_path, &time) {
            self.inner.println(&format!("warning: {e:#}"));
        }
    }
}

impl TrainingObserver for TimedProgress {
    fn step(&mut self, report: &StepReport, total: u64) {
        self.inner.step(report, total);
    }

    fn validation(&mut self, step: u64, summary: &EvaluationSummary) {
        self.inner.validation(step, summary);
    }

    fn final_validation(&mut self, step: u64, summary: &EvaluationSummary) {
        self.inner.final_validation(step, summary);
    }

    fn checkpoint(&mut self, step: u64, dir: &Path) {
        self.inner.checkpoint(step, dir);
        self.record();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session(commit: &str, first_step: u64) -> TrainingSession {
        TrainingSession { commit: commit.into(), first_step }
    }

    #[test]
    fn a_card_names_every_commit_that_trained_a_resumed_run() {
        let record = |sessions| TrainingRecord { commit: Some("c".into()), sessions, ..TrainingRecord::default() };
        assert_eq!(record(vec![]).commits().as_deref(), Some("c"), "a run recorded before its sessions");
        assert_eq!(record(vec![session("a", 0), session("a", 500)]).commits().as_deref(), Some("a"));
        let mixed = record(vec![session("a", 0), session("a", 500), session("b-dirty", 1000), session("a", 1100)]);
        assert_eq!(mixed.commits().as_deref(), Some("a (from step 0), b-dirty (from step 1000), a (from step 1100)"));
        assert_eq!(TrainingRecord::default().commits(), None);
    }

    #[test]
    fn pooled_folds_name_their_distinct_commits() {
        assert_eq!(distinct_commits([Some("a"), Some("b"), Some("a")]).as_deref(), Some("a, b"));
        assert_eq!(distinct_commits([Some("a"), None]), None);
    }
}
