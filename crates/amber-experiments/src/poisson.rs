//! The Poisson experiment (spec §1, §6, §7, §10): datasets → training of every method ×
//! difficulty × seed (cached runs, resumable) → rollouts on the test problems → `results.json`,
//! `table.md`, bar and per-step charts and a mesh gallery.

use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_mesh::{Mesh2, MeshData, write_mesh};
use amber_tasks::poisson::{Difficulty, PoissonProblem, Split, load_split, read_split};
use amber_train::{
    AmberModel, CONFIG_FILE, CnnConfig, CnnModel, CnnObserver, CnnStepReport, CnnTraining, Evaluation, EvaluationSummary,
    MODEL_DIR, Profile, Rollout, Training, TrainingConfig, TrainingObserver,
};
use anyhow::{Context, bail};
use serde::{Deserialize, Serialize};

use crate::method::{Method, MethodSpec, Variant};
use crate::plots::{Bar, Series, Tile, bar_chart, line_chart, mesh_gallery};
use crate::progress::{TrainingProgress, item_bar};
use crate::report::{commit, config_hash, machine, merge_json, read_json, write_atomic, write_json};
use crate::results::{ExperimentResults, ProblemEvaluation, RunKey, RunResult};
use crate::table;

/// Test problems whose rollouts are kept as meshes (`.vtu`) and drawn in the gallery.
const GALLERY_PROBLEMS: usize = 2;

/// Everything an invocation of the Poisson experiment decides.
#[derive(Clone, Debug, Serialize)]
pub struct PoissonExperiment {
    /// `poisson` (the paper's comparison) or `ablate` (its ablations); names the results.
    pub experiment: String,
    pub profile: Profile,
    pub difficulties: Vec<Difficulty>,
    /// Training seeds 0..seeds (each has its own training problems).
    pub seeds: usize,
    pub methods: Vec<MethodSpec>,
    /// Root of the generated datasets (`<root>/<difficulty>/<split>`).
    pub data_root: PathBuf,
    /// Split seeds and sizes.
    pub manifest: PathBuf,
    /// Root of the cached training runs.
    pub runs_root: PathBuf,
    /// Where results.json, table.md and the pictures go.
    pub out: PathBuf,
    /// Evaluate on the problem files of this directory instead of the generated test split.
    pub test_set: Option<PathBuf>,
    /// Evaluate on the first this many test problems (default: the whole split).
    pub test_problems: Option<usize>,
    /// Fields merged into every AMBER run's training config (a `--config` file).
    pub overrides: serde_json::Value,
    /// Fields merged into every CNN run's config.
    pub cnn_overrides: serde_json::Value,
    /// Retrain and re-evaluate even when cached.
    pub force: bool,
}

impl PoissonExperiment {
    /// The defaults of a profile: `smoke` runs the whole chain on two easy problems in a few
    /// minutes; `quick` is the hard difficulty with one seed; `paper` all difficulties, 4 seeds.
    pub fn new(profile: Profile) -> Self {
        let (difficulties, seeds, test_problems) = match profile {
            Profile::Smoke => (vec![Difficulty::Easy], 1, Some(3)),
            Profile::Quick => (vec![Difficulty::Hard], 1, None),
            Profile::Paper => (Difficulty::ALL.to_vec(), 4, None),
        };
        Self {
            experiment: "poisson".into(),
            profile,
            difficulties,
            seeds,
            methods: Method::DEFAULT.into_iter().map(MethodSpec::plain).collect(),
            data_root: PathBuf::from("data/poisson"),
            manifest: PathBuf::from("datasets/poisson.json"),
            runs_root: PathBuf::from("data/runs"),
            out: PathBuf::from("results/poisson"),
            test_set: None,
            test_problems,
            overrides: serde_json::json!({}),
            cnn_overrides: serde_json::json!({}),
            force: false,
        }
    }

