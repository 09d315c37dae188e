//! Inference for both methods (spec §6, reference notes §6.5): T generation steps from M⁰
//! (predict → clip at h_min → budget guard → generate), every intermediate mesh compared with
//! the expert in the same parallel pass, normalised by the initial mesh M⁰ and the reconstruction
//! M̂ (spec §7). A method plugs in through [`SizingModel`]. [`generate`] is the same loop on a
//! domain without an expert: what `amber mesh --model` runs.

use amber_mesh::Mesh;
use amber_meshgen::MeshgenError;
use amber_metrics::{compare_meshes, normalised_dcd};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Result, TrainError, in_problem};
use amber_meshgen::estimated_element_count;
use amber_tasks::{
    Domain, FinalCount, MeshLimits, Problem, ProblemError, SizeBounds, StepOutcome, generation_step,
    mesh_to_element_count,
};

/// The per-problem constants of the normalised DCD: the reconstruction M̂ (the generator run
/// with the expert's own sizing field, clipped at h_min) and the DCDs of M⁰ and M̂ to M*.
#[derive(Clone, Debug)]
pub struct Reference<const D: usize> {
    pub reconstruction: Mesh<D>,
    /// d(M⁰, M*).
    pub initial_dcd: f64,
    /// d(M̂, M*).
    pub reconstruction_dcd: f64,
}

impl<const D: usize> Reference<D> {
    /// Meshes M̂ and measures d(M⁰, M*) and d(M̂, M*).
    pub fn new<P: Problem<D> + ?Sized>(problem: &P, limits: &MeshLimits) -> Result<Self, ProblemError> {
        let expert = problem.expert_mesh();
        let sizes = expert.sizes().into_iter().map(|h| h.max(limits.min_size)).collect();
        let reconstruction = problem.remesh(expert, sizes, limits.generator_cap().max(4 * expert.num_elements()))?;
        let initial_dcd = compare_meshes(problem.initial_mesh(), expert)?.midpoints.dcd;
        let reconstruction_dcd = compare_meshes(&reconstruction, expert)?.midpoints.dcd;
        Ok(Self { reconstruction, initial_dcd, reconstruction_dcd })
    }

    /// The references of many problems, in parallel.
    pub fn for_problems<P: Problem<D>>(problems: &[P], limits: &MeshLimits) -> Result<Vec<Self>> {
        problems.par_iter().enumerate().map(|(i, p)| Self::new(p, limits).map_err(in_problem(i))).collect()
    }
}

/// What happened at one step of a rollout.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum StepStatus {
    /// A new mesh was generated.
    Meshed,
    /// The estimated element count exceeded the budget; the previous mesh is kept.
    OverBudget { estimated_elements: f64 },
    /// The generator failed; the previous mesh is kept.
    Failed { reason: String },
    /// An earlier step failed: the rollout stopped and its last mesh is carried forward (the
    /// prediction from the same mesh would be the same).
    Stopped,
}

/// The metrics of one mesh against its expert (spec §7).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshMetrics {
    /// Raw DCD d(M, M*).
    pub dcd: f64,
    /// (d(M) − d(M̂)) / (d(M⁰) − d(M̂)): 0 as good as M̂, 1 no better than M⁰.
    pub normalised_dcd: f64,
    /// Chamfer distance of the midpoints.
    pub chamfer: f64,
    /// Symmetric volume difference (summed).
    pub volume_difference: f64,
    /// Elements of the mesh.
    pub elements: usize,
}

/// One step of a rollout: the mesh after it and its metrics.
#[derive(Clone, Debug)]
pub struct RolloutStep<const D: usize> {
    pub status: StepStatus,
    pub mesh: Mesh<D>,
    pub metrics: MeshMetrics,
}

/// A rollout of one problem: M⁰'s metrics and T steps.
#[derive(Clone, Debug)]
pub struct Rollout<const D: usize> {
    pub initial: MeshMetrics,
    pub steps: Vec<RolloutStep<D>>,
    pub initial_dcd: f64,
    pub reconstruction_dcd: f64,
}

