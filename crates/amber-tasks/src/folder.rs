//! A dataset is a folder of expert meshes: what a team that adopts AMBER has, and what both paper
//! tasks' real data (Console) is an instance of.
//!
//! ```text
//! DIR/dataset.json                       optional: settings a folder cannot say (DatasetSettings)
//! DIR/train/<stem>.<mesh>                one expert mesh per part, any format amber reads
//! DIR/train/<stem>.stl|.obj|.json        optional geometry beside it (3D surface, 2D polygon)
//! DIR/train/<stem>.step|.stp|.iges|.igs|.brep   or its CAD file (3D, read through gmsh)
//! DIR/train/<stem>.inputs.json           optional inputs of the part (named scalars and points)
//! DIR/val/…  [DIR/test/…]
//! DIR/reference_surface/<split>/<stem>.stl|.obj|.json   the geometry, when not beside the mesh
//! ```
//!
//! A file is an expert mesh when `amber_mesh::read_mesh` reads its extension (a `.json` beside a
//! mesh of the same stem is that mesh's polygon instead); other files (notes) are ignored. A
//! surface, beside the mesh or under `reference_surface/`, is preferred to a CAD file, which
//! gmsh tessellates at every read (a second or two per part). A part's inputs ([`PartInputs`]) are node inputs a model may read; every part of a
//! dataset has the same names or none. The dimension comes from the files (tets: 3D, triangles: 2D). Without a geometry
//! file, the expert mesh's own boundary is the geometry. A part is a [`FolderDomain`]:
//! [`SolidPart`] in 3D, [`PlanarPart`] in 2D, with M⁰ a uniform mesh of one size for the whole
//! dataset.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use amber_mesh::{MESH_FORMATS, Mesh, MeshData, MeshError, read_mesh, read_mesh_with_data};
use amber_stdx::{median, read_json};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::TaskError;
use crate::cad::CAD_EXTENSIONS;
use crate::expert::extent_mismatch;
use crate::part::{
    FEATURE_ANGLE_DEGREES, PART_INPUTS_SUFFIX, PartInputs, PlanarPart, SolidPart, polygon_domain_of_mesh,
    read_polygon_domain, read_solid_surface, solid_surface_of_mesh,
};
use crate::problem::{Domain, WithExpert};

/// The optional settings file in a dataset's root.
pub const SETTINGS_FILE: &str = "dataset.json";

/// The folder of geometry files beside the splits (the layout of the AMBER authors' Console
/// bundle): `<GEOMETRY_DIR>/<split>/<stem>.stl`.
pub const GEOMETRY_DIR: &str = "reference_surface";

/// The default M⁰ size is this many times the median element size of the training experts: M⁰
/// must be coarser than the expert almost everywhere (the network learns to refine, and the
/// normalised DCD measures progress from M⁰), yet fine enough to resolve the part's shape. On
/// Console's 15 paper training parts (median expert size 1.23 mm) the rule gives 4.92 mm, near
/// the spec's h₀ = 4.3955 mm, which the Console experiment passes explicitly.
pub const INITIAL_SIZE_FACTOR: f64 = 4.0;

/// A split of a dataset folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    Train,
    Val,
    Test,
}

impl Split {
    /// The directory name (`train`, `val`, `test`).
    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Val => "val",
            Split::Test => "test",
        }
    }

    /// The directory of this split in the dataset `root`.
    pub fn dir(self, root: &Path) -> PathBuf {
        root.join(self.name())
    }
}

/// Fold `index` of a `count`-fold cross-validation over a split's parts in name order: part i
/// is held out by fold i mod `count`, so that the held-out parts of a fold spread over the split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fold {
    pub index: usize,
    pub count: usize,
}

impl Fold {
    /// The `count` folds over `parts` parts, or why there are none: every fold must hold out a
    /// part and train on another.
    pub fn all(count: usize, parts: usize) -> Result<Vec<Fold>, String> {
        if count < 2 || count > parts {
            return Err(format!(
                "{count} folds: a cross-validation over {parts} training parts takes 2 to {parts} folds"
            ));
        }
        Ok((0..count).map(|index| Fold { index, count }).collect())
    }

    /// Whether this fold holds out the part at `index` in name order (and does not train on it).
    pub fn holds_out(self, index: usize) -> bool {
        index % self.count == self.index
    }

    /// The parts of a split in name order, parted into those this fold trains on and those it
    /// holds out.
    pub fn split<T>(self, parts: Vec<T>) -> (Vec<T>, Vec<T>) {
        let (held_out, trained): (Vec<_>, Vec<_>) =
            parts.into_iter().enumerate().partition(|(i, _)| self.holds_out(*i));
        let strip = |parts: Vec<(usize, T)>| parts.into_iter().map(|(_, part)| part).collect();
        (strip(trained), strip(held_out))
    }
}

