//! `cargo xtask label-rollouts`: the ceiling of imitation on a split of the Poisson or the
//! Console task. Each problem is rolled out from M⁰ as at inference, but every generation step
//! meshes the projected expert labels (spec §3) instead of a network's prediction, under the
//! training run's h_min and element budget (fields over budget scaled to it). What a perfect
//! network would score, step by step: any gap to a trained model's per-step curve is the
//! network's, and a label whose rollout stalls short of the expert is the labels'.

use std::path::{Path, PathBuf};

use amber_experiments::{Task, amber_config};
use amber_graph::Aggregation;
use amber_tasks::console::{INITIAL_SIZE, TrainSet, check_data};
use amber_tasks::folder::{DatasetSettings, Split, problems, read_experts};
use amber_tasks::part::SolidPart;
use amber_tasks::poisson::read_split;
use amber_tasks::{MeshLimits, Problem, SizeBounds, StepOutcome, generation_step, labels};
use amber_train::{MeshMetrics, Reference};
use anyhow::Context;
use rayon::prelude::*;
use serde::Serialize;

use crate::report::{machine, write_json};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// The task: `poisson` (a split directory of problem files) or `console`.
    #[arg(long, value_enum, default_value_t = RolloutTask::Poisson)]
    task: RolloutTask,
    /// Poisson: a split directory of problem files to roll out. Console: the data directory,
    /// whose training and val parts are rolled out (the training parts fix h_min and the budget).
    #[arg(long, default_value = "data/poisson/hard/val")]
    data: PathBuf,
    /// Poisson: the training split whose experts fix h_min and the element budget (its first N
    /// problems, N the quick profile's training-problem count).
    #[arg(long, default_value = "data/poisson/hard/train/seed0")]
    train: PathBuf,
    /// Label aggregation: mean (AMBER-Mean), max (AMBER-Max) or density.
    #[arg(long, default_value = "mean", value_parser = parse_aggregation)]
    #[serde(skip)]
    aggregation: Aggregation,
    /// Generation steps.
    #[arg(long, default_value_t = 5)]
    steps: usize,
    /// Where to write the per-step means and the per-problem curves (default:
    /// results/<task>/label_rollouts_<aggregation>.json).
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
enum RolloutTask {
    Poisson,
    Console,
}

impl RolloutTask {
    fn task(self) -> Task {
        match self {
            RolloutTask::Poisson => Task::Poisson,
            RolloutTask::Console => Task::Console,
        }
    }
}

fn parse_aggregation(name: &str) -> Result<Aggregation, String> {
    serde_json::from_value(serde_json::Value::from(name))
        .map_err(|_| format!("unknown aggregation `{name}` (mean, max, density)"))
}

/// One problem's rollout: normalised DCD and element count after each step.
#[derive(Serialize)]
struct Row {
    problem: usize,
    name: String,
    expert_elements: usize,
    normalised_dcd: Vec<f64>,
    elements: Vec<usize>,
    /// Steps whose field the generator refused or failed on (the previous mesh was kept).
    failed_steps: usize,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let config = amber_config(args.task.task(), amber_train::Profile::Quick);
    let rows = match args.task {
        RolloutTask::Poisson => {
            let missing = |dir: &PathBuf| format!("{}: run `cargo xtask dataset poisson` first", dir.display());
            let train = read_split(&args.train).with_context(|| missing(&args.train))?;
            let train = &train[..config.data.train_problems.min(train.len())];
            let limits = training_limits(train.iter().map(|p| p.expert_mesh()), &config);
            let problems = read_split(&args.data).with_context(|| missing(&args.data))?;
            roll_out(&problems, &limits, &args)?
        }
        RolloutTask::Console => {
            check_data(&args.data)?;
            let parts = |split: Split| -> anyhow::Result<_> {
                let experts = read_experts::<3>(&split.dir(&args.data), TrainSet::All.part_limit())?;
                Ok(problems::<3, SolidPart>(experts, INITIAL_SIZE, &DatasetSettings::read(&args.data)?)?)
            };
            // No network is trained, so the training parts are as unseen as the val parts.
            let mut all = parts(Split::Train)?;
            let limits = training_limits(all.iter().map(|p| p.expert_mesh()), &config);
            all.extend(parts(Split::Val)?);
            roll_out(&all, &limits, &args)?
        }
    };
    let n = rows.len().max(1) as f64;
    let per_step = |f: &dyn Fn(&Row, usize) -> f64| {
        (0..args.steps).map(|t| rows.iter().map(|r| f(r, t)).sum::<f64>() / n).collect::<Vec<_>>()
    };
    let summary = serde_json::json!({
        "problems": rows.len(),
        "aggregation": args.aggregation,
        "normalised_dcd_per_step": per_step(&|r, t| r.normalised_dcd[t]),
        "elements_per_step": per_step(&|r, t| r.elements[t] as f64),
        "expert_elements": rows.iter().map(|r| r.expert_elements as f64).sum::<f64>() / n,
        "failed_steps": rows.iter().map(|r| r.failed_steps).sum::<usize>(),
    });
    println!("{}", serde_json::to_string_pretty(&summary)?);
    let out = args.out.clone().unwrap_or_else(|| {
        let name = serde_json::to_value(args.aggregation).ok().and_then(|v| v.as_str().map(String::from));
        Path::new("results")
            .join(args.task.task().name())
            .join(format!("label_rollouts_{}.json", name.unwrap_or_default()))
    });
    write_json(&out, &serde_json::json!({ "args": args, "summary": summary, "machine": machine(), "problems": rows }))
}

/// h_min and the element budget of a training run on these experts; fields over budget are
/// scaled to it, as at evaluation.
fn training_limits<'m, const D: usize>(
    experts: impl IntoIterator<Item = &'m amber_mesh::Mesh<D>>,
    config: &amber_train::TrainingConfig,
) -> MeshLimits {
    let mut limits = MeshLimits::from_experts(experts, config.budget_factor, config.min_size_quantile);
    limits.scale_to_budget = true;
    limits
}

/// Rolls out every problem on its own projected labels, in parallel.
fn roll_out<const D: usize, P: Problem<D> + Sync>(
    problems: &[P],
    limits: &MeshLimits,
    args: &Args,
) -> anyhow::Result<Vec<Row>> {
    problems
        .par_iter()
        .enumerate()
        .map(|(problem, p)| {
            let context = || format!("{} problem {problem}", args.data.display());
            let reference = Reference::new(p, limits).with_context(context)?;
            let mut mesh = p.initial_mesh().clone();
            let mut row = Row {
                problem,
                name: p.name(),
                expert_elements: p.expert_mesh().num_elements(),
                normalised_dcd: Vec::new(),
                elements: Vec::new(),
                failed_steps: 0,
            };
            for _ in 0..args.steps {
                let sizes = labels(p, &mesh, args.aggregation).with_context(context)?;
                match generation_step(p, &mesh, sizes, limits, &SizeBounds::default()) {
                    StepOutcome::Meshed(next) => mesh = next,
                    StepOutcome::OverBudget { .. } | StepOutcome::Failed { .. } => row.failed_steps += 1,
                }
                let metrics = MeshMetrics::of(&mesh, p.expert_mesh(), &reference).with_context(context)?;
                row.normalised_dcd.push(metrics.normalised_dcd);
                row.elements.push(metrics.elements);
            }
            Ok(row)
        })
        .collect()
}
