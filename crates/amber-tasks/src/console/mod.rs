//! The Console task (spec §9): real sheet-metal parts meshed by a human expert. A data
//! directory in the layout of the AMBER authors' bundle holds, per split, `NNN.nas` (the
//! expert tet mesh, mm) and `NNN.step` (the CAD), plus `reference_surface/<split>/NNN.stl`
//! (a fine gmsh triangulation of the CAD with the CAD face id in each facet's attribute):
//!
//! ```text
//! DIR/train/001.nas  DIR/train/001.step  …   DIR/val/…   [DIR/test/…]
//! DIR/reference_surface/train/001.stl  …
//! ```
//!
//! [`load_split`] reads one split into [`ConsoleProblem`]s: the expert mesh M*, the validated
//! reference surface, and M⁰, a uniform mesh of element volume 10 mm³ made by the 3D generator.
//! The paper trains on train/001–015, validates on val/001–002 and tests on test/001–005;
//! [`TrainSet::All`] trains on all 19.

mod problem;

use std::path::{Path, PathBuf};

use amber_mesh::{Mesh3, MeshError, read_mesh};
use amber_meshgen::mesh3d::{Mesh3dError, StlFaceIds, Surface, SurfaceError};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::part::SolidPart;

/// Element volume of M⁰ in mm³ (spec §9).
pub const INITIAL_ELEMENT_VOLUME: f64 = 10.0;

/// h₀ in mm as the spec gives it (§9); the regular tet of volume 10 mm³ has edge
/// (6√2·10)^(1/3) = 4.3943 mm.
pub const INITIAL_SIZE: f64 = 4.3955;

/// How M⁰ is made, for cache keys: the reference meshes the part uniformly with gmsh (no
/// curvature refinement, 765–5,794 tets), so ours is the 3D generator with h₀ everywhere, its
/// curvature cap and size factor off: 1,389–5,543 tets on train/001–015 and 1,613 and 5,035 on
/// val (the reference's gmsh: 1,635–5,794 and 1,704 and 5,073). With the cap, M⁰ had 1.3–1.7 times
/// more tets, which moved d(M⁰, M*), the anchor of the normalised DCD, from the reference's
/// 0.75–0.85 to 0.70.
pub const INITIAL_MESH_RECIPE: &str = "uniform h0 = 4.3955 mm, no curvature cap, size factor 1";

/// Where the data comes from and how to make the reference surfaces, for error messages.
const HOW_TO_GET_THE_DATA: &str = "download the Console data (MIT licence) of the AMBER authors' repository, \
     https://github.com/NiklasFreymuth/AMBER (branch `workshop`, data/console/{train,val,test}/NNN.{nas,step}), \
     then make the reference surfaces from the STEP files with gmsh: `pip install gmsh numpy && python \
     datasets/console/make_reference_surfaces.py DIR` (OpenCASCADE, MeshSizeFromCurvature=48, MeshSizeMax=2.5 mm, \
     MeshSizeExtendFromBoundary=0, Mesh.Algorithm=6; see datasets/console/README.md)";

/// A split of the Console data.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ConsoleSplit {
    Train,
    Val,
    Test,
}

impl ConsoleSplit {
    /// The directory name (`train`, `val`, `test`).
    pub fn name(self) -> &'static str {
        match self {
            ConsoleSplit::Train => "train",
            ConsoleSplit::Val => "val",
            ConsoleSplit::Test => "test",
        }
    }
}

/// Which training parts to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TrainSet {
    /// The paper's split: the first 15 training parts (train/001–015).
    #[default]
    Paper,
    /// All training parts (19 in the bundle).
    All,
}

/// Number of training parts of the paper's split.
const PAPER_TRAIN_PARTS: usize = 15;

/// Reading the Console data failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConsoleError {
    /// The data directory or one of its splits is absent.
    #[error("{path}: Console data not found; {HOW_TO_GET_THE_DATA}")]
    Missing { path: PathBuf },
    /// A part has its expert mesh but no reference surface.
    #[error("{path}: reference surface not found (for {step}); {HOW_TO_GET_THE_DATA}")]
    MissingReference { path: PathBuf, step: PathBuf },
    /// A directory could not be listed.
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// The training split has fewer parts than the paper's split uses.
    #[error("{path}: the paper's split trains on {expected} parts, found {found}")]
    TooFewParts { path: PathBuf, expected: usize, found: usize },
    /// An expert mesh could not be read.
    #[error("expert mesh: {0}")]
    Expert(#[from] MeshError),
    /// A reference surface could not be read or does not bound a solid.
    #[error("reference surface: {0}")]
    Reference(#[from] SurfaceError),
    /// The uniform initial mesh could not be generated.
    #[error("{name}: initial mesh: {source}")]
    InitialMesh { name: String, source: Mesh3dError },
}

/// One Console part with its expert's mesh.
#[derive(Clone, Debug)]
pub struct ConsoleProblem {
    /// The part, named `split/NNN` (e.g. `train/001`): the validated reference surface (mm, CAD
    /// face ids) and M⁰, the uniform mesh with h₀ = [`INITIAL_SIZE`].
    pub part: SolidPart,
    /// M*: the expert's mesh (mm).
    pub expert_mesh: Mesh3,
}

impl ConsoleProblem {
    /// Reads part `stem` (e.g. `001`) of `split` from the data directory `data` and makes M⁰.
    pub fn load(data: &Path, split: ConsoleSplit, stem: &str) -> Result<Self, ConsoleError> {
        let name = format!("{}/{stem}", split.name());
        let nas = data.join(format!("{name}.nas"));
        let stl = data.join("reference_surface").join(format!("{name}.stl"));
        if !stl.is_file() {
            return Err(ConsoleError::MissingReference { path: stl, step: nas.with_extension("step") });
        }
        let expert_mesh = read_mesh::<3>(&nas)?;
        let (reference, _) = Surface::load(&stl, StlFaceIds::FromFile)?;
        let part = SolidPart::new(name.clone(), reference, INITIAL_SIZE)
            .map_err(|source| ConsoleError::InitialMesh { name, source })?;
        Ok(Self { part, expert_mesh })
    }
}

/// The parts of `split` as file stems (`001`, …), sorted; for the training split only the
/// first 15 unless `train_set` is [`TrainSet::All`].
pub fn part_names(data: &Path, split: ConsoleSplit, train_set: TrainSet) -> Result<Vec<String>, ConsoleError> {
    let dir = data.join(split.name());
    if !dir.is_dir() {
        return Err(ConsoleError::Missing { path: dir });
    }
    let io = |source| ConsoleError::Io { path: dir.clone(), source };
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        if path.extension().is_some_and(|e| e == "nas")
            && let Some(stem) = path.file_stem().and_then(|s| s.to_str())
        {
            names.push(stem.to_owned());
        }
    }
    names.sort();
    if split == ConsoleSplit::Train && train_set == TrainSet::Paper {
        if names.len() < PAPER_TRAIN_PARTS {
            return Err(ConsoleError::TooFewParts { path: dir, expected: PAPER_TRAIN_PARTS, found: names.len() });
        }
        names.truncate(PAPER_TRAIN_PARTS);
    }
    Ok(names)
}

