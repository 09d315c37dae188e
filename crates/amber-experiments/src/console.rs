//! The Console experiment (spec §9, §10): AMBER-Mean, AMBER-Max and the 3D CNNs trained on the
//! real car-seat parts, evaluated on `test/` when the data has it, else on `val/`; the same
//! outputs as the Poisson experiment, with galleries of the meshes' surfaces from two
//! viewpoints and the final meshes as `.vtu` for ParaView. Its runs can be planned and run one
//! by one as the Poisson experiment's can. With [`ConsoleExperiment::folds`] it is a
//! cross-validation over the training parts instead: each fold's model is scored on the parts it
//! did not train on, so that every training part is scored once, by a model that never saw it.

use std::path::{Path, PathBuf};

use amber_mesh::Mesh3;
use amber_plot::{Tile, TileMesh, View, mesh_gallery};
use amber_tasks::console::{INITIAL_MESH_RECIPE, INITIAL_SIZE, TrainSet, check_data, has_test_split};
use amber_tasks::folder::{DatasetSettings, Fold, Split, problems, read_experts};
use amber_tasks::part::SolidPart;
use amber_tasks::{Problem, WithExpert};
use amber_train::{MethodConfig, Profile};
use anyhow::bail;
use serde::Serialize;

use crate::grid::{CachePolicy, GridRun, PlannedRun, unknown_run};
use crate::method::{Method, MethodSpec};
use crate::outputs::{Setting, gallery_rows, write_outputs};
use crate::profiles::{Overrides, Task, run_config};
use crate::results::ExperimentResults;
use crate::run::{CachedEvaluation, GALLERY_PROBLEMS, Run, RunOrigin, evaluation_name, train_run};

/// A Console part with its expert mesh.
type Part = WithExpert<SolidPart, 3>;

/// The two viewpoints of the galleries.
const VIEWS: [View; 2] =
    [View { azimuth_deg: 35.0, elevation_deg: 30.0 }, View { azimuth_deg: 215.0, elevation_deg: -20.0 }];

/// Everything an invocation of the Console experiment decides.
#[derive(Clone, Debug, Serialize)]
pub struct ConsoleExperiment {
    pub profile: Profile,
    /// The Console data directory (`train/ val/ [test/] reference_surface/`).
    pub data: PathBuf,
    /// The paper's 15 training parts, or all.
    pub train_set: TrainSet,
    /// Training seeds 0..seeds.
    pub seeds: usize,
    pub methods: Vec<MethodSpec>,
    /// Root of the cached training runs.
    pub runs_root: PathBuf,
    /// Where results.json, table.md and the pictures go.
    pub out: PathBuf,
    /// Fields merged into every AMBER run's training config.
    pub overrides: serde_json::Value,
    /// Fields merged into every CNN run's config.
    pub cnn_overrides: serde_json::Value,
    /// At evaluation, scale a predicted field whose element count exceeds the budget to the
    /// budget and mesh it (spec §11, the later version) instead of skipping the step (the
    /// paper). Training is not affected.
    pub scale_to_budget: bool,
    /// Whether cached runs are reused, retrained or required.
    pub cache: CachePolicy,
    /// `Some(k)`: a k-fold cross-validation over the train set's parts instead of an evaluation
    /// on `test/` or `val/`. Part i (in name order) is held out by fold i mod k; fold f's runs
    /// train on the other parts and are scored on fold f's. A method's row pools the folds'
    /// per-part scores.
    pub folds: Option<usize>,
}

impl ConsoleExperiment {
    /// The defaults of a profile on the data in `data`: AMBER-Mean, AMBER-Max, CNN 32³ and 64³
    /// (smoke: AMBER only), one seed (paper: 4).
    pub fn new(profile: Profile, data: &Path) -> Self {
        let mut methods: Vec<MethodSpec> = Method::DEFAULT.into_iter().map(MethodSpec::plain).collect();
        if profile != Profile::Smoke {
            methods.extend([32, 64].map(|resolution| MethodSpec::plain(Method::Cnn { resolution })));
        }
        Self {
            profile,
            data: data.to_owned(),
            train_set: TrainSet::Paper,
            seeds: if profile == Profile::Paper { 4 } else { 1 },
            methods,
            runs_root: PathBuf::from("data/runs"),
            out: PathBuf::from("results/console"),
            overrides: serde_json::json!({}),
            cnn_overrides: serde_json::json!({}),
            scale_to_budget: profile != Profile::Paper,
            cache: CachePolicy::Reuse,
            folds: None,
        }
    }

    /// The configuration of one run (see [`run_config`]).
    pub fn run_config(&self, spec: &MethodSpec, seed: usize) -> anyhow::Result<MethodConfig> {
        let overrides = Overrides { amber: &self.overrides, cnn: &self.cnn_overrides };
        run_config(Task::Console, self.profile, spec, seed, overrides)
    }

