//! `cargo xtask ship-model`: copies the model of one run of a reproduction into `models/NAME`
//! with its card, whose command, data, commit, training time and scores come from the
//! reproduction's `results.json`: a shipped model carries the evidence of where it came from.

use std::path::{Path, PathBuf};

use amber_experiments::{CardEvaluation, ModelCard, RunResult, Task};
use amber_stdx::read_json;
use amber_tasks::{console, poisson};
use amber_train::{MODEL_DIR, MethodConfig};
use anyhow::Context;

#[derive(clap::Args)]
pub struct Args {
    /// The `results.json` of the reproduction that trained the run.
    #[arg(long)]
    results: PathBuf,
    /// The run's method (`amber-mean`, `amber-max`, `cnn-64`, ...).
    #[arg(long)]
    method: String,
    /// The run's training seed.
    #[arg(long, default_value_t = 0)]
    seed: usize,
    /// The name under `models/` (what `amber mesh --model NAME` finds).
    #[arg(long)]
    name: String,
    /// Where shipped models live.
    #[arg(long, default_value = "models")]
    models: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let results: serde_json::Value = read_json(&args.results)?;
    let context = || format!("{}", args.results.display());
    let experiment = results["experiment"].as_str().with_context(|| format!("{}: no experiment", context()))?;
    let run_config = results["config"]["runs"]
        .as_array()
        .into_iter()
        .flatten()
        .find(|r| r["method"] == args.method.as_str() && r["seed"] == args.seed)
        .with_context(|| format!("{}: no run of {} with seed {}", context(), args.method, args.seed))?;
    let run: RunResult = serde_json::from_value(
        results["runs"]
            .as_array()
            .into_iter()
            .flatten()
            .find(|r| r["method"] == args.method.as_str() && r["seed"] == args.seed && r["variant"] == "default")
            .with_context(|| format!("{}: no result of {} with seed {}", context(), args.method, args.seed))?
            .clone(),
    )?;
    let run_dir = PathBuf::from(run_config["run_dir"].as_str().context("run without run_dir")?);
    let training: MethodConfig = serde_json::from_value(run_config["training"].clone())
        .with_context(|| format!("{}: the run's training config", context()))?;
    let settings = &results["config"]["experiment"];
    let profile = results["profile"].as_str().unwrap_or("quick");
    let (task, initial_size, data, command) = match experiment {
        "poisson" => (
            Task::Poisson,
            poisson::INITIAL_SIZE,
            format!(
                "{} {} problems of {}",
                settings["manifest"].as_str().unwrap_or("?"),
                run.difficulty,
                settings["data_root"].as_str().unwrap_or("?")
            ),
            format!(
                "cargo xtask reproduce poisson --profile {profile} --difficulty {} --methods {}",
                run.difficulty, args.method
            ),
        ),
        "console" => (
            Task::Console,
            console::INITIAL_SIZE,
            format!(
                "Console {} parts of {}",
                settings["train_set"].as_str().unwrap_or("paper"),
                settings["data"].as_str().unwrap_or("?")
            ),
            format!(
                "cargo xtask reproduce console --profile {profile} --data {} --methods {}",
                settings["data"].as_str().unwrap_or("?"),
                args.method
            ),
        ),
        other => anyhow::bail!("{}: experiment `{other}` trains no shippable model", context()),
    };
    let card = ModelCard {
        task,
        method: args.method.clone(),
        inference_steps: training.inference_steps(),
        initial_size,
        command,
        data,
        commit: results["commit"].as_str().unwrap_or("unknown").to_owned(),
        training_seconds: run.train_seconds,
        evaluation: Some(CardEvaluation {
            problems: format!("{} {} problems", experiment, run.test_problems),
            normalised_dcd: run.ndcd,
            normalised_dcd_per_step: run.ndcd_per_step.clone(),
            elements: run.elements,
            expert_elements: run.expert_elements,
        }),
    };
    let target = args.models.join(&args.name);
    copy_model(&run_dir.join(MODEL_DIR), &target)?;
    card.write(&target)?;
    println!(
        "{} → {} (normalised DCD {:.3} on {})",
        run_dir.display(),
        target.display(),
        run.ndcd,
        card.evaluation.as_ref().map_or("", |e| &e.problems)
    );
    Ok(())
}

/// Copies the files of a model directory (no subdirectories) into `target`.
fn copy_model(source: &Path, target: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(target).with_context(|| format!("{}: cannot create", target.display()))?;
    for entry in std::fs::read_dir(source).with_context(|| format!("{}: not a model directory", source.display()))? {
        let path = entry?.path();
        if path.is_file() {
            let bytes = std::fs::read(&path).with_context(|| format!("{}: cannot read", path.display()))?;
            amber_experiments::write_atomic(&target.join(path.file_name().expect("a file")), &bytes)?;
        }
    }
    Ok(())
}