impl MeshMetrics {
    /// The metrics of `mesh` against `expert`, normalised by the problem's `reference`.
    pub fn of<const D: usize>(
        mesh: &Mesh<D>,
        expert: &Mesh<D>,
        reference: &Reference<D>,
    ) -> Result<Self, ProblemError> {
        let c = compare_meshes(mesh, expert)?;
        Ok(Self {
            dcd: c.midpoints.dcd,
            normalised_dcd: normalised_dcd(c.midpoints.dcd, reference.initial_dcd, reference.reconstruction_dcd)?,
            chamfer: c.midpoints.chamfer,
            volume_difference: c.volume.summed,
            elements: mesh.num_elements(),
        })
    }
}

/// A sizing field predicted for one generation step: the sizes of the elements of `mesh`, or of
/// the current mesh's elements when `mesh` is `None`.
pub struct PredictedField<const D: usize> {
    /// The mesh the sizes live on when it is not the current mesh (the CNN's auxiliary mesh).
    pub mesh: Option<Mesh<D>>,
    pub sizes: Vec<f64>,
}

impl<const D: usize> PredictedField<D> {
    /// Multiplies every size by `factor`.
    fn scale(&mut self, factor: f64) {
        self.sizes.iter_mut().for_each(|h| *h *= factor);
    }
}

/// What a trained method contributes to a generation step: a sizing field for the current mesh
/// of each problem, and the clip and budget the step meshes it under. Both methods implement
/// it; [`rollouts`] is the one loop around it.
pub trait SizingModel: Sync {
    /// h_min and the element budget (from the training experts).
    fn limits(&self) -> &MeshLimits;

    /// The field of each `(problem, current mesh)` pair, in order.
    fn predict<const D: usize, P: Domain<D>>(
        &self,
        problems: &[&P],
        meshes: &[&Mesh<D>],
    ) -> Result<Vec<PredictedField<D>>>;
}

