//! Ray casts against the boundaries indexed in R-trees: how far a point's wall extends along a
//! direction, for the wall-thickness input.

use rstar::{AABB, Point, RTree, RTreeObject, SelectionFunction};

/// Selects the objects whose bounding box meets the segment `origin + t · direction`,
/// t ∈ [0, `length`] (the slab test).
struct SegmentBoxes<const D: usize> {
    origin: [f64; D],
    direction: [f64; D],
    length: f64,
}

impl<const D: usize> SegmentBoxes<D> {
    fn meets(&self, envelope: &AABB<[f64; D]>) -> bool {
        let (lo, hi) = (envelope.lower(), envelope.upper());
        let (mut enter, mut leave) = (0.0f64, self.length);
        for k in 0..D {
            let (o, d) = (self.origin[k], self.direction[k]);
            if d == 0.0 {
                if o < lo[k] || o > hi[k] {
                    return false;
                }
                continue;
            }
            let (a, b) = ((lo[k] - o) / d, (hi[k] - o) / d);
            enter = enter.max(a.min(b));
            leave = leave.min(a.max(b));
            if enter > leave {
                return false;
            }
        }
        true
    }
}

impl<const D: usize, T> SelectionFunction<T> for SegmentBoxes<D>
where
    [f64; D]: Point<Scalar = f64>,
    T: RTreeObject<Envelope = AABB<[f64; D]>>,
{
    fn should_unpack_parent(&self, envelope: &AABB<[f64; D]>) -> bool {
        self.meets(envelope)
    }

    fn should_unpack_leaf(&self, leaf: &T) -> bool {
        self.meets(&leaf.envelope())
    }
}

/// The smallest t > 0 at which the ray `origin + t · direction` (a unit `direction`) meets an
/// object of `tree`, by `hit` (an object's exact t, if the ray meets it), up to `limit`.
/// Segments of growing length, starting at `start`, keep the search near the origin: walls are
/// usually much closer than `limit`.
fn first_hit<const D: usize, T>(
    tree: &RTree<T>,
    origin: [f64; D],
    direction: [f64; D],
    start: f64,
    limit: f64,
    hit: impl Fn(&T) -> Option<f64>,
) -> Option<f64>
where
    [f64; D]: Point<Scalar = f64>,
    T: RTreeObject<Envelope = AABB<[f64; D]>>,
{
    let mut length = start.min(limit);
    loop {
        let segment = SegmentBoxes { origin, direction, length };
        let nearest =
            tree.locate_with_selection_function(segment).filter_map(&hit).filter(|&t| t <= length).reduce(f64::min);
        if nearest.is_some() || length >= limit {
            return nearest;
        }
        length = (2.0 * length).min(limit);
    }
}

/// The chord through `p` along the unit `normal`: the distance to the first object of `tree`
/// ahead plus the first behind, by `hit` (an object's exact t along a direction, past a
/// tolerance); infinite where a ray meets nothing. `near` is the distance from `p` to the
/// nearest object, which the ray towards it meets at about that distance.
pub(crate) fn chord<const D: usize, T>(
    tree: &RTree<T>,
    p: [f64; D],
    normal: [f64; D],
    near: f64,
    hit: impl Fn(&T, [f64; D], f64) -> Option<f64>,
) -> f64
where
    [f64; D]: Point<Scalar = f64>,
    T: RTreeObject<Envelope = AABB<[f64; D]>>,
{
    let envelope = tree.root().envelope();
    let (lo, hi) = (envelope.lower(), envelope.upper());
    let limit = (0..D).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    if limit == 0.0 {
        return f64::INFINITY;
    }
    let start = 2.0 * near + 1e-6 * limit;
    let along = |d: [f64; D]| first_hit(tree, p, d, start, limit, |object| hit(object, d, 1e-12 * limit));
    match (along(normal), along(normal.map(|x| -x))) {
        (Some(ahead), Some(behind)) => ahead + behind,
        _ => f64::INFINITY,
    }
}