/// What `dataset.json` may set; every field is optional.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatasetSettings {
    /// Edge length of the uniform M⁰ of every part, in the meshes' units (default:
    /// [`INITIAL_SIZE_FACTOR`] × the median training expert element size).
    pub initial_size: Option<f64>,
    /// Surfaces without CAD faces (a plain STL, a mesh boundary) are split into faces at edges
    /// sharper than this many degrees (default [`FEATURE_ANGLE_DEGREES`]).
    pub feature_angle: Option<f64>,
}

impl DatasetSettings {
    /// The settings of the dataset in `root`: its `dataset.json`, or the defaults without one.
    pub fn read(root: &Path) -> Result<Self, TaskError> {
        let path = root.join(SETTINGS_FILE);
        if !path.is_file() {
            return Ok(Self::default());
        }
        let settings: Self =
            read_json(&path).map_err(|e| TaskError::Dataset { path: path.clone(), message: e.to_string() })?;
        let positive = |value: Option<f64>| value.is_none_or(|v| v.is_finite() && v > 0.0);
        if !positive(settings.initial_size) || !positive(settings.feature_angle) {
            return Err(TaskError::Dataset { path, message: "initial_size and feature_angle must be positive".into() });
        }
        Ok(settings)
    }

    /// The feature angle in degrees.
    pub fn feature_angle(&self) -> f64 {
        self.feature_angle.unwrap_or(FEATURE_ANGLE_DEGREES)
    }
}

/// One part of a split as read: its expert mesh and where its geometry is, if anywhere.
#[derive(Clone, Debug)]
pub struct Expert<const D: usize> {
    /// `split/stem`, e.g. `train/001`.
    pub name: String,
    /// The expert mesh's file.
    pub path: PathBuf,
    pub mesh: Mesh<D>,
    /// The expert file's facet tags (physical groups, skin properties): the faces of a solid's
    /// boundary when it has no geometry file.
    pub facet_tags: BTreeMap<Vec<u32>, i32>,
    /// The geometry file (beside the mesh or under [`GEOMETRY_DIR`]); `None`: the mesh's boundary.
    pub geometry: Option<PathBuf>,
    /// The part's inputs file (`<stem>.inputs.json` beside the mesh or under [`GEOMETRY_DIR`]).
    pub inputs: Option<PathBuf>,
}

impl<const D: usize> Expert<D> {
    /// The part's inputs: its inputs file's, or none without one.
    fn read_inputs(&self) -> Result<PartInputs<D>, TaskError> {
        self.inputs.as_deref().map_or_else(|| Ok(PartInputs::default()), PartInputs::read)
    }
}

/// The extensions of the geometry files of a `D`-dimensional part, in order of preference:
/// surfaces, then CAD files in 3D; polygons in 2D.
fn geometry_extensions(dimension: usize) -> &'static [&'static [&'static str]] {
    if dimension == 3 { &[&["stl", "obj"], &CAD_EXTENSIONS] } else { &[&["json"]] }
}

fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default()
}

/// The candidate expert meshes of the split directory `dir`, by stem (sorted): every file but
/// surfaces, and a `.json` only when its stem has no other candidate. Surfaces and polygons
/// beside the mesh are kept per stem for [`find_geometry`]. An absent or empty directory is an
/// error naming it.
fn part_files(dir: &Path) -> Result<BTreeMap<String, Vec<PathBuf>>, TaskError> {
    if !dir.is_dir() {
        return Err(TaskError::Dataset { path: dir.into(), message: "split directory not found".into() });
    }
    let io = |source| TaskError::Io { path: dir.into(), source };
    let mut by_stem: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        if path.to_str().is_some_and(|p| p.ends_with(PART_INPUTS_SUFFIX)) {
            continue;
        }
        if let (true, Some(stem)) = (path.is_file(), path.file_stem().and_then(|s| s.to_str())) {
            by_stem.entry(stem.to_owned()).or_default().push(path);
        }
    }
    by_stem.values_mut().for_each(|files| files.sort());
    Ok(by_stem)
}

/// Reads the expert mesh among `files` (one stem's files): the file `read_mesh` reads, a `.json`
/// only when no other file is a mesh. `Ok(None)`: no file of the stem is a mesh.
fn read_part_mesh<const D: usize>(files: &[PathBuf]) -> Result<Option<(PathBuf, Mesh<D>, MeshData)>, TaskError> {
    let (json, others): (Vec<&PathBuf>, Vec<&PathBuf>) = files.iter().partition(|p| extension(p) == "json");
    let mut found: Option<(PathBuf, Mesh<D>, MeshData)> = None;
    for path in others.into_iter().chain(json) {
        if found.is_some() && extension(path) == "json" {
            continue;
        }
        let (mesh, data) = match read_mesh_with_data::<D>(path) {
            Ok(read) => read,
            Err(MeshError::UnsupportedFormat { .. }) => continue,
            Err(MeshError::DimensionMismatch { found: other, .. }) => {
                return Err(TaskError::Dataset {
                    path: path.clone(),
                    message: format!("holds a {other}D mesh, but the dataset is {D}D: mixed dimensions"),
                });
            }
            Err(e) => return Err(TaskError::ExpertMesh(e)),
        };
        if let Some((first, ..)) = &found {
            return Err(TaskError::Dataset {
                path: path.clone(),
                message: format!("a second expert mesh of the part (the first is {})", first.display()),
            });
        }
        found = Some((path.clone(), mesh, data));
    }
    Ok(found)
}

