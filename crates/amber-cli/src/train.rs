//! `amber train`: trains AMBER on a task with a named profile into a run directory (resumes a
//! killed run there) and writes the model's card. The task is a dataset folder of expert meshes
//! when `--data` holds a `train/` directory, else generated Poisson problems.

use std::path::PathBuf;

use amber_experiments::{Method, ModelCard, amber_config, commit, merge_json, train_folder, train_poisson};
use amber_stdx::read_json;
use amber_tasks::folder::{Split, mesh_dimension};
use amber_tasks::poisson::{Difficulty, INITIAL_SIZE};
use amber_train::{MODEL_DIR, MethodConfig, Profile};
use anyhow::Context;
use clap::{Args, ValueEnum};

/// The learning tasks.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Task {
    /// Poisson problems on random L-shapes (spec §1).
    Poisson,
    /// A dataset folder: `DIR/train/`, `DIR/val/` of expert meshes (any format amber reads), with
    /// optional geometry files and `DIR/dataset.json`.
    Folder,
}

#[derive(Args)]
pub struct TrainArgs {
    /// The task (default: `folder` when --data holds a `train/` directory, else `poisson`).
    #[arg(long, value_enum)]
    task: Option<Task>,
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
    /// A dataset folder of expert meshes (`train/`, `val/`), or the Poisson dataset root (problems
    /// are generated there when missing).
    #[arg(long, default_value = "data/poisson")]
    data: PathBuf,
    /// Split seeds and sizes.
    #[arg(long, default_value = "datasets/poisson.json")]
    manifest: PathBuf,
    /// Folder datasets: the edge length of every part's uniform M⁰ (default: the folder's
    /// `dataset.json`, else 4 × the median training expert element size).
    #[arg(long)]
    initial_size: Option<f64>,
    /// Run directory: config, log, checkpoints, and the model in `<out>/model`.
    #[arg(long)]
    out: PathBuf,
}

pub fn train(args: TrainArgs) -> anyhow::Result<()> {
    let task = args.task.unwrap_or(if args.data.join("train").is_dir() { Task::Folder } else { Task::Poisson });
    // A folder's dimension: its meshes'.
    let dimension = match task {
        Task::Poisson => None,
        Task::Folder => Some(mesh_dimension(&Split::Train.dir(&args.data))?),
    };
    let card_task =
        dimension.map_or(amber_experiments::Task::Poisson, |dimension| amber_experiments::Task::Folder { dimension });
    let mut config = amber_config(card_task, args.profile);
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
    let inference_steps = config.inference_steps;
    let config = MethodConfig::Amber(config);
    config.validate().with_context(|| match &args.config {
        Some(path) => format!("{}: with the {} profile", path.display(), args.profile),
        None => format!("the {} profile", args.profile),
    })?;
    let (seconds, initial_size, data) = match dimension {
        None => {
            let label = format!("{} {} seed {}", args.method, args.difficulty, args.seed);
            let seconds = train_poisson(&config, args.difficulty, &args.data, &args.manifest, &args.out, &label)?;
            let data = format!(
                "{} problems of {}, difficulty {}, seed {}",
                args.data.display(),
                args.manifest.display(),
                args.difficulty,
                args.seed
            );
            (seconds, INITIAL_SIZE, data)
        }
        Some(dimension) => {
            let label = format!("{} {} seed {}", args.method, args.data.display(), args.seed);
            let trained = train_folder(&config, dimension, &args.data, args.initial_size, &args.out, &label)?;
            let data = format!("{} ({} training parts, {dimension}D)", args.data.display(), trained.parts);
            (trained.seconds, trained.initial_size, data)
        }
    };
    let model = args.out.join(MODEL_DIR);
    let card = ModelCard {
        task: card_task,
        method: args.method.to_string(),
        inference_steps,
        initial_size,
        command: std::env::args().collect::<Vec<_>>().join(" "),
        data,
        commit: commit().to_owned(),
        training_seconds: seconds,
        evaluation: None,
    };
    card.write(&model)?;
    println!("trained in {seconds:.0} s; model in {}", model.display());
    Ok(())
}
