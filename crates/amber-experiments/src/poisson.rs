//! The Poisson experiment (spec §1, §6, §7, §10): datasets → training of every method ×
//! difficulty × seed (cached runs, resumable) → rollouts on the test problems → `results.json`,
//! `table.md`, bar and per-step charts and a mesh gallery; or the same runs planned for a
//! scheduler, the datasets generated once beforehand, and run one by one.

use std::path::{Path, PathBuf};

use amber_mesh::Mesh2;
use amber_plot::{Tile, TileMesh, mesh_gallery};
use amber_stdx::read_json;
use amber_tasks::LOG_SIZE_COLUMN;
use amber_tasks::poisson::LOG_ERROR_INDICATOR_COLUMN;
use amber_tasks::poisson::{Difficulty, INITIAL_SIZE, PoissonProblem, Split, load_split, read_split};
use amber_train::{MethodConfig, Profile};
use anyhow::bail;
use serde::Serialize;

use crate::grid::{CachePolicy, GridRun, PlannedRun, unknown_run};
use crate::method::{Method, MethodSpec, Variant};
use crate::outputs::{Setting, gallery_rows, write_outputs};
use crate::profiles::{Overrides, Task, amber_config, run_config};
use crate::progress::item_bar;
use crate::report::merge_json;
use crate::results::ExperimentResults;
use crate::run::{CachedEvaluation, GALLERY_PROBLEMS, Run, RunOrigin, evaluation_name, train_run};

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
    /// At evaluation, scale a predicted field whose element count exceeds the budget to the
    /// budget and mesh it (spec §11, the later version) instead of skipping the step (the
    /// paper). Training is not affected.
    pub scale_to_budget: bool,
    /// Whether cached runs are reused, retrained or required.
    pub cache: CachePolicy,
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
            scale_to_budget: profile != Profile::Paper,
            cache: CachePolicy::Reuse,
        }
    }

    /// The ablations of spec §10 on Poisson hard (easy for `smoke`), each a variant of the same
    /// training code: AMBER-Mean and AMBER-Max as configured (their per-step curves are the
    /// generation-steps study), both with the CNN's log-MSE loss, AMBER-Max without the softplus
    /// output, with uniformly random buffer additions, without input normalisation, with 5, 10,
    /// 50 and 100 training problems (20 is the default); AMBER-Mean with each of the quick
    /// profile's two additions (graph context, error-indicator feature); the 256² CNN with its
    /// log-MSE loss, with MSE after a softplus, with plain MSE on raw sizes, and with
    /// max-aggregated labels.
    /// Writes `results/ablate/`.
    pub fn ablation(profile: Profile) -> Self {
        let mut experiment = Self::new(profile);
        // The ablations vary the paper's choices on the paper's network, inputs and rollouts:
        // without the graph context, the error-indicator feature, the final step scale and the
        // count regression of the quick profile.
        experiment.overrides = serde_json::json!({
            "network": { "graph_context": false },
            "inputs": [LOG_SIZE_COLUMN],
            "calibrate_element_count": false,
            "count_regression": false,
        });
        if profile == Profile::Quick {
            // Seventeen runs in three hours on two cores: each AMBER run gets 600 of the
            // reproduction's 2,500 steps (4–5 min of training on Poisson hard); the 256² CNNs
            // keep their quick schedule (~10 min). The variants are compared with the defaults
            // trained on the same schedule (docs/PROFILES.md).
            merge_json(
                &mut experiment.overrides,
                &serde_json::json!({ "steps": 600, "checkpoint_interval": 200, "validation_interval": 600 }),
            );
        }
        experiment.experiment = "ablate".into();
        experiment.out = PathBuf::from("results/ablate");
        experiment.seeds = 1;
        experiment.difficulties = vec![if profile == Profile::Smoke { Difficulty::Easy } else { Difficulty::Hard }];
        let variant = |method, name: &str, overrides| MethodSpec { method, variant: Variant::new(name, overrides) };
        let log_loss = serde_json::json!({ "objective": "log_mse" });
        experiment.methods = vec![
            MethodSpec::plain(Method::AmberMean),
            MethodSpec::plain(Method::AmberMax),
            variant(Method::AmberMean, "log-loss", log_loss.clone()),
            variant(Method::AmberMax, "log-loss", log_loss),
            variant(
                Method::AmberMax,
                "no-softplus",
                serde_json::json!({ "objective": "mse", "normalise_labels": false }),
            ),
            variant(Method::AmberMax, "random-buffer", serde_json::json!({ "source_selection": "uniform" })),
            variant(Method::AmberMax, "no-input-normalisation", serde_json::json!({ "normalise_inputs": false })),
            variant(Method::AmberMean, "graph-context", serde_json::json!({ "network": { "graph_context": true } })),
            variant(
                Method::AmberMean,
                "error-indicator",
                serde_json::json!({ "inputs": [LOG_SIZE_COLUMN, LOG_ERROR_INDICATOR_COLUMN] }),
            ),
        ];
        let cnn = Method::Cnn { resolution: if profile == Profile::Smoke { 32 } else { 256 } };
        experiment.methods.extend([
            MethodSpec::plain(cnn),
            variant(cnn, "softplus-mse", serde_json::json!({ "loss": "softplus_mse", "normalise_labels": false })),
            variant(cnn, "plain-mse", serde_json::json!({ "loss": "mse", "normalise_labels": false })),
            variant(cnn, "max-labels", serde_json::json!({ "aggregation": "max" })),
        ]);
        let default_problems = amber_config(Task::Poisson, profile).data.train_problems;
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

    /// The configuration of one run (see [`run_config`]).
    pub fn run_config(&self, spec: &MethodSpec, seed: usize) -> anyhow::Result<MethodConfig> {
        let overrides = Overrides { amber: &self.overrides, cnn: &self.cnn_overrides };
        run_config(Task::Poisson, self.profile, spec, seed, overrides)
    }

    /// Runs the experiment and writes its outputs under `out`: trains and evaluates every run
    /// of the grid as [`Self::cache`] says, then writes `results.json`, `table.md` and the
    /// pictures from the runs' evaluations.
    pub fn run(&self) -> anyhow::Result<ExperimentResults> {
        let grid = self.grid()?;
        self.cache.prepare(grid.iter().flat_map(|d| &d.runs))?;
        let mut runs = Vec::new();
        let mut configs = Vec::new();
        let mut galleries = Vec::new();
        for d in &grid {
            let mut rows: Vec<(String, Vec<Vec<Mesh2>>)> = Vec::new();
            for r in &d.runs {
                let evaluated = self.train_and_evaluate(d, r)?;
                configs.push(serde_json::json!({
                    "method": r.spec.method, "variant": r.spec.variant.name, "difficulty": d.difficulty.name(),
                    "seed": r.seed, "run_dir": r.run.dir, "training": r.config,
                }));
                runs.push(evaluated.result(&r.spec, d.difficulty.name(), r.seed));
                if r.seed == 0 && r.spec.variant.name == "default" {
                    rows.push((r.spec.label(), r.run.gallery_meshes(r.config.inference_steps())?));
                }
            }
            galleries.push((d.difficulty, &d.test, rows));
        }
        let config = serde_json::json!({ "experiment": self, "runs": configs });
        let results = ExperimentResults::new(&self.experiment, self.profile.name(), config, runs);
        let settings: Vec<Setting> = self
            .difficulties
            .iter()
            .map(|d| Setting { name: d.name().into(), caption: format!("{d} ({} expert steps)", d.steps()) })
            .collect();
        write_outputs(&self.out, &results, &settings, &self.methods, &paper_number)?;
        for (difficulty, test, rows) in &galleries {
            let experts: Vec<&Mesh2> = test.iter().take(GALLERY_PROBLEMS).map(|p| &p.expert_mesh).collect();
            fn tile(title: String, mesh: &Mesh2) -> Tile<'_> {
                Tile { title, mesh: TileMesh::Flat(mesh), values: mesh.sizes() }
            }
            let tiles = gallery_rows(rows, &experts, tile, Mesh2::num_elements);
            mesh_gallery(&self.out.join(format!("gallery_{difficulty}.png")), &tiles, (420, 380))?;
        }
        Ok(results)
    }

    /// Every run of the grid, in table order, for a scheduler to run apart with
    /// [`Self::run_one`]. Generates every dataset split the runs read first, so that the runs
    /// find their data cached and only write their own directories.
    pub fn plan(&self) -> anyhow::Result<Vec<PlannedRun>> {
        let grid = self.grid()?;
        for d in &grid {
            for r in &d.runs {
                self.training_problems(&r.config, d.difficulty)(r.config.validates())?;
            }
        }
        Ok(grid.iter().flat_map(|d| d.runs.iter().map(GridRun::planned)).collect())
    }

    /// Trains and evaluates the run with `key` (a [`PlannedRun::key`]) alone, as
    /// [`Self::cache`] says; writes nothing outside its directory.
    pub fn run_one(&self, key: &str) -> anyhow::Result<()> {
        let grid = self.grid()?;
        let found = grid.iter().flat_map(|d| d.runs.iter().map(move |r| (d, r))).find(|(_, r)| r.has_key(key));
        let (d, r) = found.ok_or_else(|| unknown_run(key, grid.iter().flat_map(|d| &d.runs)))?;
        self.cache.prepare([r])?;
        self.train_and_evaluate(d, r)?;
        Ok(())
    }

    /// Per difficulty, its test problems and runs (seed-major, then the methods' order).
    fn grid(&self) -> anyhow::Result<Vec<DifficultyRuns>> {
        if self.methods.is_empty() || self.difficulties.is_empty() || self.seeds == 0 {
            bail!("nothing to run: give at least one method, difficulty and seed");
        }
        let manifest: serde_json::Value = read_json(&self.manifest)?;
        let mut grid = Vec::new();
        for &difficulty in &self.difficulties {
            let (test, test_name) = self.test_problems(difficulty)?;
            let test_name = evaluation_name(test_name, self.scale_to_budget);
            let data = serde_json::json!({ "manifest": manifest, "difficulty": difficulty });
            let origin = RunOrigin {
                task: Task::Poisson,
                initial_size: INITIAL_SIZE,
                data: format!(
                    "{difficulty} training problems of {} under {}",
                    self.manifest.display(),
                    self.data_root.display()
                ),
            };
            let mut runs = Vec::new();
            for seed in 0..self.seeds {
                for spec in &self.methods {
                    let config = self.run_config(spec, seed)?;
                    let run =
                        Run::new(&self.runs_root, &origin, difficulty.name(), spec, &config, data.clone(), &test_name);
                    runs.push(GridRun { spec: spec.clone(), seed, config, run });
                }
            }
            grid.push(DifficultyRuns { difficulty, test, runs });
        }
        Ok(grid)
    }

    /// Trains (or reuses) and evaluates one run of the grid.
    fn train_and_evaluate(&self, d: &DifficultyRuns, r: &GridRun) -> anyhow::Result<CachedEvaluation> {
        r.run.train_and_evaluate(&r.config, &d.test, self.scale_to_budget, |dir, label| {
            train_run(&r.config, self.training_problems(&r.config, d.difficulty), dir, label)
        })
    }

    /// The training problems of a run of `config` and, when asked, its validation problems,
    /// generated under `data_root` first where missing.
    fn training_problems(&self, config: &MethodConfig, difficulty: Difficulty) -> impl FnOnce(bool) -> Problems {
        poisson_problems(config, difficulty, &self.data_root, &self.manifest)
    }

    /// The first `count` problems of a split, generated first where missing.
    fn load(
        &self,
        difficulty: Difficulty,
        split: Split,
        seed: usize,
        count: usize,
    ) -> anyhow::Result<Vec<PoissonProblem>> {
        load_problems(&self.data_root, &self.manifest, difficulty, split, seed, count)
    }

    /// The test problems of a difficulty and a name that identifies them in caches.
    fn test_problems(&self, difficulty: Difficulty) -> anyhow::Result<(Vec<PoissonProblem>, String)> {
        let (mut problems, name) = match &self.test_set {
            Some(dir) => (read_split(dir)?, format!("external {}", dir.display())),
            None => {
                let count = self.test_problems.unwrap_or(100);
                (self.load(difficulty, Split::Test, 0, count)?, format!("{difficulty} test"))
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
}

/// One difficulty of the grid: its test problems and its runs.
struct DifficultyRuns {
    difficulty: Difficulty,
    test: Vec<PoissonProblem>,
    runs: Vec<GridRun>,
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

/// Trains a method on the Poisson task into `dir` until the config's last step (see
/// [`train_run`]), generating the training and validation problems the config names under
/// `data_root` first where missing. Returns the training wall time; `label` names the run in
/// progress lines.
pub fn train_poisson(
    config: &MethodConfig,
    difficulty: Difficulty,
    data_root: &Path,
    manifest: &Path,
    dir: &Path,
    label: &str,
) -> anyhow::Result<f64> {
    train_run(config, poisson_problems(config, difficulty, data_root, manifest), dir, label)
}

/// A run's training problems and, when it validates, its validation problems.
type Problems = anyhow::Result<(Vec<PoissonProblem>, Vec<PoissonProblem>)>;

/// The training problems of a run of `config` and, when asked, the validation problems (see
/// [`train_run`]), generated under `data_root` first where missing.
fn poisson_problems<'a>(
    config: &MethodConfig,
    difficulty: Difficulty,
    data_root: &'a Path,
    manifest: &'a Path,
) -> impl FnOnce(bool) -> Problems + 'a {
    let (seed, data) = (config.seed() as usize, config.data().clone());
    move |validates: bool| {
        let train = load_problems(data_root, manifest, difficulty, Split::Train, seed, data.train_problems)?;
        let val = if validates {
            load_problems(data_root, manifest, difficulty, Split::Val, 0, data.val_problems)?
        } else {
            Vec::new()
        };
        Ok((train, val))
    }
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