    /// The ablations of spec §10 on Poisson hard (easy for `smoke`), each a variant of the same
    /// training code: AMBER-Mean and AMBER-Max as configured (their per-step curves are the
    /// generation-steps study), both with the CNN's log-MSE loss, AMBER-Max without the softplus
    /// output, with uniformly random buffer additions, without input normalisation, with 5, 10,
    /// 50 and 100 training problems (20 is the default); the 256² CNN with its log-MSE loss,
    /// with MSE after a softplus, with plain MSE on raw sizes, and with max-aggregated labels.
    /// Writes `results/ablate/`.
    pub fn ablation(profile: Profile) -> Self {
        let mut experiment = Self::new(profile);
        experiment.experiment = "ablate".into();
        experiment.out = PathBuf::from("results/ablate");
        experiment.seeds = 1;
        experiment.difficulties = vec![if profile == Profile::Smoke { Difficulty::Easy } else { Difficulty::Hard }];
        let variant = |method, name: &str, overrides| MethodSpec { method, variant: Variant::new(name, overrides) };
        let log_loss = serde_json::json!({ "objective": "log" });
        experiment.methods = vec![
            MethodSpec::plain(Method::AmberMean),
            MethodSpec::plain(Method::AmberMax),
            variant(Method::AmberMean, "log-loss", log_loss.clone()),
            variant(Method::AmberMax, "log-loss", log_loss),
            variant(Method::AmberMax, "no-softplus", serde_json::json!({ "objective": "linear", "normalise_labels": false })),
            variant(Method::AmberMax, "random-buffer", serde_json::json!({ "source_selection": "uniform" })),
            variant(Method::AmberMax, "no-input-normalisation", serde_json::json!({ "normalise_inputs": false })),
        ];
        let cnn = Method::Cnn { resolution: if profile == Profile::Smoke { 32 } else { 256 } };
        experiment.methods.extend([
            MethodSpec::plain(cnn),
            variant(cnn, "softplus-mse", serde_json::json!({ "loss": "softplus_mse", "normalise_labels": false })),
            variant(cnn, "plain-mse", serde_json::json!({ "loss": "mse", "normalise_labels": false })),
            variant(cnn, "max-labels", serde_json::json!({ "aggregation": "max" })),
        ]);
        let default_problems = TrainingConfig::profile(profile).data.train_problems;
        let sizes: &[usize] = if profile == Profile::Smoke { &[1, 3] } else { &[5, 10, 50, 100] };
        for &n in sizes.iter().filter(|&&n| n != default_problems) {
            experiment.methods.push(variant(
                Method::AmberMax,
                &format!("{n}-problems"),
                serde_json::json!({ "data": { "train_problems": n } }),
            ));
        }
        experiment
    }

    /// The configuration of one run: the profile's, with the method's labels, the variant's and
    /// the user's overrides (AMBER runs: `overrides`, CNN runs: `cnn_overrides`), the difficulty
    /// and the seed.
    pub fn run_config(&self, spec: &MethodSpec, difficulty: Difficulty, seed: usize) -> anyhow::Result<RunConfig> {
        fn patched<T: Serialize + serde::de::DeserializeOwned>(
            base: &T,
            overrides: [&serde_json::Value; 2],
            spec: &MethodSpec,
        ) -> anyhow::Result<T> {
            let mut value = serde_json::to_value(base)?;
            overrides.iter().for_each(|o| merge_json(&mut value, o));
            serde_json::from_value(value)
                .with_context(|| format!("the overrides of {} do not fit its configuration", spec.label()))
        }
        Ok(match spec.method {
            Method::AmberMean | Method::AmberMax => {
                let mut config = TrainingConfig::profile(self.profile);
                config.aggregation = spec.method.aggregation();
                config.data.difficulty = difficulty;
                config.seed = seed as u64;
                let config = patched(&config, [&self.overrides, &spec.variant.overrides], spec)?;
                config.validate()?;
                RunConfig::Amber(config)
            }
            Method::Cnn { resolution } => {
                let mut config = CnnConfig::profile(self.profile);
                config.resolution = resolution;
                config.aggregation = spec.method.aggregation();
                config.data.difficulty = difficulty;
                config.seed = seed as u64;
                let config = patched(&config, [&self.cnn_overrides, &spec.variant.overrides], spec)?;
                config.validate()?;
                RunConfig::Cnn(config)
            }
        })
    }

