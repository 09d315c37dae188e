//! `amber mesh`: a geometry in, a mesh out, its sizes from a trained model (`--model`) or a given
//! sizing field (`--size`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_experiments::{ModelCard, Task, resolve_model};
use amber_mesh::{
    AnyMesh, ElementOrder, Mesh, Mesh2, Mesh3, MeshData, WriteOptions, check_output, read_any_mesh, read_mesh,
    read_mesh_with_data, write_mesh, write_mesh_as,
};
use amber_meshgen::mesh3d::{Mesh3dParams, SurfaceDistance, generate_3d};
use amber_meshgen::{
    ConstantSize, Mesh2dParams, MeshSizing, PolygonDistance, PolygonDomain, QualityReport, SizingField, generate_2d,
};
use amber_metrics::{SizeRatios, log_size_ratios};
use amber_plot::{RenderOptions, TileMesh, View, render_png, render_surface_png};
use amber_stdx::{median, quantile};
use amber_tasks::cad::is_cad;
use amber_tasks::part::{
    FEATURE_ANGLE_DEGREES, PartInputs, PlanarPart, SolidPart, cad_face_tags, polygon_side_tags, read_polygon_domain,
    read_solid_surface,
};
use amber_tasks::poisson::{PoissonPart, read_part};
use amber_tasks::{Domain, RefineBox, RefineFace, SizeBounds, WithExpert};
use amber_train::{FinalStep, GeneratedStep, MeshMetrics, Reference, TrainError, TrainedModel};
use anyhow::{Context, bail};
use clap::Args;

#[derive(Args, Clone)]
pub struct MeshArgs {
    /// The geometry: `lshape` (with --corner), `square`, a polygon JSON
    /// `{"outer": [[x, y], ...], "holes": [[[x, y], ...], ...]}`, a closed surface (.stl, .obj), a
    /// CAD file (.step, .stp, .iges, .igs, .brep; tessellated by gmsh, which must be installed), or
    /// a 2D or 3D mesh file whose boundary is the geometry. With --problem it may be left out: the
    /// problem's own domain is meshed. Several geometries are meshed in turn, each to --output
    /// with `{stem}` replaced by the geometry's file stem (`-o meshed/{stem}.msh`).
    #[arg(num_args = 0..)]
    geometries: Vec<String>,
    /// The one geometry being meshed (set from `geometries`).
    #[arg(skip)]
    geometry: Option<String>,
    /// Re-entrant corner of the `lshape` geometry.
    #[arg(long, value_parser = parse_point, default_value = "0.5,0.5")]
    corner: [f64; 2],
    /// A trained model: a shipped model's name (`poisson-hard`, `console`: the `models/` directory
    /// of the repository the binary was built from, or `$AMBER_MODELS`) or a model or run
    /// directory.
    #[arg(long, conflicts_with = "size", required_unless_present = "size")]
    model: Option<String>,
    /// Instead of a model: a constant size (edge length), or a mesh file whose element sizes define
    /// a piecewise-constant field (a `size` cell array overrides them), triangles for a 2D
    /// geometry and tetrahedra for a solid: a field from a solver's error estimate, say.
    #[arg(long, allow_hyphen_values = true)]
    size: Option<String>,
    /// Generation steps (default: the model's own number).
    #[arg(long)]
    steps: Option<usize>,
    /// Aim the final mesh at this many elements (within ±10 %): the last step's predicted field
    /// keeps its shape and is scaled by one factor.
    #[arg(long)]
    elements: Option<usize>,
    /// Hold the final step's sizing field at or above this size (in the geometry's units), e.g.
    /// for an explicit solver's time step. The field bounds the elements as it sizes them: they
    /// scatter around it, and are smaller where the geometry's curvature or thin walls ask.
    #[arg(long)]
    min_size: Option<f64>,
    /// Hold the final step's sizing field at or below this size.
    #[arg(long)]
    max_size: Option<f64>,
    /// A box where 90 % of the final mesh's elements are to be no larger than SIZE (a bolt hole,
    /// a weld, where the stresses matter): `X0,Y0,X1,Y1,SIZE` in 2D, `X0,Y0,Z0,X1,Y1,Z1,SIZE` in
    /// 3D, the box's lower and upper corners. The last step's field is held at 0.85 × SIZE (2D)
    /// or 0.75 × SIZE (3D), since elements scatter around their field, on every element of the
    /// mesh before it that meets the box (so the refinement may reach one such element beyond
    /// it); --elements counts the box's elements in. May be given more than once.
    #[arg(long, value_parser = parse_refine_box, value_name = "CORNERS,SIZE", allow_hyphen_values = true)]
    refine_box: Vec<RefineBox>,
    /// A piece of the boundary where 90 % of the final mesh's elements are to be no larger than
    /// SIZE (a contact face, a hole's wall, a loaded edge): `FACE,SIZE`, FACE the number of a CAD
    /// face of a solid or of a side of a polygon, as in the written mesh's `boundary_<FACE>`
    /// groups, or the name the geometry gives a face (a physical group of a mesh file, a solid of
    /// an ASCII STL, a group of an OBJ; `--list-faces` lists them). The last step's field is held
    /// at the fraction of SIZE of --refine-box on every element of the mesh before it with a
    /// vertex on the face, a layer as deep as that mesh's elements there; --elements counts them
    /// in. May be given more than once.
    #[arg(long, value_parser = parse_refine_face, value_name = "FACE,SIZE")]
    refine_face: Vec<RefineFaceArg>,
    /// Inputs beyond the geometry, for models that read them: a Poisson problem JSON (its load,
    /// and its domain when no geometry is given; its expert mesh, when present, is the default
    /// --expert), or a part's inputs (`<stem>.inputs.json`: named numbers and points) for a model
    /// trained on a dataset folder whose parts have them.
    #[arg(long)]
    problem: Option<PathBuf>,
    /// The expert's mesh of this geometry: each step is scored against it (normalised DCD, DCD,
    /// volume difference).
    #[arg(long)]
    expert: Option<PathBuf>,
    /// Also write every step's mesh (`step<t>.vtu`) and picture (`step<t>.png`) here.
    #[arg(long)]
    every_step: Option<PathBuf>,
    /// Surfaces without CAD faces (a plain STL, a mesh without boundary groups) are split into
    /// faces at edges sharper than this many degrees, and where a flat face meets a curved one.
    #[arg(long, default_value_t = FEATURE_ANGLE_DEGREES)]
    feature_angle: f64,
    /// Refuse to build more elements than this. A model's own field is first held to the model's
    /// element budget; what --elements, the size range and the refinements ask for beyond it is
    /// capped by this.
    #[arg(long, default_value_t = 5_000_000)]
    max_elements: usize,
    /// Output: .vtu (ParaView), .msh (gmsh 4.1, one physical group per CAD face), .inp (Abaqus),
    /// .nas (NASTRAN, one skin PSHELL per CAD face), .vtk, .mesh (medit), .json, or .png (a
    /// picture coloured by element size).
    #[arg(short, long, required_unless_present = "list_faces")]
    output: Option<PathBuf>,
    /// Print the pieces of the geometry's boundary that --refine-face and the written mesh's
    /// `boundary_<FACE>` groups number (CAD faces of a solid, sides of a polygon), each with its
    /// area (length in 2D), centre and bounding box, as the model meshes the geometry; mesh nothing.
    #[arg(long)]
    list_faces: bool,
    /// Element order of the output: 1, or 2 for 10-node tetrahedra and 6-node triangles (edge
    /// nodes at the edges' midpoints; .msh, .vtu, .vtk, .nas, .inp).
    #[arg(long, default_value = "1", value_parser = crate::convert::parse_order)]
    order: ElementOrder,
}

