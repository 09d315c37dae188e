//! `cargo xtask reproduce poisson`: the paper's Poisson experiment end to end (datasets,
//! training of every method × difficulty × seed, test rollouts, tables and plots under
//! `results/poisson/`). Trained runs are cached under `data/runs/`, keyed by their config.

use std::path::{Path, PathBuf};

use amber_experiments::{ConsoleExperiment, ExperimentResults, Method, MethodSpec, PoissonExperiment};
use amber_stdx::read_json;
use amber_tasks::console::TrainSet;
use amber_tasks::poisson::Difficulty;
use amber_train::Profile;

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
    /// Methods, comma-separated (default: the profile's).
    #[arg(long, value_delimiter = ',')]
    methods: Vec<Method>,
    #[command(flatten)]
    overrides: OverrideArgs,
    /// Retrain and re-evaluate even when cached.
    #[arg(long)]
    force: bool,
    /// Write under `results/` even from code with uncommitted changes (its results would name
    /// no commit that made them).
    #[arg(long)]
    allow_dirty: bool,
    /// Output directory.
    #[arg(long, default_value = "results/console")]
    out: PathBuf,
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
    overrides: OverrideArgs,
    /// Skip a generation step whose field exceeds the element budget, as the paper does,
    /// instead of scaling the field to the budget (the default outside the paper profile).
    #[arg(long)]
    skip_over_budget: bool,
    /// Retrain and re-evaluate even when cached.
    #[arg(long)]
    force: bool,
    /// Write under `results/` even from code with uncommitted changes (its results would name
    /// no commit that made them).
    #[arg(long)]
    allow_dirty: bool,
    /// Output directory.
    #[arg(long, default_value = "results/poisson")]
    out: PathBuf,
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

pub fn run(args: Args) -> anyhow::Result<()> {
    match args.experiment {
        Experiment::Poisson(args) => poisson(args),
        Experiment::Console(args) => console(args),
    }
}

fn console(args: ConsoleArgs) -> anyhow::Result<()> {
    check_provenance(&args.out, args.allow_dirty)?;
    let mut experiment = ConsoleExperiment::new(args.profile, &args.data);
    if args.all_train {
        experiment.train_set = TrainSet::All;
    }
    if !args.methods.is_empty() {
        experiment.methods = args.methods.into_iter().map(MethodSpec::plain).collect();
    }
    (experiment.overrides, experiment.cnn_overrides) = args.overrides.read()?;
    experiment.force = args.force;
    experiment.out = args.out;
    report(&experiment.run()?, &experiment.out);
    Ok(())
}

fn poisson(args: PoissonArgs) -> anyhow::Result<()> {
    check_provenance(&args.out, args.allow_dirty)?;
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
    experiment.force = args.force;
    experiment.out = args.out;
    report(&experiment.run()?, &experiment.out);
    Ok(())
}

#[derive(clap::Args, Debug)]
pub struct AblateArgs {
    /// smoke (CI: minutes), quick (hours on 2 cores), paper (GPU scale).
    #[arg(long, default_value = "quick")]
    profile: Profile,
    /// Retrain and re-evaluate even when cached.
    #[arg(long)]
    force: bool,
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
    check_provenance(&args.out, args.allow_dirty)?;
    let mut experiment = PoissonExperiment::ablation(args.profile);
    experiment.force = args.force;
    experiment.out = args.out;
    report(&experiment.run()?, &experiment.out);
    Ok(())
}

/// Refuses to write under `results/` (the committed evidence) from a binary built from a dirty
/// tree, unless `allow_dirty`.
fn check_provenance(out: &Path, allow_dirty: bool) -> anyhow::Result<()> {
    if out.starts_with("results") && !allow_dirty && !amber_experiments::built_from_a_clean_commit() {
        anyhow::bail!(
            "{}: this binary was built from {}, not a clean commit; commit first, write elsewhere (--out) or pass \
             --allow-dirty",
            out.display(),
            amber_experiments::commit()
        );
    }
    Ok(())
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
