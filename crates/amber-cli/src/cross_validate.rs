//! `amber cross-validate`: how well a model of a folder's experts meshes a part it has not seen,
//! measured on the folder itself. K models, each trained on the training parts but every K-th
//! (`amber_tasks::folder::Fold`), score the parts they held out; the scores of all parts, each by
//! the model that did not train on it, make one table, with each fold's mean beside it to show
//! the spread.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use amber_experiments::{Task, train_folder, write_atomic, write_json};
use amber_mesh::Mesh;
use amber_stdx::read_json;
use amber_tasks::folder::{DatasetSettings, Fold, FolderDomain, Split, mesh_dimension, read_experts};
use amber_tasks::part::{PlanarPart, SolidPart};
use amber_train::{MODEL_DIR, MethodConfig, TrainedModel};
use anyhow::{Context, bail};
use clap::Args;
use serde::Serialize;

use crate::evaluate::{PartScore, PartScorer, SCORES, score_table};
use crate::mesh::Picture;
use crate::train::{Trained, TrainingArgs};

/// The file in a fold's run directory that names the parts the fold held out.
const HELD_OUT_FILE: &str = "held_out.json";

#[derive(Args)]
pub struct CrossValidateArgs {
    /// A dataset folder of expert meshes: its `train/` parts are parted into the folds (part i,
    /// in name order, into fold i mod FOLDS), its `val/` parts, if any, validate every fold's
    /// training.
    #[arg(long)]
    data: PathBuf,
    /// Folds: each trains a model on the training parts it does not hold out (2 up to the number
    /// of training parts).
    #[arg(long, default_value_t = 4)]
    folds: usize,
    #[command(flatten)]
    training: TrainingArgs,
    /// The edge length of every part's uniform M⁰ (default: the folder's `dataset.json`, else 4 ×
    /// the median element size of the fold's training experts).
    #[arg(long)]
    initial_size: Option<f64>,
    /// Output directory: a run directory per fold (`fold<k>/`, resumed when run again), the
    /// pooled `evaluation.json` and `evaluation.md`, and a picture per part.
    #[arg(long)]
    out: PathBuf,
}

/// One fold's model and its scores on the parts it held out.
#[derive(Serialize)]
struct FoldScore {
    fold: usize,
    /// The fold's model directory.
    model: PathBuf,
    held_out: Vec<String>,
    /// Mean normalised DCD of the held-out parts after the last step.
    normalised_dcd: f64,
    /// Geometric mean over the held-out parts of final elements over the expert's.
    element_ratio: f64,
    training_seconds: f64,
}

pub fn run(args: CrossValidateArgs) -> anyhow::Result<()> {
    let dimension = mesh_dimension(&Split::Train.dir(&args.data))?;
    let mut config = args.training.config(Task::Folder { dimension })?;
    // The held-out parts are the test; a folder of a few parts need not spare some to validate.
    if !Split::Val.dir(&args.data).is_dir()
        && let MethodConfig::Amber(amber) = &mut config
    {
        amber.data.val_problems = 0;
        println!("{}: no val/, so the folds train without validation", args.data.display());
    }
    match dimension {
        2 => cross_validate::<2, PlanarPart>(&args, &config),
        3 => cross_validate::<3, SolidPart>(&args, &config),
        dimension => bail!("{}: {dimension}D meshes; a dataset holds triangles or tets", args.data.display()),
    }
}