impl MeshArgs {
    fn output(&self) -> &Path {
        self.output.as_deref().expect("clap requires --output without --list-faces")
    }
}

pub fn run(mut args: MeshArgs) -> anyhow::Result<()> {
    if args.geometries.len() > 1 {
        return run_batch(&args);
    }
    args.geometry = args.geometries.pop();
    if let (Some(geometry), Some(output)) = (&args.geometry, &args.output) {
        args.output = Some(PathBuf::from(output.to_string_lossy().replace("{stem}", &part_name(geometry))));
    }
    run_one(args)
}

/// Several geometries, each meshed as alone to the output with `{stem}` replaced; a failure is
/// reported and the rest are meshed, and the command fails if any did.
fn run_batch(args: &MeshArgs) -> anyhow::Result<()> {
    let template = args.output.as_deref().map(|o| o.to_string_lossy().into_owned()).unwrap_or_default();
    if !template.contains("{stem}") {
        bail!(
            "with {} geometries, --output needs `{{stem}}` for each one's name (`-o meshed/{{stem}}.msh`)",
            args.geometries.len()
        );
    }
    let per_part = [
        ("--expert", args.expert.is_some()),
        ("--problem", args.problem.is_some()),
        ("--every-step", args.every_step.is_some()),
        ("--list-faces", args.list_faces),
    ];
    if let Some((flag, _)) = per_part.iter().find(|(_, given)| *given) {
        bail!("{flag} belongs to one geometry: give one geometry with it");
    }
    let mut stems = BTreeSet::new();
    if let Some(twice) = args.geometries.iter().map(|g| part_name(g)).find(|stem| !stems.insert(stem.clone())) {
        bail!("two geometries have the stem `{twice}`: their meshes would overwrite each other");
    }
    let mut failed = Vec::new();
    for geometry in &args.geometries {
        let output = PathBuf::from(template.replace("{stem}", &part_name(geometry)));
        eprintln!("{geometry} → {}", output.display());
        let one =
            MeshArgs { geometries: Vec::new(), geometry: Some(geometry.clone()), output: Some(output), ..args.clone() };
        if let Err(e) = run_one(one) {
            eprintln!("{geometry}: {e:#}");
            failed.push(geometry.as_str());
        }
    }
    if !failed.is_empty() {
        bail!("{} of {} geometries failed: {}", failed.len(), args.geometries.len(), failed.join(", "));
    }
    Ok(())
}

