//! Distances from points to a solid's surface and to its feature curves (the edges where two CAD
//! faces meet), the geometric inputs a model of expert meshing reads: an expert refines near
//! holes, bends and thin walls, which an element's own size and volume do not show.

use nalgebra::Vector3;
use rstar::primitives::{GeomWithData, Line};
use rstar::{AABB, PointDistance, RTree, RTreeObject};

use super::surface::Surface;

/// R-trees over a surface's triangles and its feature curves, for exact nearest-distance queries.
#[derive(Clone, Debug)]
pub struct SurfaceDistance {
    triangles: RTree<RefTriangle>,
    /// The edges between two different CAD faces, each with the angle between its two faces'
    /// normals (0: the faces continue tangentially, π/2: a right-angled bend).
    curves: RTree<GeomWithData<Line<[f64; 3]>, f64>>,
}

impl SurfaceDistance {
    /// Indexes `surface` (any closed surface whose triangles carry CAD face ids).
    pub fn new(surface: &Surface) -> Self {
        let (v, t) = (surface.vertices(), surface.triangles());
        let corners = |tri: &[u32; 3]| tri.map(|i| v[i as usize]);
        let curves = surface
            .feature_edges()
            .map(|([a, b], [k, l])| {
                let turn = unit_normal(corners(&t[k])).dot(&unit_normal(corners(&t[l]))).clamp(-1.0, 1.0).acos();
                GeomWithData::new(Line::new(v[a as usize], v[b as usize]), turn)
            })
            .collect();
        Self {
            triangles: RTree::bulk_load(t.iter().map(|tri| RefTriangle(corners(tri))).collect()),
            curves: RTree::bulk_load(curves),
        }
    }

    /// The distance from `p` to the surface.
    pub fn to_surface(&self, p: [f64; 3]) -> f64 {
        self.triangles.nearest_neighbor(p).map_or(f64::INFINITY, |t| t.distance_2(&p).sqrt())
    }

    /// The distance from `p` to the nearest feature curve and the angle between the normals of
    /// the two faces that meet there, or `None` for a surface of one CAD face.
    pub fn to_feature_curve(&self, p: [f64; 3]) -> Option<(f64, f64)> {
        self.curves.nearest_neighbor(p).map(|edge| (edge.distance_2(&p).sqrt(), edge.data))
    }
}

/// The unit normal of a triangle (zero for a degenerate one).
fn unit_normal([a, b, c]: [[f64; 3]; 3]) -> Vector3<f64> {
    let [a, b, c] = [a, b, c].map(Vector3::from);
    (b - a).cross(&(c - a)).try_normalize(0.0).unwrap_or_else(Vector3::zeros)
}

/// A reference triangle in an R-tree that answers distance queries exactly.
#[derive(Clone, Debug)]
pub(crate) struct RefTriangle(pub(crate) [[f64; 3]; 3]);

impl RefTriangle {
    /// Closest point of the triangle to `p` (Ericson, Real-Time Collision Detection §5.1.5).
    pub(crate) fn closest(&self, p: [f64; 3]) -> [f64; 3] {
        let [a, b, c] = self.0.map(Vector3::from);
        let p = Vector3::from(p);
        let (ab, ac, ap) = (b - a, c - a, p - a);
        let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return a.into();
        }
        let bp = p - b;
        let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
        if d3 >= 0.0 && d4 <= d3 {
            return b.into();
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return (a + ab * (d1 / (d1 - d3))).into();
        }
        let cp = p - c;
        let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
        if d6 >= 0.0 && d5 <= d6 {
            return c.into();
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return (a + ac * (d2 / (d2 - d6))).into();
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            return (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))).into();
        }
        let denom = 1.0 / (va + vb + vc);
        (a + ab * (vb * denom) + ac * (vc * denom)).into()
    }
}

impl RTreeObject for RefTriangle {
    type Envelope = AABB<[f64; 3]>;

    fn envelope(&self) -> Self::Envelope {
        AABB::from_points(self.0.iter())
    }
}

impl PointDistance for RefTriangle {
    fn distance_2(&self, p: &[f64; 3]) -> f64 {
        (Vector3::from(self.closest(*p)) - Vector3::from(*p)).norm_squared()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh3d::unit_cube;

    #[test]
    fn closest_point_on_a_triangle() {
        let t = RefTriangle([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]]);
        assert_eq!(t.closest([0.5, 0.5, 3.0]), [0.5, 0.5, 0.0]);
        assert_eq!(t.closest([-1.0, -1.0, 1.0]), [0.0, 0.0, 0.0]);
        assert_eq!(t.closest([3.0, -1.0, 0.0]), [2.0, 0.0, 0.0]);
        assert_eq!(t.closest([1.0, -5.0, 0.0]), [1.0, 0.0, 0.0]);
        assert_eq!(t.closest([2.0, 2.0, 0.0]), [1.0, 1.0, 0.0]);
        assert_eq!(t.distance_2(&[0.5, 0.5, 3.0]), 9.0);
    }

    /// The unit cube has a CAD face per side: its feature curves are its 12 edges, where faces meet
    /// at right angles.
    #[test]
    fn distances_inside_the_unit_cube() {
        let distance = SurfaceDistance::new(&unit_cube());
        let centre = [0.5, 0.5, 0.5];
        assert!((distance.to_surface(centre) - 0.5).abs() < 1e-12);
        let (to_curve, turn) = distance.to_feature_curve(centre).unwrap();
        assert!((to_curve - 0.5 * 2f64.sqrt()).abs() < 1e-12);
        assert!((turn - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let near_an_edge = [0.1, 0.2, 0.5];
        assert!((distance.to_surface(near_an_edge) - 0.1).abs() < 1e-12);
        assert!((distance.to_feature_curve(near_an_edge).unwrap().0 - 0.05f64.sqrt()).abs() < 1e-12);
    }
}