fn cross_validate<const D: usize, P: FolderDomain<D>>(
    args: &CrossValidateArgs,
    config: &MethodConfig,
) -> anyhow::Result<()>
where
    Mesh<D>: Picture,
{
    let train_dir = Split::Train.dir(&args.data);
    let experts = read_experts::<D>(&train_dir, None)?;
    let folds = Fold::all(args.folds, experts.len()).map_err(|m| anyhow::anyhow!("{}: {m}", train_dir.display()))?;
    let settings = DatasetSettings::read(&args.data)?;
    let (mut parts, mut fold_scores) = (Vec::new(), Vec::new());
    for fold in folds {
        let dir = args.out.join(format!("fold{}", fold.index));
        let held_out: Vec<_> =
            experts.iter().enumerate().filter(|(i, _)| fold.holds_out(*i)).map(|(_, e)| e.clone()).collect();
        let names: Vec<String> = held_out.iter().map(|e| e.name.clone()).collect();
        check_held_out(&dir, &names)?;
        let label = format!("{} fold {} of {}", args.training.method, fold.index, fold.count);
        let trained = train_folder(config, D, &args.data, args.initial_size, Some(fold), &dir, &label)?;
        let model_dir = dir.join(MODEL_DIR);
        let data = format!(
            "{} ({} training parts, {D}D; fold {} of {} holds out {})",
            args.data.display(),
            trained.parts,
            fold.index,
            fold.count,
            names.join(", ")
        );
        let card = Trained { seconds: trained.seconds, initial_size: trained.initial_size, data };
        let card = args.training.write_card(&model_dir, Task::Folder { dimension: D }, config, card)?;
        let mut model = TrainedModel::load(&model_dir)
            .with_context(|| format!("{}: cannot load the model", model_dir.display()))?;
        // As `amber evaluate` does: a field over the budget is scaled to it, not skipped.
        model.limits_mut().scale_to_budget = true;
        let scorer = PartScorer {
            model: &model,
            initial_size: card.initial_size,
            settings: &settings,
            steps: card.inference_steps,
        };
        let (scores, summary) = scorer.score::<D, P>(held_out, Some(fold.index), &args.out)?;
        fold_scores.push(FoldScore {
            fold: fold.index,
            model: model_dir,
            held_out: names,
            normalised_dcd: summary.final_normalised_dcd().unwrap_or(f64::NAN),
            element_ratio: element_ratio(&scores),
            training_seconds: trained.seconds,
        });
        parts.extend(scores);
    }
    write_outputs(args, config, &fold_scores, &parts)
}

/// Fails when the fold's run directory `dir` holds a model of other held-out parts (the folder
/// or the number of folds changed), which would otherwise be taken as finished; records the
/// parts for a new run.
fn check_held_out(dir: &Path, names: &[String]) -> anyhow::Result<()> {
    let path = dir.join(HELD_OUT_FILE);
    if path.is_file() {
        let recorded: Vec<String> = read_json(&path)?;
        if recorded != names {
            bail!(
                "{}: this fold's model held out {}, but the fold now holds out {}: cross-validate into a new --out",
                path.display(),
                recorded.join(", "),
                names.join(", ")
            );
        }
        return Ok(());
    }
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    write_json(&path, &names)
}

/// The geometric mean over `parts` of their final elements over the expert's.
fn element_ratio(parts: &[PartScore]) -> f64 {
    (parts.iter().map(|p| p.element_ratio().ln()).sum::<f64>() / parts.len() as f64).exp()
}

fn write_outputs(
    args: &CrossValidateArgs,
    config: &MethodConfig,
    folds: &[FoldScore],
    parts: &[PartScore],
) -> anyhow::Result<()> {
    let mean = parts.iter().map(|p| p.evaluation.last().normalised_dcd).sum::<f64>() / parts.len() as f64;
    let element_ratio = element_ratio(parts);
    let json = serde_json::json!({
        "data": args.data, "folds": folds, "config": config, "normalised_dcd": mean,
        "element_ratio": element_ratio, "parts": parts,
    });
    write_json(&args.out.join("evaluation.json"), &json)?;

    let mut md = format!(
        "# {}-fold cross-validation of {} on {}\n\nEvery training part scored by the model of the fold that held it \
         out, which trained on the other parts; {SCORES} Elements ÷ expert's: geometric mean over the parts.\n\n",
        folds.len(),
        args.training.method,
        args.data.display()
    );
    md.push_str(
        "| fold | held-out parts | normalised DCD | elements ÷ expert's | training s |\n|---:|---|---:|---:|---:|\n",
    );
    for fold in folds {
        let _ = writeln!(
            md,
            "| {} | {} | {:.3} | {:.2} | {:.0} |",
            fold.fold,
            fold.held_out.join(", "),
            fold.normalised_dcd,
            fold.element_ratio,
            fold.training_seconds
        );
    }
    let _ = writeln!(md, "| **all** | {} parts | **{mean:.3}** | **{element_ratio:.2}** | |\n", parts.len());
    md.push_str(&score_table(parts));
    write_atomic(&args.out.join("evaluation.md"), md.as_bytes())?;
    let (low, high) = folds
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), f| (lo.min(f.normalised_dcd), hi.max(f.normalised_dcd)));
    println!(
        "{} parts, {} folds: mean normalised DCD {mean:.3} (folds {low:.3} to {high:.3}), elements {element_ratio:.2} of \
         the experts'; wrote {}",
        parts.len(),
        folds.len(),
        args.out.display()
    );
    Ok(())
}
