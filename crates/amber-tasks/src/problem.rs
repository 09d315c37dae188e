//! What the training and inference loops need to know about a learning task. A [`Domain`] is what
//! inference needs: an initial mesh, the per-element input columns on any mesh of the domain, and
//! re-meshing from a per-element sizing field. A [`Problem`] is a domain with its expert's mesh,
//! what training and evaluation need. Around them, what every task shares: a mesh with its
//! columns and graph ([`MeshState`]), the labels (the expert's sizing field projected onto a
//! mesh), and one generation step under h_min and the element budget ([`MeshLimits`]), or to a
//! requested element count ([`mesh_to_element_count`]). Each task implements the traits beside
//! its data (`poisson`, `console`); geometry-only domains live in `part`.

use std::collections::BTreeMap;
use std::path::Path;

use amber_fem::FemError;
use amber_graph::{Aggregation, ElementColumn, FeatureSet, GraphError, MeshGraph, NodeFeature, project_expert_sizing};
use amber_mesh::Mesh;
use amber_meshgen::{MeshgenError, estimated_element_count};
use amber_metrics::MetricsError;
use amber_stdx::quantile;
use serde::{Deserialize, Serialize};

use crate::TaskError;
use crate::expert::check_expert_mesh;

/// Why one problem's step failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ProblemError {
    /// The mesh generator failed.
    #[error("meshing: {0}")]
    Meshing(#[from] MeshgenError),
    /// The FEM solve behind the features failed.
    #[error("FEM: {0}")]
    Fem(#[from] FemError),
    /// Graph building or label projection failed.
    #[error("graph: {0}")]
    Graph(#[from] GraphError),
    /// A metric was undefined.
    #[error("metrics: {0}")]
    Metrics(#[from] MetricsError),
}

/// A named per-element input column (e.g. the mean of the FEM solution over each element).
#[derive(Clone, Debug, PartialEq)]
pub struct Column {
    pub name: String,
    /// One value per element.
    pub values: Vec<f64>,
}

/// A domain of a learning task in `D` dimensions: its geometry and task inputs, everything a
/// trained model needs to mesh it (no expert mesh).
pub trait Domain<const D: usize>: Sync {
    /// The node and edge features of this task's graphs (the same for all its problems).
    fn feature_set(&self) -> FeatureSet;
    /// Names of the columns this task computes beyond its feature set, which a model may take as
    /// extra node inputs (see [`with_inputs`]); [`LOG_SIZE_COLUMN`] is offered by every task.
    fn optional_inputs(&self) -> Vec<String> {
        Vec::new()
    }
    /// M⁰, the start of every rollout.
    fn initial_mesh(&self) -> &Mesh<D>;
    /// The per-element columns the feature set names, on `mesh` (a mesh of this problem's
    /// domain); the geometric features are computed by the graph.
    fn columns(&self, mesh: &Mesh<D>) -> Result<Vec<Column>, ProblemError>;
    /// A new mesh of the domain whose element sizes follow the piecewise-constant field `sizes`
    /// on `mesh`; the generator refuses to build more than `max_elements` elements.
    fn remesh(&self, mesh: &Mesh<D>, sizes: Vec<f64>, max_elements: usize) -> Result<Mesh<D>, ProblemError>;
    /// The boundary facets of `mesh` (a mesh of this domain), keyed by their sorted vertices,
    /// each tagged with the piece of the domain's boundary it lies on (a solid's CAD faces), for
    /// the writers that group the boundary (gmsh physical groups, medit references); empty where
    /// the boundary is one piece.
    fn boundary_tags(&self, _mesh: &Mesh<D>) -> BTreeMap<Vec<u32>, i32> {
        BTreeMap::new()
    }
    /// The names of the tags of [`Domain::boundary_tags`] where the geometry gives them (a
    /// mesh file's physical groups, an STL's solids, an OBJ's groups).
    fn boundary_names(&self) -> BTreeMap<i32, String> {
        BTreeMap::new()
    }
    /// The name of the domain's element group where the geometry gives one (a mesh file's).
    fn domain_name(&self) -> Option<String> {
        None
    }
}

/// One problem of a learning task in `D` dimensions: a domain with the expert's mesh of it.
pub trait Problem<const D: usize>: Domain<D> {
    /// M*, the expert's mesh the labels come from.
    fn expert_mesh(&self) -> &Mesh<D>;
    /// The problem's name for people and result files: its expert mesh file's stem, or the
    /// seed of a generated problem.
    fn name(&self) -> String;
}

/// A domain with an expert's mesh of it: a [`Problem`] put together from its parts, e.g. a user's
/// geometry and the mesh their expert made of it.
#[derive(Clone, Debug)]
pub struct WithExpert<P, const D: usize> {
    pub domain: P,
    pub expert_mesh: Mesh<D>,
    /// The stem of the expert mesh's file.
    name: String,
}

impl<const D: usize, P: Domain<D>> WithExpert<P, D> {
    /// `domain` with `expert_mesh`, read from `path`, checked to be a mesh of it: conforming,
    /// covering M⁰'s region and no more, without holes M⁰ lacks.
    pub fn new(domain: P, expert_mesh: Mesh<D>, path: &Path) -> Result<Self, TaskError> {
        check_expert_mesh(path, &expert_mesh, domain.initial_mesh())?;
        let name = path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned());
        Ok(Self { domain, expert_mesh, name })
    }
}

impl<const D: usize, P: Domain<D>> Domain<D> for WithExpert<P, D> {
    fn feature_set(&self) -> FeatureSet {
        self.domain.feature_set()
    }

    fn optional_inputs(&self) -> Vec<String> {
        self.domain.optional_inputs()
    }

    fn initial_mesh(&self) -> &Mesh<D> {
        self.domain.initial_mesh()
    }

    fn columns(&self, mesh: &Mesh<D>) -> Result<Vec<Column>, ProblemError> {
        self.domain.columns(mesh)
    }

    fn remesh(&self, mesh: &Mesh<D>, sizes: Vec<f64>, max_elements: usize) -> Result<Mesh<D>, ProblemError> {
        self.domain.remesh(mesh, sizes, max_elements)
    }

    fn boundary_tags(&self, mesh: &Mesh<D>) -> BTreeMap<Vec<u32>, i32> {
        self.domain.boundary_tags(mesh)
    }

    fn boundary_names(&self) -> BTreeMap<i32, String> {
        self.domain.boundary_names()
    }

    fn domain_name(&self) -> Option<String> {
        self.domain.domain_name()
    }
}

impl<const D: usize, P: Domain<D>> Problem<D> for WithExpert<P, D> {
    fn expert_mesh(&self) -> &Mesh<D> {
        &self.expert_mesh
    }

    fn name(&self) -> String {
        self.name.clone()
    }
}

/// The clip and the element budget every predicted sizing field passes before meshing (spec
/// §2, §6), fixed by the training set and reused for validation, test and inference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshLimits {
    /// h_min: predicted sizes are clipped below at this size.
    pub min_size: f64,
    /// Fields whose estimated element count Σ|K|/V(h) exceeds this are not meshed as they are.
    pub max_elements: usize,
    /// What becomes of such a field: `false` (the paper) skips the step; `true` (the later
    /// version, spec §11) scales every size up by one factor so that the estimate meets the
    /// budget, and meshes that.
    #[serde(default)]
    pub scale_to_budget: bool,
    /// The last generation step's sizes are multiplied by this: fitted after training so that
    /// the model's meshes of its training parts have their experts' element counts (1: not
    /// fitted). See `amber_train::fit_final_step`.
    #[serde(default = "unit_scale")]
    pub final_step_scale: f64,
    /// The last step's element count as a function of what the model's own (scaled) field asks
    /// for, fitted after training as well (`None`: what the field asks for stands). See
    /// [`FinalCount`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_count: Option<FinalCount>,
}

fn unit_scale() -> f64 {
    1.0
}

/// ln(count) = `expert_log_mean` + `slope` · (ln(estimate) − `model_log_mean`): the regression of
/// the calibration experts' log element counts on the log of the count the model's last field
/// asks for ([`estimated_element_count`], after the final step scale), over the calibration
/// problems. Slope 1 leaves the model's count as it is; slope 0 gives every geometry the experts'
/// typical count, which is what a model whose counts say nothing of its experts' should do (on
/// Poisson, the model's final counts and the experts' are uncorrelated over test problems).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FinalCount {
    /// In [0, 1].
    pub slope: f64,
    /// Mean of ln(estimate) over the calibration problems.
    pub model_log_mean: f64,
    /// Mean of ln(expert's element count) over the calibration problems.
    pub expert_log_mean: f64,
}

