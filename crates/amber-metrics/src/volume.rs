//! Symmetric volume difference between two meshes of the same domain (spec §7, paper Eq. 1).

use amber_mesh::{Mesh, PointLocator};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Element-wise volume mismatch between two meshes, summed over the elements of both.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct VolumeDifference {
    /// Σ |V(K) − V(K')|, K' the element of the other mesh containing K's midpoint.
    pub summed: f64,
    /// Σ (V(K) − V(K'))².
    pub squared: f64,
}

/// For every element K of each mesh, compares its volume with that of the element of the other
/// mesh containing K's midpoint, or, when the midpoint lies outside the other mesh, the element
/// with the nearest midpoint (the reference code silently used the last element there).
pub fn volume_difference<const D: usize>(first: &Mesh<D>, second: &Mesh<D>) -> VolumeDifference {
    let forward = one_direction(first, second);
    let backward = one_direction(second, first);
    VolumeDifference { summed: forward.summed + backward.summed, squared: forward.squared + backward.squared }
}

fn one_direction<const D: usize>(from: &Mesh<D>, to: &Mesh<D>) -> VolumeDifference {
    let locator = PointLocator::new(to);
    let to_volumes = to.volumes();
    let differences: Vec<f64> = from
        .midpoints()
        .par_iter()
        .zip(from.volumes().par_iter())
        .map(|(&m, &v)| v - to_volumes[locator.locate_or_nearest(m).element()])
        .collect();
    VolumeDifference {
        summed: differences.iter().map(|d| d.abs()).sum(),
        squared: differences.iter().map(|d| d * d).sum(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::Mesh2;

    fn square(split_along_other_diagonal: bool) -> Mesh2 {
        let cells = if split_along_other_diagonal { vec![0, 1, 3, 1, 2, 3] } else { vec![0, 1, 2, 0, 2, 3] };
        Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], cells).unwrap()
    }

    #[test]
    fn a_mesh_has_no_volume_difference_with_itself() {
        let m = square(false);
        assert_eq!(volume_difference(&m, &m), VolumeDifference { summed: 0.0, squared: 0.0 });
    }

    #[test]
    fn coarse_against_fine_counts_both_directions() {
        // One square as 2 triangles against a 4-triangle fan around the centre: every fine
        // midpoint lies in a coarse triangle (difference 0.5 − 0.25) and vice versa.
        let fine = Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]],
            vec![0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4],
        )
        .unwrap();
        let d = volume_difference(&square(true), &fine);
        assert!((d.summed - 6.0 * 0.25).abs() < 1e-15);
        assert!((d.squared - 6.0 * 0.0625).abs() < 1e-15);
    }

    #[test]
    fn midpoints_outside_the_other_mesh_use_the_nearest_midpoint() {
        // The second mesh also covers [1, 2] × [0, 1]; that triangle's midpoint is outside the
        // first mesh and is compared with the first mesh's triangle of nearest midpoint (area 0.5).
        let wide = Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.0]],
            vec![0, 1, 2, 0, 2, 3, 1, 4, 2],
        )
        .unwrap();
        let d = volume_difference(&square(false), &wide);
        assert_eq!(d.summed, 0.0);
    }
}
