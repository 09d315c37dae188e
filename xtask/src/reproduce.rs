//! `cargo xtask reproduce poisson`: the paper's Poisson experiment end to end (datasets,
//! training of every method × difficulty × seed, test rollouts, tables and plots under
//! `results/poisson/`); `reproduce console` and `ablate` likewise. Trained runs are cached under
//! `data/runs/`, keyed by their config; `--plan`, `--only` and `--collect` hand the runs to a
//! scheduler (`plan.rs`).

use std::path::{Component, Path, PathBuf};

use amber_experiments::{ConsoleExperiment, ExperimentResults, Method, MethodSpec, PlannedRun, PoissonExperiment};
use amber_stdx::read_json;
use amber_tasks::console::TrainSet;
use amber_tasks::poisson::Difficulty;
use amber_train::Profile;

use crate::plan::{self, Action, GridArgs};
use crate::report;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    experiment: Experiment,
}

#[derive(clap::Subcommand, Debug)]
enum Experiment {
    /// Poisson on random L-shapes (spec §1): AMBER-Mean and AMBER-Max per difficulty.
    Poisson(PoissonArgs),
    /// The Console car-seat parts (spec §9): AMBER-Mean, AMBER-Max, CNN 32³ and 64³.
    Console(ConsoleArgs),
}

#[derive(clap::Args, Debug)]
struct ConsoleArgs {
    /// smoke (CI: minutes), quick (default), paper (GPU scale).
    #[arg(long, default_value = "quick")]
    profile: Profile,
    /// The Console data: `train/ val/ [test/]` with NNN.nas, and `reference_surface/<split>/NNN.stl`.
    #[arg(long, default_value = "../shared/data/console")]
    data: PathBuf,
    /// Train on all 19 training parts instead of the paper's 15.
    #[arg(long)]
    all_train: bool,
    /// A K-fold cross-validation over the training parts (with --all-train, all 19) instead of
    /// scoring on test/ or val/: part i is held out by fold i mod K, and each part is scored by
    /// the model that did not train on it. For choosing settings without touching val/ or test/.
    #[arg(long)]
    folds: Option<usize>,
    /// Training seeds 0..N (default: the profile's).
    #[arg(long)]
    seeds: Option<usize>,
    /// Methods, comma-separated (default: the profile's).
    #[arg(long, value_delimiter = ',')]
    methods: Vec<Method>,
    #[command(flatten)]
    overrides: OverrideArgs,
    #[command(flatten)]
    grid: GridArgs,
    /// Write under `results/` even from code with uncommitted changes (its results would name
    /// no commit that made them).
    #[arg(long)]
    allow_dirty: bool,
    /// Output directory [default: results/console, or results/console-cv with --folds].
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(clap::Args, Debug)]
struct PoissonArgs {
    /// smoke (CI: minutes), quick (default: about an hour on 2 cores), paper (GPU scale).
    #[arg(long, default_value = "quick")]
    profile: Profile,
    /// Difficulties, comma-separated (default: the profile's).
    #[arg(long, value_delimiter = ',')]
    difficulty: Vec<Difficulty>,
    /// Training seeds 0..N (default: the profile's).
    #[arg(long)]
    seeds: Option<usize>,
    /// Methods, comma-separated (default: all).
    #[arg(long, value_delimiter = ',')]
    methods: Vec<Method>,
    /// Evaluate on the problem files (JSON, ours or the reference's format) of this directory
    /// instead of the generated test split.
    #[arg(long)]
    test_set: Option<PathBuf>,
    /// Evaluate on the first N test problems only.
    #[arg(long)]
    test_problems: Option<usize>,
    #[command(flatten)]
    data: PoissonDataArgs,
    #[command(flatten)]
    overrides: OverrideArgs,
    /// Skip a generation step whose field exceeds the element budget, as the paper does,
    /// instead of scaling the field to the budget (the default outside the paper profile).
    #[arg(long)]
    skip_over_budget: bool,
    #[command(flatten)]
    grid: GridArgs,
    /// Write under `results/` even from code with uncommitted changes (its results would name
    /// no commit that made them).
    #[arg(long)]
    allow_dirty: bool,
    /// Output directory.
    #[arg(long, default_value = "results/poisson")]
    out: PathBuf,
}