impl FinalCount {
    /// The element count for a field that asks for `estimate` elements.
    pub fn target(&self, estimate: f64) -> usize {
        (self.expert_log_mean + self.slope * (estimate.ln() - self.model_log_mean)).exp().round().max(1.0) as usize
    }

    /// The least-squares fit of `(ln estimate, ln expert count)` pairs, the slope clipped to
    /// [0, 1] (0 when the estimates do not vary); `None` without pairs.
    pub fn fit(pairs: &[(f64, f64)]) -> Option<Self> {
        if pairs.is_empty() {
            return None;
        }
        let n = pairs.len() as f64;
        let model_log_mean = pairs.iter().map(|p| p.0).sum::<f64>() / n;
        let expert_log_mean = pairs.iter().map(|p| p.1).sum::<f64>() / n;
        let covariance = pairs.iter().map(|(m, e)| (m - model_log_mean) * (e - expert_log_mean)).sum::<f64>();
        let variance = pairs.iter().map(|(m, _)| (m - model_log_mean).powi(2)).sum::<f64>();
        let slope = if variance > 0.0 { (covariance / variance).clamp(0.0, 1.0) } else { 0.0 };
        Some(Self { slope, model_log_mean, expert_log_mean })
    }
}

impl MeshLimits {
    /// h_min = the `min_size_quantile` quantile of all training expert element sizes (0: the
    /// smallest); budget = ⌊`budget_factor` × the largest training expert's element count⌋.
    pub fn from_experts<'m, const D: usize>(
        experts: impl IntoIterator<Item = &'m Mesh<D>>,
        budget_factor: f64,
        min_size_quantile: f64,
    ) -> Self {
        let mut sizes = Vec::new();
        let mut largest = 0;
        for expert in experts {
            sizes.extend(expert.sizes());
            largest = largest.max(expert.num_elements());
        }
        sizes.sort_by(f64::total_cmp);
        Self {
            min_size: quantile(&sizes, min_size_quantile),
            max_elements: (budget_factor * largest as f64) as usize,
            scale_to_budget: false,
            final_step_scale: 1.0,
            final_count: None,
        }
    }

    /// The generator's own hard cap: a safety net well above the budget (the estimate is only
    /// an estimate), so a runaway field fails fast instead of meshing millions of elements.
    pub fn generator_cap(&self) -> usize {
        self.max_elements.saturating_mul(4).max(1_000)
    }
}