    /// Runs the experiment and writes its outputs under `out`: trains and evaluates every run
    /// as [`Self::cache`] says, then writes `results.json`, `table.md` and the pictures from the
    /// runs' evaluations.
    pub fn run(&self) -> anyhow::Result<ExperimentResults> {
        let grid = self.grid()?;
        self.cache.prepare(grid.runs.iter().map(|(r, _)| r))?;
        let mut evaluations: Vec<(&GridRun, Vec<CachedEvaluation>)> = Vec::new();
        let mut configs = Vec::new();
        let mut rows: Vec<(String, Vec<Vec<Mesh3>>)> = Vec::new();
        for (r, fold) in &grid.runs {
            let evaluated = self.train_and_evaluate(&grid, r, *fold)?;
            configs.push(serde_json::json!({
                "method": r.spec.method, "variant": r.spec.variant.name, "seed": r.seed, "fold": fold,
                "run_dir": r.run.dir, "training": r.config,
            }));
            if r.seed == 0 && r.spec.variant.name == "default" && *fold == 0 {
                rows.push((r.spec.label(), r.run.gallery_meshes(r.config.inference_steps())?));
            }
            // The folds of a method and seed follow each other, fold 0 first (see `grid`).
            match evaluations.last_mut() {
                Some((_, folds)) if *fold > 0 => folds.push(evaluated),
                _ => evaluations.push((r, vec![evaluated])),
            }
        }
        let runs = evaluations
            .into_iter()
            .map(|(r, folds)| CachedEvaluation::pooled(folds).result(&r.spec, &grid.setting.name, r.seed))
            .collect();
        let test_split = &grid.split;
        let config = serde_json::json!({ "experiment": self, "test_split": test_split, "runs": configs });
        let results = ExperimentResults::new("console", self.profile.name(), config, runs);
        write_outputs(&self.out, &results, std::slice::from_ref(&grid.setting), &self.methods, &paper_number)?;
        let experts: Vec<&Mesh3> = grid.tests[0].iter().take(GALLERY_PROBLEMS).map(|p| &p.expert_mesh).collect();
        for (k, view) in VIEWS.into_iter().enumerate() {
            let tiles = gallery_rows(&rows, &experts, solid_tile(view), Mesh3::num_elements);
            mesh_gallery(&self.out.join(format!("gallery_console_view{}.png", k + 1)), &tiles, (460, 380))?;
        }
        Ok(results)
    }

    /// Every run, in table order, for a scheduler to run apart with [`Self::run_one`] (the data
    /// folder is only read).
    pub fn plan(&self) -> anyhow::Result<Vec<PlannedRun>> {
        Ok(self.grid()?.runs.iter().map(|(r, _)| r.planned()).collect())
    }

    /// Trains and evaluates the run with `key` (a [`PlannedRun::key`]) alone, as
    /// [`Self::cache`] says; writes nothing outside its directory.
    pub fn run_one(&self, key: &str) -> anyhow::Result<()> {
        let grid = self.grid()?;
        let (r, fold) = grid
            .runs
            .iter()
            .find(|(r, _)| r.has_key(key))
            .ok_or_else(|| unknown_run(key, grid.runs.iter().map(|(r, _)| r)))?;
        self.cache.prepare([r])?;
        self.train_and_evaluate(&grid, r, *fold)?;
        Ok(())
    }

    /// The test parts and the runs (seed-major, then the methods' order, then the folds).
    fn grid(&self) -> anyhow::Result<ConsoleGrid> {
        if self.methods.is_empty() || self.seeds == 0 {
            bail!("nothing to run: give at least one method and seed");
        }
        check_data(&self.data)?;
        let (setting, tests, test_names, split) = match self.folds {
            None => {
                let split = if has_test_split(&self.data) { Split::Test } else { Split::Val };
                let test = self.load(split, usize::MAX, |_| true)?;
                let name = format!("console {} ({} parts)", split.name(), test.len());
                let caption = format!("Console ({} parts)", split.name());
                (Setting { name: "console".into(), caption }, vec![test], vec![name], split.name().to_owned())
            }
            Some(folds) => {
                let all = self.load(Split::Train, usize::MAX, |_| true)?;
                let parts = all.len();
                let fold_list = Fold::all(folds, parts).map_err(anyhow::Error::msg)?;
                let mut tests: Vec<Vec<Part>> = (0..folds).map(|_| Vec::new()).collect();
                for (i, part) in all.into_iter().enumerate() {
                    let fold = fold_list.iter().position(|f| f.holds_out(i)).expect("every part is in one fold");
                    tests[fold].push(part);
                }
                let names = (0..folds)
                    .map(|f| format!("console {folds}-fold cross-validation, fold {f} ({} parts)", tests[f].len()))
                    .collect();
                let caption = format!("Console ({parts} training parts, {folds}-fold cross-validation)");
                let setting = Setting { name: "console-cv".into(), caption };
                (setting, tests, names, "cross-validation".to_owned())
            }
        };
        let parts = self.train_set.part_limit().map_or("all".to_owned(), |n| format!("the first {n}"));
        let origin = |fold: usize| {
            let held_out = match self.folds {
                Some(folds) => {
                    let names: Vec<String> = tests[fold].iter().map(|p| p.name()).collect();
                    format!(" but the {} fold {fold} of {folds} holds out ({})", names.len(), names.join(", "))
                }
                None => String::new(),
            };
            RunOrigin {
                task: Task::Console,
                initial_size: INITIAL_SIZE,
                data: format!("{parts} Console training parts of {}{held_out}", self.data.display()),
            }
        };
        let mut runs = Vec::new();
        for seed in 0..self.seeds {
            for spec in &self.methods {
                let config = self.run_config(spec, seed)?;
                for (fold, test_name) in test_names.iter().enumerate() {
                    let mut data = serde_json::json!({
                        "dir": self.data, "train_set": self.train_set, "initial_mesh": INITIAL_MESH_RECIPE,
                    });
                    let mut setting = setting.name.clone();
                    if let Some(folds) = self.folds {
                        data["fold"] = serde_json::json!({ "fold": fold, "folds": folds });
                        setting = format!("console-cv{folds}-fold{fold}");
                    }
                    let test_name = evaluation_name(test_name.clone(), self.scale_to_budget);
                    let run = Run::new(&self.runs_root, &origin(fold), &setting, spec, &config, data, &test_name);
                    runs.push((GridRun { spec: spec.clone(), seed, config: config.clone(), run }, fold));
                }
            }
        }
        Ok(ConsoleGrid { setting, split, tests, runs })
    }