    /// Runs the experiment and writes its outputs under `out`.
    pub fn run(&self) -> anyhow::Result<ExperimentResults> {
        if self.methods.is_empty() || self.difficulties.is_empty() || self.seeds == 0 {
            bail!("nothing to run: give at least one method, difficulty and seed");
        }
        let mut runs = Vec::new();
        let mut configs = Vec::new();
        let mut galleries = Vec::new();
        for &difficulty in &self.difficulties {
            let (test, test_name) = self.test_problems(difficulty)?;
            let mut rows = Vec::new();
            for seed in 0..self.seeds {
                for spec in &self.methods {
                    let config = self.run_config(spec, difficulty, seed)?;
                    let run = Run::new(self, spec, &config, &test_name)?;
                    let evaluated = run.train_and_evaluate(self, &config, &test)?;
                    configs.push(serde_json::json!({
                        "method": spec.method, "variant": spec.variant.name, "difficulty": difficulty.name(),
                        "seed": seed, "run_dir": run.dir, "training": config.to_json()?,
                    }));
                    runs.push(RunResult::new(
                        RunKey {
                            method: &spec.method.name(),
                            variant: &spec.variant.name,
                            difficulty: difficulty.name(),
                            seed,
                            train_seconds: evaluated.train_seconds,
                            eval_seconds: evaluated.eval_seconds,
                        },
                        &evaluated.problems,
                    ));
                    if seed == 0 && spec.variant.name == "default" {
                        rows.push((spec.label(), run.gallery_meshes(config.inference_steps())?));
                    }
                }
            }
            galleries.push((difficulty, test, rows));
        }
        let results = ExperimentResults {
            experiment: self.experiment.clone(),
            profile: self.profile.name().into(),
            commit: commit(),
            machine: machine(),
            config: serde_json::json!({ "experiment": self, "runs": configs }),
            runs,
        };
        self.write_outputs(&results, &galleries)?;
        Ok(results)
    }

    /// The test problems of a difficulty and a name that identifies them in caches.
    fn test_problems(&self, difficulty: Difficulty) -> anyhow::Result<(Vec<PoissonProblem>, String)> {
        let (mut problems, name) = match &self.test_set {
            Some(dir) => (read_split(dir)?, format!("external {}", dir.display())),
            None => {
                let bar = item_bar(&format!("{difficulty} test problems"), self.test_problems.unwrap_or(100));
                let (problems, _) = load_split(
                    &self.data_root,
                    &self.manifest,
                    difficulty,
                    Split::Test,
                    0,
                    self.test_problems,
                    &|| bar.inc(1),
                )?;
                bar.finish_and_clear();
                (problems, format!("{difficulty} test"))
            }
        };
        if let Some(n) = self.test_problems {
            problems.truncate(n);
        }
        if problems.is_empty() {
            bail!("no test problems for {difficulty}");
        }
        let name = format!("{name} ({} problems)", problems.len());
        Ok((problems, name))
    }

