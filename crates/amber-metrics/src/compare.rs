//! All metrics of one generated mesh against its expert mesh.

use amber_mesh::Mesh;
use serde::{Deserialize, Serialize};

use crate::{MetricsError, PointSetDistance, VolumeDifference, point_set_distance, volume_difference};

/// The per-mesh evaluation numbers of spec §7 (normalisation needs three of these; see
/// [`crate::normalised_dcd`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshComparison {
    /// DCD and Chamfer distance between the element midpoints.
    pub midpoints: PointSetDistance,
    /// Symmetric volume difference.
    pub volume: VolumeDifference,
    /// Number of expert elements minus number of generated elements.
    pub element_delta: i64,
}

/// DCD and Chamfer distance between the element midpoints of two meshes.
pub fn midpoint_distance<const D: usize>(first: &Mesh<D>, second: &Mesh<D>) -> Result<PointSetDistance, MetricsError> {
    point_set_distance(&first.midpoints(), &second.midpoints())
}

/// Compares a generated mesh with the expert mesh of the same domain.
pub fn compare_meshes<const D: usize>(generated: &Mesh<D>, expert: &Mesh<D>) -> Result<MeshComparison, MetricsError> {
    Ok(MeshComparison {
        midpoints: midpoint_distance(generated, expert)?,
        volume: volume_difference(generated, expert),
        element_delta: expert.num_elements() as i64 - generated.num_elements() as i64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::Mesh2;

    #[test]
    fn a_mesh_compared_with_itself_scores_zero() {
        let m = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
        let c = compare_meshes(&m, &m).unwrap();
        assert_eq!(c.midpoints, PointSetDistance { dcd: 0.0, chamfer: 0.0 });
        assert_eq!(c.volume.summed, 0.0);
        assert_eq!(c.element_delta, 0);
    }

    #[test]
    fn element_delta_is_expert_minus_generated() {
        let one = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap();
        let two = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
        assert_eq!(compare_meshes(&one, &two).unwrap().element_delta, 1);
    }
}