/// Rolls out `steps` generation steps of `model` on every problem in lockstep (one prediction
/// for all running problems per step, then meshing and metrics in one parallel pass).
/// `references[i]` belongs to `problems[i]`. A step over the budget or failed keeps the previous
/// mesh and stops that problem's rollout; later steps carry it forward as [`StepStatus::Stopped`].
/// The last step's field is scaled by the model's `final_step_scale`.
pub fn rollouts<const D: usize, P: Problem<D>, M: SizingModel + ?Sized>(
    model: &M,
    problems: &[P],
    references: &[Reference<D>],
    steps: usize,
) -> Result<Vec<Rollout<D>>> {
    if problems.len() != references.len() {
        let message = format!("{} problems but {} references", problems.len(), references.len());
        return Err(TrainError::InvalidConfig(message));
    }
    let mut out: Vec<Rollout<D>> = problems
        .par_iter()
        .zip(references)
        .enumerate()
        .map(|(i, (p, r))| {
            Ok(Rollout {
                initial: MeshMetrics::of(p.initial_mesh(), p.expert_mesh(), r).map_err(in_problem(i))?,
                steps: Vec::with_capacity(steps),
                initial_dcd: r.initial_dcd,
                reconstruction_dcd: r.reconstruction_dcd,
            })
        })
        .collect::<Result<_>>()?;
    let mut active = vec![true; problems.len()];
    for step in 1..=steps {
        let running: Vec<usize> = (0..problems.len()).filter(|&i| active[i]).collect();
        let current = |i: usize| out[i].steps.last().map_or(problems[i].initial_mesh(), |s| &s.mesh);
        let mut fields = model.predict(
            &running.iter().map(|&i| &problems[i]).collect::<Vec<_>>(),
            &running.iter().map(|&i| current(i)).collect::<Vec<_>>(),
        )?;
        if step == steps {
            fields.iter_mut().for_each(|f| f.scale(model.limits().final_step_scale));
        }
        let mut fields: Vec<Option<PredictedField<D>>> = fields.into_iter().map(Some).collect();
        let mut per_problem: Vec<Option<PredictedField<D>>> = (0..problems.len()).map(|_| None).collect();
        for (&i, field) in running.iter().zip(&mut fields) {
            per_problem[i] = field.take();
        }
        let advanced: Vec<RolloutStep<D>> = per_problem
            .into_par_iter()
            .enumerate()
            .map(|(i, field)| {
                let (problem, previous) = (&problems[i], current(i));
                let carried = |status| RolloutStep {
                    status,
                    mesh: previous.clone(),
                    metrics: out[i].steps.last().map_or(out[i].initial, |s| s.metrics),
                };
                let Some(field) = field else { return Ok(carried(StepStatus::Stopped)) };
                let on = field.mesh.as_ref().unwrap_or(previous);
                let limits = model.limits();
                let counted = (step == steps).then(|| last_step_count(limits, on, &field.sizes, None)).flatten();
                let outcome = match counted {
                    Some((sizes, target)) => {
                        let unbounded = &SizeBounds::default();
                        match mesh_to_element_count(problem, on, &sizes, target, unbounded, limits.generator_cap()) {
                            Ok(mesh) => StepOutcome::Meshed(mesh),
                            Err(e) => StepOutcome::Failed { reason: e.to_string() },
                        }
                    }
                    None => generation_step(problem, on, field.sizes, limits, &SizeBounds::default()),
                };
                Ok(match outcome {
                    StepOutcome::Meshed(mesh) => {
                        let metrics =
                            MeshMetrics::of(&mesh, problem.expert_mesh(), &references[i]).map_err(in_problem(i))?;
                        RolloutStep { status: StepStatus::Meshed, mesh, metrics }
                    }
                    StepOutcome::OverBudget { estimated_elements } => {
                        carried(StepStatus::OverBudget { estimated_elements })
                    }
                    StepOutcome::Failed { reason } => carried(StepStatus::Failed { reason }),
                })
            })
            .collect::<Result<_>>()?;
        for (i, step) in advanced.into_iter().enumerate() {
            active[i] &= step.status == StepStatus::Meshed;
            out[i].steps.push(step);
        }
    }
    Ok(out)
}

/// One step of [`generate`]: the field predicted on the previous mesh (per element of it, or of
/// the method's own auxiliary mesh) and the mesh made from it.
pub struct GeneratedStep<const D: usize> {
    pub field: PredictedField<D>,
    pub mesh: Mesh<D>,
}

/// What a user asks of the last step of [`generate`]: an element count (reached within
/// `amber_tasks::ELEMENT_COUNT_TOLERANCE` when the generator allows), and a range, refinement
/// boxes and faces for its sizes with a cap on its elements. The default asks nothing: the model's
/// own final step scale and budget decide.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FinalStep {
    pub elements: Option<usize>,
    pub bounds: SizeBounds,
}