/// A mesh with everything the network reads from it: the input columns and the graph.
#[derive(Clone, Debug)]
pub struct MeshState<const D: usize> {
    pub mesh: Mesh<D>,
    pub columns: Vec<Column>,
    pub graph: MeshGraph,
}

/// Name of the generic optional node input log h(K): normalised linearly, raw element volumes
/// that span many orders of magnitude (10⁻¹ to 10⁻¹² on the hard Poisson meshes) cannot tell the
/// small elements apart, yet the size of the current element is what a prediction relative to it
/// needs most. Any task offers it; [`MeshState::new`] computes it.
pub const LOG_SIZE_COLUMN: &str = "log_size";

/// `features` with the optional node inputs `inputs` appended in order: column names that the
/// task computes beyond its own feature set (see [`Problem::optional_inputs`]), or
/// [`LOG_SIZE_COLUMN`].
pub fn with_inputs(mut features: FeatureSet, inputs: &[String]) -> FeatureSet {
    features.node.extend(inputs.iter().map(|name| NodeFeature::Column(name.clone())));
    features
}

impl<const D: usize> MeshState<D> {
    /// Computes the columns of `mesh` from `problem` (plus log h(K) if `features` asks for it)
    /// and builds its graph.
    pub fn new<P: Domain<D> + ?Sized>(problem: &P, features: &FeatureSet, mesh: Mesh<D>) -> Result<Self, ProblemError> {
        let mut columns = problem.columns(&mesh)?;
        if features.node.iter().any(|f| *f == NodeFeature::Column(LOG_SIZE_COLUMN.into())) {
            let values = mesh.sizes().into_iter().map(f64::ln).collect();
            columns.push(Column { name: LOG_SIZE_COLUMN.into(), values });
        }
        Self::from_columns(features, mesh, columns)
    }

    /// Builds the graph of `mesh` from already computed columns (used when loading checkpoints).
    pub fn from_columns(features: &FeatureSet, mesh: Mesh<D>, columns: Vec<Column>) -> Result<Self, ProblemError> {
        let named: Vec<ElementColumn<'_>> =
            columns.iter().map(|c| ElementColumn { name: &c.name, values: &c.values }).collect();
        let graph = MeshGraph::new(&mesh, features, &named)?;
        Ok(Self { mesh, columns, graph })
    }
}

/// The labels of `mesh`: the problem's expert sizing field projected onto it (spec §3).
pub fn labels<const D: usize, P: Problem<D> + ?Sized>(
    problem: &P,
    mesh: &Mesh<D>,
    aggregation: Aggregation,
) -> Result<Vec<f64>, ProblemError> {
    Ok(project_expert_sizing(mesh, problem.expert_mesh(), aggregation)?)
}

/// What became of one generation step.
#[derive(Clone, Debug)]
pub enum StepOutcome<const D: usize> {
    /// The new mesh.
    Meshed(Mesh<D>),
    /// The element budget was exceeded: nothing was meshed.
    OverBudget {
        /// Σ|K|/V(h) of the clipped field, or the generator's cap when its own cap stopped it.
        estimated_elements: f64,
    },
    /// The generator failed for another reason (reported, not fatal to a training run).
    Failed { reason: String },
}

/// Fraction of the element budget a field scaled to the budget aims at.
const BUDGET_TARGET: f64 = 0.95;

