//! `amber train`: trains AMBER on a task with a named profile into a run directory (resumes a
//! killed run there), and `amber generate`: applies a trained model to a problem.

use std::path::PathBuf;

use amber_experiments::{Method, amber_config, merge_json, train_poisson};
use amber_mesh::{MeshData, write_mesh};
use amber_plot::{RenderOptions, render_png};
use amber_stdx::read_json;
use amber_tasks::poisson::{Difficulty, read_problem};
use amber_train::{AmberModel, Evaluation, MODEL_DIR, MethodConfig, Profile, StepStatus};
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
    let config = MethodConfig::Amber(config);
    config.validate()?;
    let seconds = train_poisson(&config, args.difficulty, &args.data, &args.manifest, &args.out, &label)?;
    println!("trained in {seconds:.0} s; model in {}", args.out.join(MODEL_DIR).display());
    Ok(())
}

#[derive(Args)]
pub struct GenerateArgs {
    /// A trained model directory (`<run>/model`) or a checkpoint directory.
    #[arg(long)]
    model: PathBuf,
    /// A Poisson problem file (ours or the reference's JSON format) with its expert mesh.
    #[arg(long)]
    problem: PathBuf,
    /// Generation steps T.
    #[arg(long, default_value_t = 5)]
    steps: usize,
    /// Output directory: `step<t>.vtu` and `step<t>.png` per step and `metrics.json`.
    #[arg(long)]
    out: PathBuf,
}

pub fn generate(args: GenerateArgs) -> anyhow::Result<()> {
    let model =
        AmberModel::load(&args.model).with_context(|| format!("{}: cannot load the model", args.model.display()))?;
    let problem = read_problem(&args.problem)?;
    let problems = [problem];
    let evaluation = Evaluation::new(&problems, &model.predictor.limits)?;
    let (rollouts, summary) = evaluation.run(&model.sizing(), args.steps)?;
    let rollout = &rollouts[0];
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}: cannot create", args.out.display()))?;
    let range = rollout
        .steps
        .iter()
        .flat_map(|s| s.mesh.sizes())
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), h| (lo.min(h), hi.max(h)));
    for (t, step) in rollout.steps.iter().enumerate() {
        let sizes = step.mesh.sizes();
        let mut data = MeshData::default();
        data.cell.insert("size".into(), sizes.clone());
        write_mesh(&step.mesh, args.out.join(format!("step{}.vtu", t + 1)), &data)?;
        let title = format!(
            "step {}: {} elements, normalised DCD {:.3}{}",
            t + 1,
            step.mesh.num_elements(),
            step.metrics.normalised_dcd,
            if step.status == StepStatus::Meshed { String::new() } else { format!(" ({:?})", step.status) }
        );
        let options = RenderOptions { title: Some(title), log_scale: true, range: Some(range), ..Default::default() };
        render_png(&step.mesh, &sizes, &options, args.out.join(format!("step{}.png", t + 1)))?;
        println!(
            "step {}: {} elements (expert {}), normalised DCD {:.3}, raw DCD {:.4}",
            t + 1,
            step.mesh.num_elements(),
            problems[0].expert_mesh.num_elements(),
            step.metrics.normalised_dcd,
            step.metrics.dcd
        );
    }
    amber_experiments::write_json(&args.out.join("metrics.json"), &summary)?;
    println!("wrote {}/step*.vtu, step*.png, metrics.json", args.out.display());
    Ok(())
}