/// Meshes `domain` with `model` for `steps` generation steps from its M⁰ (predict, clip at
/// h_min, budget guard, mesh), as a rollout does but without an expert to compare with. The
/// last step does what `last` asks: with a target, its field keeps its shape and is scaled to
/// the target's element count (instead of the budget guard): the model decides where elements
/// go, the user how many; without one, by the model's `final_step_scale`, and meshed to the
/// count its [`FinalCount`] gives if it has one; either way its sizes are then held within
/// `last.bounds` (after the model's budget guard, see [`generation_step`]).
/// A step that makes no mesh is an error naming the step.
pub fn generate<const D: usize, P: Domain<D>, M: SizingModel + ?Sized>(
    model: &M,
    domain: &P,
    steps: usize,
    last: FinalStep,
) -> Result<Vec<GeneratedStep<D>>> {
    let mut out: Vec<GeneratedStep<D>> = Vec::with_capacity(steps);
    let unbounded = SizeBounds::default();
    let bounds_at = |step| if step == steps { &last.bounds } else { &unbounded };
    for step in 1..=steps {
        let current = out.last().map_or(domain.initial_mesh(), |s| &s.mesh);
        let mut field = model.predict(&[domain], &[current])?.pop().expect("one field per domain");
        if step == steps && last.elements.is_none() {
            field.scale(model.limits().final_step_scale);
        }
        let on = field.mesh.as_ref().unwrap_or(current);
        let counted = (step == steps).then(|| last_step_count(model.limits(), on, &field.sizes, last.elements));
        let mesh = match counted.flatten() {
            Some((sizes, elements)) => {
                let cap = last.bounds.element_cap(model.limits());
                mesh_to_element_count(domain, on, &sizes, elements, &last.bounds, cap).map_err(|e| match e {
                    ProblemError::Meshing(MeshgenError::TooManyElements { cap }) => TrainError::OverCap { step, cap },
                    e => TrainError::Generation { step, reason: e.to_string() },
                })?
            }
            None => match generation_step(domain, on, field.sizes.clone(), model.limits(), bounds_at(step)) {
                StepOutcome::Meshed(mesh) => mesh,
                StepOutcome::OverBudget { estimated_elements } => {
                    if let Some(cap) = bounds_at(step).max_elements() {
                        return Err(TrainError::OverCap { step, cap });
                    }
                    let reason = format!(
                        "the predicted field asks for about {estimated_elements:.0} elements, over the model's budget of {}",
                        model.limits().max_elements
                    );
                    return Err(TrainError::Generation { step, reason });
                }
                StepOutcome::Failed { reason } => return Err(TrainError::Generation { step, reason }),
            },
        };
        out.push(GeneratedStep { field, mesh });
    }
    Ok(out)
}

/// The last step's field clipped at h_min, with the element count it is meshed to: `asked` (the
/// user's) if given, else the count the model's [`FinalCount`] fits to what the clipped field asks
/// for, within the budget. `None` when neither gives a count: the budget guard decides then.
fn last_step_count<const D: usize>(
    limits: &MeshLimits,
    mesh: &Mesh<D>,
    sizes: &[f64],
    asked: Option<usize>,
) -> Option<(Vec<f64>, usize)> {
    let clip = || sizes.iter().map(|h| h.max(limits.min_size)).collect::<Vec<f64>>();
    match (asked, limits.final_count) {
        (Some(elements), _) => Some((clip(), elements)),
        (None, Some(count)) => {
            let clipped = clip();
            let elements = count.target(estimated_element_count(mesh, &clipped)).min(limits.max_elements);
            Some((clipped, elements))
        }
        (None, None) => None,
    }
}

/// Meshings of the last step [`fit_final_step`] spends per problem at most.
const CALIBRATION_ROUNDS: usize = 3;

/// A fitted scale within this factor of the previous round's is final.
const CALIBRATION_TOLERANCE: f64 = 1.01;

/// What [`fit_final_step`] fits from the same last fields: the final step scale and the count
/// regression after it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FinalStepFit {
    pub scale: f64,
    pub count: FinalCount,
}