/// One generation step from `mesh` with the predicted per-element `sizes`: clip below at h_min,
/// check the element budget (skip, or scale to it, as `limits` says), hold the field within a
/// user's `bounds` (after the budget, which guards the model's field: a refinement box adds its
/// elements rather than coarsening the rest), mesh (up to the bounds' cap on elements when the
/// user set one, else [`MeshLimits::generator_cap`]).
pub fn generation_step<const D: usize, P: Domain<D> + ?Sized>(
    problem: &P,
    mesh: &Mesh<D>,
    mut sizes: Vec<f64>,
    limits: &MeshLimits,
    bounds: &SizeBounds,
) -> StepOutcome<D> {
    // `f64::max` maps NaN to the minimum: a broken prediction asks for the finest mesh, which
    // the budget then rejects.
    sizes.iter_mut().for_each(|h| *h = h.max(limits.min_size));
    let estimated_elements = estimated_element_count(mesh, &sizes);
    if estimated_elements > limits.max_elements as f64 {
        if !limits.scale_to_budget || !estimated_elements.is_finite() {
            return StepOutcome::OverBudget { estimated_elements };
        }
        // The count goes as h^-D: aim a little below the budget, the estimate being an estimate.
        let factor = (estimated_elements / (BUDGET_TARGET * limits.max_elements as f64)).powf(1.0 / D as f64);
        sizes.iter_mut().for_each(|h| *h *= factor);
    }
    bounds.apply(problem, mesh, &mut sizes);
    match problem.remesh(mesh, sizes, bounds.element_cap(limits)) {
        Ok(mesh) => StepOutcome::Meshed(mesh),
        Err(ProblemError::Meshing(MeshgenError::TooManyElements { cap })) => {
            StepOutcome::OverBudget { estimated_elements: cap as f64 }
        }
        Err(e) => StepOutcome::Failed { reason: e.to_string() },
    }
}

/// How far from the requested count [`mesh_to_element_count`] may land before it corrects the
/// field and meshes again: half the ±10 % users are promised, so one correction usually suffices.
pub const ELEMENT_COUNT_TOLERANCE: f64 = 0.05;

/// Meshings [`mesh_to_element_count`] tries before it returns its closest mesh.
const ELEMENT_COUNT_ATTEMPTS: usize = 5;

/// What a user allows a final mesh's sizing field (`amber mesh --min-size/--max-size/--refine-box/
/// --refine-face`): a range (an explicit solver's time step is set by its smallest element; a
/// contact or a result plot wants no element above a size), and boxes and boundary faces where
/// 90 % of the elements are to be no larger than a size (a bolt hole, a weld, a contact face: where the
/// stresses matter). They act after every other scaling, so the model still decides where
/// elements go within them. What they add is the user's call, so the user caps the mesh they make
/// (`--max-elements`), not the model's budget, which guards only the model's own field.
#[derive(Clone, Debug, PartialEq)]
pub struct SizeBounds {
    min: f64,
    max: f64,
    boxes: Vec<RefineBox>,
    faces: Vec<RefineFace>,
    max_elements: Option<usize>,
}

/// An axis-aligned box (corners `lo`, `hi` in the geometry's `lo.len()` dimensions) where the
/// sizing field is held at or below `max_size`.
#[derive(Clone, Debug, PartialEq)]
pub struct RefineBox {
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
    pub max_size: f64,
}

/// A piece of the boundary (a solid's CAD face, a polygon's side: the tag of
/// [`Domain::boundary_tags`], the `boundary_<face>` group of the written mesh) where the sizing
/// field is held at or below `max_size`.
#[derive(Clone, Debug, PartialEq)]
pub struct RefineFace {
    pub face: i32,
    pub max_size: f64,
}

impl Default for SizeBounds {
    /// No bounds.
    fn default() -> Self {
        Self { min: 0.0, max: f64::INFINITY, boxes: Vec::new(), faces: Vec::new(), max_elements: None }
    }
}

impl SizeBounds {
    /// Sizes at least `min` and at most `max` (either may be absent); an error says why a range is
    /// not one: a bound that is not a positive number, or `min` above `max`.
    pub fn new(min: Option<f64>, max: Option<f64>) -> Result<Self, String> {
        for (name, bound) in [("minimum", min), ("maximum", max)] {
            if let Some(h) = bound.filter(|h| !(h.is_finite() && *h > 0.0)) {
                return Err(format!("the {name} size must be a positive number, not {h}"));
            }
        }
        let bounds = Self { min: min.unwrap_or(0.0), max: max.unwrap_or(f64::INFINITY), ..Self::default() };
        if bounds.min > bounds.max {
            return Err(format!("the minimum size {} is above the maximum size {}", bounds.min, bounds.max));
        }
        Ok(bounds)
    }

    /// These bounds and a box where sizes are at most `refine.max_size`; an error says why it is
    /// not one: corners of different dimensions or not below one another, non-finite
    /// coordinates, or a size that is not positive or is below the minimum size.
    pub fn with_box(mut self, refine: RefineBox) -> Result<Self, String> {
        let RefineBox { lo, hi, max_size } = &refine;
        if lo.len() != hi.len() || lo.iter().chain(hi).any(|x| !x.is_finite()) {
            return Err("the box needs two corners of finite coordinates in the same dimensions".into());
        }
        if lo.iter().zip(hi).any(|(a, b)| a >= b) {
            return Err(format!("the corner {lo:?} is not below the corner {hi:?} along every axis"));
        }
        self.check_refined_size("box", *max_size)?;
        self.boxes.push(refine);
        Ok(self)
    }