/// The geometry file of part `stem` of the split `dir`: beside the mesh, else under
/// `<root>/reference_surface/<split>/`.
fn find_geometry(dir: &Path, stem: &str, files: &[PathBuf], mesh: &Path, dimension: usize) -> Option<PathBuf> {
    let (root, split) = (dir.parent()?, dir.file_name()?);
    geometry_extensions(dimension).iter().find_map(|extensions| {
        let beside = files.iter().find(|p| p.as_path() != mesh && extensions.contains(&extension(p).as_str()));
        beside.cloned().or_else(|| {
            extensions
                .iter()
                .map(|e| root.join(GEOMETRY_DIR).join(split).join(format!("{stem}.{e}")))
                .find(|p| p.is_file())
        })
    })
}

/// The inputs file of part `stem` of the split `dir`: beside the mesh, else under
/// `<root>/reference_surface/<split>/`.
fn find_inputs(dir: &Path, stem: &str) -> Option<PathBuf> {
    let name = format!("{stem}{PART_INPUTS_SUFFIX}");
    let beside = dir.join(&name);
    if beside.is_file() {
        return Some(beside);
    }
    let (root, split) = (dir.parent()?, dir.file_name()?);
    Some(root.join(GEOMETRY_DIR).join(split).join(name)).filter(|p| p.is_file())
}

/// The dimension of the meshes in the split directory `dir`: that of its first expert mesh (the
/// others must match when read).
pub fn mesh_dimension(dir: &Path) -> Result<usize, TaskError> {
    let files = part_files(dir)?;
    for files in files.values() {
        let (json, others): (Vec<&PathBuf>, Vec<&PathBuf>) = files.iter().partition(|p| extension(p) == "json");
        for path in others.into_iter().chain(json) {
            match read_mesh::<3>(path) {
                Ok(_) => return Ok(3),
                Err(MeshError::DimensionMismatch { found, .. }) => return Ok(found),
                Err(MeshError::UnsupportedFormat { .. }) => {}
                Err(e) => return Err(TaskError::ExpertMesh(e)),
            }
        }
    }
    Err(no_expert_mesh(dir, files.values().map(Vec::len).sum()))
}

/// The error of the split directory `dir` holding `files` files, none of them a mesh.
fn no_expert_mesh(dir: &Path, files: usize) -> TaskError {
    let message = match files {
        0 => "the split directory is empty: no expert mesh".to_owned(),
        n => format!("no expert mesh in this split: none of its {n} files is a mesh amber reads ({MESH_FORMATS})"),
    };
    TaskError::Dataset { path: dir.into(), message }
}

/// Reads the expert meshes of the split directory `dir` (at most `limit` parts, the first by
/// stem), in parallel, and finds their geometry files. Every file that holds a mesh must be
/// `D`-dimensional; a directory without a mesh is an error.
pub fn read_experts<const D: usize>(dir: &Path, limit: Option<usize>) -> Result<Vec<Expert<D>>, TaskError> {
    let split = dir.file_name().map_or_else(|| dir.display().to_string(), |s| s.to_string_lossy().into_owned());
    let stems: Vec<(String, Vec<PathBuf>)> = part_files(dir)?.into_iter().collect();
    let limit = limit.unwrap_or(usize::MAX);
    let mut experts: Vec<Expert<D>> = Vec::new();
    let mut next = 0;
    // Batches of as many stems as parts are still wanted, read in parallel: a stem whose files
    // hold no mesh (a lone `.step`) makes the next batch take the one after.
    while experts.len() < limit && next < stems.len() {
        let batch = &stems[next..stems.len().min(next.saturating_add(limit - experts.len()))];
        next += batch.len();
        let read: Vec<Option<Expert<D>>> = batch
            .par_iter()
            .map(|(stem, files)| {
                Ok(read_part_mesh::<D>(files)?.map(|(path, mesh, data)| {
                    let geometry = find_geometry(dir, stem, files, &path, D);
                    let inputs = find_inputs(dir, stem);
                    let facet_tags = data.facet_tags;
                    Expert { name: format!("{split}/{stem}"), path, mesh, facet_tags, geometry, inputs }
                }))
            })
            .collect::<Result<_, TaskError>>()?;
        experts.extend(read.into_iter().flatten());
    }
    if experts.is_empty() {
        return Err(no_expert_mesh(dir, stems.iter().map(|(_, files)| files.len()).sum()));
    }
    Ok(experts)
}

/// The default M⁰ size of a dataset: [`INITIAL_SIZE_FACTOR`] × the median element size of its
/// training experts.
pub fn default_initial_size<const D: usize>(train: &[Expert<D>]) -> f64 {
    let sizes: Vec<f64> = train.iter().flat_map(|e| e.mesh.sizes()).collect();
    INITIAL_SIZE_FACTOR * median(&sizes)
}