/// Where the Poisson experiments keep their generated datasets.
#[derive(clap::Args, Debug)]
struct PoissonDataArgs {
    /// Root of the generated Poisson datasets (`<root>/<difficulty>/<split>`), generated where
    /// missing.
    #[arg(long, value_name = "DIR", default_value = "data/poisson")]
    data_root: PathBuf,
}

/// Config overrides from JSON files, shared by the experiments.
#[derive(clap::Args, Debug)]
struct OverrideArgs {
    /// A JSON file of training-config fields overriding the profile's for every AMBER run.
    #[arg(long)]
    config: Option<PathBuf>,
    /// A JSON file of config fields overriding the profile's for every CNN run.
    #[arg(long)]
    cnn_config: Option<PathBuf>,
}

impl OverrideArgs {
    /// The AMBER and CNN overrides (empty objects where no file is given).
    fn read(&self) -> anyhow::Result<(serde_json::Value, serde_json::Value)> {
        let read = |path: &Option<PathBuf>| path.as_deref().map_or(Ok(serde_json::json!({})), read_json);
        Ok((read(&self.config)?, read(&self.cnn_config)?))
    }
}

/// `path` relative to the directory `from` (through `..` where they part), both resolved; as
/// given when either does not exist (the experiment then names what is missing).
fn seen_from(path: &Path, from: &Path) -> PathBuf {
    let (Ok(path_abs), Ok(from_abs)) = (path.canonicalize(), from.canonicalize()) else { return path.to_owned() };
    let shared = path_abs.components().zip(from_abs.components()).take_while(|(a, b)| a == b).count();
    let ups = from_abs.components().count() - shared;
    let seen: PathBuf =
        std::iter::repeat_n(Component::ParentDir, ups).chain(path_abs.components().skip(shared)).collect();
    if seen.as_os_str().is_empty() { PathBuf::from(".") } else { seen }
}

pub fn run(args: Args) -> anyhow::Result<()> {
    match args.experiment {
        Experiment::Poisson(args) => poisson(args),
        Experiment::Console(args) => console(args),
    }
}

fn console(args: ConsoleArgs) -> anyhow::Result<()> {
    let default_out = if args.folds.is_some() { "results/console-cv" } else { "results/console" };
    let out = args.out.unwrap_or_else(|| default_out.into());
    report::check_provenance(&out, Some(args.allow_dirty))?;
    // Run keys hash the data path: every spelling of one directory gets the same.
    let data = seen_from(&args.data, Path::new("."));
    let mut experiment = ConsoleExperiment::new(args.profile, &data);
    if args.all_train {
        experiment.train_set = TrainSet::All;
    }
    experiment.folds = args.folds;
    if let Some(seeds) = args.seeds {
        experiment.seeds = seeds;
    }
    if !args.methods.is_empty() {
        experiment.methods = args.methods.into_iter().map(MethodSpec::plain).collect();
    }
    (experiment.overrides, experiment.cnn_overrides) = args.overrides.read()?;
    experiment.cache = args.grid.cache_policy();
    experiment.runs_root = args.grid.runs_root().into();
    experiment.out = out;
    schedule(&args.grid, &experiment.out, || experiment.plan(), |key| experiment.run_one(key), || experiment.run())
}

fn poisson(args: PoissonArgs) -> anyhow::Result<()> {
    report::check_provenance(&args.out, Some(args.allow_dirty))?;
    let mut experiment = PoissonExperiment::new(args.profile);
    if !args.difficulty.is_empty() {
        experiment.difficulties = args.difficulty;
    }
    if let Some(seeds) = args.seeds {
        experiment.seeds = seeds;
    }
    if !args.methods.is_empty() {
        experiment.methods = args.methods.into_iter().map(MethodSpec::plain).collect();
    }
    (experiment.overrides, experiment.cnn_overrides) = args.overrides.read()?;
    if args.test_problems.is_some() {
        experiment.test_problems = args.test_problems;
    }
    experiment.test_set = args.test_set;
    if args.skip_over_budget {
        experiment.scale_to_budget = false;
    }
    poisson_schedule(experiment, args.data, &args.grid, args.out)
}