    /// Trains (or reuses) and evaluates one run of the grid, of fold `fold` (0 without
    /// cross-validation).
    fn train_and_evaluate(&self, grid: &ConsoleGrid, r: &GridRun, fold: usize) -> anyhow::Result<CachedEvaluation> {
        let data = r.config.data();
        r.run.train_and_evaluate(&r.config, &grid.tests[fold], self.scale_to_budget, |dir, label| {
            let problems = |validates: bool| {
                let val = if validates { self.load(Split::Val, data.val_problems, |_| true)? } else { Vec::new() };
                Ok((self.training_parts(fold, data.train_problems)?, val))
            };
            train_run(&r.config, problems, dir, label)
        })
    }

    /// The first `count` training parts that fold `fold` trains on: all but those it holds out.
    fn training_parts(&self, fold: usize, count: usize) -> anyhow::Result<Vec<Part>> {
        self.load(Split::Train, count, |i| self.folds.is_none_or(|count| !Fold { index: fold, count }.holds_out(i)))
    }

    /// The parts of a split (of the training split, only the train set's) whose index in name
    /// order `keep` accepts, the first `count` of them (`usize::MAX`: all), loaded through the
    /// folder loader in parallel with M⁰ at the spec's h₀.
    fn load(&self, split: Split, count: usize, keep: impl Fn(usize) -> bool) -> anyhow::Result<Vec<Part>> {
        let limit = match split {
            Split::Train => self.train_set.part_limit(),
            Split::Val | Split::Test => None,
        };
        let experts = read_experts::<3>(&split.dir(&self.data), limit)?;
        let experts = experts.into_iter().enumerate().filter(|(i, _)| keep(*i)).map(|(_, e)| e).take(count).collect();
        Ok(problems(experts, INITIAL_SIZE, &DatasetSettings::read(&self.data)?)?)
    }
}

/// The grid of the Console experiment: the column it fills, the parts each fold is scored on
/// (one entry without cross-validation), and its runs with their folds.
struct ConsoleGrid {
    setting: Setting,
    /// The `test_split` of results.json: `test`, `val` or `cross-validation`.
    split: String,
    tests: Vec<Vec<Part>>,
    runs: Vec<(GridRun, usize)>,
}

/// A gallery tile of a mesh's surface from `view`, coloured by element size.
fn solid_tile(view: View) -> impl for<'m> Fn(String, &'m Mesh3) -> Tile<'m> {
    move |title, mesh| Tile { title, mesh: TileMesh::Solid(mesh, view), values: mesh.sizes() }
}

/// The paper's normalised DCD on the Console test split (spec §10, mean of 4 seeds); none for a
/// cross-validation, which scores other parts.
fn paper_number(row: &str, setting: &str) -> Option<f64> {
    if setting != "console" {
        return None;
    }
    match row {
        "amber-mean" => Some(0.196),
        "amber-max" => Some(0.238),
        "cnn-32" => Some(0.418),
        "cnn-64" => Some(0.309),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_tasks::Problem;

    /// Reads ../shared/data/console.
    #[test]
    fn a_fold_trains_on_the_parts_it_does_not_hold_out() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        let mut experiment = ConsoleExperiment::new(Profile::Smoke, &data);
        let names = |parts: Vec<Part>| parts.iter().map(|p| p.name()).collect::<Vec<_>>();
        assert_eq!(names(experiment.training_parts(0, 3).unwrap()), ["001", "002", "003"]);
        experiment.folds = Some(5);
        let trained = names(experiment.training_parts(1, usize::MAX).unwrap());
        let held_out = ["002", "007", "012"];
        assert_eq!(trained.len(), 12);
        assert!(held_out.iter().all(|h| !trained.iter().any(|t| t == h)), "{trained:?}");
        assert_eq!(names(experiment.training_parts(1, 2).unwrap()), ["001", "003"]);
    }
}
