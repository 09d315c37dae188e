//! `amber train`: trains AMBER on a task with a named profile into a run directory (resumes a
//! killed run there) and writes the model's card.

use std::path::PathBuf;

use amber_experiments::{Method, ModelCard, amber_config, commit, merge_json, train_poisson};
use amber_stdx::read_json;
use amber_tasks::poisson::{Difficulty, INITIAL_SIZE};
use amber_train::{MODEL_DIR, MethodConfig, Profile};
use anyhow::Context;
use clap::{Args, ValueEnum};

/// The learning tasks.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Task {
    /// Poisson problems on random L-shapes (spec §1).
    Poisson,
}

#[derive(Args)]
pub struct TrainArgs {
    #[arg(long, value_enum, default_value = "poisson")]
    task: Task,
    /// smoke (minutes), quick (about 30 minutes on 2 cores), paper (GPU scale).
    #[arg(long, default_value = "quick")]
    profile: Profile,
    /// Expert refinement steps of the problems: easy (25), medium (50), hard (75).
    #[arg(long, default_value = "hard")]
    difficulty: Difficulty,
    /// amber-mean or amber-max.
    #[arg(long, default_value = "amber-mean")]
    method: Method,
    /// Training seed: selects the training problems and seeds the run.
    #[arg(long, default_value_t = 0)]
    seed: usize,
    /// Override the number of gradient steps.
    #[arg(long)]
    steps: Option<u64>,
    /// A JSON file of training-config fields overriding the profile's.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Dataset root (problems are generated there when missing).
    #[arg(long, default_value = "data/poisson")]
    data: PathBuf,
    /// Split seeds and sizes.
    #[arg(long, default_value = "datasets/poisson.json")]
    manifest: PathBuf,
    /// Run directory: config, log, checkpoints, and the model in `<out>/model`.
    #[arg(long)]
    out: PathBuf,
}

pub fn train(args: TrainArgs) -> anyhow::Result<()> {
    let Task::Poisson = args.task;
    let mut config = amber_config(amber_experiments::Task::Poisson, args.profile);
    config.aggregation = args.method.aggregation();
    config.seed = args.seed as u64;
    if let Some(path) = &args.config {
        let mut value = serde_json::to_value(&config)?;
        merge_json(&mut value, &read_json(path)?);
        config = serde_json::from_value(value).with_context(|| format!("{}: not a training config", path.display()))?;
    }
    if let Some(steps) = args.steps {
        config.steps = steps;
    }
    let label = format!("{} {} seed {}", args.method, args.difficulty, args.seed);
    let inference_steps = config.inference_steps;
    let config = MethodConfig::Amber(config);
    config.validate()?;
    let seconds = train_poisson(&config, args.difficulty, &args.data, &args.manifest, &args.out, &label)?;
    let model = args.out.join(MODEL_DIR);
    let card = ModelCard {
        task: amber_experiments::Task::Poisson,
        method: args.method.to_string(),
        inference_steps,
        initial_size: INITIAL_SIZE,
        command: std::env::args().collect::<Vec<_>>().join(" "),
        data: format!(
            "{} problems of {}, difficulty {}, seed {}",
            args.data.display(),
            args.manifest.display(),
            args.difficulty,
            args.seed
        ),
        commit: commit().to_owned(),
        training_seconds: seconds,
        evaluation: None,
    };
    card.write(&model)?;
    println!("trained in {seconds:.0} s; model in {}", model.display());
    Ok(())
}