    fn write_outputs(
        &self,
        results: &ExperimentResults,
        galleries: &[(Difficulty, Vec<PoissonProblem>, Vec<(String, Vec<Mesh2>)>)],
    ) -> anyhow::Result<()> {
        write_json(&self.out.join("results.json"), results)?;
        write_atomic(&self.out.join("table.md"), table::markdown(results, &paper_number).as_bytes())?;
        let groups: Vec<(String, Vec<Bar>)> = self
            .difficulties
            .iter()
            .map(|d| {
                let bars = self
                    .methods
                    .iter()
                    .filter_map(|spec| {
                        let of: Vec<&RunResult> = results
                            .runs
                            .iter()
                            .filter(|r| r.difficulty == d.name() && table::row_label(r) == spec.label())
                            .collect();
                        (!of.is_empty()).then(|| Bar {
                            label: spec.label(),
                            mean: mean(of.iter().map(|r| r.ndcd)),
                            quantiles: [
                                mean(of.iter().map(|r| r.ndcd_quantiles[0])),
                                mean(of.iter().map(|r| r.ndcd_quantiles[1])),
                            ],
                        })
                    })
                    .collect();
                (format!("{d} ({} expert steps)", d.steps()), bars)
            })
            .collect();
        bar_chart(
            &self.out.join("ndcd_bars.png"),
            &format!("{}: normalised DCD on the test problems", self.experiment),
            "normalised DCD",
            &groups,
        )?;
        // The per-step curves compare methods; variants would crowd them out.
        let defaults: Vec<&MethodSpec> = self.methods.iter().filter(|m| m.variant.name == "default").collect();
        let curves = if defaults.is_empty() { self.methods.iter().collect() } else { defaults };
        for d in &self.difficulties {
            let series: Vec<Series> = curves
                .iter()
                .filter_map(|spec| {
                    let of: Vec<&RunResult> = results
                        .runs
                        .iter()
                        .filter(|r| r.difficulty == d.name() && table::row_label(r) == spec.label())
                        .collect();
                    let steps = of.iter().map(|r| r.ndcd_per_step.len()).min()?;
                    let mut points = vec![(0.0, 1.0)];
                    points.extend((0..steps).map(|t| ((t + 1) as f64, mean(of.iter().map(|r| r.ndcd_per_step[t])))));
                    Some(Series { label: spec.label(), points })
                })
                .collect();
            line_chart(
                &self.out.join(format!("ndcd_per_step_{d}.png")),
                &format!("{} {d}: normalised DCD per generation step (step 0 = M⁰)", self.experiment),
                "generation step",
                "normalised DCD",
                &series,
            )?;
        }
        for (difficulty, test, rows) in galleries {
            let mut tiles = Vec::new();
            for (label, meshes) in rows {
                let steps = meshes.len() / GALLERY_PROBLEMS.min(test.len()).max(1);
                for (k, problem) in test.iter().take(GALLERY_PROBLEMS).enumerate() {
                    let per_problem = &meshes[k * steps..(k + 1) * steps];
                    let chosen: Vec<usize> = gallery_steps(steps);
                    let mut row: Vec<Tile<'_>> = chosen
                        .iter()
                        .map(|&t| Tile {
                            title: format!("{label}, problem {k}, step {}: {} el.", t + 1, per_problem[t].num_elements()),
                            mesh: &per_problem[t],
                            values: per_problem[t].sizes(),
                        })
                        .collect();
                    row.push(Tile {
                        title: format!("expert, problem {k}: {} el.", problem.expert_mesh.num_elements()),
                        mesh: &problem.expert_mesh,
                        values: problem.expert_mesh.sizes(),
                    });
                    tiles.push(row);
                }
            }
            mesh_gallery(&self.out.join(format!("gallery_{difficulty}.png")), &tiles, (420, 380))?;
        }
        Ok(())
    }
}

/// Steps 1, 2 and the last (0-based indices), as the paper's figure shows them.
fn gallery_steps(steps: usize) -> Vec<usize> {
    let mut chosen: Vec<usize> = [0, 1, steps.saturating_sub(1)].into_iter().filter(|&t| t < steps).collect();
    chosen.dedup();
    chosen
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    sum / n.max(1) as f64
}

/// The paper's normalised DCD (spec §10) of a row on Poisson hard, the only difficulty whose
/// numbers the text gives: the main results and the ablations (mean of 4 seeds).
fn paper_number(row: &str, difficulty: &str) -> Option<f64> {
    if difficulty != "hard" {
        return None;
    }
    Some(match row {
        "amber-mean" | "amber-max" => 0.200,
        "amber-mean (log-loss)" => 0.228,
        "amber-max (log-loss)" => 0.227,
        "amber-max (no-softplus)" => 0.233,
        "amber-max (random-buffer)" => 0.215,
        "amber-max (no-input-normalisation)" => 0.226,
        "amber-max (5-problems)" => 0.221,
        "amber-max (10-problems)" => 0.213,
        "amber-max (50-problems)" => 0.175,
        "amber-max (100-problems)" => 0.169,
        "cnn-256" => 0.215,
        "cnn-256 (softplus-mse)" => 0.289,
        "cnn-256 (plain-mse)" => 0.521,
        "cnn-256 (max-labels)" => 0.242,
        _ => return None,
    })
}

