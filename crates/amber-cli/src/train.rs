//! `amber train`: trains AMBER on a task with a named profile into a run directory (resumes a
//! killed run there) and writes the model's card. The task is a dataset folder of expert meshes
//! when `--data` holds a `train/` directory, else generated Poisson problems.

use std::path::{Path, PathBuf};

use amber_experiments::{Method, ModelCard, amber_config, merge_json, train_folder, train_poisson, training_commits};
use amber_stdx::read_json;
use amber_tasks::folder::{Split, mesh_dimension};
use amber_tasks::poisson::{Difficulty, INITIAL_SIZE};
use amber_train::{MODEL_DIR, MethodConfig, Profile};
use anyhow::{Context, bail};
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

/// How to train, as `amber train` and `amber cross-validate` both take it.
#[derive(Args)]
pub struct TrainingArgs {
    /// smoke (minutes), quick (on 2 cores: 21–26 minutes of training on Poisson, 44–51 on the
    /// Console parts, results/), paper (GPU scale).
    #[arg(long, default_value = "quick")]
    profile: Profile,
    /// amber-mean or amber-max: how the expert's sizes become labels on a coarser mesh. Mean,
    /// the default, meshes the Console parts better with the profile's log objective
    /// (normalised DCD 0.147 against Max's 0.157 on the val parts, 0.237 against 0.244 on
    /// train/016–019, two seeds each, docs/PROFILES.md) and Poisson as well (0.089 against
    /// 0.090, two seeds, results/poisson).
    #[arg(long, default_value = "amber-mean")]
    pub method: Method,
    /// Training seed: selects the training problems and seeds the run.
    #[arg(long, default_value_t = 0)]
    seed: usize,
    /// Override the number of gradient steps.
    #[arg(long)]
    steps: Option<u64>,
    /// A JSON file of training-config fields overriding the profile's.
    #[arg(long)]
    config: Option<PathBuf>,
}

impl TrainingArgs {
    /// The validated training config of `task`: the profile's, with the method, seed, config
    /// file and steps given.
    pub fn config(&self, task: amber_experiments::Task) -> anyhow::Result<MethodConfig> {
        let mut config = amber_config(task, self.profile);
        config.aggregation = self.method.aggregation();
        config.seed = self.seed as u64;
        if let Some(path) = &self.config {
            let mut value = serde_json::to_value(&config)?;
            merge_json(&mut value, &read_json(path)?);
            config =
                serde_json::from_value(value).with_context(|| format!("{}: not a training config", path.display()))?;
        }
        if let Some(steps) = self.steps {
            config.steps = steps;
        }
        let config = MethodConfig::Amber(config);
        config.validate().with_context(|| match &self.config {
            Some(path) => format!("{}: with the {} profile", path.display(), self.profile),
            None => format!("the {} profile", self.profile),
        })?;
        Ok(config)
    }

    /// Writes the card of the model trained with `config` into `model` (a run's model directory,
    /// whose run names the commits that trained it) and returns it.
    pub fn write_card(
        &self,
        model: &Path,
        task: amber_experiments::Task,
        config: &MethodConfig,
        trained: Trained,
    ) -> anyhow::Result<ModelCard> {
        let MethodConfig::Amber(amber) = config else { bail!("amber trains AMBER models") };
        let run = model.parent().unwrap_or(model);
        let commit =
            training_commits(run)?.with_context(|| format!("{}: no record of the training's commit", run.display()))?;
        let card = ModelCard {
            task,
            method: self.method.to_string(),
            inference_steps: amber.inference_steps,
            initial_size: trained.initial_size,
            command: std::env::args().collect::<Vec<_>>().join(" "),
            data: trained.data,
            commit,
            training_seconds: trained.seconds,
            evaluation: None,
            calibration: None,
        };
        card.write(model)?;
        Ok(card)
    }
}

/// What a training made, for its model's card.
pub struct Trained {
    /// Training wall time, seconds.
    pub seconds: f64,
    /// Edge length of M⁰.
    pub initial_size: f64,
    /// The training data, in words.
    pub data: String,
}

#[derive(Args)]
pub struct TrainArgs {
    /// The task (default: `folder` when --data holds a `train/` directory, else `poisson`).
    #[arg(long, value_enum)]
    task: Option<Task>,
    #[command(flatten)]
    training: TrainingArgs,
    /// Expert refinement steps of the problems: easy (25), medium (50), hard (75).
    #[arg(long, default_value = "hard")]
    difficulty: Difficulty,
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
    let training = &args.training;
    let config = training.config(card_task)?;
    let trained = match dimension {
        None => {
            let label = format!("{} {} seed {}", training.method, args.difficulty, training.seed);
            let seconds = train_poisson(&config, args.difficulty, &args.data, &args.manifest, &args.out, &label)?;
            let data = format!(
                "{} problems of {}, difficulty {}, seed {}",
                args.data.display(),
                args.manifest.display(),
                args.difficulty,
                training.seed
            );
            Trained { seconds, initial_size: INITIAL_SIZE, data }
        }
        Some(dimension) => {
            let label = format!("{} {} seed {}", training.method, args.data.display(), training.seed);
            let trained = train_folder(&config, dimension, &args.data, args.initial_size, None, &args.out, &label)?;
            let data = format!("{} ({} training parts, {dimension}D)", args.data.display(), trained.parts);
            Trained { seconds: trained.seconds, initial_size: trained.initial_size, data }
        }
    };
    let seconds = trained.seconds;
    let model = args.out.join(MODEL_DIR);
    training.write_card(&model, card_task, &config, trained)?;
    println!("trained in {seconds:.0} s; model in {}", model.display());
    Ok(())
}
