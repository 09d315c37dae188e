//! `amber calibrate`: a trained model re-fitted to the element counts of a folder of expert
//! meshes (its final step scale and count regression, see `amber_train::fit_final_step`),
//! written as a new model directory whose card records the calibration (and keeps the scores it
//! held, which were the replaced predictor's, apart): where a team's experts mesh finer or coarser
//! overall than the ones the model learned from, a handful of their meshes set the model's
//! default element budget.

use std::path::{Path, PathBuf};

use amber_experiments::{CardCalibration, ModelCard, Task, commit};
use amber_tasks::folder::{DatasetSettings, FolderDomain, Split, problems, read_experts};
use amber_tasks::part::{PlanarPart, SolidPart};
use amber_train::{FinalStepFit, TrainedModel};
use anyhow::{Context, bail};
use clap::Args;

use crate::evaluate::{LoadedModel, ModelArgs};

#[derive(Args)]
pub struct CalibrateArgs {
    /// The model, and the steps the scale is fitted for.
    #[command(flatten)]
    model: ModelArgs,
    /// A directory of expert meshes, or a dataset folder whose `train/` is taken.
    #[arg(long)]
    data: PathBuf,
    /// The new model directory (the model's files with the fitted predictor).
    #[arg(long, short)]
    out: PathBuf,
    /// Also fit the count regression (the last step meshed to the count the experts' log counts
    /// regress to) for a model trained without one; a model with one always refits it.
    #[arg(long)]
    count_regression: bool,
}

pub fn run(args: CalibrateArgs) -> anyhow::Result<()> {
    let train = Split::Train.dir(&args.data);
    let split = if train.is_dir() { train } else { args.data.clone() };
    let loaded = args.model.load()?;
    loaded.check_dimension(&split)?;
    let LoadedModel { dir, mut card, mut model, steps } = loaded;
    let settings = DatasetSettings::read(split.parent().unwrap_or(Path::new(".")))?;
    let before = model.limits().final_step_scale;
    let count_regression = args.count_regression;
    let fit = match card.task {
        Task::Console | Task::Folder { dimension: 3 } => {
            fit::<3, SolidPart>(&mut model, &split, &card, &settings, steps, count_regression)?
        }
        Task::Folder { dimension: 2 } => {
            fit::<2, PlanarPart>(&mut model, &split, &card, &settings, steps, count_regression)?
        }
        Task::Poisson => bail!("{}: a Poisson model is calibrated on Poisson problems, not meshes", dir.display()),
        Task::Folder { dimension } => bail!("{}: a model of {dimension}D meshes", dir.display()),
    };
    copy_model(&dir, &args.out)?;
    model.write_predictor(&args.out)?;
    let slope = model.limits().final_count.map(|count| count.slope);
    card.calibration = Some(CardCalibration {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        data: split.display().to_string(),
        commit: commit().to_owned(),
        steps,
        final_step_scale: fit.scale,
        count_regression_slope: slope,
        evaluation_before: card.evaluation.take(),
    });
    card.write(&args.out)?;
    let count = slope.map_or(String::new(), |slope| format!("; count regression slope {slope:.3}"));
    println!(
        "final step scale {:.4} (was {before:.4}){count}, fitted on {} after {steps} steps; wrote {}",
        fit.scale,
        split.display(),
        args.out.display()
    );
    Ok(())
}

/// Loads the experts of `split` as parts with the card's M⁰ and fits the model's last step on them.
fn fit<const D: usize, P: FolderDomain<D>>(
    model: &mut TrainedModel,
    split: &Path,
    card: &ModelCard,
    settings: &DatasetSettings,
    steps: usize,
    count_regression: bool,
) -> anyhow::Result<FinalStepFit> {
    let parts = problems::<D, P>(read_experts::<D>(split, None)?, card.initial_size, settings)?;
    Ok(model.calibrate(&parts, steps, count_regression)?)
}

/// Copies the files of the model directory `from` (weights, predictor, card) into `to`.
fn copy_model(from: &Path, to: &Path) -> anyhow::Result<()> {
    if to.exists() && std::fs::read_dir(to).is_ok_and(|mut d| d.next().is_some()) {
        bail!("{}: exists and is not empty; calibrate into a new directory", to.display());
    }
    std::fs::create_dir_all(to).with_context(|| format!("{}: cannot create", to.display()))?;
    for entry in std::fs::read_dir(from).with_context(|| format!("{}: cannot read", from.display()))? {
        let path = entry?.path();
        if path.is_file() {
            let target = to.join(path.file_name().expect("a file has a name"));
            std::fs::copy(&path, &target)
                .with_context(|| format!("{}: cannot copy to {}", path.display(), target.display()))?;
        }
    }
    Ok(())
}