/// Whether `data` has a `test/` split (the shipped bundle has only `train/` and `val/`).
pub fn has_test_split(data: &Path) -> bool {
    data.join(ConsoleSplit::Test.name()).is_dir()
}

/// Reads every part of `split` (in parallel), in the order of [`part_names`].
pub fn load_split(data: &Path, split: ConsoleSplit, train_set: TrainSet) -> Result<Vec<ConsoleProblem>, ConsoleError> {
    if !data.is_dir() {
        return Err(ConsoleError::Missing { path: data.to_owned() });
    }
    part_names(data, split, train_set)?.par_iter().map(|stem| ConsoleProblem::load(data, split, stem)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn initial_size_is_the_regular_tet_of_ten_cubic_millimetres() {
        assert!((amber_mesh::size_from_volume::<3>(INITIAL_ELEMENT_VOLUME) - INITIAL_SIZE).abs() < 2e-3);
    }

    #[test]
    fn absent_data_says_what_to_download() {
        let err = load_split(Path::new("/nonexistent/console"), ConsoleSplit::Train, TrainSet::Paper).unwrap_err();
        let message = err.to_string();
        assert!(matches!(err, ConsoleError::Missing { .. }));
        for needle in ["/nonexistent/console", "MIT", "NiklasFreymuth/AMBER", "gmsh", "MeshSizeFromCurvature=48"] {
            assert!(message.contains(needle), "{needle} missing from: {message}");
        }
    }

    #[test]
    fn shipped_splits_follow_the_paper() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        let train = part_names(&data, ConsoleSplit::Train, TrainSet::Paper).unwrap();
        assert_eq!(train.len(), 15);
        assert_eq!((train[0].as_str(), train[14].as_str()), ("001", "015"));
        assert_eq!(part_names(&data, ConsoleSplit::Train, TrainSet::All).unwrap().len(), 19);
        assert_eq!(part_names(&data, ConsoleSplit::Val, TrainSet::Paper).unwrap(), ["001", "002"]);
        if !has_test_split(&data) {
            assert!(matches!(
                part_names(&data, ConsoleSplit::Test, TrainSet::Paper),
                Err(ConsoleError::Missing { .. })
            ));
        }
    }

    #[test]
    fn shipped_part_loads_with_a_uniform_initial_mesh() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        let start = std::time::Instant::now();
        let problem = ConsoleProblem::load(&data, ConsoleSplit::Val, "002").unwrap();
        let (m0, expert) = (&problem.part.initial_mesh, &problem.expert_mesh);
        println!(
            "{}: expert {} tets, M⁰ {} tets, {:.2} s",
            problem.part.name,
            expert.num_elements(),
            m0.num_elements(),
            start.elapsed().as_secs_f64()
        );
        assert_eq!(problem.part.name, "val/002");
        assert_eq!(expert.num_elements(), 17489);
        // M⁰ fills the same solid, with elements far coarser than the expert's.
        let volume = problem.part.surface.enclosed_volume();
        assert!((m0.total_volume() / volume - 1.0).abs() < 5e-3 && (expert.total_volume() / volume - 1.0).abs() < 5e-3);
        assert!((500..6_000).contains(&m0.num_elements()), "{} tets", m0.num_elements());
        assert!(problem.part.surface.is_validated());
    }

    #[test]
    fn a_missing_reference_surface_says_how_to_make_it() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        let dir = std::env::temp_dir().join(format!("amber-console-test-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("val")).unwrap();
        std::fs::copy(data.join("val/002.nas"), dir.join("val/002.nas")).unwrap();
        let err = load_split(&dir, ConsoleSplit::Val, TrainSet::Paper).unwrap_err();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(matches!(err, ConsoleError::MissingReference { .. }), "{err}");
        assert!(err.to_string().contains("make_reference_surfaces.py"), "{err}");
    }
}