    /// These bounds and a boundary face where sizes are at most `refine.max_size`; an error says
    /// why the size is not one (as for a box). Whether the geometry has the face is the caller's
    /// to check, against [`Domain::boundary_tags`].
    pub fn with_face(mut self, refine: RefineFace) -> Result<Self, String> {
        self.check_refined_size("face", refine.max_size)?;
        self.faces.push(refine);
        Ok(self)
    }

    fn check_refined_size(&self, what: &str, max_size: f64) -> Result<(), String> {
        if !(max_size.is_finite() && max_size > 0.0) {
            return Err(format!("the {what}'s size must be a positive number, not {max_size}"));
        }
        if max_size < self.min {
            return Err(format!("the {what}'s size {max_size} is below the minimum size {}", self.min));
        }
        Ok(())
    }

    /// These bounds with the generator refusing to build more than `max_elements` elements under
    /// them (instead of the model's [`MeshLimits::generator_cap`]).
    pub fn with_max_elements(self, max_elements: usize) -> Self {
        Self { max_elements: Some(max_elements), ..self }
    }

    /// The user's cap on the elements of a mesh under these bounds, if one was set.
    pub fn max_elements(&self) -> Option<usize> {
        self.max_elements
    }

    /// The cap on the elements of a mesh under these bounds: the user's, else the generator's
    /// own safety net of `limits`.
    pub fn element_cap(&self, limits: &MeshLimits) -> usize {
        self.max_elements.unwrap_or_else(|| limits.generator_cap())
    }

    /// `h` moved into the range (the boxes aside).
    pub fn clamp(&self, h: f64) -> f64 {
        h.clamp(self.min, self.max)
    }

    /// `sizes`, one per element of `mesh` (a mesh of `domain`), moved into the range; at most
    /// `refined_field` of a box's size on every element whose bounding box meets the box, and
    /// of a face's size on every element with a vertex on the face. Panics if a box is not of
    /// dimension `D` (callers check it against the geometry).
    pub fn apply<const D: usize, P: Domain<D> + ?Sized>(&self, domain: &P, mesh: &Mesh<D>, sizes: &mut [f64]) {
        sizes.iter_mut().for_each(|h| *h = self.clamp(*h));
        let refined = |max_size: f64| refined_field::<D>(max_size).max(self.min);
        if !self.faces.is_empty() {
            // The smallest size any refined face asks of each vertex.
            let mut vertex_size = vec![f64::INFINITY; mesh.num_vertices()];
            for (facet, tag) in domain.boundary_tags(mesh) {
                for refine in self.faces.iter().filter(|f| f.face == tag) {
                    for &v in &facet {
                        let h = &mut vertex_size[v as usize];
                        *h = h.min(refined(refine.max_size));
                    }
                }
            }
            for (element, h) in mesh.elements().zip(sizes.iter_mut()) {
                *h = element.iter().fold(*h, |h, &v| h.min(vertex_size[v as usize]));
            }
        }
        if self.boxes.is_empty() {
            return;
        }
        assert!(self.boxes.iter().all(|b| b.lo.len() == D), "a refinement box of another dimension than the mesh");
        for (element, h) in mesh.elements().zip(sizes) {
            let corner = |pick: fn(f64, f64) -> f64, start: f64| {
                std::array::from_fn::<f64, D, _>(|k| {
                    element.iter().fold(start, |acc, &v| pick(acc, mesh.vertices()[v as usize][k]))
                })
            };
            let (lo, hi) = (corner(f64::min, f64::INFINITY), corner(f64::max, f64::NEG_INFINITY));
            for b in &self.boxes {
                if (0..D).all(|k| lo[k] <= b.hi[k] && hi[k] >= b.lo[k]) {
                    *h = h.min(refined(b.max_size));
                }
            }
        }
    }
}

/// The field that meshes a refined region (a box, a face) with 90 % of its elements no larger
/// than `max_size`: the generators' elements scatter around the field, and more so in 3D, where
/// the surface remesher keeps edges below 4/3 of it and TetGen grades the thin refined layer
/// into its coarser surroundings. The factors are measured (docs/PROFILES.md): at the field
/// itself the 90th percentile came out at 1.16–1.18× in 2D and 1.31–1.46× in 3D.
fn refined_field<const D: usize>(max_size: f64) -> f64 {
    max_size * if D == 3 { 0.75 } else { 0.85 }
}

