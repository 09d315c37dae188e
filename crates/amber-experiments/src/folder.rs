//! Training on a dataset folder (`amber train --data DIR`): any folder of expert meshes, 2D or
//! 3D (see `amber_tasks::folder`), through the same run machinery as the paper's experiments.

use std::path::Path;

use amber_tasks::folder::{DatasetSettings, Fold, FolderDomain, Split, default_initial_size, problems, read_experts};
use amber_tasks::part::{PlanarPart, SolidPart};
use amber_train::MethodConfig;
use anyhow::bail;

use crate::run::train_run;

/// What a training on a folder made, for the model card.
#[derive(Clone, Debug)]
pub struct FolderTraining {
    /// Training wall time, seconds (summed over resumed sessions).
    pub seconds: f64,
    /// Edge length of the uniform M⁰ of every part (`dataset.json`'s, else the default rule).
    pub initial_size: f64,
    /// Training parts read.
    pub parts: usize,
}

/// Trains the run of `config` on the dataset folder `data` of `dimension`-dimensional meshes
/// (`amber_tasks::folder::mesh_dimension`) into `dir` (resuming what `dir` holds): the first
/// `train_problems` parts of `train/` (of those `fold` does not hold out, with a fold),
/// validating on the first `val_problems` of `val/`, M⁰ of size `initial_size` when given (else
/// `dataset.json`'s, else the default rule on the training parts). `label` names the run in
/// progress lines.
pub fn train_folder(
    config: &MethodConfig,
    dimension: usize,
    data: &Path,
    initial_size: Option<f64>,
    fold: Option<Fold>,
    dir: &Path,
    label: &str,
) -> anyhow::Result<FolderTraining> {
    let mut settings = DatasetSettings::read(data)?;
    settings.initial_size = initial_size.or(settings.initial_size);
    match dimension {
        2 => train_parts::<2, PlanarPart>(config, data, &settings, fold, dir, label),
        3 => train_parts::<3, SolidPart>(config, data, &settings, fold, dir, label),
        dimension => bail!("{}: {dimension}D meshes; a dataset holds triangles or tets", data.display()),
    }
}

fn train_parts<const D: usize, P: FolderDomain<D>>(
    config: &MethodConfig,
    data: &Path,
    settings: &DatasetSettings,
    fold: Option<Fold>,
    dir: &Path,
    label: &str,
) -> anyhow::Result<FolderTraining> {
    let count = config.data().train_problems;
    let train = match fold {
        None => read_experts::<D>(&Split::Train.dir(data), Some(count))?,
        Some(fold) => fold.split(read_experts::<D>(&Split::Train.dir(data), None)?).0.into_iter().take(count).collect(),
    };
    let initial_size = settings.initial_size.unwrap_or_else(|| default_initial_size(&train));
    let parts = train.len();
    let load = |validates: bool| {
        let val = if validates && config.data().val_problems > 0 {
            let experts = read_experts::<D>(&Split::Val.dir(data), Some(config.data().val_problems))?;
            problems::<D, P>(experts, initial_size, settings)?
        } else {
            Vec::new()
        };
        Ok((problems::<D, P>(train, initial_size, settings)?, val))
    };
    let seconds = train_run(config, load, dir, label)?;
    Ok(FolderTraining { seconds, initial_size, parts })
}
