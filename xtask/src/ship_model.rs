//! `cargo xtask ship-model`: copies the model of one run of a reproduction into `models/NAME`
//! with the card the reproduction wrote (the command, data, commit, training time and scores):
//! a shipped model carries the evidence of where it came from.

use std::path::{Path, PathBuf};

use amber_experiments::ModelCard;
use amber_stdx::read_json;
use amber_train::MODEL_DIR;
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
    let run_config = results["config"]["runs"]
        .as_array()
        .into_iter()
        .flatten()
        .find(|r| r["method"] == args.method.as_str() && r["seed"] == args.seed && r["variant"] == "default")
        .with_context(|| format!("{}: no run of {} with seed {}", args.results.display(), args.method, args.seed))?;
    let run_dir = PathBuf::from(run_config["run_dir"].as_str().context("run without run_dir")?);
    let source = run_dir.join(MODEL_DIR);
    // The reproduction wrote the card when it evaluated the run.
    let card = ModelCard::read(&source)
        .with_context(|| format!("{}: rerun the reproduction to write the card", source.display()))?;
    let target = args.models.join(&args.name);
    copy_model(&source, &target)?;
    println!(
        "{} → {} (normalised DCD {:.3} on {})",
        run_dir.display(),
        target.display(),
        card.evaluation.as_ref().map_or(f64::NAN, |e| e.normalised_dcd),
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
