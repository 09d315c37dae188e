//! The Console task (spec §9) as a [`Problem<3>`]: a [`SolidPart`](crate::part::SolidPart)
//! (geometric features only, every new mesh made by the 3D generator from the part's reference
//! surface and the piecewise-constant field on the current mesh) with labels from the expert's
//! tet mesh.

use amber_graph::FeatureSet;
use amber_mesh::Mesh;

use super::ConsoleProblem;
use crate::problem::{Column, Domain, Problem, ProblemError};

impl Domain<3> for ConsoleProblem {
    fn feature_set(&self) -> FeatureSet {
        self.part.feature_set()
    }

    fn initial_mesh(&self) -> &Mesh<3> {
        &self.part.initial_mesh
    }

    fn columns(&self, mesh: &Mesh<3>) -> Result<Vec<Column>, ProblemError> {
        self.part.columns(mesh)
    }

    fn remesh(&self, mesh: &Mesh<3>, sizes: Vec<f64>, max_elements: usize) -> Result<Mesh<3>, ProblemError> {
        self.part.remesh(mesh, sizes, max_elements)
    }
}

impl Problem<3> for ConsoleProblem {
    fn expert_mesh(&self) -> &Mesh<3> {
        &self.expert_mesh
    }
}

#[cfg(test)]
mod tests {
    use amber_graph::Aggregation;

    use super::*;
    use crate::console::ConsoleSplit;
    use crate::problem::{MeshLimits, MeshState, StepOutcome, generation_step, labels};

    /// One generation step on val/002 from M⁰ with a smoke-size field (3 mm everywhere): a new
    /// mesh of the same solid with about the expected element count, its graph and labels; and a
    /// field far too fine is stopped by the budget, not meshed.
    #[test]
    fn one_generation_step_on_a_shipped_part() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        let problem = ConsoleProblem::load(&data, ConsoleSplit::Val, "002").unwrap();
        let m0 = problem.initial_mesh();
        let limits = MeshLimits::from_experts([problem.expert_mesh()], 1.2, 0.005);
        let start = std::time::Instant::now();
        let StepOutcome::Meshed(mesh) = generation_step(&problem, m0, vec![3.0; m0.num_elements()], &limits) else {
            panic!("the 3 mm step was not meshed")
        };
        let volume = problem.part.surface.enclosed_volume();
        let expected = volume / amber_mesh::volume_from_size::<3>(3.0);
        println!(
            "{}: M⁰ {} tets -> {} tets with 3 mm (≈{expected:.0} regular tets) in {:.2} s",
            problem.part.name,
            m0.num_elements(),
            mesh.num_elements(),
            start.elapsed().as_secs_f64()
        );
        assert!((mesh.total_volume() / volume - 1.0).abs() < 5e-3);
        assert!((0.5 * expected..3.0 * expected).contains(&(mesh.num_elements() as f64)));
        let state = MeshState::new(&problem, &problem.feature_set(), mesh).unwrap();
        assert_eq!(state.graph.num_nodes(), state.mesh.num_elements());
        assert_eq!(state.graph.node_features().len(), state.mesh.num_elements());
        let y = labels(&problem, &state.mesh, Aggregation::Mean).unwrap();
        assert!(y.len() == state.mesh.num_elements() && y.iter().all(|h| h.is_finite() && *h > 0.0));
        let outcome = generation_step(&problem, m0, vec![0.05; m0.num_elements()], &limits);
        assert!(matches!(outcome, StepOutcome::OverBudget { .. }), "{outcome:?}");
    }
}
