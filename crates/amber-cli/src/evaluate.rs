//! `amber evaluate`: a trained model on a folder of expert meshes it has not seen, scored part by
//! part against the experts (normalised DCD, DCD, volume difference, element counts) into
//! `evaluation.json`, `evaluation.md` and a picture per part (generated beside expert).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use amber_experiments::{ModelCard, ProblemEvaluation, Task, resolve_model, write_atomic, write_json};
use amber_mesh::Mesh;
use amber_metrics::{SizeRatios, log_size_ratios};
use amber_plot::{Tile, mesh_gallery};
use amber_tasks::Problem;
use amber_tasks::folder::{DatasetSettings, Expert, FolderDomain, Split, mesh_dimension, problems, read_experts};
use amber_tasks::part::{PlanarPart, SolidPart};
use amber_train::{Evaluation, EvaluationSummary, TrainedModel};
use anyhow::{Context, bail};
use clap::Args;
use serde::Serialize;

use crate::mesh::{Picture, shipped_models};

/// A trained model to roll out on a folder of expert meshes, and for how many steps.
#[derive(Args)]
pub struct ModelArgs {
    /// A trained model: a model or run directory, or a shipped model's name.
    #[arg(long)]
    pub model: String,
    /// Generation steps (default: the model's own number).
    #[arg(long)]
    pub steps: Option<usize>,
}

/// A loaded model with its directory, card and number of steps.
pub struct LoadedModel {
    pub dir: PathBuf,
    pub card: ModelCard,
    pub model: TrainedModel,
    pub steps: usize,
}

impl ModelArgs {
    pub fn load(&self) -> anyhow::Result<LoadedModel> {
        let dir = resolve_model(&self.model, &shipped_models())?;
        let card = ModelCard::read(&dir)?;
        let model = TrainedModel::load(&dir).with_context(|| format!("{}: cannot load the model", dir.display()))?;
        let steps = self.steps.unwrap_or(card.inference_steps);
        if steps == 0 {
            bail!("--steps must be at least 1");
        }
        Ok(LoadedModel { dir, card, model, steps })
    }
}

impl LoadedModel {
    /// Fails, naming both, when the meshes of `split` are not of the dimension the model meshes.
    pub fn check_dimension(&self, split: &Path) -> anyhow::Result<()> {
        let model = match self.card.task {
            Task::Console => 3,
            Task::Folder { dimension } => dimension,
            // Poisson models read problems, not meshes: the callers say so.
            Task::Poisson => return Ok(()),
        };
        let found = mesh_dimension(split)?;
        if found != model {
            bail!(
                "{}: holds {found}D meshes, but the model {} meshes in {model}D",
                split.display(),
                self.dir.display()
            );
        }
        Ok(())
    }
}

#[derive(Args)]
pub struct EvaluateArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// A directory of expert meshes (e.g. `DIR/test`; geometry files beside them or in
    /// `DIR/reference_surface/test/`), or a dataset folder, whose `test/` (else `val/`) is taken.
    #[arg(long)]
    data: PathBuf,
    /// Where `evaluation.json`, `evaluation.md` and the pictures go.
    #[arg(long, default_value = "evaluation")]
    out: PathBuf,
}

pub fn run(args: EvaluateArgs) -> anyhow::Result<()> {
    // A dataset folder need not hold a train/ split to be evaluated.
    let split = [Split::Test, Split::Val]
        .into_iter()
        .map(|split| split.dir(&args.data))
        .find(|dir| dir.is_dir())
        .unwrap_or_else(|| args.data.clone());
    let loaded = args.model.load()?;
    loaded.check_dimension(&split)?;
    let LoadedModel { dir, card, mut model, steps } = loaded;
    // As `amber mesh` does: a field over the budget is scaled to it, not skipped.
    model.limits_mut().scale_to_budget = true;
    let settings = DatasetSettings::read(split.parent().unwrap_or(Path::new(".")))?;
    let scorer = PartScorer { model: &model, initial_size: card.initial_size, settings: &settings, steps };
    let out = &args.out;
    let (parts, summary) = match card.task {
        Task::Console | Task::Folder { dimension: 3 } => {
            scorer.score::<3, SolidPart>(read_experts(&split, None)?, None, out)?
        }
        Task::Folder { dimension: 2 } => scorer.score::<2, PlanarPart>(read_experts(&split, None)?, None, out)?,
        Task::Poisson => bail!(
            "{}: a Poisson model reads each problem's load; evaluate it with `cargo xtask reproduce poisson --test-set`",
            dir.display()
        ),
        Task::Folder { dimension } => bail!("{}: a model of {dimension}D meshes", dir.display()),
    };
    let json = serde_json::json!({
        "model": args.model.model, "card": card, "data": split, "steps": steps, "summary": summary, "parts": parts,
    });
    write_json(&out.join("evaluation.json"), &json)?;
    let mut md = format!(
        "# Evaluation of {} on {}\n\n{} ({}), {steps} generation steps; {SCORES}\n\n",
        args.model.model,
        split.display(),
        card.method,
        card.data,
    );
    md.push_str(&score_table(&parts));
    write_atomic(&out.join("evaluation.md"), md.as_bytes())?;
    println!(
        "{} parts of {}: mean normalised DCD {:.3} after {steps} steps; wrote {}",
        parts.len(),
        split.display(),
        summary.final_normalised_dcd().unwrap_or(f64::NAN),
        out.display()
    );
    Ok(())
}

