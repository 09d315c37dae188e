//! Point location in a mesh: exact containment through an R-tree of element boxes, with a
//! nearest-midpoint fallback for points outside the mesh.

use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};

use crate::{Mesh, mesh::signed_volume};

/// Relative tolerance of the containment test: a point counts as inside an element when every
/// barycentric coordinate is ≥ −`CONTAINMENT_TOLERANCE`.
pub const CONTAINMENT_TOLERANCE: f64 = 1e-10;

/// Where a query point was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// Inside (or on the boundary of) this element.
    Inside(usize),
    /// Outside the mesh; this element has the nearest midpoint.
    Nearest(usize),
}

impl Location {
    /// The element, however it was found.
    pub fn element(self) -> usize {
        match self {
            Location::Inside(e) | Location::Nearest(e) => e,
        }
    }
}

/// Locates points in a fixed mesh. Build once, query many times (queries are `&self` and can run
/// in parallel).
pub struct PointLocator<'m, const D: usize> {
    mesh: &'m Mesh<D>,
    boxes: RTree<GeomWithData<Rectangle<[f64; D]>, u32>>,
    midpoints: RTree<GeomWithData<[f64; D], u32>>,
    /// Each element's signed volume, the denominator of its barycentric coordinates, computed
    /// once rather than per candidate (most candidates are rejected after one or two
    /// coordinates).
    volumes: Vec<f64>,
}

impl<'m, const D: usize> PointLocator<'m, D> {
    /// Indexes the elements of `mesh`.
    pub fn new(mesh: &'m Mesh<D>) -> Self {
        let boxes = (0..mesh.num_elements())
            .map(|e| {
                let mut lo = [f64::INFINITY; D];
                let mut hi = [f64::NEG_INFINITY; D];
                for &v in mesh.element(e) {
                    let p = mesh.vertices()[v as usize];
                    for k in 0..D {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                // Inflate so that points within the containment tolerance of a facet find the box.
                let pad = (0..D).map(|k| hi[k] - lo[k]).fold(0.0, f64::max) * CONTAINMENT_TOLERANCE * 4.0;
                GeomWithData::new(Rectangle::from_corners(lo.map(|x| x - pad), hi.map(|x| x + pad)), e as u32)
            })
            .collect();
        let midpoints = mesh.midpoints().into_iter().enumerate().map(|(e, m)| GeomWithData::new(m, e as u32)).collect();
        let volumes = (0..mesh.num_elements()).map(|e| signed_volume::<D>(mesh.vertices(), mesh.element(e))).collect();
        Self { mesh, boxes: RTree::bulk_load(boxes), midpoints: RTree::bulk_load(midpoints), volumes }
    }

    /// The mesh being queried.
    pub fn mesh(&self) -> &'m Mesh<D> {
        self.mesh
    }

    /// The element containing `p`, if any. On shared facets the element in which `p` lies
    /// deepest wins (ties: the lower index), so the answer is deterministic.
    pub fn locate(&self, p: [f64; D]) -> Option<usize> {
        let mut best: Option<(f64, usize)> = None;
        for candidate in self.boxes.locate_in_envelope_intersecting(AABB::from_point(p)) {
            let e = candidate.data as usize;
            if let Some(depth) = self.containment_depth(e, p) {
                let better = match best {
                    None => true,
                    Some((d, b)) => depth > d || (depth == d && e < b),
                };
                if better {
                    best = Some((depth, e));
                }
            }
        }
        best.map(|(_, e)| e)
    }

    /// The element containing `p`, or else the element whose midpoint is nearest.
    pub fn locate_or_nearest(&self, p: [f64; D]) -> Location {
        match self.locate(p) {
            Some(e) => Location::Inside(e),
            None => Location::Nearest(self.nearest_midpoint(p)),
        }
    }

    /// The element whose midpoint is nearest to `p` (a [`Mesh`] has at least one element).
    pub fn nearest_midpoint(&self, p: [f64; D]) -> usize {
        self.midpoints.nearest_neighbor(p).expect("Mesh::new refuses meshes without elements").data as usize
    }

    /// The smallest barycentric coordinate of `p` in element `e`, or `None` as soon as one is
    /// below −[`CONTAINMENT_TOLERANCE`]: most candidates of a box query are outside, and how far
    /// does not matter.
    fn containment_depth(&self, e: usize, p: [f64; D]) -> Option<f64> {
        let cell = self.mesh.element(e);
        let vertices = self.mesh.vertices();
        let volume = self.volumes[e];
        let mut local: [[f64; D]; 4] = [[0.0; D]; 4];
        for (j, &v) in cell.iter().enumerate() {
            local[j] = vertices[v as usize];
        }
        let ids = [0u32, 1, 2, 3];
        let mut depth = f64::INFINITY;
        for i in 0..=D {
            let mut q = local;
            q[i] = p;
            let coordinate = signed_volume::<D>(&q, &ids[..=D]) / volume;
            if coordinate < -CONTAINMENT_TOLERANCE {
                return None;
            }
            depth = depth.min(coordinate);
        }
        Some(depth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Mesh2, Mesh3};

    fn square() -> Mesh2 {
        Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap()
    }

    #[test]
    fn inside_points_are_found_exactly() {
        let m = square();
        let loc = PointLocator::new(&m);
        assert_eq!(loc.locate([0.9, 0.1]), Some(0));
        assert_eq!(loc.locate([0.1, 0.9]), Some(1));
        // A vertex belongs to both; the tie goes to the lower index.
        assert_eq!(loc.locate([0.0, 0.0]), Some(0));
        // A point on the shared diagonal, within tolerance.
        assert!(loc.locate([0.5, 0.5 + 1e-13]).is_some());
    }

    #[test]
    fn outside_points_fall_back_to_the_nearest_midpoint() {
        let m = square();
        let loc = PointLocator::new(&m);
        assert_eq!(loc.locate([2.0, 0.0]), None);
        assert_eq!(loc.locate_or_nearest([2.0, 0.0]), Location::Nearest(0));
        assert_eq!(loc.locate_or_nearest([-1.0, 2.0]), Location::Nearest(1));
    }

    #[test]
    fn tetrahedra_are_located() {
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
        let m = Mesh3::new_reoriented(v, vec![0, 1, 2, 3, 0, 1, 2, 4]).unwrap();
        let loc = PointLocator::new(&m);
        assert_eq!(loc.locate([0.1, 0.1, 0.1]), Some(0));
        assert_eq!(loc.locate([0.1, 0.1, -0.1]), Some(1));
        assert_eq!(loc.locate([1.0, 1.0, 1.0]), None);
    }
}
