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
//! This is a dataset folder (see [`crate::folder`]) whose geometry lies under
//! `reference_surface/`: it loads as any other, each part a [`SolidPart`](crate::part::SolidPart)
//! with its expert mesh and M⁰ a uniform mesh of element volume 10 mm³ ([`INITIAL_SIZE`]). What
//! is Console's own is here: that size, the paper's split (train on train/001–015, validate on
//! val/001–002, test on test/001–005; [`TrainSet::All`] trains on all 19) and where to get the
//! data.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::folder::{GEOMETRY_DIR, Split};

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

impl TrainSet {
    /// How many training parts (the first, by name) the set takes; `None`: all.
    pub fn part_limit(self) -> Option<usize> {
        match self {
            TrainSet::Paper => Some(PAPER_TRAIN_PARTS),
            TrainSet::All => None,
        }
    }
}

/// The Console data is absent (or lacks its reference surfaces).
#[derive(Debug, thiserror::Error)]
#[error("{path}: Console data not found; {HOW_TO_GET_THE_DATA}")]
pub struct MissingData {
    pub path: PathBuf,
}

/// Checks that `data` holds the Console data: the training split and the reference surfaces,
/// without which the folder loader would fall back to the experts' own boundaries.
pub fn check_data(data: &Path) -> Result<(), MissingData> {
    for dir in [Split::Train.dir(data), data.join(GEOMETRY_DIR)] {
        if !dir.is_dir() {
            return Err(MissingData { path: dir });
        }
    }
    Ok(())
}

/// Whether `data` has a `test/` split (the shipped bundle has only `train/` and `val/`).
pub fn has_test_split(data: &Path) -> bool {
    Split::Test.dir(data).is_dir()
}

#[cfg(test)]
mod tests {
    use amber_graph::Aggregation;
    use amber_stdx::{median, quantile};

    use super::*;
    use crate::folder::{DatasetSettings, problems, read_experts};
    use crate::part::SolidPart;
    use crate::problem::{Domain, MeshLimits, MeshState, Problem, SizeBounds, StepOutcome, generation_step, labels};

    #[test]
    fn initial_size_is_the_regular_tet_of_ten_cubic_millimetres() {
        assert!((amber_mesh::size_from_volume::<3>(INITIAL_ELEMENT_VOLUME) - INITIAL_SIZE).abs() < 2e-3);
    }

    #[test]
    fn absent_data_says_what_to_download() {
        let err = check_data(Path::new("/nonexistent/console")).unwrap_err();
        let message = err.to_string();
        for needle in ["/nonexistent/console", "MIT", "NiklasFreymuth/AMBER", "gmsh", "MeshSizeFromCurvature=48"] {
            assert!(message.contains(needle), "{needle} missing from: {message}");
        }
    }