fn run_one(args: MeshArgs) -> anyhow::Result<()> {
    // A format that cannot take the output fails now, not after the meshing.
    if let Some(output) = args.output.as_deref().filter(|o| o.extension().and_then(|e| e.to_str()) != Some("png")) {
        check_output(output, output_options(&args))?;
    }
    match &args.model {
        Some(model) => with_model(&args, model),
        None => {
            // clap's `requires` yields to `conflicts_with` between --model and --size, so the
            // flags that act on a model's rollout are checked here.
            let model_only = [
                ("--steps", args.steps.is_some()),
                ("--elements", args.elements.is_some()),
                ("--min-size", args.min_size.is_some()),
                ("--max-size", args.max_size.is_some()),
                ("--refine-box", !args.refine_box.is_empty()),
                ("--refine-face", !args.refine_face.is_empty()),
                ("--list-faces", args.list_faces),
                ("--problem", args.problem.is_some()),
                ("--expert", args.expert.is_some()),
                ("--every-step", args.every_step.is_some()),
            ];
            if let Some((flag, _)) = model_only.iter().find(|(_, given)| *given) {
                bail!("{flag} needs --model: with --size the sizes are given, not predicted");
            }
            with_size(&args, args.size.as_deref().expect("clap requires --size without --model"))
        }
    }
}

/// `--model`: the model's task decides what the geometry becomes.
fn with_model(args: &MeshArgs, model: &str) -> anyhow::Result<()> {
    let dir = resolve_model(model, &shipped_models())?;
    let card = ModelCard::read(&dir)?;
    let mut trained = TrainedModel::load(&dir).with_context(|| format!("{}: cannot load the model", dir.display()))?;
    // A user's geometry is meshed whatever the field asks for: over the budget, it is scaled to it.
    trained.limits_mut().scale_to_budget = true;
    let steps = args.steps.unwrap_or(card.inference_steps);
    if steps == 0 {
        bail!("--steps must be at least 1");
    }
    match card.task {
        Task::Poisson => {
            let problem = args.problem.as_deref().with_context(|| {
                format!("the model `{model}` reads the load f of a Poisson problem: give it with --problem FILE.json")
            })?;
            let (mut part, file_expert) = read_part(problem)?;
            if args.geometry.is_some() {
                part = PoissonPart::new(planar_domain(args)?, part.load, None, part.quadrature_order)?;
            }
            let expert = match &args.expert {
                Some(path) => Some((read_mesh::<2>(path)?, path.clone())),
                None if args.geometry.is_none() => file_expert.map(|mesh| (mesh, problem.to_path_buf())),
                None => None,
            };
            mesh_domain(args, &trained, part, expert, steps)
        }
        Task::Console | Task::Folder { dimension: 3 } => {
            let geometry = args
                .geometry
                .as_deref()
                .context("give the geometry to mesh: a closed STL, a STEP file or a tet mesh")?;
            let path = Path::new(geometry);
            let surface = read_solid_surface(path, args.feature_angle, card.initial_size)?;
            let mut part = SolidPart::new(part_name(geometry), surface, card.initial_size)
                .with_context(|| initial_mesh_failed(geometry, card.initial_size))?;
            check_initial_mesh(&part.initial_mesh, card.initial_size);
            part.inputs = part_inputs(args)?;
            let expert = args.expert.as_ref().map(|p| read_mesh::<3>(p).map(|m| (m, p.clone()))).transpose()?;
            mesh_domain(args, &trained, part, expert, steps)
        }
        Task::Folder { dimension: 2 } => {
            let geometry = args.geometry.as_deref().unwrap_or("lshape");
            let mut part = PlanarPart::new(part_name(geometry), planar_domain(args)?, card.initial_size)
                .with_context(|| initial_mesh_failed(geometry, card.initial_size))?;
            check_initial_mesh(&part.initial_mesh, card.initial_size);
            part.inputs = part_inputs(args)?;
            let expert = args.expert.as_ref().map(|p| read_mesh::<2>(p).map(|m| (m, p.clone()))).transpose()?;
            mesh_domain(args, &trained, part, expert, steps)
        }
        Task::Folder { dimension } => {
            bail!("{}: a model of {dimension}D meshes; amber meshes 2D and 3D", dir.display())
        }
    }
}

/// The part's own inputs of `--problem` (none without it).
fn part_inputs<const D: usize>(args: &MeshArgs) -> anyhow::Result<PartInputs<D>> {
    Ok(args.problem.as_deref().map(PartInputs::read).transpose()?.unwrap_or_default())
}