/// The evaluation of a trained run on a test set, as cached in the run directory.
#[derive(Serialize, Deserialize)]
struct CachedEvaluation {
    test_set: String,
    train_seconds: f64,
    eval_seconds: f64,
    problems: Vec<ProblemEvaluation>,
}

/// Training wall time, accumulated over resumed sessions.
#[derive(Default, Serialize, Deserialize)]
struct TrainingTime {
    seconds: f64,
    finished: bool,
}

/// The configuration of one run of either kind of method.
#[derive(Clone, Debug, PartialEq)]
pub enum RunConfig {
    Amber(TrainingConfig),
    Cnn(CnnConfig),
}

impl RunConfig {
    /// Generation steps of the method's rollouts (the CNN predicts once).
    pub fn inference_steps(&self) -> usize {
        match self {
            RunConfig::Amber(c) => c.inference_steps,
            RunConfig::Cnn(_) => 1,
        }
    }

    fn difficulty(&self) -> Difficulty {
        match self {
            RunConfig::Amber(c) => c.data.difficulty,
            RunConfig::Cnn(c) => c.data.difficulty,
        }
    }

    fn seed(&self) -> u64 {
        match self {
            RunConfig::Amber(c) => c.seed,
            RunConfig::Cnn(c) => c.seed,
        }
    }

    /// The config as JSON, tagged with its kind.
    pub fn to_json(&self) -> anyhow::Result<serde_json::Value> {
        Ok(match self {
            RunConfig::Amber(c) => serde_json::json!({ "amber": c }),
            RunConfig::Cnn(c) => serde_json::json!({ "cnn": c }),
        })
    }
}

/// A run directory: `<runs>/poisson/<difficulty>/<method>[-<variant>]/seed<r>-<config hash>`.
struct Run {
    dir: PathBuf,
    label: String,
    test_name: String,
    eval_dir: PathBuf,
}

impl Run {
    fn new(experiment: &PoissonExperiment, spec: &MethodSpec, config: &RunConfig, test_name: &str) -> anyhow::Result<Self> {
        let name = match spec.variant.name.as_str() {
            "default" => spec.method.name(),
            variant => format!("{}-{variant}", spec.method.name()),
        };
        let config_json = match config {
            RunConfig::Amber(c) => serde_json::to_value(c)?,
            RunConfig::Cnn(c) => serde_json::to_value(c)?,
        };
        let key = serde_json::json!({ "config": config_json, "manifest": read_json::<serde_json::Value>(&experiment.manifest)? });
        let dir = experiment
            .runs_root
            .join("poisson")
            .join(config.difficulty().name())
            .join(&name)
            .join(format!("seed{}-{}", config.seed(), config_hash(&key)));
        if experiment.force && dir.exists() {
            std::fs::remove_dir_all(&dir).with_context(|| format!("{}: cannot remove for --force", dir.display()))?;
        }
        let eval_dir = dir.join(format!("eval-{}", config_hash(&serde_json::json!(test_name))));
        let label = format!("{} {} seed {}", spec.label(), config.difficulty(), config.seed());
        Ok(Self { dir, label, test_name: test_name.into(), eval_dir })
    }