    #[test]
    fn shipped_splits_follow_the_paper() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        check_data(&data).unwrap();
        let train = read_experts::<3>(&Split::Train.dir(&data), TrainSet::Paper.part_limit()).unwrap();
        assert_eq!(train.len(), 15);
        assert_eq!((train[0].name.as_str(), train[14].name.as_str()), ("train/001", "train/015"));
        assert!(train.iter().all(|e| e.geometry.as_ref().is_some_and(|g| g.starts_with(data.join(GEOMETRY_DIR)))));
        assert_eq!(read_experts::<3>(&Split::Train.dir(&data), TrainSet::All.part_limit()).unwrap().len(), 19);
        let val: Vec<String> =
            read_experts::<3>(&Split::Val.dir(&data), None).unwrap().into_iter().map(|e| e.name).collect();
        assert_eq!(val, ["val/001", "val/002"]);
    }

    /// train/014 is a bent plate with a round hole, where its expert refines most:
    /// `log_curvature_radius` marks the hole. Its finest 5 % of expert elements lie where the
    /// nearest surface's radius of curvature is at most a fifth of the median element's (whose
    /// nearest surface is flat: the cap, the part's extent). The wall thickness there is the
    /// chord from the hole's wall in the plate's plane (15.8 mm), not across the plate (2.9 mm at
    /// the median element).
    #[test]
    fn the_geometry_inputs_mark_where_the_expert_refines() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        let mut experts = read_experts::<3>(&Split::Train.dir(&data), Some(14)).unwrap();
        let expert = experts.pop().unwrap();
        assert_eq!(expert.name, "train/014");
        let part = problems::<3, SolidPart>(vec![expert], INITIAL_SIZE, &DatasetSettings::default()).unwrap().remove(0);
        let columns = part.domain.columns(part.expert_mesh()).unwrap();
        let radius = &columns.iter().find(|c| c.name == "log_curvature_radius").unwrap().values;
        let sizes = part.expert_mesh().sizes();
        let mut sorted = sizes.clone();
        sorted.sort_by(f64::total_cmp);
        let cut = quantile(&sorted, 0.05);
        let finest: Vec<f64> = (0..sizes.len()).filter(|&e| sizes[e] <= cut).map(|e| radius[e]).collect();
        let (finest, all) = (median(&finest), median(radius));
        let cap = radius.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(all, cap, "flat at the median element");
        assert!(finest < all - 5f64.ln(), "log radius {finest} at the finest elements, {all} at the median");
        let thickness = &columns.iter().find(|c| c.name == "log_wall_thickness").unwrap().values;
        let finest: Vec<f64> = (0..sizes.len()).filter(|&e| sizes[e] <= cut).map(|e| thickness[e]).collect();
        let (finest, all) = (median(&finest).exp(), median(thickness).exp());
        println!("wall thickness: {finest} mm at the finest elements, {all} mm at the median");
        assert!((2.0..4.0).contains(&all), "{all} mm at the median element");
        assert!(finest > 1.2 * all, "{finest} mm at the finest elements, {all} at the median");
    }

    /// val/002 through the folder loader: its reference surface, a uniform M⁰, the expert; then
    /// one generation step from M⁰ with a smoke-size field (3 mm everywhere): a new mesh of the
    /// same solid with about the expected element count, its graph and labels; and a field far
    /// too fine is stopped by the budget, not meshed.
    #[test]
    fn a_shipped_part_loads_through_the_folder_and_takes_a_step() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        let start = std::time::Instant::now();
        let mut experts = read_experts::<3>(&Split::Val.dir(&data), None).unwrap();
        let expert = experts.pop().unwrap();
        let mut loaded = problems::<3, SolidPart>(vec![expert], INITIAL_SIZE, &DatasetSettings::default()).unwrap();
        let problem = loaded.pop().unwrap();
        let (m0, expert) = (problem.initial_mesh(), problem.expert_mesh());
        println!(
            "{}: expert {} tets, M⁰ {} tets, {:.2} s",
            problem.domain.name,
            expert.num_elements(),
            m0.num_elements(),
            start.elapsed().as_secs_f64()
        );
        assert_eq!(problem.domain.name, "val/002");
        assert_eq!(expert.num_elements(), 17489);
        // M⁰ fills the same solid, with elements far coarser than the expert's.
        let volume = problem.domain.surface.enclosed_volume();
        assert!((m0.total_volume() / volume - 1.0).abs() < 5e-3 && (expert.total_volume() / volume - 1.0).abs() < 5e-3);
        assert!((500..6_000).contains(&m0.num_elements()), "{} tets", m0.num_elements());
        assert!(problem.domain.surface.is_validated());

        let limits = MeshLimits::from_experts([problem.expert_mesh()], 1.2, 0.005);
        let StepOutcome::Meshed(mesh) =
            generation_step(&problem, m0, vec![3.0; m0.num_elements()], &limits, &SizeBounds::default())
        else {
            panic!("the 3 mm step was not meshed")
        };
        let expected = volume / amber_mesh::volume_from_size::<3>(3.0);
        assert!((mesh.total_volume() / volume - 1.0).abs() < 5e-3);
        assert!((0.5 * expected..3.0 * expected).contains(&(mesh.num_elements() as f64)));
        let state = MeshState::new(&problem, &problem.feature_set(), mesh).unwrap();
        assert_eq!(state.graph.num_nodes(), state.mesh.num_elements());
        let y = labels(&problem, &state.mesh, Aggregation::Mean).unwrap();
        assert!(y.len() == state.mesh.num_elements() && y.iter().all(|h| h.is_finite() && *h > 0.0));
        let outcome = generation_step(&problem, m0, vec![0.05; m0.num_elements()], &limits, &SizeBounds::default());
        assert!(matches!(outcome, StepOutcome::OverBudget { .. }), "{outcome:?}");
    }
}