/// M⁰'s median element size below this fraction of the model's initial size h0 says that the
/// part is far smaller than the parts the model learned from (theirs have medians near 0.8 h0): most
/// likely it is in other units.
const SMALL_INITIAL_MESH: f64 = 0.25;

/// Why M⁰ of `geometry` may have failed, the part being in other units than the model's.
fn initial_mesh_failed(geometry: &str, initial_size: f64) -> String {
    format!(
        "{geometry}: cannot mesh the initial mesh M⁰ at the model's initial size {initial_size} \
         (is the geometry in the units of the model's training parts?)"
    )
}

/// Says how many elements M⁰ has and how large, with a warning when they are much smaller than
/// the model's initial size.
fn check_initial_mesh<const D: usize>(initial_mesh: &Mesh<D>, initial_size: f64) {
    let mut sizes = initial_mesh.sizes();
    sizes.sort_by(f64::total_cmp);
    let median = quantile(&sizes, 0.5);
    eprintln!(
        "M⁰: {} elements of median size {median:.4} at the model's initial size {initial_size}",
        initial_mesh.num_elements()
    );
    if median < SMALL_INITIAL_MESH * initial_size {
        eprintln!(
            "warning: the part is small for this model: M⁰'s elements are {:.1e} of the model's initial size. Is \
             the geometry in the units of the model's training parts?",
            median / initial_size
        );
    }
}

/// What reports call a part: the geometry file's stem.
fn part_name(geometry: &str) -> String {
    Path::new(geometry).file_stem().map_or_else(|| geometry.to_owned(), |s| s.to_string_lossy().into_owned())
}

/// Where shipped models are: `$AMBER_MODELS`, else the `models/` directory of the repository the
/// binary was built from.
pub(crate) fn shipped_models() -> PathBuf {
    std::env::var_os("AMBER_MODELS")
        .map_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models"), PathBuf::from)
}

/// Rolls the model out on `domain`, scores each step against `expert` when there is one, and
/// writes the outputs.
fn mesh_domain<const D: usize, P: Domain<D>>(
    args: &MeshArgs,
    model: &TrainedModel,
    domain: P,
    expert: Option<(Mesh<D>, PathBuf)>,
    steps: usize,
) -> anyhow::Result<()>
where
    Mesh<D>: Picture,
{
    if args.list_faces {
        print_faces(&domain);
        return Ok(());
    }
    let start = Instant::now();
    let mut bounds = SizeBounds::new(args.min_size, args.max_size)
        .map_err(|e| anyhow::anyhow!("--min-size/--max-size: {e}"))?
        .with_max_elements(args.max_elements);
    for refine in &args.refine_box {
        if refine.lo.len() != D {
            anyhow::bail!("--refine-box: a box of {} dimensions for a {D}D geometry", refine.lo.len());
        }
        bounds = bounds.with_box(refine.clone()).map_err(|e| anyhow::anyhow!("--refine-box: {e}"))?;
    }
    if !args.refine_face.is_empty() {
        let faces: BTreeSet<i32> = domain.boundary_tags(domain.initial_mesh()).into_values().collect();
        let names = domain.boundary_names();
        for refine in &args.refine_face {
            let face = match &refine.face {
                FaceArg::Number(face) => *face,
                FaceArg::Name(name) => match names.iter().find(|(_, n)| *n == name) {
                    Some((&face, _)) => face,
                    None if names.is_empty() => anyhow::bail!(
                        "--refine-face: the geometry names no faces, so `{name}` must be a face number; its faces \
                         are {}",
                        face_list(&faces)
                    ),
                    None => anyhow::bail!(
                        "--refine-face: the geometry has no face named `{name}`; its named faces are {}",
                        names.values().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
                    ),
                },
            };
            if !faces.contains(&face) {
                anyhow::bail!("--refine-face: the geometry has no face {face}; its faces are {}", face_list(&faces));
            }
            bounds = bounds
                .with_face(RefineFace { face, max_size: refine.max_size })
                .map_err(|e| anyhow::anyhow!("--refine-face: {e}"))?;
        }
    }
    let generated =
        model.generate(&domain, steps, FinalStep { elements: args.elements, bounds }).map_err(|e| match e {
            TrainError::MissingInputs(_) => {
                anyhow::anyhow!("{e}: give the part's inputs with --problem FILE.inputs.json")
            }
            TrainError::OverCap { .. } => {
                anyhow::anyhow!("{e} (--max-elements): raise it, or ask for fewer or larger elements")
            }
            e => e.into(),
        })?;
    let seconds = start.elapsed().as_secs_f64();
    let last = &generated.last().expect("at least one step").mesh;
    // The boundary grouped by CAD face, for a solver's boundary conditions.
    let facet_tags = domain.boundary_tags(last);
    let (facet_names, domain_name) = (domain.boundary_names(), domain.domain_name());
    let scored = expert.map(|(mesh, path)| WithExpert::new(domain, mesh, &path)).transpose()?;
    let reference = scored.as_ref().map(|p| Reference::new(p, model.limits())).transpose()?;
    let metrics: Vec<Option<MeshMetrics>> = generated
        .iter()
        .map(|step| match (&scored, &reference) {
            (Some(p), Some(r)) => MeshMetrics::of(&step.mesh, &p.expert_mesh, r).map(Some),
            _ => Ok(None),
        })
        .collect::<Result<_, _>>()?;
    if let Some(dir) = &args.every_step {
        write_steps(dir, &generated)?;
    }
    // Where the final mesh is coarser (> 0) or finer than the expert's, for a viewer.
    let log_ratios = scored.as_ref().map(|p| log_size_ratios(last, &p.expert_mesh));
    let mut data = MeshData { facet_tags, facet_names, domain_name, ..MeshData::new() };
    if let Some(ratios) = &log_ratios {
        data = data.with_cell("log_size_ratio_to_expert", ratios.clone());
    }
    write_output(last, args, data)?;
    for (t, (step, metrics)) in generated.iter().zip(&metrics).enumerate() {
        let score = metrics.map_or(String::new(), |m| {
            format!(
                ", normalised DCD {:.3}, DCD {:.4}, volume difference {:.3e}",
                m.normalised_dcd, m.dcd, m.volume_difference
            )
        });
        eprintln!("step {}: {} elements{score}", t + 1, step.mesh.num_elements());
    }
    if let (Some(p), Some(r)) = (&scored, &reference) {
        eprintln!(
            "expert: {} elements; normalised by d(M⁰) {:.4} and d(M̂) {:.4}",
            p.expert_mesh.num_elements(),
            r.initial_dcd,
            r.reconstruction_dcd
        );
    }
    if let Some(ratios) = &log_ratios {
        let s = SizeRatios::of(ratios);
        eprintln!(
            "final element sizes ÷ the expert's where they lie: median {:.2} (10 % below {:.2}, 10 % above {:.2}); \
             field `log_size_ratio_to_expert` in the output",
            s.median, s.p10, s.p90
        );
    }
    eprintln!("{steps} steps in {seconds:.2} s; wrote {}", args.output().display());
    Ok(())
}