/// What the columns of [`score_table`] mean, for the text above it.
pub const SCORES: &str = "normalised DCD: 0 as good as the expert's own field re-meshed, 1 no better than M⁰. \
    Sizes ÷ expert's: each final element's size over the expert's element at its midpoint, 10th percentile, \
    median, 90th percentile (above 1: coarser than the expert).";

/// A gallery tile of `mesh` coloured by element size.
fn tile<const D: usize>(title: String, mesh: &Mesh<D>) -> Tile<'_>
where
    Mesh<D>: Picture,
{
    Tile { title, mesh: mesh.tile_mesh(), values: mesh.sizes() }
}

/// One part's scores, as `evaluation.json` lists them.
#[derive(Serialize)]
pub struct PartScore {
    /// `split/stem`.
    pub name: String,
    /// The part's picture (generated beside expert), in the output directory.
    pub picture: String,
    pub evaluation: ProblemEvaluation,
    pub size_ratios: SizeRatios,
    /// The cross-validation fold that held the part out.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fold: Option<usize>,
}

impl PartScore {
    /// Final elements over the expert's.
    pub fn element_ratio(&self) -> f64 {
        self.evaluation.last().elements as f64 / self.evaluation.expert_elements as f64
    }
}

/// A model's rollouts on parts of a folder, scored against their experts.
pub struct PartScorer<'a> {
    pub model: &'a TrainedModel,
    /// Edge length of every part's M⁰ (the model card's).
    pub initial_size: f64,
    pub settings: &'a DatasetSettings,
    pub steps: usize,
}

impl PartScorer<'_> {
    /// Rolls the model out on `experts`' parts, writes a picture per part into `out` and returns
    /// each part's scores (marked with `fold`) and their summary.
    pub fn score<const D: usize, P: FolderDomain<D>>(
        &self,
        experts: Vec<Expert<D>>,
        fold: Option<usize>,
        out: &Path,
    ) -> anyhow::Result<(Vec<PartScore>, EvaluationSummary)>
    where
        Mesh<D>: Picture,
    {
        let names: Vec<String> = experts.iter().map(|e| e.name.clone()).collect();
        let parts = problems::<D, P>(experts, self.initial_size, self.settings)?;
        let evaluation = Evaluation::new(&parts, self.model.limits())?;
        let rollouts = self.model.rollouts(&evaluation, self.steps)?;
        std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
        let mut scores = Vec::new();
        for ((name, rollout), part) in names.into_iter().zip(&rollouts).zip(&parts) {
            let generated = &rollout.steps.last().context("no generation step")?.mesh;
            let expert = part.expert_mesh();
            let picture = format!("{}.png", name.replace(['/', '\\'], "-"));
            let row = vec![
                tile(format!("{name}: generated, {} el.", generated.num_elements()), generated),
                tile(format!("{name}: expert, {} el.", expert.num_elements()), expert),
            ];
            mesh_gallery(&out.join(&picture), &[row], (520, 440))?;
            let size_ratios = SizeRatios::of(&log_size_ratios(generated, expert));
            scores.push(PartScore {
                name,
                picture,
                evaluation: ProblemEvaluation::of(rollout, part),
                size_ratios,
                fold,
            });
        }
        Ok((scores, EvaluationSummary::new(&parts, &rollouts)))
    }
}

/// The per-part table of `parts` with their means (a fold column when they came from folds).
pub fn score_table(parts: &[PartScore]) -> String {
    let folds = parts.iter().any(|p| p.fold.is_some());
    let fold_column = if folds { ["fold | ", "---:|"] } else { ["", ""] };
    let mut md = format!(
        "| part | {}normalised DCD | DCD | volume difference | elements | expert elements | sizes ÷ expert's |\n",
        fold_column[0]
    );
    let _ = writeln!(md, "|---|{}---:|---:|---:|---:|---:|---:|", fold_column[1]);
    for part in parts {
        let (last, r) = (part.evaluation.last(), &part.size_ratios);
        let fold = part.fold.map_or(String::new(), |f| format!("{f} | "));
        let _ = writeln!(
            md,
            "| {} | {fold}{:.3} | {:.4} | {:.3e} | {} | {} | {:.2}, {:.2}, {:.2} |",
            part.name,
            last.normalised_dcd,
            last.dcd,
            last.volume_difference,
            last.elements,
            part.evaluation.expert_elements,
            r.p10,
            r.median,
            r.p90
        );
    }
    let n = parts.len().max(1) as f64;
    let mean = |f: &dyn Fn(&PartScore) -> f64| parts.iter().map(f).sum::<f64>() / n;
    let _ = writeln!(
        md,
        "| **mean** | {}**{:.3}** | **{:.4}** | **{:.3e}** | **{:.0}** | **{:.0}** | |",
        if folds { " | " } else { "" },
        mean(&|p| p.evaluation.last().normalised_dcd),
        mean(&|p| p.evaluation.last().dcd),
        mean(&|p| p.evaluation.last().volume_difference),
        mean(&|p| p.evaluation.last().elements as f64),
        mean(&|p| p.evaluation.expert_elements as f64),
    );
    md
}