    /// Trains (or resumes, or reuses) the run, then evaluates it on `test` (or reuses the
    /// cached evaluation).
    fn train_and_evaluate(
        &self,
        experiment: &PoissonExperiment,
        config: &RunConfig,
        test: &[PoissonProblem],
    ) -> anyhow::Result<CachedEvaluation> {
        let cache = self.eval_dir.join("evaluation.json");
        if cache.exists() {
            let cached: CachedEvaluation = read_json(&cache)?;
            println!("{}: reusing the evaluation in {}", self.label, cache.display());
            return Ok(cached);
        }
        let (data, manifest) = (&experiment.data_root, &experiment.manifest);
        let (train_seconds, eval_seconds, rollouts) = match config {
            RunConfig::Amber(config) => {
                let train_seconds = train_poisson(config, data, manifest, &self.dir, &self.label)?;
                let model = AmberModel::load(&self.dir.join(MODEL_DIR))?;
                let started = Instant::now();
                let evaluation = Evaluation::new(test, &model.predictor.limits)?;
                let (rollouts, _) = evaluation.run(&model.network, &model.predictor, config.inference_steps)?;
                (train_seconds, started.elapsed().as_secs_f64(), rollouts)
            }
            RunConfig::Cnn(config) => {
                let train_seconds = train_cnn_poisson(config, data, manifest, &self.dir, &self.label)?;
                let model = CnnModel::load(&self.dir.join(MODEL_DIR))?;
                let started = Instant::now();
                let references = Evaluation::new(test, &model.predictor.limits)?.references;
                let rollouts = model.rollouts(test, &references)?;
                (train_seconds, started.elapsed().as_secs_f64(), rollouts)
            }
        };
        let problems: Vec<ProblemEvaluation> = rollouts
            .iter()
            .zip(test)
            .map(|(r, p)| ProblemEvaluation::of(r, p.expert_mesh.num_elements()))
            .collect();
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
        let evaluated = CachedEvaluation { test_set: self.test_name.clone(), train_seconds, eval_seconds, problems };
        write_json(&cache, &evaluated)?;
        Ok(evaluated)
    }

    fn gallery_path(&self, problem: usize, step: usize) -> PathBuf {
        self.eval_dir.join(format!("problem{problem:03}-step{}.vtu", step + 1))
    }