/// Each step's mesh as `step<t>.vtu` (element sizes) and `step<t>.png`, on one colour scale.
fn write_steps<const D: usize>(dir: &Path, steps: &[GeneratedStep<D>]) -> anyhow::Result<()>
where
    Mesh<D>: Picture,
{
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let range =
        steps.iter().flat_map(|s| s.mesh.sizes()).fold((f64::INFINITY, 0.0f64), |(lo, hi), h| (lo.min(h), hi.max(h)));
    for (t, step) in steps.iter().enumerate() {
        let sizes = step.mesh.sizes();
        write_mesh(
            &step.mesh,
            dir.join(format!("step{}.vtu", t + 1)),
            &MeshData::new().with_cell("size", sizes.clone()),
        )?;
        let title = format!("step {}: {} elements", t + 1, step.mesh.num_elements());
        let options = RenderOptions { title: Some(title), log_scale: true, range: Some(range), ..Default::default() };
        step.mesh.picture(&sizes, &options, &dir.join(format!("step{}.png", t + 1)))?;
    }
    Ok(())
}

/// The viewpoint of pictures of 3D meshes.
const VIEW: View = View { azimuth_deg: 35.0, elevation_deg: 30.0 };

/// A picture of a mesh coloured by per-element values: the mesh itself in 2D, its boundary
/// surface in 3D; alone, or as a tile of a gallery.
pub(crate) trait Picture {
    fn picture(&self, values: &[f64], options: &RenderOptions, path: &Path) -> anyhow::Result<()>;
    fn tile_mesh(&self) -> TileMesh<'_>;
}

impl Picture for Mesh2 {
    fn picture(&self, values: &[f64], options: &RenderOptions, path: &Path) -> anyhow::Result<()> {
        Ok(render_png(self, values, options, path)?)
    }

    fn tile_mesh(&self) -> TileMesh<'_> {
        TileMesh::Flat(self)
    }
}

impl Picture for Mesh3 {
    fn picture(&self, values: &[f64], options: &RenderOptions, path: &Path) -> anyhow::Result<()> {
        Ok(render_surface_png(self, values, options, VIEW, path)?)
    }

    fn tile_mesh(&self) -> TileMesh<'_> {
        TileMesh::Solid(self, VIEW)
    }
}

/// Elements whose smallest angle (2D) or dihedral angle (3D) is below this many degrees are
/// reported: a solver's stiffness matrix degrades with them, and some solvers refuse them.
const DEGENERATE_ANGLE_DEGREES: f64 = 5.0;

/// The smallest angle of `mesh` (dihedral in 3D) and how many elements have one below
/// [`DEGENERATE_ANGLE_DEGREES`].
fn degenerate_elements<const D: usize>(mesh: &Mesh<D>) -> (f64, usize) {
    let angles = mesh.min_angles();
    let smallest = angles.iter().copied().fold(f64::INFINITY, f64::min);
    (smallest, angles.iter().filter(|&&a| a < DEGENERATE_ANGLE_DEGREES).count())
}