/// The factor on the last step's sizes that gives `model`'s meshes of `problems` after `steps`
/// steps their experts' element counts, in the geometric mean over problems: the element budget
/// the experts chose, learned from them. A model that learned where to refine but not how much
/// overall (residual steps that converge short of the expert's level) is corrected by one
/// number. `model` must have a `final_step_scale` of 1 and no `final_count`. The first
/// `steps - 1` steps are generated once; the last is meshed with the current factor, which each
/// round corrects by the mean ratio of counts to the power 1/D, until it moves by less than
/// [`CALIBRATION_TOLERANCE`] or [`CALIBRATION_ROUNDS`] meshings are spent. A problem whose
/// rollout or last meshing fails is left out of the mean. The same last fields, scaled, then fit
/// the [`FinalCount`] regression (no meshing: it regresses on the fields' estimated counts).
pub fn fit_final_step<const D: usize, P: Problem<D>, M: SizingModel + ?Sized>(
    model: &M,
    problems: &[P],
    steps: usize,
) -> Result<FinalStepFit> {
    let limits = model.limits();
    if limits.final_step_scale != 1.0 || limits.final_count.is_some() {
        return Err(TrainError::InvalidConfig("fitting the final step needs a model without a fitted one".into()));
    }
    let last_fields: Vec<(&P, Mesh<D>, PredictedField<D>)> = problems
        .par_iter()
        .filter_map(|p| {
            let before = generate(model, p, steps.saturating_sub(1), FinalStep::default()).ok()?;
            let mesh = before.last().map_or(p.initial_mesh(), |s| &s.mesh).clone();
            let field = model.predict(&[p], &[&mesh]).ok()?.pop()?;
            Some((p, mesh, field))
        })
        .collect();
    let scaled = |field: &PredictedField<D>, scale: f64| -> Vec<f64> {
        field.sizes.iter().map(|h| (h * scale).max(limits.min_size)).collect()
    };
    let mut scale = 1.0;
    for _ in 0..CALIBRATION_ROUNDS {
        let log_ratios: Vec<f64> = last_fields
            .par_iter()
            .filter_map(|(problem, mesh, field)| {
                let on = field.mesh.as_ref().unwrap_or(mesh);
                let made = problem.remesh(on, scaled(field, scale), limits.generator_cap()).ok()?;
                Some((made.num_elements() as f64 / problem.expert_mesh().num_elements() as f64).ln())
            })
            .collect();
        if log_ratios.is_empty() {
            let reason = "no problem could be meshed to fit the final step scale".into();
            return Err(TrainError::Generation { step: steps, reason });
        }
        let correction = (log_ratios.iter().sum::<f64>() / log_ratios.len() as f64 / D as f64).exp();
        scale *= correction;
        if correction.max(1.0 / correction) < CALIBRATION_TOLERANCE {
            break;
        }
    }
    let log_counts: Vec<(f64, f64)> = last_fields
        .iter()
        .map(|(problem, mesh, field)| {
            let estimate = estimated_element_count(field.mesh.as_ref().unwrap_or(mesh), &scaled(field, scale));
            (estimate.ln(), (problem.expert_mesh().num_elements() as f64).ln())
        })
        .filter(|(model, _)| model.is_finite())
        .collect();
    let count = FinalCount::fit(&log_counts).ok_or_else(|| {
        let reason = "no problem's last field asks for a finite element count".into();
        TrainError::Generation { step: steps, reason }
    })?;
    Ok(FinalStepFit { scale, count })
}

/// Means over problems at one generation step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepSummary {
    /// Mean normalised DCD over all problems (failed steps carry the last mesh forward, as the
    /// later version does).
    pub normalised_dcd: f64,
    /// Mean normalised DCD over the problems whose rollout has not failed so far (the workshop
    /// code's protocol, biased towards easy problems); `None` if every rollout failed.
    pub normalised_dcd_successful: Option<f64>,
    /// Mean raw DCD (carried forward).
    pub dcd: f64,
    /// Mean element count (carried forward).
    pub elements: f64,
    /// Problems whose rollout has failed at this step or before.
    pub failed: usize,
}

/// The summary of rollouts over a set of problems.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvaluationSummary {
    pub problems: usize,
    /// Mean d(M⁰, M*).
    pub initial_dcd: f64,
    /// Mean d(M̂, M*).
    pub reconstruction_dcd: f64,
    /// Mean element count of the experts.
    pub expert_elements: f64,
    /// One entry per generation step.
    pub steps: Vec<StepSummary>,
}