#[derive(clap::Args, Debug)]
pub struct AblateArgs {
    /// smoke (CI: minutes), quick (hours on 2 cores), paper (GPU scale).
    #[arg(long, default_value = "quick")]
    profile: Profile,
    #[command(flatten)]
    data: PoissonDataArgs,
    #[command(flatten)]
    grid: GridArgs,
    /// Write under `results/` even from code with uncommitted changes (its results would name
    /// no commit that made them).
    #[arg(long)]
    allow_dirty: bool,
    /// Output directory.
    #[arg(long, default_value = "results/ablate")]
    out: PathBuf,
}

/// `cargo xtask ablate`: every ablation of spec §10 as variants of the same training code.
pub fn ablate(args: AblateArgs) -> anyhow::Result<()> {
    report::check_provenance(&args.out, Some(args.allow_dirty))?;
    poisson_schedule(PoissonExperiment::ablation(args.profile), args.data, &args.grid, args.out)
}

/// Runs the Poisson `experiment` (or its ablations) on the datasets of `data` as `grid` says,
/// writing results to `out`.
fn poisson_schedule(
    mut experiment: PoissonExperiment,
    data: PoissonDataArgs,
    grid: &GridArgs,
    out: PathBuf,
) -> anyhow::Result<()> {
    experiment.data_root = data.data_root;
    experiment.cache = grid.cache_policy();
    experiment.runs_root = grid.runs_root().into();
    experiment.out = out;
    schedule(grid, &experiment.out, || experiment.plan(), |key| experiment.run_one(key), || experiment.run())
}

/// Does what `grid` asks of an experiment given as its three entry points: writes the plan of
/// its runs, runs one of them, or runs (or collects) them all and reports the results in `out`.
fn schedule(
    grid: &GridArgs,
    out: &Path,
    plan: impl FnOnce() -> anyhow::Result<Vec<PlannedRun>>,
    run_one: impl FnOnce(&str) -> anyhow::Result<()>,
    run: impl FnOnce() -> anyhow::Result<ExperimentResults>,
) -> anyhow::Result<()> {
    match grid.action() {
        Action::Plan(file) => plan::write(file, &plan()?),
        Action::Only(key) => run_one(key),
        Action::All => {
            report(&run()?, out);
            Ok(())
        }
    }
}

/// Prints each run's headline numbers and where the outputs went.
fn report(results: &ExperimentResults, out: &Path) {
    for run in &results.runs {
        println!(
            "{} {} seed {}: normalised DCD {:.3} [{:.3}, {:.3}], per step {:?}",
            amber_experiments::row_label(run),
            run.difficulty,
            run.seed,
            run.ndcd,
            run.ndcd_quantiles[0],
            run.ndcd_quantiles[1],
            run.ndcd_per_step.iter().map(|v| (v * 1000.0).round() / 1000.0).collect::<Vec<_>>()
        );
        println!(
            "  raw DCD d(Mᵀ) {:.4}, d(M⁰) {:.4}, d(M̂) {:.4}; {:.0} elements (expert {:.0}); {} failed steps",
            run.dcd, run.dcd_initial, run.dcd_reconstruction, run.elements, run.expert_elements, run.failed_steps
        );
    }
    println!("wrote {}/{{results.json, table.md, *.png}}", out.display());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_spelling_of_a_directory_is_seen_alike_from_another() {
        let dir = tempfile::tempdir().unwrap();
        let (root, data) = (dir.path().join("work/main"), dir.path().join("work/shared/data"));
        std::fs::create_dir_all(&root).unwrap();
        std::fs::create_dir_all(&data).unwrap();
        let expected = PathBuf::from("../shared/data");
        assert_eq!(seen_from(&data, &root), expected);
        assert_eq!(seen_from(&root.join("../shared/./data"), &root), expected);
        assert_eq!(seen_from(&root, &root), PathBuf::from("."));
        assert_eq!(seen_from(&root.join("sub"), &root), root.join("sub"), "a missing path stays as given");
    }
}