/// Writes `mesh` to `--output` by extension, in `--order`, with its element sizes added to `data`
/// (fields and facet tags); `.png` is a picture. Says how well shaped the mesh is, with a warning
/// when elements are nearly degenerate.
fn write_output<const D: usize>(mesh: &Mesh<D>, args: &MeshArgs, data: MeshData) -> anyhow::Result<()>
where
    Mesh<D>: Picture,
{
    let (smallest, degenerate) = degenerate_elements(mesh);
    let angle = if D == 2 { "angle" } else { "dihedral angle" };
    let sizes = mesh.sizes();
    let mut sorted = sizes.clone();
    sorted.sort_by(f64::total_cmp);
    let at = |q| quantile(&sorted, q);
    eprintln!(
        "element sizes from {:.4} (1 % below {:.4}) to {:.4}, median {:.4}; smallest {angle} {smallest:.1}°",
        at(0.0),
        at(0.01),
        at(1.0),
        at(0.5)
    );
    if degenerate > 0 {
        eprintln!(
            "warning: {degenerate} of {} elements are nearly degenerate, their smallest {angle} below {DEGENERATE_ANGLE_DEGREES}°",
            mesh.num_elements()
        );
    }
    let output = args.output();
    match output.extension().and_then(|e| e.to_str()) {
        Some("png") => {
            let options = RenderOptions { title: Some("element size h".into()), log_scale: true, ..Default::default() };
            mesh.picture(&sizes, &options, output)
        }
        _ => Ok(write_mesh_as(mesh, output, &data.with_cell("size", sizes), output_options(args))?),
    }
}

/// How the output mesh is written: in `--order`, each format's default encoding.
fn output_options(args: &MeshArgs) -> WriteOptions {
    WriteOptions { order: args.order, ..WriteOptions::default() }
}

/// `--size`: a geometry meshed from a given field, a constant or a mesh file's sizes.
fn with_size(args: &MeshArgs, size: &str) -> anyhow::Result<()> {
    let geometry = args.geometry.as_deref().unwrap_or("lshape");
    let start = Instant::now();
    let solid = is_solid(geometry);
    let (elements, report) = if solid {
        match size.parse::<f64>() {
            Ok(h) => mesh_solid_with(args, geometry, &ConstantSize(h), h).map(|(m, r)| (m.num_elements(), r))?,
            Err(_) => {
                let (field_mesh, sizes) = read_sizing_mesh::<3>(Path::new(size))?;
                let typical_size = median(&sizes);
                let (mesh, report) =
                    mesh_solid_with(args, geometry, &MeshSizing::new(&field_mesh, sizes), typical_size)?;
                warn_outside_field(&field_mesh, &mesh, size);
                (mesh.num_elements(), report)
            }
        }
    } else {
        let domain = planar_domain(args)?;
        match size.parse::<f64>() {
            Ok(h) => mesh_planar_with(args, &domain, &ConstantSize(h)).map(|(m, r)| (m.num_elements(), r))?,
            Err(_) => {
                let (field_mesh, sizes) = read_sizing_mesh::<2>(Path::new(size))?;
                let (mesh, report) = mesh_planar_with(args, &domain, &MeshSizing::new(&field_mesh, sizes))?;
                warn_outside_field(&field_mesh, &mesh, size);
                (mesh.num_elements(), report)
            }
        }
    };
    eprintln!(
        "{elements} {} in {:.3} s; size ratio median {:.3} (p10 {:.3}, p90 {:.3}); mean smallest {} {:.1}°; wrote {}",
        if solid { "tetrahedra" } else { "triangles" },
        start.elapsed().as_secs_f64(),
        report.size_ratio_median,
        report.size_ratio_p10,
        report.size_ratio_p90,
        if solid { "dihedral angle" } else { "angle" },
        report.mean_min_angle,
        args.output().display()
    );
    Ok(())
}

/// Meshes the solid `geometry` (a CAD file tessellated at about `typical_size`) to `field` and
/// writes it: the mesh and how its sizes follow the field.
fn mesh_solid_with(
    args: &MeshArgs,
    geometry: &str,
    field: &impl SizingField<3>,
    typical_size: f64,
) -> anyhow::Result<(Mesh3, QualityReport)> {
    let surface = read_solid_surface(Path::new(geometry), args.feature_angle, typical_size)?;
    let params = Mesh3dParams::default().with_max_elements(args.max_elements);
    let mesh = generate_3d(&surface, field, &params).context("mesh generation failed")?;
    let facet_tags = cad_face_tags(&SurfaceDistance::new(&surface), &mesh);
    let (facet_names, domain_name) = (surface.face_names().clone(), surface.solid_name().map(str::to_owned));
    write_output(&mesh, args, MeshData { facet_tags, facet_names, domain_name, ..MeshData::new() })?;
    let report = QualityReport::measure(&mesh, field);
    Ok((mesh, report))
}