/// A geometry-only domain that a folder dataset's part becomes.
pub trait FolderDomain<const D: usize>: Domain<D> + Sized + Send {
    /// The part of `expert`: its geometry file, or the expert mesh's boundary, checked against
    /// the expert mesh, with a uniform M⁰ of size `initial_size`.
    fn from_expert(expert: &Expert<D>, initial_size: f64, settings: &DatasetSettings) -> Result<Self, TaskError>;
}

/// The error of a geometry file that is not its expert mesh's: its bounding box `bounds` lies
/// elsewhere, or its enclosed volume (area) `volume` differs.
fn check_geometry<const D: usize>(
    expert: &Expert<D>,
    bounds: ([f64; D], [f64; D]),
    volume: f64,
) -> Result<(), TaskError> {
    let Some(path) = &expert.geometry else { return Ok(()) };
    match extent_mismatch(bounds, volume, &expert.mesh) {
        Some(what) => {
            let message = format!("{what}: not the geometry of the expert mesh {}", expert.path.display());
            Err(TaskError::Dataset { path: path.clone(), message })
        }
        None => Ok(()),
    }
}

/// The error of an M⁰ that could not be meshed.
fn initial_mesh_error<const D: usize>(expert: &Expert<D>, error: impl std::fmt::Display) -> TaskError {
    let path = expert.geometry.clone().unwrap_or_else(|| expert.path.clone());
    TaskError::Dataset { path, message: format!("initial mesh M⁰: {error}") }
}

impl FolderDomain<3> for SolidPart {
    fn from_expert(expert: &Expert<3>, initial_size: f64, settings: &DatasetSettings) -> Result<Self, TaskError> {
        let surface = match &expert.geometry {
            Some(path) => read_solid_surface(path, settings.feature_angle(), initial_size)?,
            None => solid_surface_of_mesh(
                &expert.path,
                &expert.mesh,
                &expert.facet_tags,
                BTreeMap::new(),
                settings.feature_angle(),
            )?,
        };
        let bounds = amber_mesh::bounding_box(surface.vertices()).expect("a validated surface has vertices");
        check_geometry(expert, bounds, surface.enclosed_volume())?;
        let mut part =
            SolidPart::new(expert.name.clone(), surface, initial_size).map_err(|e| initial_mesh_error(expert, e))?;
        part.inputs = expert.read_inputs()?;
        Ok(part)
    }
}

impl FolderDomain<2> for PlanarPart {
    fn from_expert(expert: &Expert<2>, initial_size: f64, _settings: &DatasetSettings) -> Result<Self, TaskError> {
        let domain = match &expert.geometry {
            Some(path) => read_polygon_domain(path)?,
            None => polygon_domain_of_mesh(&expert.path, &expert.mesh)?,
        };
        check_geometry(expert, domain.bounding_box(), domain.area())?;
        let mut part =
            PlanarPart::new(expert.name.clone(), domain, initial_size).map_err(|e| initial_mesh_error(expert, e))?;
        part.inputs = expert.read_inputs()?;
        Ok(part)
    }
}

/// The problems of `experts`: each part's domain (M⁰ of size `initial_size`, generated in
/// parallel) with its expert mesh.
pub fn problems<const D: usize, P: FolderDomain<D>>(
    experts: Vec<Expert<D>>,
    initial_size: f64,
    settings: &DatasetSettings,
) -> Result<Vec<WithExpert<P, D>>, TaskError> {
    let paths: Vec<PathBuf> = experts.iter().map(|e| e.inputs.clone().unwrap_or_else(|| e.path.clone())).collect();
    let problems: Vec<WithExpert<P, D>> = experts
        .into_par_iter()
        .map(|expert| {
            let domain = P::from_expert(&expert, initial_size, settings)?;
            WithExpert::new(domain, expert.mesh, &expert.path)
        })
        .collect::<Result<_, TaskError>>()?;
    // A model reads the same inputs on every part.
    if let Some(first) = problems.first() {
        let names = first.optional_inputs();
        if let Some(k) = problems.iter().position(|p| p.optional_inputs() != names) {
            let message = format!(
                "its part inputs ({}) differ from those of {} ({}): every part of a dataset needs the same",
                problems[k].optional_inputs().join(", "),
                paths[0].display(),
                names.join(", ")
            );
            return Err(TaskError::Dataset { path: paths[k].clone(), message });
        }
    }
    Ok(problems)
}

/// Parts of each split of [`write_demo_dataset`].
const DEMO_PARTS: [(Split, usize); 3] = [(Split::Train, 3), (Split::Val, 1), (Split::Test, 2)];

