//! Distances from points to a solid's surface and to its feature curves (the edges where two CAD
//! faces meet), the geometric inputs a model of expert meshing reads: an expert refines near
//! holes, bends and thin walls, which an element's own size and volume do not show.

use nalgebra::Vector3;
use rstar::primitives::{GeomWithData, Line};
use rstar::{AABB, PointDistance, RTree, RTreeObject};

use super::surface::Surface;
use crate::ray::{chord, ray_triangle};

/// R-trees over a surface's triangles and its feature curves, for exact nearest-distance queries.
#[derive(Clone, Debug)]
pub struct SurfaceDistance {
    /// Every triangle with the surface's radius of curvature there (see
    /// [`SurfaceDistance::to_surface`]) and its CAD face.
    triangles: RTree<GeomWithData<RefTriangle, (f64, i32)>>,
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
        // The curvature across an edge inside a CAD face: the angle between its two triangles'
        // normals over half the distance, across the edge, between their vertices opposite it
        // (the part along the edge removed, for the long thin triangles along a cylinder's
        // axis): 1/r across a cylinder of radius r cut into strips. A triangle takes the
        // largest of its edges'. Edges between faces are features, not curvature.
        let opposite = |k: usize, a: u32, b: u32| {
            let far = t[k].into_iter().find(|&i| i != a && i != b).unwrap_or(a);
            Vector3::from(v[far as usize])
        };
        let mut curvature = vec![0.0f64; t.len()];
        for ([a, b], [k, l]) in surface.smooth_edges() {
            let angle = unit_normal(corners(&t[k])).dot(&unit_normal(corners(&t[l]))).clamp(-1.0, 1.0).acos();
            let along = (Vector3::from(v[b as usize]) - Vector3::from(v[a as usize])).try_normalize(0.0);
            let apart = opposite(k, a, b) - opposite(l, a, b);
            let apart = along.map_or(apart, |e| apart - e * apart.dot(&e));
            let across = angle / (0.5 * apart.norm());
            if across.is_finite() {
                curvature[k] = curvature[k].max(across);
                curvature[l] = curvature[l].max(across);
            }
        }
        let triangles = (t.iter().zip(&curvature).zip(surface.face_ids()))
            .map(|((tri, &c), &face)| GeomWithData::new(RefTriangle(corners(tri)), (1.0 / c, face)))
            .collect();
        Self { triangles: RTree::bulk_load(triangles), curves: RTree::bulk_load(curves) }
    }

    /// The distance from `p` to the surface and the surface's radius of curvature at the surface
    /// point nearest to `p` (the largest principal curvature's, within a CAD face): infinite on
    /// a flat face.
    pub fn to_surface(&self, p: [f64; 3]) -> (f64, f64) {
        self.triangles
            .nearest_neighbor(p)
            .map_or((f64::INFINITY, f64::INFINITY), |t| (t.distance_2(&p).sqrt(), t.data.0))
    }

    /// The CAD face of the surface point nearest to `p`, or `None` for a surface without
    /// triangles.
    pub fn nearest_face(&self, p: [f64; 3]) -> Option<i32> {
        self.triangles.nearest_neighbor(p).map(|t| t.data.1)
    }

    /// The distance from `p` to the nearest feature curve and the angle between the normals of
    /// the two faces that meet there, or `None` for a surface of one CAD face.
    pub fn to_feature_curve(&self, p: [f64; 3]) -> Option<(f64, f64)> {
        self.curves.nearest_neighbor(p).map(|edge| (edge.distance_2(&p).sqrt(), edge.data))
    }

    /// The thickness of the wall at `p`: the chord through `p` along the normal of the nearest
    /// triangle, from the surface on one side to the surface on the other. Infinite where a ray
    /// leaves without meeting the surface (a point outside, an open surface).
    pub fn wall_thickness(&self, p: [f64; 3]) -> f64 {
        let Some(nearest) = self.triangles.nearest_neighbor(p) else {
            return f64::INFINITY;
        };
        let normal = unit_normal(nearest.geom().0);
        if normal == Vector3::zeros() {
            return f64::INFINITY;
        }
        chord(&self.triangles, p, normal.into(), nearest.distance_2(&p).sqrt(), |t, d, tolerance| {
            ray_triangle(p, d, t.geom().0, tolerance)
        })
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

    /// A closed cylinder of radius 0.2 and height 1 (side, bottom and top as three CAD faces,
    /// 64 long thin triangles around): near the side the radius of curvature is the cylinder's,
    /// near a flat cap infinite.
    #[test]
    fn a_cylinder_has_its_radius_of_curvature() {
        let n = 64u32;
        let ring = |z: f64| {
            (0..n).map(move |k| {
                let angle = std::f64::consts::TAU * f64::from(k) / f64::from(n);
                [0.2 * angle.cos(), 0.2 * angle.sin(), z]
            })
        };
        let mut vertices: Vec<[f64; 3]> = ring(0.0).chain(ring(1.0)).collect();
        vertices.extend([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
        let (mut triangles, mut faces) = (Vec::new(), Vec::new());
        for k in 0..n {
            let (a0, a1, b0, b1) = (k, (k + 1) % n, n + k, n + (k + 1) % n);
            triangles.extend([[a0, a1, b1], [a0, b1, b0], [2 * n, a1, a0], [2 * n + 1, b0, b1]]);
            faces.extend([1, 1, 2, 3]);
        }
        let distance = SurfaceDistance::new(&Surface::new(vertices, triangles, faces).unwrap());
        for p in [[0.15, 0.0, 0.5], [0.0, -0.18, 0.3], [0.1, 0.1, 0.45]] {
            let (_, radius) = distance.to_surface(p);
            assert!((radius - 0.2).abs() < 0.01, "{p:?}: {radius}");
        }
        assert_eq!(distance.to_surface([0.0, 0.0, 0.95]).1, f64::INFINITY);
    }

    /// The unit cube has a CAD face per side: its feature curves are its 12 edges, where faces meet
    /// at right angles.
    #[test]
    fn distances_inside_the_unit_cube() {
        let distance = SurfaceDistance::new(&unit_cube());
        let centre = [0.5, 0.5, 0.5];
        assert!((distance.to_surface(centre).0 - 0.5).abs() < 1e-12);
        let (to_curve, turn) = distance.to_feature_curve(centre).unwrap();
        assert!((to_curve - 0.5 * 2f64.sqrt()).abs() < 1e-12);
        assert!((turn - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let near_an_edge = [0.1, 0.2, 0.5];
        assert!((distance.to_surface(near_an_edge).0 - 0.1).abs() < 1e-12);
        assert!((distance.to_feature_curve(near_an_edge).unwrap().0 - 0.05f64.sqrt()).abs() < 1e-12);
    }

    /// Across the unit cube the wall is 1 thick wherever the chord runs along the nearest face's
    /// normal; outside it no ray meets the surface twice.
    #[test]
    fn the_unit_cube_is_one_thick() {
        let distance = SurfaceDistance::new(&unit_cube());
        for p in [[0.5, 0.5, 0.5], [0.1, 0.2, 0.5], [0.9, 0.3, 0.7], [0.5, 0.02, 0.98]] {
            assert!((distance.wall_thickness(p) - 1.0).abs() < 1e-12, "{p:?}: {}", distance.wall_thickness(p));
        }
        assert_eq!(distance.wall_thickness([2.0, 0.5, 0.5]), f64::INFINITY);
    }
}
