//! The Console experiment (spec §9, §10): AMBER-Mean, AMBER-Max and the 3D CNNs trained on the
//! real car-seat parts, evaluated on `test/` when the data has it, else on `val/`; the same
//! outputs as the Poisson experiment, with galleries of the meshes' surfaces from two
//! viewpoints and the final meshes as `.vtu` for ParaView. Its runs can be planned and run one
//! by one as the Poisson experiment's can.

use std::path::{Path, PathBuf};

use amber_mesh::Mesh3;
use amber_plot::{Tile, TileMesh, View, mesh_gallery};
use amber_tasks::WithExpert;
use amber_tasks::console::{INITIAL_MESH_RECIPE, INITIAL_SIZE, TrainSet, check_data, has_test_split};
use amber_tasks::folder::{DatasetSettings, Split, problems, read_experts};
use amber_tasks::part::SolidPart;
use amber_train::{MethodConfig, Profile};
use anyhow::bail;
use serde::Serialize;

use crate::grid::{CachePolicy, GridRun, PlannedRun, unknown_run};
use crate::method::{Method, MethodSpec};
use crate::outputs::{Setting, gallery_rows, write_outputs};
use crate::profiles::{Overrides, Task, run_config};
use crate::results::ExperimentResults;
use crate::run::{CachedEvaluation, GALLERY_PROBLEMS, Run, RunOrigin, evaluation_name, train_run};

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
        self.cache.prepare(&grid.runs)?;
        let mut runs = Vec::new();
        let mut configs = Vec::new();
        let mut rows: Vec<(String, Vec<Vec<Mesh3>>)> = Vec::new();
        for r in &grid.runs {
            let evaluated = self.train_and_evaluate(&grid, r)?;
            configs.push(serde_json::json!({
                "method": r.spec.method, "variant": r.spec.variant.name, "seed": r.seed, "run_dir": r.run.dir,
                "training": r.config,
            }));
            runs.push(evaluated.result(&r.spec, "console", r.seed));
            if r.seed == 0 && r.spec.variant.name == "default" {
                rows.push((r.spec.label(), r.run.gallery_meshes(r.config.inference_steps())?));
            }
        }
        let test_split = grid.test_split.name();
        let config = serde_json::json!({ "experiment": self, "test_split": test_split, "runs": configs });
        let results = ExperimentResults::new("console", self.profile.name(), config, runs);
        let setting = Setting { name: "console".into(), caption: format!("Console ({test_split} parts)") };
        write_outputs(&self.out, &results, &[setting], &self.methods, &paper_number)?;
        let experts: Vec<&Mesh3> = grid.test.iter().take(GALLERY_PROBLEMS).map(|p| &p.expert_mesh).collect();
        for (k, view) in VIEWS.into_iter().enumerate() {
            let tiles = gallery_rows(&rows, &experts, solid_tile(view), Mesh3::num_elements);
            mesh_gallery(&self.out.join(format!("gallery_console_view{}.png", k + 1)), &tiles, (460, 380))?;
        }
        Ok(results)
    }

    /// Every run, in table order, for a scheduler to run apart with [`Self::run_one`] (the data
    /// folder is only read).
    pub fn plan(&self) -> anyhow::Result<Vec<PlannedRun>> {
        Ok(self.grid()?.runs.iter().map(GridRun::planned).collect())
    }

    /// Trains and evaluates the run with `key` (a [`PlannedRun::key`]) alone, as
    /// [`Self::cache`] says; writes nothing outside its directory.
    pub fn run_one(&self, key: &str) -> anyhow::Result<()> {
        let grid = self.grid()?;
        let r = grid.runs.iter().find(|r| r.has_key(key)).ok_or_else(|| unknown_run(key, &grid.runs))?;
        self.cache.prepare([r])?;
        self.train_and_evaluate(&grid, r)?;
        Ok(())
    }

    /// The test parts and the runs (seed-major, then the methods' order).
    fn grid(&self) -> anyhow::Result<ConsoleGrid> {
        if self.methods.is_empty() || self.seeds == 0 {
            bail!("nothing to run: give at least one method and seed");
        }
        check_data(&self.data)?;
        let test_split = if has_test_split(&self.data) { Split::Test } else { Split::Val };
        let test = self.load(test_split, usize::MAX)?;
        let test_name =
            evaluation_name(format!("console {} ({} parts)", test_split.name(), test.len()), self.scale_to_budget);
        let data = serde_json::json!({
            "dir": self.data, "train_set": self.train_set, "initial_mesh": INITIAL_MESH_RECIPE,
        });
        let parts = self.train_set.part_limit().map_or("all".to_owned(), |n| format!("the first {n}"));
        let origin = RunOrigin {
            task: Task::Console,
            initial_size: INITIAL_SIZE,
            data: format!("{parts} Console training parts of {}", self.data.display()),
        };
        let mut runs = Vec::new();
        for seed in 0..self.seeds {
            for spec in &self.methods {
                let config = self.run_config(spec, seed)?;
                let run = Run::new(&self.runs_root, &origin, "console", spec, &config, data.clone(), &test_name);
                runs.push(GridRun { spec: spec.clone(), seed, config, run });
            }
        }
        Ok(ConsoleGrid { test_split, test, runs })
    }

    /// Trains (or reuses) and evaluates one run of the grid.
    fn train_and_evaluate(&self, grid: &ConsoleGrid, r: &GridRun) -> anyhow::Result<CachedEvaluation> {
        let data = r.config.data();
        r.run.train_and_evaluate(&r.config, &grid.test, self.scale_to_budget, |dir, label| {
            let problems = |validates: bool| {
                let val = if validates { self.load(Split::Val, data.val_problems)? } else { Vec::new() };
                Ok((self.load(Split::Train, data.train_problems)?, val))
            };
            train_run(&r.config, problems, dir, label)
        })
    }

    /// The first `count` parts of a split (all of them for `usize::MAX`; of the training split,
    /// at most those of the train set), loaded through the folder loader in parallel with M⁰ at
    /// the spec's h₀.
    fn load(&self, split: Split, count: usize) -> anyhow::Result<Vec<WithExpert<SolidPart, 3>>> {
        let limit = match split {
            Split::Train => self.train_set.part_limit().map_or(count, |parts| parts.min(count)),
            Split::Val | Split::Test => count,
        };
        let experts = read_experts::<3>(&split.dir(&self.data), Some(limit))?;
        Ok(problems(experts, INITIAL_SIZE, &DatasetSettings::read(&self.data)?)?)
    }
}

/// The grid of the Console experiment: its test parts and its runs.
struct ConsoleGrid {
    test_split: Split,
    test: Vec<WithExpert<SolidPart, 3>>,
    runs: Vec<GridRun>,
}

/// A gallery tile of a mesh's surface from `view`, coloured by element size.
fn solid_tile(view: View) -> impl for<'m> Fn(String, &'m Mesh3) -> Tile<'m> {
    move |title, mesh| Tile { title, mesh: TileMesh::Solid(mesh, view), values: mesh.sizes() }
}

/// The paper's normalised DCD on the Console test split (spec §10, mean of 4 seeds).
fn paper_number(row: &str, _setting: &str) -> Option<f64> {
    match row {
        "amber-mean" => Some(0.196),
        "amber-max" => Some(0.238),
        "cnn-32" => Some(0.418),
        "cnn-64" => Some(0.309),
        _ => None,
    }
}
