//! `cargo xtask label-rollouts`: the ceiling of imitation on a Poisson split. Each problem is
//! rolled out from M⁰ as at inference, but every generation step meshes the projected expert
//! labels (spec §3) instead of a network's prediction, under the training run's h_min and element
//! budget (fields over budget scaled to it). What a perfect network would score, step by step:
//! any gap to a trained model's per-step curve is the network's.

use std::path::PathBuf;

use amber_experiments::{Task, amber_config};
use amber_graph::Aggregation;
use amber_tasks::poisson::read_split;
use amber_tasks::{Domain, MeshLimits, Problem, StepOutcome, generation_step, labels};
use amber_train::{MeshMetrics, Reference};
use anyhow::Context;
use rayon::prelude::*;
use serde::Serialize;

use crate::report::{machine, write_json};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// A split directory of Poisson problem files to roll out.
    #[arg(long, default_value = "data/poisson/hard/val")]
    data: PathBuf,
    /// The training split whose experts fix h_min and the element budget (its first N problems,
    /// N the quick profile's training-problem count).
    #[arg(long, default_value = "data/poisson/hard/train/seed0")]
    train: PathBuf,
    /// Label aggregation: mean (AMBER-Mean) or max (AMBER-Max).
    #[arg(long, default_value = "mean", value_parser = parse_aggregation)]
    #[serde(skip)]
    aggregation: Aggregation,
    /// Generation steps.
    #[arg(long, default_value_t = 5)]
    steps: usize,
    /// Where to write the per-step means and the per-problem curves (default:
    /// results/poisson/label_rollouts_{mean,max}.json).
    #[arg(long)]
    out: Option<PathBuf>,
}

fn parse_aggregation(name: &str) -> Result<Aggregation, String> {
    match name {
        "mean" => Ok(Aggregation::Mean),
        "max" => Ok(Aggregation::Max),
        _ => Err(format!("unknown aggregation `{name}` (mean, max)")),
    }
}

/// One problem's rollout: normalised DCD and element count after each step.
#[derive(Serialize)]
struct Row {
    problem: usize,
    expert_elements: usize,
    normalised_dcd: Vec<f64>,
    elements: Vec<usize>,
    /// Steps whose field the generator refused or failed on (the previous mesh was kept).
    failed_steps: usize,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let missing = |dir: &PathBuf| format!("{}: run `cargo xtask dataset poisson` first", dir.display());
    let config = amber_config(Task::Poisson, amber_train::Profile::Quick);
    let train = read_split(&args.train).with_context(|| missing(&args.train))?;
    let train = &train[..config.data.train_problems.min(train.len())];
    let mut limits =
        MeshLimits::from_experts(train.iter().map(|p| p.expert_mesh()), config.budget_factor, config.min_size_quantile);
    limits.scale_to_budget = true;
    let problems = read_split(&args.data).with_context(|| missing(&args.data))?;
    let rows = problems
        .par_iter()
        .enumerate()
        .map(|(problem, p)| {
            let context = || format!("{} problem {problem}", args.data.display());
            let reference = Reference::new(p, &limits).with_context(context)?;
            let mut mesh = p.initial_mesh().clone();
            let mut row = Row {
                problem,
                expert_elements: p.expert_mesh().num_elements(),
                normalised_dcd: Vec::new(),
                elements: Vec::new(),
                failed_steps: 0,
            };
            for _ in 0..args.steps {
                let sizes = labels(p, &mesh, args.aggregation).with_context(context)?;
                match generation_step(p, &mesh, sizes, &limits) {
                    StepOutcome::Meshed(next) => mesh = next,
                    StepOutcome::OverBudget { .. } | StepOutcome::Failed { .. } => row.failed_steps += 1,
                }
                let metrics = MeshMetrics::of(&mesh, p.expert_mesh(), &reference).with_context(context)?;
                row.normalised_dcd.push(metrics.normalised_dcd);
                row.elements.push(metrics.elements);
            }
            Ok(row)
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
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
        let name = if args.aggregation == Aggregation::Mean { "mean" } else { "max" };
        PathBuf::from(format!("results/poisson/label_rollouts_{name}.json"))
    });
    write_json(&out, &serde_json::json!({ "args": args, "summary": summary, "machine": machine(), "problems": rows }))
}
