//! Projection of an expert mesh's sizing field onto another mesh: the training labels (spec §3).

use amber_mesh::{Mesh, PointLocator, size_from_volume};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::GraphError;

/// How the sizes of the expert elements assigned to one element are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Aggregation {
    /// Unweighted mean over the expert elements (AMBER-Mean).
    Mean,
    /// Maximum over the expert elements (AMBER-Max).
    Max,
    /// The size at which the element would hold as many elements as the expert has there: the
    /// regular simplex of volume |K| / n for n assigned expert elements, kept within their
    /// smallest and largest size. Of a coarse element in a graded region, Max asks for fewer
    /// elements than the expert has in it (a mesh can stay at such a fixed point, coarser than
    /// the expert's) and Mean, dominated by the many small ones, for more; this label asks for
    /// as many.
    Density,
}

/// The expert sizing field as one label per element of `current`.
///
/// Every expert element is assigned to the element of `current` containing its midpoint (or, if
/// the midpoint lies outside `current`, the element with the nearest midpoint); an element's label
/// aggregates the sizes h(K) of the expert elements assigned to it. Elements that received none
/// (where `current` is finer than the expert) take the size of the expert element containing their
/// own midpoint, else of the expert element with the nearest midpoint.
///
/// ```
/// use amber_graph::{Aggregation, project_expert_sizing};
/// use amber_mesh::Mesh2;
/// let square = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
/// assert_eq!(project_expert_sizing(&square, &square, Aggregation::Mean).unwrap(), square.sizes());
/// ```
pub fn project_expert_sizing<const D: usize>(
    current: &Mesh<D>,
    expert: &Mesh<D>,
    aggregation: Aggregation,
) -> Result<Vec<f64>, GraphError> {
    let expert_sizes = expert.sizes();
    let locator = PointLocator::new(current);
    let owners: Vec<usize> =
        expert.midpoints().par_iter().with_min_len(256).map(|&c| locator.locate_or_nearest(c).element()).collect();

    let n = current.num_elements();
    let mut sums = vec![0.0; n];
    let mut smallest = vec![f64::INFINITY; n];
    let mut largest = vec![0.0f64; n];
    let mut counts = vec![0u32; n];
    for (&owner, &h) in owners.iter().zip(&expert_sizes) {
        sums[owner] += h;
        smallest[owner] = smallest[owner].min(h);
        largest[owner] = largest[owner].max(h);
        counts[owner] += 1;
    }
    let mut labels: Vec<f64> = (0..n)
        .map(|i| {
            if counts[i] == 0 {
                return 0.0; // filled below
            }
            let count = f64::from(counts[i]);
            match aggregation {
                Aggregation::Mean => sums[i] / count,
                Aggregation::Max => largest[i],
                Aggregation::Density => size_from_volume::<D>(current.volume(i) / count).clamp(smallest[i], largest[i]),
            }
        })
        .collect();

    let unassigned: Vec<usize> = (0..n).filter(|&i| counts[i] == 0).collect();
    if !unassigned.is_empty() {
        // Only built when needed: indexing the (usually much finer) expert costs more than the rest.
        let expert_locator = PointLocator::new(expert);
        let fills: Vec<f64> = unassigned
            .par_iter()
            .map(|&i| expert_sizes[expert_locator.locate_or_nearest(current.midpoint(i)).element()])
            .collect();
        for (&i, h) in unassigned.iter().zip(fills) {
            labels[i] = h;
        }
    }
    Ok(labels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::{Mesh2, Mesh3};

    /// The unit square split by its diagonal (0,0)–(1,1).
    fn square() -> Mesh2 {
        Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap()
    }

    /// The unit square as a fan of 4 triangles around `centre`.
    fn fan(centre: [f64; 2]) -> Mesh2 {
        Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], centre],
            vec![0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4],
        )
        .unwrap()
    }

    /// The unit square as three triangles of areas 0.2, 0.3 and 0.5, fanned from (0.4, 0).
    fn uneven_expert() -> Mesh2 {
        Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.4, 0.0]], vec![0, 4, 3, 4, 1, 2, 4, 2, 3])
            .unwrap()
    }

    fn size(area: f64) -> f64 {
        amber_mesh::size_from_volume::<2>(area)
    }

    #[test]
    fn a_mesh_projected_onto_itself_keeps_its_sizes() {
        let m = fan([0.3, 0.6]);
        assert_eq!(project_expert_sizing(&m, &m, Aggregation::Max).unwrap(), m.sizes());
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -2.0]];
        let tets = Mesh3::new_reoriented(v, vec![0, 1, 2, 3, 0, 1, 2, 4]).unwrap();
        assert_eq!(project_expert_sizing(&tets, &tets, Aggregation::Mean).unwrap(), tets.sizes());
    }

    #[test]
    fn mean_and_max_aggregate_the_contained_expert_elements() {
        // Current: the square's lower-right and upper-left triangles. The expert splits the first
        // at (0.75, 0) into areas 0.375 and 0.125, the second at (0.5, 1) into two of 0.25.
        let expert = Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.75, 0.0], [0.5, 1.0]],
            vec![0, 4, 2, 4, 1, 2, 0, 5, 3, 0, 2, 5],
        )
        .unwrap();
        let sizes = expert.sizes();
        let mean = project_expert_sizing(&square(), &expert, Aggregation::Mean).unwrap();
        let max = project_expert_sizing(&square(), &expert, Aggregation::Max).unwrap();
        assert!((mean[0] - 0.5 * (sizes[0] + sizes[1])).abs() < 1e-15);
        assert_eq!(max[0], sizes[0].max(sizes[1]));
        assert!((mean[1] - size(0.25)).abs() < 1e-15);
    }

    #[test]
    fn density_labels_keep_the_expert_element_count() {
        // The lower-right triangle (area 0.5) holds the expert's two elements of areas 0.375 and
        // 0.125: two elements of 0.25 each, the regular size of area 0.25. The max asks for
        // larger elements, the mean (dominated by the small one) for smaller.
        let expert = Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.75, 0.0]],
            vec![0, 4, 2, 4, 1, 2, 0, 2, 3],
        )
        .unwrap();
        let density = project_expert_sizing(&square(), &expert, Aggregation::Density).unwrap();
        let mean = project_expert_sizing(&square(), &expert, Aggregation::Mean).unwrap();
        let max = project_expert_sizing(&square(), &expert, Aggregation::Max).unwrap();
        assert!((density[0] - size(0.25)).abs() < 1e-15);
        assert!(mean[0] < density[0] && density[0] < max[0]);
        // One expert element per current element: its own size, as for the other aggregations.
        assert!((density[1] - size(0.5)).abs() < 1e-15);
        // A current element smaller than the one expert element assigned to it takes the
        // expert's size, not its own.
        let fine = fan([0.3, 0.3]);
        let labels = project_expert_sizing(&fine, &uneven_expert(), Aggregation::Density).unwrap();
        assert_eq!(labels, project_expert_sizing(&fine, &uneven_expert(), Aggregation::Max).unwrap());
    }

    #[test]
    fn expert_midpoints_outside_go_to_the_nearest_element() {
        // The expert also covers [1, 2] × [0, 1]; that triangle (area 0.5) belongs to the current
        // element with the nearest midpoint, the lower-right triangle.
        let expert = Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.0]],
            vec![0, 1, 2, 0, 2, 3, 1, 4, 2],
        )
        .unwrap();
        let max = project_expert_sizing(&square(), &expert, Aggregation::Max).unwrap();
        assert_eq!(max, vec![size(0.5), size(0.5)]);
        let mean = project_expert_sizing(&square(), &expert, Aggregation::Mean).unwrap();
        assert!((mean[0] - size(0.5)).abs() < 1e-15);
    }

    #[test]
    fn elements_without_expert_midpoints_take_the_containing_expert_size() {
        // The fan around (0.3, 0.3) has 4 elements for 3 expert midpoints. Its bottom triangle
        // receives none; its midpoint (0.43, 0.1) lies in the expert's 0.5 triangle although the
        // nearest expert midpoint is that of the 0.2 triangle.
        let labels = project_expert_sizing(&fan([0.3, 0.3]), &uneven_expert(), Aggregation::Mean).unwrap();
        assert_eq!(labels, vec![size(0.5), size(0.3), size(0.5), size(0.2)]);
    }

    #[test]
    fn elements_outside_the_expert_take_the_nearest_expert_size() {
        // The current mesh reaches [1, 2] × [0, 1] beyond the expert: its extra triangle (midpoint
        // (4/3, 1/3)) gets the size of the expert element with the nearest midpoint, (0.8, 1/3).
        let current = Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.0]],
            vec![0, 1, 2, 0, 2, 3, 1, 4, 2],
        )
        .unwrap();
        let labels = project_expert_sizing(&current, &uneven_expert(), Aggregation::Max).unwrap();
        assert_eq!(labels[2], size(0.3));
    }
}