/// Writes a small 2D dataset folder into `dir`, made by the project's own generator so that
/// tests (and a new user) can train and evaluate a folder dataset end to end in seconds: plates
/// (1.2–1.8 × 1) with one or two square holes (seeded), each meshed by `generate_2d` with a known
/// sizing rule (0.02 at a hole's boundary growing linearly to 0.15 at 0.3 away) and written as
/// gmsh `.msh` experts with no geometry files.
pub fn write_demo_dataset(dir: &Path, seed: u64) -> Result<(), TaskError> {
    use amber_meshgen::{FnSize, Mesh2dParams, PolygonDomain, generate_2d};
    use rand::{Rng, SeedableRng};

    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    for (split, parts) in DEMO_PARTS {
        let split_dir = split.dir(dir);
        std::fs::create_dir_all(&split_dir).map_err(|source| TaskError::Io { path: split_dir.clone(), source })?;
        for k in 0..parts {
            let width = rng.random_range(1.2..1.8);
            let holes: usize = rng.random_range(1..=2);
            // Holes of half-width 0.1–0.15 centred in their own slice of the plate, so they never meet.
            let squares: Vec<([f64; 2], f64)> = (0..holes)
                .map(|i| {
                    let slice = width / holes as f64;
                    let x = slice * (i as f64 + rng.random_range(0.35..0.65));
                    ([x, rng.random_range(0.35..0.65)], rng.random_range(0.1..0.15))
                })
                .collect();
            let hole_rings =
                squares.iter().map(|&([x, y], r)| vec![[x - r, y - r], [x - r, y + r], [x + r, y + r], [x + r, y - r]]);
            let outer = vec![[0.0, 0.0], [width, 0.0], [width, 1.0], [0.0, 1.0]];
            let path = split_dir.join(format!("plate{k:02}.msh"));
            let geometry = |message: String| TaskError::Geometry { path: path.clone(), message };
            let domain = PolygonDomain::new(outer, hole_rings.collect()).map_err(|e| geometry(e.to_string()))?;
            let size = FnSize(|p: [f64; 2]| {
                let distance = squares
                    .iter()
                    .map(|&([x, y], r)| {
                        let (dx, dy) = (((p[0] - x).abs() - r).max(0.0), ((p[1] - y).abs() - r).max(0.0));
                        dx.hypot(dy)
                    })
                    .fold(f64::INFINITY, f64::min);
                0.02 + 0.13 * (distance / 0.3).min(1.0)
            });
            let mesh = generate_2d(&domain, &size, &Mesh2dParams::default()).map_err(|e| geometry(e.to_string()))?;
            amber_mesh::write_mesh(&mesh, &path, &amber_mesh::MeshData::default()).map_err(TaskError::ExpertMesh)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::part::GEOMETRY_INPUTS;
    use crate::problem::Problem;

    #[test]
    fn folds_part_a_split_into_held_out_parts_spread_over_it() {
        let folds = Fold::all(3, 7).unwrap();
        let mut held_out = Vec::new();
        for fold in &folds {
            let (trained, held) = fold.split((0..7).collect::<Vec<usize>>());
            assert_eq!(trained.len() + held.len(), 7);
            assert!(held.iter().all(|i| i % 3 == fold.index) && trained.iter().all(|i| !held.contains(i)));
            held_out.extend(held);
        }
        held_out.sort();
        assert_eq!(held_out, (0..7).collect::<Vec<_>>(), "every part is held out by exactly one fold");
        for (count, parts) in [(1, 7), (8, 7), (2, 1)] {
            assert!(Fold::all(count, parts).unwrap_err().contains(&format!("takes 2 to {parts} folds")));
        }
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("amber-folder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    /// The demo dataset loads as 2D planar parts whose geometry is the experts' boundary, with the
    /// default M⁰ size coarser than the experts; the same seed writes the same files.
    #[test]
    fn the_demo_dataset_loads_as_planar_parts() {
        let dir = temp_dir("demo");
        write_demo_dataset(&dir, 7).unwrap();
        assert_eq!(mesh_dimension(&Split::Train.dir(&dir)).unwrap(), 2);
        let train = read_experts::<2>(&Split::Train.dir(&dir), None).unwrap();
        assert_eq!(train.len(), 3);
        assert!(train.iter().all(|e| e.geometry.is_none()));
        let h0 = default_initial_size(&train);
        let settings = DatasetSettings::read(&dir).unwrap();
        let parts = problems::<2, PlanarPart>(train, h0, &settings).unwrap();
        for part in &parts {
            let (m0, expert) = (part.initial_mesh(), part.expert_mesh());
            assert!((m0.total_volume() / expert.total_volume() - 1.0).abs() < 1e-9, "{}", part.domain.name);
            assert!(m0.num_elements() * 4 < expert.num_elements(), "{}: M⁰ {}", part.domain.name, m0.num_elements());
        }
        let again = temp_dir("demo-again");
        write_demo_dataset(&again, 7).unwrap();
        let bytes = |d: &Path| std::fs::read(Split::Test.dir(d).join("plate01.msh")).unwrap();
        assert_eq!(bytes(&dir), bytes(&again));
        std::fs::remove_dir_all(&dir).unwrap();
        std::fs::remove_dir_all(&again).unwrap();
    }

    /// Malformed folders fail with one error naming the file or directory at fault.
    #[test]
    fn malformed_folders_name_the_file_at_fault() {
        let dir = temp_dir("malformed");
        write_demo_dataset(&dir, 3).unwrap();
        let train = Split::Train.dir(&dir);
        let message = |e: TaskError| e.to_string();

        // A missing split, an empty split.
        let err = message(read_experts::<2>(&dir.join("missing"), None).unwrap_err());
        assert!(err.contains("missing") && err.contains("not found"), "{err}");
        std::fs::create_dir_all(dir.join("empty")).unwrap();
        std::fs::write(dir.join("empty/notes.txt"), "no meshes here").unwrap();
        let err = message(read_experts::<2>(&dir.join("empty"), None).unwrap_err());
        assert!(err.contains("empty") && err.contains("no expert mesh"), "{err}");

        // A geometry of another size than its mesh.
        let polygon = r#"{"outer": [[0,0],[3,0],[3,1],[0,1]], "holes": []}"#;
        std::fs::write(train.join("plate00.json"), polygon).unwrap();
        let experts = read_experts::<2>(&train, None).unwrap();
        assert_eq!(experts[0].geometry.as_deref(), Some(train.join("plate00.json").as_path()));
        let err = message(problems::<2, PlanarPart>(experts, 0.2, &DatasetSettings::default()).unwrap_err());
        assert!(err.contains("plate00.json") && err.contains("not the geometry of the expert mesh"), "{err}");
        std::fs::remove_file(train.join("plate00.json")).unwrap();

        // A mesh that does not parse.
        std::fs::write(train.join("plate01.msh"), "$MeshFormat\ngarbage\n").unwrap();
        let err = message(read_experts::<2>(&train, None).unwrap_err());
        assert!(err.contains("plate01.msh"), "{err}");

        // Mixed dimensions: a tet mesh among triangle meshes.
        let tet =
            Mesh::<3>::new(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], vec![0, 1, 2, 3])
                .unwrap();
        amber_mesh::write_mesh(&tet, train.join("plate01.msh"), &amber_mesh::MeshData::default()).unwrap();
        let err = message(read_experts::<2>(&train, None).unwrap_err());
        assert!(err.contains("plate01.msh") && err.contains("mixed dimensions"), "{err}");

        // An unreadable settings file.
        std::fs::write(dir.join(SETTINGS_FILE), r#"{"initial_size": -1}"#).unwrap();
        let err = message(DatasetSettings::read(&dir).unwrap_err());
        assert!(err.contains(SETTINGS_FILE), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Parts' own inputs become node inputs of every element; a part whose inputs differ from the
    /// others', and an inputs file that is not one, are errors naming the file.
    #[test]
    fn part_inputs_are_read_and_checked() {
        let dir = temp_dir("inputs");
        write_demo_dataset(&dir, 4).unwrap();
        let train = Split::Train.dir(&dir);
        let stems = ["plate00", "plate01", "plate02"];
        for (k, stem) in stems.iter().enumerate() {
            let inputs = format!(r#"{{"clamp": [0.1, {k}], "load": {}}}"#, k + 1);
            std::fs::write(train.join(format!("{stem}{PART_INPUTS_SUFFIX}")), inputs).unwrap();
        }
        let load = || problems::<2, PlanarPart>(read_experts(&train, None)?, 0.2, &DatasetSettings::default());
        let parts = load().unwrap();
        assert_eq!(parts.len(), 3, "an inputs file is not a part");
        let offered = parts[2].optional_inputs();
        assert_eq!(offered[GEOMETRY_INPUTS.len()..], ["load".to_owned(), "log_distance_to_clamp".to_owned()]);
        let part = &parts[2].domain;
        let columns = part.columns(&part.initial_mesh).unwrap();
        let column = |name: &str| &columns.iter().find(|c| c.name == name).unwrap().values;
        assert!(column("load").iter().all(|&x| x == 3.0));
        for (e, &value) in column("log_distance_to_clamp").iter().enumerate() {
            let [x, y] = part.initial_mesh.midpoint(e);
            assert!((value - (x - 0.1).hypot(y - 2.0).ln()).abs() < 1e-12);
        }

        let odd = train.join(format!("plate01{PART_INPUTS_SUFFIX}"));
        std::fs::write(&odd, r#"{"clamp": [0.1, 1]}"#).unwrap();
        let err = load().unwrap_err().to_string();
        assert!(err.contains("plate01.inputs.json") && err.contains("differ"), "{err}");
        for (text, what) in
            [("[1, 2]", "JSON object"), (r#"{"clamp": [0.1, 1, 2]}"#, "point"), (r#"{"load": "x"}"#, "number")]
        {
            std::fs::write(&odd, text).unwrap();
            let err = load().unwrap_err().to_string();
            assert!(err.contains("plate01.inputs.json") && err.contains(what), "{text}: {err}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The unit cube shifted by `offset`, as 6 tets (Kuhn's split along the main diagonal).
    fn cube_tets(offset: [f64; 3]) -> Mesh<3> {
        let vertices = (0..8).map(|i| [0, 1, 2].map(|k| ((i >> k) & 1) as f64 + offset[k])).collect();
        let cells = [[1, 3], [1, 5], [2, 3], [2, 6], [4, 5], [4, 6]].iter().flat_map(|&[a, b]| [0, a, b, 7]).collect();
        Mesh::new_reoriented(vertices, cells).unwrap()
    }

    /// Writes the boundary of `mesh` as an ASCII STL file.
    fn write_boundary_stl(mesh: &Mesh<3>, path: &Path) {
        let surface = amber_meshgen::mesh3d::Surface::from_mesh_boundary(mesh, &BTreeMap::new()).unwrap();
        let mut stl = String::from("solid part\n");
        for t in surface.triangles() {
            stl += "facet normal 0 0 0\nouter loop\n";
            for &v in t {
                let [x, y, z] = surface.vertices()[v as usize];
                stl += &format!("vertex {x} {y} {z}\n");
            }
            stl += "endloop\nendfacet\n";
        }
        std::fs::write(path, stl + "endsolid part\n").unwrap();
    }

    /// A 3D folder of `.vtk` experts without geometry files: each part's geometry is its mesh's
    /// boundary, split into faces at feature edges, and M⁰ fills it.
    #[test]
    fn a_solid_folder_without_geometry_files_loads() {
        let dir = temp_dir("solid");
        let train = Split::Train.dir(&dir);
        std::fs::create_dir_all(&train).unwrap();
        amber_mesh::write_mesh(&cube_tets([0.0; 3]), train.join("cube.vtk"), &amber_mesh::MeshData::default()).unwrap();
        assert_eq!(mesh_dimension(&train).unwrap(), 3);
        let experts = read_experts::<3>(&train, None).unwrap();
        assert!(experts[0].geometry.is_none());
        let part = problems::<3, SolidPart>(experts, 0.25, &DatasetSettings::default()).unwrap().pop().unwrap();
        assert_eq!(part.domain.surface.face_ids().iter().max(), Some(&6));
        assert!((part.initial_mesh().total_volume() - 1.0).abs() < 1e-12);
        assert!(part.initial_mesh().num_elements() > 50);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A surface of another part beside a mesh is named, whether its volume differs (a larger
    /// cube) or only its place (the same cube moved by half its side).
    #[test]
    fn a_surface_of_another_part_is_named() {
        let dir = temp_dir("other-part");
        let train = Split::Train.dir(&dir);
        std::fs::create_dir_all(&train).unwrap();
        amber_mesh::write_mesh(&cube_tets([0.0; 3]), train.join("cube.vtk"), &amber_mesh::MeshData::default()).unwrap();
        let stl = train.join("cube.stl");
        let load = || problems::<3, SolidPart>(read_experts(&train, None)?, 0.25, &DatasetSettings::default());
        write_boundary_stl(&cube_tets([0.0; 3]), &stl);
        assert!(load().is_ok());
        write_boundary_stl(&cube_tets([0.5, 0.0, 0.0]), &stl);
        let err = load().unwrap_err().to_string();
        assert!(err.contains("cube.stl") && err.contains("cube.vtk") && err.contains("bounding box"), "{err}");
        let larger = cube_tets([0.0; 3]);
        let larger = Mesh::new(larger.vertices().iter().map(|p| p.map(|x| 1.1 * x)).collect(), larger.cells().to_vec());
        write_boundary_stl(&larger.unwrap(), &stl);
        let err = load().unwrap_err().to_string();
        assert!(err.contains("cube.stl") && err.contains("encloses volume"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A CAD file beside a mesh is the part's geometry, unless a surface is there too (beside
    /// the mesh or under `reference_surface/`).
    #[test]
    fn a_surface_is_preferred_to_a_cad_file() {
        let dir = temp_dir("cad");
        let train = Split::Train.dir(&dir);
        std::fs::create_dir_all(&train).unwrap();
        amber_mesh::write_mesh(&cube_tets([0.0; 3]), train.join("cube.vtk"), &amber_mesh::MeshData::default()).unwrap();
        std::fs::write(train.join("cube.step"), "ISO-10303-21;\n").unwrap();
        let geometry = || read_experts::<3>(&train, None).unwrap().pop().unwrap().geometry;
        assert_eq!(geometry(), Some(train.join("cube.step")));
        let reference = dir.join(GEOMETRY_DIR).join("train");
        std::fs::create_dir_all(&reference).unwrap();
        write_boundary_stl(&cube_tets([0.0; 3]), &reference.join("cube.stl"));
        assert_eq!(geometry(), Some(reference.join("cube.stl")));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A Console part given as its expert mesh and STEP file only: gmsh's surface of the STEP
    /// passes the check against the expert mesh (volume, bounding box), keeps the part's 11 CAD
    /// faces, encloses the expert's volume to 0.1 % and bounds M⁰ (its chords on the bends and
    /// hole cut 0.2 % off). Reads `../shared/data/console`; needs gmsh.
    #[test]
    fn a_part_with_a_step_file_loads_with_the_cad_faces() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        if crate::cad::Gmsh::default().version().is_none() {
            return amber_testdata::skip("gmsh is not on the PATH (`pip install gmsh`)");
        }
        let dir = temp_dir("step-part");
        let train = Split::Train.dir(&dir);
        std::fs::create_dir_all(&train).unwrap();
        for extension in ["nas", "step"] {
            std::fs::copy(data.join(format!("train/014.{extension}")), train.join(format!("014.{extension}"))).unwrap();
        }
        let experts = read_experts::<3>(&train, None).unwrap();
        assert_eq!(experts[0].geometry, Some(train.join("014.step")));
        let size = crate::console::INITIAL_SIZE;
        let part = problems::<3, SolidPart>(experts, size, &DatasetSettings::default()).unwrap().pop().unwrap();
        assert_eq!(part.domain.surface.face_ids().iter().max(), Some(&11));
        let expert_volume = part.expert_mesh.total_volume();
        let (surface, initial) = (part.domain.surface.enclosed_volume(), part.initial_mesh().total_volume());
        assert!((surface / expert_volume - 1.0).abs() < 1e-3, "surface {surface} vs expert {expert_volume}");
        assert!((initial / expert_volume - 1.0).abs() < 1e-2, "M⁰ {initial} vs expert {expert_volume}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The errors of splits that hold no expert mesh say whether the directory is empty or its
    /// files are no meshes; a 3D split in a 2D dataset and a truncated binary mesh are named.
    #[test]
    fn splits_without_meshes_and_broken_meshes_are_named() {
        let dir = temp_dir("splits");
        write_demo_dataset(&dir, 5).unwrap();
        let empty = dir.join("empty");
        std::fs::create_dir_all(&empty).unwrap();
        let err = read_experts::<2>(&empty, None).unwrap_err().to_string();
        assert!(err.contains("empty") && err.contains("is empty"), "{err}");
        let err = mesh_dimension(&empty).unwrap_err().to_string();
        assert!(err.contains("is empty"), "{err}");
        std::fs::write(empty.join("part.step"), "ISO-10303-21;").unwrap();
        std::fs::write(empty.join("notes.txt"), "no meshes here").unwrap();
        let err = read_experts::<2>(&empty, None).unwrap_err().to_string();
        assert!(err.contains("none of its 2 files is a mesh"), "{err}");

        // Mixed dimensions across splits: the dataset is 2D (train), val holds tets.
        let val = Split::Val.dir(&dir);
        std::fs::remove_dir_all(&val).unwrap();
        std::fs::create_dir_all(&val).unwrap();
        amber_mesh::write_mesh(&cube_tets([0.0; 3]), val.join("cube.vtk"), &amber_mesh::MeshData::default()).unwrap();
        assert_eq!(mesh_dimension(&Split::Train.dir(&dir)).unwrap(), 2);
        let err = read_experts::<2>(&val, None).unwrap_err().to_string();
        assert!(err.contains("cube.vtk") && err.contains("mixed dimensions"), "{err}");

        // A binary mesh cut short.
        let test = Split::Test.dir(&dir);
        let plate: Mesh<2> = read_mesh(test.join("plate00.msh")).unwrap();
        let binary = test.join("plate00.msh");
        amber_mesh::write_mesh_as(
            &plate,
            &binary,
            &amber_mesh::MeshData::default(),
            amber_mesh::WriteOptions { encoding: Some(amber_mesh::Encoding::Binary), ..Default::default() },
        )
        .unwrap();
        let bytes = std::fs::read(&binary).unwrap();
        std::fs::write(&binary, &bytes[..bytes.len() / 2]).unwrap();
        let err = read_experts::<2>(&test, None).unwrap_err().to_string();
        assert!(err.contains("plate00.msh"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Console's val/001 expert (reads `../shared/data/console`) with no geometry file: its own
    /// boundary is the geometry. The uniform M⁰ once failed: the near-coplanar vertices of its
    /// planar faces made a flat tet in TetGen's background mesh.
    #[test]
    fn a_console_expert_without_its_surface_loads() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        let dir = temp_dir("console-boundary");
        let val = Split::Val.dir(&dir);
        std::fs::create_dir_all(&val).unwrap();
        std::fs::copy(data.join("val/001.nas"), val.join("001.nas")).unwrap();
        let experts = read_experts::<3>(&val, None).unwrap();
        assert!(experts[0].geometry.is_none());
        let size = crate::console::INITIAL_SIZE;
        let part = problems::<3, SolidPart>(experts, size, &DatasetSettings::default()).unwrap().pop().unwrap();
        let (m0, expert) = (part.initial_mesh(), part.expert_mesh());
        assert!((m0.total_volume() / expert.total_volume() - 1.0).abs() < 5e-3, "{}", m0.total_volume());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