/// A new mesh of `domain` whose sizes follow the shape of the field `sizes` on `mesh`, scaled by
/// one factor (then held within `bounds`) so that the mesh has about `target` elements: the budget
/// knob of `amber mesh --elements`. Bounds that forbid the count leave the closest mesh they
/// allow. The first factor makes the estimate Σ|K|/V(h) equal `target`; the generator's count
/// differs from the estimate (boundary grading, quality refinement, the 3D curvature cap), so each
/// further attempt corrects the factor from the count n it got: by (n/target)^(1/D) at first,
/// then along the slope the last two meshings measured (bounds hold part of the field fixed),
/// until n is within [`ELEMENT_COUNT_TOLERANCE`] of `target` or [`ELEMENT_COUNT_ATTEMPTS`]
/// meshings are spent; the mesh closest to `target` is returned. `max_elements` caps every
/// meshing.
pub fn mesh_to_element_count<const D: usize, P: Domain<D> + ?Sized>(
    domain: &P,
    mesh: &Mesh<D>,
    sizes: &[f64],
    target: usize,
    bounds: &SizeBounds,
    max_elements: usize,
) -> Result<Mesh<D>, ProblemError> {
    if target == 0 || target > max_elements {
        return Err(ProblemError::Meshing(MeshgenError::TooManyElements { cap: max_elements }));
    }
    let estimate = estimated_element_count(mesh, sizes);
    if !estimate.is_finite() || estimate <= 0.0 {
        let (at, value) = sizes
            .iter()
            .zip(mesh.midpoints())
            .find(|(h, _)| !(h.is_finite() && **h > 0.0))
            .map_or((Vec::new(), estimate), |(h, x)| (x.to_vec(), *h));
        return Err(ProblemError::Meshing(MeshgenError::InvalidSize { at, value }));
    }
    let target_f = target as f64;
    let mut factor = (estimate / target_f).powf(1.0 / D as f64);
    let mut best: Option<Mesh<D>> = None;
    let mut previous: Option<(f64, f64)> = None;
    for _ in 0..ELEMENT_COUNT_ATTEMPTS {
        let mut scaled: Vec<f64> = sizes.iter().map(|h| h * factor).collect();
        bounds.apply(domain, mesh, &mut scaled);
        let candidate = domain.remesh(mesh, scaled, max_elements)?;
        let count = candidate.num_elements() as f64;
        let miss = |m: &Mesh<D>| (m.num_elements() as f64 / target_f - 1.0).abs();
        let done = miss(&candidate) <= ELEMENT_COUNT_TOLERANCE;
        if best.as_ref().is_none_or(|b| miss(&candidate) < miss(b)) {
            best = Some(candidate);
        }
        if done {
            break;
        }
        // The count goes as factor^-D where the field is free; the bounds hold part of it fixed,
        // so after two meshings the slope of ln count over ln factor is measured instead (kept
        // within [-2D, -D/10], so that a step stays bounded where the bounds fix nearly all).
        let point = (factor.ln(), count.ln());
        let slope = previous
            .filter(|(f, _)| (point.0 - f).abs() > 1e-9)
            .map_or(-(D as f64), |(f, c)| ((point.1 - c) / (point.0 - f)).clamp(-2.0 * D as f64, -0.1 * D as f64));
        factor *= ((target_f.ln() - point.1) / slope).exp();
        previous = Some(point);
    }
    Ok(best.expect("at least one attempt"))
}

#[cfg(test)]
mod tests {
    use amber_meshgen::PolygonDomain;

    use super::*;
    use crate::part::PlanarPart;