impl EvaluationSummary {
    /// Summarises rollouts of `problems` (same order).
    pub fn new<const D: usize, P: Problem<D>>(problems: &[P], rollouts: &[Rollout<D>]) -> Self {
        let n = rollouts.len().max(1) as f64;
        let mean = |f: &dyn Fn(&Rollout<D>) -> f64| rollouts.iter().map(f).sum::<f64>() / n;
        let steps = rollouts.first().map_or(0, |r| r.steps.len());
        let steps = (0..steps)
            .map(|t| {
                let ok: Vec<f64> = rollouts
                    .iter()
                    .filter(|r| r.steps[..=t].iter().all(|s| s.status == StepStatus::Meshed))
                    .map(|r| r.steps[t].metrics.normalised_dcd)
                    .collect();
                StepSummary {
                    normalised_dcd: mean(&|r| r.steps[t].metrics.normalised_dcd),
                    normalised_dcd_successful: (!ok.is_empty()).then(|| ok.iter().sum::<f64>() / ok.len() as f64),
                    dcd: mean(&|r| r.steps[t].metrics.dcd),
                    elements: mean(&|r| r.steps[t].metrics.elements as f64),
                    failed: rollouts.len() - ok.len(),
                }
            })
            .collect();
        Self {
            problems: rollouts.len(),
            initial_dcd: mean(&|r| r.initial_dcd),
            reconstruction_dcd: mean(&|r| r.reconstruction_dcd),
            expert_elements: problems.iter().map(|p| p.expert_mesh().num_elements() as f64).sum::<f64>() / n,
            steps,
        }
    }

    /// The mean normalised DCD after the last step (the headline number).
    pub fn final_normalised_dcd(&self) -> Option<f64> {
        self.steps.last().map(|s| s.normalised_dcd)
    }
}

/// A fixed set of evaluation problems with their references, built once and rolled out as often
/// as needed (validation during training, the final test).
pub struct Evaluation<'p, const D: usize, P: Problem<D>> {
    pub problems: &'p [P],
    pub references: Vec<Reference<D>>,
}

impl<'p, const D: usize, P: Problem<D>> Evaluation<'p, D, P> {
    /// Builds the references of `problems` with the training run's `limits`.
    pub fn new(problems: &'p [P], limits: &MeshLimits) -> Result<Self> {
        Ok(Self { problems, references: Reference::for_problems(problems, limits)? })
    }

    /// Rolls out `steps` steps of `model` on every problem and summarises.
    pub fn run(&self, model: &impl SizingModel, steps: usize) -> Result<(Vec<Rollout<D>>, EvaluationSummary)> {
        let rollouts = rollouts(model, self.problems, &self.references, steps)?;
        let summary = EvaluationSummary::new(self.problems, &rollouts);
        Ok((rollouts, summary))
    }
}

#[cfg(test)]
mod tests {
    use amber_meshgen::PolygonDomain;
    use amber_tasks::WithExpert;
    use amber_tasks::part::PlanarPart;

    use super::*;

    /// Asks for the same size everywhere, whatever the mesh.
    struct Uniform {
        size: f64,
        limits: MeshLimits,
    }

    impl SizingModel for Uniform {
        fn limits(&self) -> &MeshLimits {
            &self.limits
        }

        fn predict<const D: usize, P: Domain<D>>(
            &self,
            _problems: &[&P],
            meshes: &[&Mesh<D>],
        ) -> Result<Vec<PredictedField<D>>> {
            Ok(meshes.iter().map(|m| PredictedField { mesh: None, sizes: vec![self.size; m.num_elements()] }).collect())
        }
    }