/// The t > `tolerance` at which the ray `origin + t · direction` crosses the segment `[a, b]`
/// (2D), if it does.
pub(crate) fn ray_segment(origin: [f64; 2], direction: [f64; 2], [a, b]: [[f64; 2]; 2], tolerance: f64) -> Option<f64> {
    let cross = |u: [f64; 2], v: [f64; 2]| u[0] * v[1] - u[1] * v[0];
    let edge = [b[0] - a[0], b[1] - a[1]];
    let denominator = cross(direction, edge);
    if denominator == 0.0 {
        return None;
    }
    let to_a = [a[0] - origin[0], a[1] - origin[1]];
    let t = cross(to_a, edge) / denominator;
    let s = cross(to_a, direction) / denominator;
    (t > tolerance && (0.0..=1.0).contains(&s)).then_some(t)
}

/// The t > `tolerance` at which the ray `origin + t · direction` crosses the triangle `[a, b, c]`
/// (Möller–Trumbore), if it does.
pub(crate) fn ray_triangle(
    origin: [f64; 3],
    direction: [f64; 3],
    [a, b, c]: [[f64; 3]; 3],
    tolerance: f64,
) -> Option<f64> {
    use nalgebra::Vector3;
    let [a, b, c, o, d] = [a, b, c, origin, direction].map(Vector3::from);
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(&e2);
    let determinant = e1.dot(&p);
    if determinant == 0.0 {
        return None;
    }
    let s = o - a;
    let u = s.dot(&p) / determinant;
    let q = s.cross(&e1);
    let v = d.dot(&q) / determinant;
    let t = e2.dot(&q) / determinant;
    (t > tolerance && u >= 0.0 && v >= 0.0 && u + v <= 1.0).then_some(t)
}

#[cfg(test)]
mod tests {
    use rstar::primitives::Line;

    use super::*;

    #[test]
    fn rays_cross_segments_and_triangles_ahead_only() {
        let edge = [[1.0, -1.0], [1.0, 1.0]];
        assert_eq!(ray_segment([0.0, 0.0], [1.0, 0.0], edge, 0.0), Some(1.0));
        assert_eq!(ray_segment([0.0, 0.0], [-1.0, 0.0], edge, 0.0), None);
        assert_eq!(ray_segment([0.0, 2.0], [1.0, 0.0], edge, 0.0), None);
        assert_eq!(ray_segment([0.0, 0.0], [0.0, 1.0], edge, 0.0), None, "parallel");
        let triangle = [[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.0]];
        assert_eq!(ray_triangle([0.2, 0.2, 0.0], [0.0, 0.0, 1.0], triangle, 0.0), Some(2.0));
        assert_eq!(ray_triangle([0.2, 0.2, 0.0], [0.0, 0.0, -1.0], triangle, 0.0), None);
        assert_eq!(ray_triangle([0.8, 0.8, 0.0], [0.0, 0.0, 1.0], triangle, 0.0), None);
        assert_eq!(ray_triangle([0.2, 0.2, 2.0], [0.0, 0.0, 1.0], triangle, 1e-9), None, "on it");
    }

    /// Ten parallel walls at x = 1, …, 10: the first hit is the nearest wall ahead, however short
    /// the first segment, and nothing lies beyond the limit.
    #[test]
    fn the_first_hit_is_the_nearest_wall_ahead() {
        let walls: Vec<Line<[f64; 2]>> =
            (1..=10).map(|x| Line::new([f64::from(x), -1.0], [f64::from(x), 1.0])).collect();
        let tree = RTree::bulk_load(walls);
        let hit = |l: &Line<[f64; 2]>| ray_segment([0.5, 0.0], [1.0, 0.0], [l.from, l.to], 0.0);
        assert_eq!(first_hit(&tree, [0.5, 0.0], [1.0, 0.0], 0.01, 100.0, hit), Some(0.5));
        let from_6 = |l: &Line<[f64; 2]>| ray_segment([6.5, 0.0], [-1.0, 0.0], [l.from, l.to], 0.0);
        assert_eq!(first_hit(&tree, [6.5, 0.0], [-1.0, 0.0], 0.01, 100.0, from_6), Some(0.5));
        let beyond = |l: &Line<[f64; 2]>| ray_segment([10.5, 0.0], [1.0, 0.0], [l.from, l.to], 0.0);
        assert_eq!(first_hit(&tree, [10.5, 0.0], [1.0, 0.0], 0.01, 100.0, beyond), None);
        let off = |l: &Line<[f64; 2]>| ray_segment([0.5, 5.0], [1.0, 0.0], [l.from, l.to], 0.0);
        assert_eq!(first_hit(&tree, [0.5, 5.0], [1.0, 0.0], 0.01, 100.0, off), None);
    }
}