/// Meshes the polygon `domain` to `field` and writes it, as [`mesh_solid_with`].
fn mesh_planar_with(
    args: &MeshArgs,
    domain: &PolygonDomain,
    field: &impl SizingField<2>,
) -> anyhow::Result<(Mesh2, QualityReport)> {
    let params = Mesh2dParams::default().with_max_elements(args.max_elements);
    let mesh = generate_2d(domain, field, &params).context("mesh generation failed")?;
    let facet_tags = polygon_side_tags(&PolygonDistance::new(domain), &mesh);
    write_output(&mesh, args, MeshData { facet_tags, ..MeshData::new() })?;
    let report = QualityReport::measure(&mesh, field);
    Ok((mesh, report))
}

/// Warns when more than 1 % of the vertices of `mesh` lie outside the bounding box of the mesh
/// that gave its sizes (grown by 1 % of its diagonal): there the field is its nearest element's,
/// and a field mesh of another part or in other units goes unnoticed otherwise.
fn warn_outside_field<const D: usize>(field_mesh: &Mesh<D>, mesh: &Mesh<D>, field_path: &str) {
    let Some((lo, hi)) = field_mesh.bounding_box() else { return };
    let margin = 0.01 * (0..D).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let outside = mesh.vertices().iter().filter(|p| (0..D).any(|k| p[k] < lo[k] - margin || p[k] > hi[k] + margin));
    let share = outside.count() as f64 / mesh.num_vertices().max(1) as f64;
    if share > 0.01 {
        eprintln!(
            "warning: {:.0} % of the mesh lies outside the box of the field mesh {field_path}, where each size is its \
             nearest element's: is the field of this geometry, in its units?",
            100.0 * share
        );
    }
}

/// Whether `geometry` names a solid: a surface file, or a mesh file holding tetrahedra.
fn is_solid(geometry: &str) -> bool {
    let path = Path::new(geometry);
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    matches!(extension.as_deref(), Some("stl" | "obj"))
        || is_cad(path)
        || matches!(read_any_mesh(path), Ok(AnyMesh::Three(..)))
}

fn parse_refine_box(text: &str) -> Result<RefineBox, String> {
    match text.split(',').map(str::trim).map(str::parse::<f64>).collect::<Result<Vec<_>, _>>() {
        Ok(v) if v.len() == 5 || v.len() == 7 => {
            let dim = (v.len() - 1) / 2;
            Ok(RefineBox { lo: v[..dim].to_vec(), hi: v[dim..2 * dim].to_vec(), max_size: v[2 * dim] })
        }
        _ => Err(format!(
            "expected X0,Y0,X1,Y1,SIZE (2D) or X0,Y0,Z0,X1,Y1,Z1,SIZE (3D), comma-separated numbers, got `{text}`"
        )),
    }
}

/// Prints each piece of `domain`'s boundary (its tag, as M⁰'s boundary facets carry it) with its
/// area (length in 2D), centre and bounding box, on standard output.
fn print_faces<const D: usize, P: Domain<D>>(domain: &P) {
    /// A face's measure, measure-weighted sum of facet centroids, and corners of its box.
    struct Face<const D: usize> {
        measure: f64,
        weighted: [f64; D],
        lo: [f64; D],
        hi: [f64; D],
    }
    let mesh = domain.initial_mesh();
    let mut faces: BTreeMap<i32, Face<D>> = BTreeMap::new();
    for (facet, tag) in domain.boundary_tags(mesh) {
        let corners: Vec<[f64; D]> = facet.iter().map(|&v| mesh.vertices()[v as usize]).collect();
        let measure = simplex_measure(&corners);
        let face = faces.entry(tag).or_insert(Face {
            measure: 0.0,
            weighted: [0.0; D],
            lo: [f64::INFINITY; D],
            hi: [f64::NEG_INFINITY; D],
        });
        face.measure += measure;
        for p in &corners {
            for (k, &x) in p.iter().enumerate() {
                face.weighted[k] += measure * x / corners.len() as f64;
                face.lo[k] = face.lo[k].min(x);
                face.hi[k] = face.hi[k].max(x);
            }
        }
    }
    if faces.is_empty() {
        println!("the boundary is one piece: no faces to refine");
        return;
    }
    let what = if D == 3 { "area" } else { "length" };
    let point = |p: [f64; D]| p.map(|x| format!("{x:.4}")).join(", ");
    let names = domain.boundary_names();
    for (tag, face) in faces {
        let centre = face.weighted.map(|x| x / face.measure);
        let name = names.get(&tag).map_or(String::new(), |name| format!(" `{name}`"));
        println!(
            "face {tag}{name}: {what} {:.4}, centre ({}), box ({}) to ({})",
            face.measure,
            point(centre),
            point(face.lo),
            point(face.hi)
        );
    }
}