    /// Squares of the given sides, each with an expert mesh of the paired uniform size.
    fn squares(experts: &[(f64, f64)]) -> Vec<WithExpert<PlanarPart, 2>> {
        let square = |side: f64| vec![[0.0, 0.0], [side, 0.0], [side, side], [0.0, side]];
        experts
            .iter()
            .map(|&(side, size)| {
                let domain = PlanarPart::new("square".into(), PolygonDomain::new(square(side), vec![]).unwrap(), 0.2);
                let domain = domain.unwrap();
                let mesh = domain.initial_mesh().clone();
                let expert_mesh = domain.remesh(&mesh, vec![size; mesh.num_elements()], 1_000_000).unwrap();
                WithExpert::new(domain, expert_mesh, std::path::Path::new("square.json")).unwrap()
            })
            .collect()
    }

    const UNSCALED: MeshLimits = MeshLimits {
        min_size: 1e-3,
        max_elements: 1_000_000,
        scale_to_budget: false,
        final_step_scale: 1.0,
        final_count: None,
    };

    /// A model that asks for twice the experts' size (a quarter of their elements) is scaled by
    /// about one half, and its meshes then have the experts' counts; the last step alone is. Its
    /// counts follow the experts' (both go as the area), so the count regression keeps them.
    #[test]
    fn the_final_step_scale_gives_the_experts_element_counts() {
        let problems = squares(&[(1.0, 0.04), (1.5, 0.04)]);
        let mut model = Uniform { size: 0.08, limits: UNSCALED };
        let fit = fit_final_step(&model, &problems, 2).unwrap();
        assert!((0.45..0.55).contains(&fit.scale), "scale {}", fit.scale);
        assert!(fit.count.slope > 0.9, "{:?}", fit.count);
        let unscaled = generate(&model, &problems[1], 2, FinalStep::default()).unwrap();
        model.limits.final_step_scale = fit.scale;
        assert!(fit_final_step(&model, &problems, 2).is_err(), "a scaled model is refitted from 1");
        let scaled = generate(&model, &problems[1], 2, FinalStep::default()).unwrap();
        assert_eq!(scaled[0].mesh.num_elements(), unscaled[0].mesh.num_elements());
        let (made, expert) = (scaled[1].mesh.num_elements() as f64, problems[1].expert_mesh.num_elements() as f64);
        assert!((made / expert - 1.0).abs() < 0.05, "{made} elements for the expert's {expert}");
    }

    /// Experts that mesh a square and one of 2.25 times its area with the same number of
    /// elements, and a model whose count goes as the area: the regression's slope is 0, and
    /// with it both the evaluation's rollouts and `generate` end at the experts' count, where
    /// the scale alone misses both squares by half.
    #[test]
    fn the_count_regression_gives_a_count_the_model_misses() {
        let problems = squares(&[(1.0, 0.04), (1.5, 0.06)]);
        let references = Reference::for_problems(&problems, &UNSCALED).unwrap();
        let mut model = Uniform { size: 0.08, limits: UNSCALED };
        let fit = fit_final_step(&model, &problems, 2).unwrap();
        assert_eq!(fit.count.slope, 0.0, "{:?}", fit.count);
        let final_counts = |model: &Uniform| -> Vec<f64> {
            let rolled = rollouts(model, &problems, &references, 2).unwrap();
            problems
                .iter()
                .zip(&rolled)
                .map(|(p, r)| r.steps[1].metrics.elements as f64 / p.expert_mesh.num_elements() as f64)
                .collect()
        };
        model.limits.final_step_scale = fit.scale;
        let scaled = final_counts(&model);
        assert!(scaled[0] < 0.8 && scaled[1] > 1.2, "the scale alone: {scaled:?} of the experts' counts");
        model.limits.final_count = Some(fit.count);
        let regressed = final_counts(&model);
        assert!(regressed.iter().all(|r| (r - 1.0).abs() < 0.1), "{regressed:?} of the experts' counts");
        let generated = generate(&model, &problems[1], 2, FinalStep::default()).unwrap();
        let made = generated[1].mesh.num_elements() as f64 / problems[1].expert_mesh.num_elements() as f64;
        assert!((made - 1.0).abs() < 0.1, "generate: {made} of the expert's count");
    }
}
