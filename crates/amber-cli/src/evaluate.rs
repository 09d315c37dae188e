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
use amber_tasks::folder::{DatasetSettings, FolderDomain, Split, mesh_dimension, problems, read_experts};
use amber_tasks::part::{PlanarPart, SolidPart};
use amber_train::{Evaluation, EvaluationSummary, TrainedModel};
use anyhow::{Context, bail};
use clap::Args;

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
    let evaluation = Run { args: &args, card: &card, model: &model, split: &split, settings: &settings, steps };
    match card.task {
        Task::Console | Task::Folder { dimension: 3 } => evaluation.parts::<3, SolidPart>(),
        Task::Folder { dimension: 2 } => evaluation.parts::<2, PlanarPart>(),
        Task::Poisson => bail!(
            "{}: a Poisson model reads each problem's load; evaluate it with `cargo xtask reproduce poisson --test-set`",
            dir.display()
        ),
        Task::Folder { dimension } => bail!("{}: a model of {dimension}D meshes", dir.display()),
    }
}

/// A gallery tile of `mesh` coloured by element size.
fn tile<const D: usize>(title: String, mesh: &Mesh<D>) -> Tile<'_>
where
    Mesh<D>: Picture,
{
    Tile { title, mesh: mesh.tile_mesh(), values: mesh.sizes() }
}

/// One evaluation's inputs.
struct Run<'a> {
    args: &'a EvaluateArgs,
    card: &'a ModelCard,
    model: &'a TrainedModel,
    split: &'a Path,
    settings: &'a DatasetSettings,
    steps: usize,
}

impl Run<'_> {
    /// Loads the parts (M⁰ at the card's size), rolls the model out on each, writes the outputs.
    fn parts<const D: usize, P: FolderDomain<D>>(&self) -> anyhow::Result<()>
    where
        Mesh<D>: Picture,
    {
        let experts = read_experts::<D>(self.split, None)?;
        let names: Vec<String> = experts.iter().map(|e| e.name.clone()).collect();
        let parts = problems::<D, P>(experts, self.card.initial_size, self.settings)?;
        let evaluation = Evaluation::new(&parts, self.model.limits())?;
        let rollouts = self.model.rollouts(&evaluation, self.steps)?;
        let summary = EvaluationSummary::new(&parts, &rollouts);
        let scores: Vec<ProblemEvaluation> =
            rollouts.iter().zip(&parts).map(|(r, p)| ProblemEvaluation::of(r, p)).collect();
        let out = &self.args.out;
        std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
        let (mut pictures, mut size_ratios) = (Vec::new(), Vec::new());
        for ((name, rollout), part) in names.iter().zip(&rollouts).zip(&parts) {
            let generated = &rollout.steps.last().context("no generation step")?.mesh;
            let expert = part.expert_mesh();
            size_ratios.push(SizeRatios::of(&log_size_ratios(generated, expert)));
            let picture = format!("{}.png", name.replace(['/', '\\'], "-"));
            let row = vec![
                tile(format!("{name}: generated, {} el.", generated.num_elements()), generated),
                tile(format!("{name}: expert, {} el.", expert.num_elements()), expert),
            ];
            mesh_gallery(&out.join(&picture), &[row], (520, 440))?;
            pictures.push(picture);
        }
        let json = serde_json::json!({
            "model": self.args.model.model,
            "card": self.card,
            "data": self.split,
            "steps": self.steps,
            "summary": summary,
            "parts": names.iter().zip(&scores).zip(&pictures).zip(&size_ratios).map(|(((name, score), picture), ratios)| {
                serde_json::json!({ "name": name, "picture": picture, "evaluation": score, "size_ratios": ratios })
            }).collect::<Vec<_>>(),
        });
        write_json(&out.join("evaluation.json"), &json)?;
        write_atomic(&out.join("evaluation.md"), self.markdown(&names, &scores, &size_ratios, &summary).as_bytes())?;
        println!(
            "{} parts of {}: mean normalised DCD {:.3} after {} steps; wrote {}",
            parts.len(),
            self.split.display(),
            summary.final_normalised_dcd().unwrap_or(f64::NAN),
            self.steps,
            out.display()
        );
        Ok(())
    }

    /// The per-part table with the means, as `evaluation.md` holds it.
    fn markdown(
        &self,
        names: &[String],
        scores: &[ProblemEvaluation],
        size_ratios: &[SizeRatios],
        summary: &EvaluationSummary,
    ) -> String {
        let mut md = format!(
            "# Evaluation of {} on {}\n\n{} ({}), {} generation steps; normalised DCD: 0 as good as the expert's \
             own field re-meshed, 1 no better than M⁰. Sizes ÷ expert's: each final element's size over the \
             expert's element at its midpoint, 10th percentile, median, 90th percentile (above 1: coarser than \
             the expert).\n\n",
            self.args.model.model,
            self.split.display(),
            self.card.method,
            self.card.data,
            self.steps
        );
        md.push_str(
            "| part | normalised DCD | DCD | volume difference | elements | expert elements | sizes ÷ expert's |\n",
        );
        md.push_str("|---|---:|---:|---:|---:|---:|---:|\n");
        for ((name, score), r) in names.iter().zip(scores).zip(size_ratios) {
            let last = score.last();
            let _ = writeln!(
                md,
                "| {name} | {:.3} | {:.4} | {:.3e} | {} | {} | {:.2}, {:.2}, {:.2} |",
                last.normalised_dcd,
                last.dcd,
                last.volume_difference,
                last.elements,
                score.expert_elements,
                r.p10,
                r.median,
                r.p90
            );
        }
        let n = scores.len().max(1) as f64;
        let volume = scores.iter().map(|s| s.last().volume_difference).sum::<f64>() / n;
        if let Some(step) = summary.steps.last() {
            let _ = writeln!(
                md,
                "| **mean** | **{:.3}** | **{:.4}** | **{volume:.3e}** | **{:.0}** | **{:.0}** | |",
                step.normalised_dcd, step.dcd, step.elements, summary.expert_elements
            );
        }
        md
    }
}