/// The length of a segment (2 corners) or the area of a triangle (3 corners).
fn simplex_measure<const D: usize>(corners: &[[f64; D]]) -> f64 {
    let edge =
        |a: [f64; D], b: [f64; D]| -> [f64; 3] { std::array::from_fn(|k| if k < D { b[k] - a[k] } else { 0.0 }) };
    let u = edge(corners[0], corners[1]);
    match corners.len() {
        2 => u.iter().map(|x| x * x).sum::<f64>().sqrt(),
        _ => {
            let v = edge(corners[0], corners[2]);
            let cross = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            0.5 * cross.iter().map(|x| x * x).sum::<f64>().sqrt()
        }
    }
}

/// A face of `--refine-face`: its number, or the name the geometry gives it.
#[derive(Clone, Debug, PartialEq)]
enum FaceArg {
    Number(i32),
    Name(String),
}

/// `--refine-face FACE,SIZE` before its face is looked up in the geometry.
#[derive(Clone, Debug, PartialEq)]
struct RefineFaceArg {
    face: FaceArg,
    max_size: f64,
}

fn parse_refine_face(text: &str) -> Result<RefineFaceArg, String> {
    // The size comes last, so that a face name may hold commas.
    match text.rsplit_once(',').map(|(face, size)| (face.trim(), size.trim().parse::<f64>())) {
        Some((face, Ok(max_size))) if !face.is_empty() => {
            let face = face.parse().map_or_else(|_| FaceArg::Name(face.to_owned()), FaceArg::Number);
            Ok(RefineFaceArg { face, max_size })
        }
        _ => {
            Err(format!("expected FACE,SIZE (a face number or name and a size, like 3,0.5 or inlet,0.5), got `{text}`"))
        }
    }
}

/// `faces` for a message: `none (the boundary is one piece)`, or the numbers, runs shortened to
/// `first–last`.
fn face_list(faces: &BTreeSet<i32>) -> String {
    if faces.is_empty() {
        return "none (the boundary is one piece)".into();
    }
    let mut runs: Vec<(i32, i32)> = Vec::new();
    for &face in faces {
        match runs.last_mut() {
            Some((_, last)) if *last + 1 == face => *last = face,
            _ => runs.push((face, face)),
        }
    }
    let runs: Vec<String> =
        runs.iter().map(|&(a, b)| if a == b { a.to_string() } else { format!("{a}–{b}") }).collect();
    runs.join(", ")
}

fn parse_point(text: &str) -> Result<[f64; 2], String> {
    match text.split(',').map(str::trim).map(str::parse::<f64>).collect::<Result<Vec<_>, _>>() {
        Ok(v) if v.len() == 2 => Ok([v[0], v[1]]),
        _ => Err(format!("expected two comma-separated numbers like 0.5,0.5, got `{text}`")),
    }
}

/// The 2D geometry argument as a domain (the L-shape when none is given).
fn planar_domain(args: &MeshArgs) -> anyhow::Result<PolygonDomain> {
    Ok(match args.geometry.as_deref().unwrap_or("lshape") {
        "lshape" => PolygonDomain::lshape(args.corner)?,
        "square" => PolygonDomain::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![])?,
        path => read_polygon_domain(Path::new(path))?,
    })
}

fn read_sizing_mesh<const D: usize>(path: &Path) -> anyhow::Result<(Mesh<D>, Vec<f64>)> {
    let (mesh, data) = read_mesh_with_data::<D>(path)
        .with_context(|| format!("--size {}: neither a number nor a readable {D}D mesh", path.display()))?;
    let sizes = data.cell.get("size").cloned().unwrap_or_else(|| mesh.sizes());
    if sizes.len() != mesh.num_elements() {
        bail!(
            "{}: the `size` cell array has {} values for {} elements",
            path.display(),
            sizes.len(),
            mesh.num_elements()
        );
    }
    Ok((mesh, sizes))
}

#[cfg(test)]
mod tests {
    use amber_mesh::Mesh2;

    use super::*;

    #[test]
    fn facets_measure_their_length_or_area() {
        assert_eq!(simplex_measure(&[[0.0, 0.0], [3.0, 4.0]]), 5.0);
        assert_eq!(simplex_measure(&[[1.0, 0.0, 0.0], [1.0, 2.0, 0.0], [1.0, 0.0, 3.0]]), 3.0);
    }

    #[test]
    fn slivers_are_counted_as_degenerate() {
        // A right triangle (45°) and an isosceles sliver with base angles of 1°.
        let sliver = [[3.0, 0.0], [5.0, 0.0], [4.0, 1.0f64.to_radians().tan()]];
        let vertices = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]].into_iter().chain(sliver).collect();
        let mesh = Mesh2::new(vertices, vec![0, 1, 2, 3, 4, 5]).unwrap();
        let (smallest, degenerate) = degenerate_elements(&mesh);
        assert!((smallest - 1.0).abs() < 1e-9 && degenerate == 1, "{smallest}° {degenerate}");
    }
}