    /// A field graded by a factor of 20 towards one corner, asked for 0.25×, 1× and 4× its own
    /// count: every mesh lands within the tolerance, keeps the grading, and covers the domain.
    #[test]
    fn meshes_reach_the_requested_element_count() {
        let hole = vec![[0.4, 0.4], [0.4, 0.6], [0.6, 0.6], [0.6, 0.4]];
        let domain = PolygonDomain::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![hole]).unwrap();
        let holed = PlanarPart::new("holed".into(), domain, 0.1).unwrap();
        let mesh = holed.initial_mesh();
        let sizes: Vec<f64> = mesh.midpoints().iter().map(|x| 0.004 + 0.08 * (x[0] + x[1]) / 2.0).collect();
        let natural = holed.remesh(mesh, sizes.clone(), 1_000_000).unwrap().num_elements();
        for target in [natural / 4, natural, 4 * natural] {
            let made = mesh_to_element_count(&holed, mesh, &sizes, target, &SizeBounds::default(), 1_000_000).unwrap();
            let ratio = made.num_elements() as f64 / target as f64;
            assert!((ratio - 1.0).abs() <= ELEMENT_COUNT_TOLERANCE, "{} elements for {target}", made.num_elements());
            assert!((made.total_volume() - 0.96).abs() < 1e-12);
            let near = made.midpoints().iter().filter(|x| x[0] + x[1] < 1.0).count();
            assert!(near > made.num_elements() / 2, "the grading is kept: {near} of {}", made.num_elements());
        }
        assert!(mesh_to_element_count(&holed, mesh, &sizes, 10, &SizeBounds::default(), 5).is_err());
        let broken: Vec<f64> = sizes.iter().map(|_| f64::NAN).collect();
        assert!(mesh_to_element_count(&holed, mesh, &broken, 100, &SizeBounds::default(), 1_000).is_err());
    }

    /// The same graded field (sizes 0.004 to 0.084) held within [0.01, 0.025]: the count still
    /// lands on the target, the sizes stay in the range but for the generator's own spread (about
    /// ±15 %), and the grading is kept inside it.
    #[test]
    fn size_bounds_hold_the_field_while_the_count_is_met() {
        let domain = PolygonDomain::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![]).unwrap();
        let square = PlanarPart::new("square".into(), domain, 0.1).unwrap();
        let mesh = square.initial_mesh();
        let sizes: Vec<f64> = mesh.midpoints().iter().map(|x| 0.004 + 0.08 * (x[0] + x[1]) / 2.0).collect();
        let quantiles = |m: &Mesh<2>| {
            let mut h = m.sizes();
            h.sort_by(f64::total_cmp);
            (quantile(&h, 0.02), quantile(&h, 0.98))
        };
        let unbounded = mesh_to_element_count(&square, mesh, &sizes, 8_000, &SizeBounds::default(), 1_000_000).unwrap();
        let (low, high) = quantiles(&unbounded);
        assert!(
            low < 0.007 && high > 0.032,
            "the unbounded field leaves the range: 2 % and 98 % quantiles {low}, {high}"
        );
        let bounds = SizeBounds::new(Some(0.01), Some(0.025)).unwrap();
        let made = mesh_to_element_count(&square, mesh, &sizes, 8_000, &bounds, 1_000_000).unwrap();
        let ratio = made.num_elements() as f64 / 8_000.0;
        assert!((ratio - 1.0).abs() <= ELEMENT_COUNT_TOLERANCE, "{} elements", made.num_elements());
        let (low, high) = quantiles(&made);
        assert!(low > 0.0075 && high < 0.03, "2 % and 98 % quantiles {low}, {high}");
        let near = made.midpoints().iter().filter(|x| x[0] + x[1] < 1.0).count();
        assert!(near > made.num_elements() * 6 / 10, "the grading is kept: {near} of {}", made.num_elements());
    }

    /// The `q` quantile of the element sizes of `mesh` over the elements whose midpoint is
    /// `inside`.
    fn size_quantile_where(mesh: &Mesh<2>, q: f64, inside: impl Fn([f64; 2]) -> bool) -> f64 {
        let mut h: Vec<f64> =
            mesh.midpoints().iter().zip(mesh.sizes()).filter(|(x, _)| inside(**x)).map(|(_, h)| h).collect();
        h.sort_by(f64::total_cmp);
        quantile(&h, q)
    }

    /// A uniform field with a box asking for a fifth of its size: the count still lands on the
    /// target, 90 % of the box's elements are no larger than its size (and not far below it),
    /// and the rest of the square is coarser.
    #[test]
    fn a_refinement_box_holds_its_elements_while_the_count_is_met() {
        let domain = PolygonDomain::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![]).unwrap();
        let square = PlanarPart::new("square".into(), domain, 0.1).unwrap();
        let mesh = square.initial_mesh();
        let sizes = vec![0.05; mesh.num_elements()];
        let refine = RefineBox { lo: vec![0.2, 0.2], hi: vec![0.4, 0.4], max_size: 0.01 };
        let bounds = SizeBounds::default().with_box(refine).unwrap();
        let made = mesh_to_element_count(&square, mesh, &sizes, 3_000, &bounds, 1_000_000).unwrap();
        let ratio = made.num_elements() as f64 / 3_000.0;
        assert!((ratio - 1.0).abs() <= ELEMENT_COUNT_TOLERANCE, "{} elements", made.num_elements());
        let in_box = |q| size_quantile_where(&made, q, |x| (0.2..0.4).contains(&x[0]) && (0.2..0.4).contains(&x[1]));
        let (median, p90) = (in_box(0.5), in_box(0.9));
        let far = size_quantile_where(&made, 0.5, |x| x[0] > 0.7 && x[1] > 0.7);
        assert!(p90 <= 0.0102 && median > 0.0075, "the box's sizes: median {median}, 90 % {p90}");
        assert!(far > 2.5 * median, "far from the box {far}, in it {median}");

        let bad = |lo: Vec<f64>, hi: Vec<f64>, max_size| {
            SizeBounds::new(Some(0.005), None).unwrap().with_box(RefineBox { lo, hi, max_size }).unwrap_err()
        };
        assert!(bad(vec![0.0, 0.0], vec![1.0, 1.0, 1.0], 0.01).contains("same dimensions"));
        assert!(bad(vec![0.0, 1.0], vec![1.0, 0.5], 0.01).contains("not below"));
        assert!(bad(vec![0.0, 0.0], vec![1.0, 1.0], -1.0).contains("positive"));
        assert!(bad(vec![0.0, 0.0], vec![1.0, 1.0], 0.001).contains("below the minimum size"));
    }

    /// A uniform field with the square's bottom side asking for a fifth of its size: the count
    /// still lands on the target, 90 % of the elements along that side are no larger than its
    /// size, the other sides' are larger, and a face's size is checked as a box's.
    #[test]
    fn a_refined_face_holds_its_elements_while_the_count_is_met() {
        let domain = PolygonDomain::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![]).unwrap();
        let square = PlanarPart::new("square".into(), domain, 0.1).unwrap();
        let mesh = square.initial_mesh();
        let bottom = square
            .boundary_tags(mesh)
            .iter()
            .find(|(edge, _)| edge.iter().all(|&v| mesh.vertices()[v as usize][1] == 0.0))
            .map(|(_, &tag)| tag)
            .unwrap();
        let bounds = SizeBounds::default().with_face(RefineFace { face: bottom, max_size: 0.01 }).unwrap();
        let made =
            mesh_to_element_count(&square, mesh, &vec![0.05; mesh.num_elements()], 4_000, &bounds, 1_000_000).unwrap();
        let ratio = made.num_elements() as f64 / 4_000.0;
        assert!((ratio - 1.0).abs() <= ELEMENT_COUNT_TOLERANCE, "{} elements", made.num_elements());
        let along = |q| size_quantile_where(&made, q, |x| x[1] < 0.03);
        let (median, p90) = (along(0.5), along(0.9));
        let top = size_quantile_where(&made, 0.5, |x| x[1] > 0.97);
        assert!(p90 <= 0.0102 && median > 0.0075, "the bottom side's sizes: median {median}, 90 % {p90}");
        assert!(top > 2.5 * median, "along the top side {top}, the bottom {median}");

        let bounds = SizeBounds::new(Some(0.005), None).unwrap();
        let bad = |max_size| bounds.clone().with_face(RefineFace { face: bottom, max_size }).unwrap_err();
        assert!(bad(f64::NAN).contains("positive"));
        assert!(bad(0.001).contains("below the minimum size"));
    }

    /// The fit recovers an exact power law, clips a slope beyond [0, 1], and maps the mean
    /// estimate to the experts' geometric mean count whatever the slope.
    #[test]
    fn the_final_count_regresses_log_counts() {
        let line = |slope: f64| -> Vec<(f64, f64)> {
            [1_000.0f64, 2_000.0, 8_000.0].iter().map(|m| (m.ln(), 5.0 + slope * m.ln())).collect()
        };
        let half = FinalCount::fit(&line(0.5)).unwrap();
        assert!((half.slope - 0.5).abs() < 1e-12, "{half:?}");
        assert_eq!(FinalCount::fit(&line(1.7)).unwrap().slope, 1.0);
        assert_eq!(FinalCount::fit(&line(-0.3)).unwrap().slope, 0.0);
        let flat = FinalCount::fit(&[(7.0, 9.0), (7.0, 10.0)]).unwrap();
        assert_eq!(
            (flat.slope, flat.target(1.0), flat.target(1e6)),
            (0.0, 9.5f64.exp().round() as usize, 9.5f64.exp().round() as usize)
        );
        assert!(FinalCount::fit(&[]).is_none());
        let mean_estimate = half.model_log_mean.exp();
        assert_eq!(half.target(mean_estimate), half.expert_log_mean.exp().round() as usize);
        assert_eq!(half.target(4.0 * mean_estimate), (2.0 * half.expert_log_mean.exp()).round() as usize);
    }

    /// A field over the model's budget is scaled to it before a refinement box acts: the box's
    /// elements keep within its size, and only the model's field pays for the budget.
    #[test]
    fn a_refinement_box_acts_after_the_budget_guard() {
        let domain = PolygonDomain::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![]).unwrap();
        let square = PlanarPart::new("square".into(), domain, 0.1).unwrap();
        let mesh = square.initial_mesh();
        let limits = MeshLimits {
            min_size: 1e-3,
            max_elements: 500,
            scale_to_budget: true,
            final_step_scale: 1.0,
            final_count: None,
        };
        let refine = RefineBox { lo: vec![0.0, 0.0], hi: vec![0.2, 0.2], max_size: 0.012 };
        let bounds = SizeBounds::default().with_box(refine).unwrap();
        // An estimate of 924 elements, about twice the budget, before the box adds about 900.
        let StepOutcome::Meshed(made) =
            generation_step(&square, mesh, vec![0.05; mesh.num_elements()], &limits, &bounds)
        else {
            panic!("not meshed")
        };
        let in_box = size_quantile_where(&made, 0.9, |x| x[0] < 0.2 && x[1] < 0.2);
        let far = size_quantile_where(&made, 0.5, |x| x[0] > 0.6 && x[1] > 0.6);
        assert!((0.0096..0.0122).contains(&in_box), "the box's sizes at 90 %: {in_box}");
        assert!((0.06..0.085).contains(&far), "the budget's scale, 0.05 × √(924/475) = 0.070: {far}");
    }

    #[test]
    fn a_size_range_is_positive_and_ordered() {
        assert!(SizeBounds::new(None, None).is_ok_and(|b| b.clamp(1e-9) == 1e-9 && b.clamp(1e9) == 1e9));
        assert!(SizeBounds::new(Some(2.0), None).is_ok_and(|b| b.clamp(1.0) == 2.0 && b.clamp(3.0) == 3.0));
        assert!(SizeBounds::new(Some(1.0), Some(1.0)).is_ok_and(|b| b.clamp(0.5) == 1.0 && b.clamp(3.0) == 1.0));
        for (min, max) in [(Some(0.0), None), (None, Some(-1.0)), (Some(f64::NAN), None), (Some(2.0), Some(1.0))] {
            assert!(SizeBounds::new(min, max).is_err(), "{min:?}, {max:?}");
        }
    }
}