    /// Keeps every step's mesh of the first test problems as `.vtu` (ParaView) for the gallery.
    fn save_gallery_meshes(&self, rollouts: &[Rollout<2>]) -> anyhow::Result<()> {
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

    /// The saved gallery meshes: problem-major, every step.
    fn gallery_meshes(&self, steps: usize) -> anyhow::Result<Vec<Mesh2>> {
        let mut meshes = Vec::new();
        for k in 0..GALLERY_PROBLEMS {
            for t in 0..steps {
                let path = self.gallery_path(k, t);
                if !path.exists() {
                    return Ok(meshes);
                }
                meshes.push(amber_mesh::read_mesh(&path)?);
            }
        }
        Ok(meshes)
    }
}

/// Trains AMBER on the Poisson task into `dir` until the config's last step: generates the
/// training and validation problems the config names under `data_root` if needed, resumes from
/// the newest checkpoint in `dir`, validates as configured, and writes the model to
/// `dir/model`. A finished run is not retrained. Returns the training wall time, summed over
/// resumed sessions. `label` names the run in progress lines.
pub fn train_poisson(
    config: &TrainingConfig,
    data_root: &Path,
    manifest: &Path,
    dir: &Path,
    label: &str,
) -> anyhow::Result<f64> {
    if let Some(seconds) = finished_run(dir, config)? {
        return Ok(seconds);
    }
    let train = load_problems(data_root, manifest, config.data.difficulty, Split::Train, config.seed as usize, config.data.train_problems)?;
    let val = load_problems(data_root, manifest, config.data.difficulty, Split::Val, 0, config.data.val_problems)?;
    let mut training = Training::open(config.clone(), train, dir)?;
    let validation = Evaluation::new(&val, training.limits())?;
    let mut progress = TimedProgress::start(dir, label, training.step(), config.steps)?;
    progress.inner.println(&format!(
        "{} at step {} in {}: h_min {:.3e}, budget {} elements",
        if training.step() > 0 { "resumed" } else { "training" },
        training.step(),
        dir.display(),
        training.limits().min_size,
        training.limits().max_elements
    ));
    training.run(dir, Some(&validation), &mut progress)?;
    progress.finish()
}

/// The first `count` problems of a split, generated first where missing (with a progress bar).
fn load_problems(
    data_root: &Path,
    manifest: &Path,
    difficulty: Difficulty,
    split: Split,
    seed: usize,
    count: usize,
) -> anyhow::Result<Vec<PoissonProblem>> {
    let bar = item_bar(&format!("{difficulty} {split} problems"), count);
    let (problems, _) = load_split(data_root, manifest, difficulty, split, seed, Some(count), &|| bar.inc(1))?;
    bar.finish_and_clear();
    Ok(problems)
}

/// Trains the U-Net baseline on the Poisson task into `dir` (as [`train_poisson`] does AMBER):
/// resumable, not retrained once finished; returns the training wall time.
pub fn train_cnn_poisson(
    config: &CnnConfig,
    data_root: &Path,
    manifest: &Path,
    dir: &Path,
    label: &str,
) -> anyhow::Result<f64> {
    if let Some(seconds) = finished_run(dir, config)? {
        return Ok(seconds);
    }
    let train = load_problems(data_root, manifest, config.data.difficulty, Split::Train, config.seed as usize, config.data.train_problems)?;
    let mut training = CnnTraining::open(config.clone(), train, dir)?;
    let mut progress = TimedProgress::start(dir, label, training.step(), config.steps)?;
    training.run(dir, &mut progress)?;
    progress.finish()
}

/// Where a run directory records its training wall time.
const TIME_FILE: &str = "training_time.json";

/// The training time of `dir` if it holds a finished run of `config`; an error if it holds a
/// finished run of another configuration.
fn finished_run<C: PartialEq + serde::de::DeserializeOwned>(dir: &Path, config: &C) -> anyhow::Result<Option<f64>> {
    let time_path = dir.join(TIME_FILE);
    let time: TrainingTime = if time_path.exists() { read_json(&time_path)? } else { TrainingTime::default() };
    if !(time.finished && dir.join(MODEL_DIR).exists()) {
        return Ok(None);
    }
    if read_json::<C>(&dir.join(CONFIG_FILE))? != *config {
        bail!("{}: holds a finished run with another configuration; train into a new directory or delete it", dir.display());
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
}

impl TimedProgress {
    /// Progress of the run in `dir` standing at step `done` of `total`, its clock continuing
    /// from the time recorded there.
    fn start(dir: &Path, label: &str, done: u64, total: u64) -> anyhow::Result<Self> {
        let time_path = dir.join(TIME_FILE);
        let before = if time_path.exists() { read_json::<TrainingTime>(&time_path)?.seconds } else { 0.0 };
        Ok(Self { inner: TrainingProgress::new(label, done, total), time_path, before, started: Instant::now() })
    }

    fn seconds(&self) -> f64 {
        self.before + self.started.elapsed().as_secs_f64()
    }

    /// Records the run as finished; returns its total training time.
    fn finish(self) -> anyhow::Result<f64> {
        self.inner.finish();
        let time = TrainingTime { seconds: self.seconds(), finished: true };
        write_json(&self.time_path, &time)?;
        Ok(time.seconds)
    }
}

impl CnnObserver for TimedProgress {
    fn step(&mut self, report: &CnnStepReport, total: u64) {
        self.inner.cnn_step(report, total);
    }

    fn checkpoint(&mut self, step: u64, dir: &Path) {
        TrainingObserver::checkpoint(self, step, dir);
    }
}

impl TrainingObserver for TimedProgress {
    fn step(&mut self, report: &amber_train::StepReport, total: u64) {
        self.inner.step(report, total);
    }

    fn validation(&mut self, step: u64, summary: &amber_train::EvaluationSummary) {
        self.inner.validation(step, summary);
    }

    fn checkpoint(&mut self, step: u64, dir: &Path) {
        self.inner.checkpoint(step, dir);
        let time = TrainingTime { seconds: self.seconds(), finished: false };
        if let Err(e) = write_json(&self.time_path, &time) {
            self.inner.println(&format!("warning: {e:#}"));
        }
    }
}
