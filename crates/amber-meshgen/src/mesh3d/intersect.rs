//! Exact intersection tests between closed triangles and the search for intersecting pairs in a
//! triangle surface (an R-tree of triangle bounding boxes).

use std::cmp::Ordering::{self, Equal, Greater, Less};

use rayon::prelude::*;
use rstar::{AABB, RTree, primitives::GeomWithData, primitives::Rectangle};

use super::predicates::{orient2d, orient3d};

type Triangle = [[f64; 3]; 3];

/// Whether two closed triangles share at least one point. Both must be non-degenerate.
///
/// Two triangles intersect iff an edge of one meets the other: if they are not coplanar, each
/// end of the intersection segment lies on an edge of one of them; if they are coplanar, either
/// edges cross or one triangle holds an edge of the other.
pub(crate) fn triangles_intersect(t: &Triangle, u: &Triangle) -> bool {
    (0..3).any(|i| segment_meets_triangle(t[i], t[(i + 1) % 3], u) || segment_meets_triangle(u[i], u[(i + 1) % 3], t))
}

/// Whether the closed segment [p, q] meets the closed triangle `t`.
fn segment_meets_triangle(p: [f64; 3], q: [f64; 3], t: &Triangle) -> bool {
    let (op, oq) = (orient3d(t[0], t[1], t[2], p), orient3d(t[0], t[1], t[2], q));
    match (op, oq) {
        (Equal, Equal) => coplanar_segment_meets_triangle(p, q, t),
        _ if op == oq => false,
        // The segment reaches the triangle's plane: its line must pass inside or on every edge.
        _ => {
            let sides = [0, 1, 2].map(|i| orient3d(p, q, t[i], t[(i + 1) % 3]));
            !(sides.contains(&Greater) && sides.contains(&Less))
        }
    }
}

/// Whether two triangles of a surface (corner indices and positions) meet anywhere besides
/// their shared corners and edge: disjoint triangles must not meet at all; triangles sharing a
/// corner v meet elsewhere iff the edge opposite v in one meets the other (the common part
/// is a segment from v); triangles sharing an edge overlap iff they fold flat onto one side.
pub(crate) fn triangles_overlap(t: [u32; 3], tc: &Triangle, u: [u32; 3], uc: &Triangle) -> bool {
    let shared: Vec<usize> = (0..3).filter(|&k| u.contains(&t[k])).collect();
    let opposite = |x: [u32; 3], xc: &Triangle, k: usize| {
        let j = (0..3).find(|&j| x[j] == t[k]).unwrap_or(0);
        (xc[(j + 1) % 3], xc[(j + 2) % 3])
    };
    match shared[..] {
        [] => triangles_intersect(tc, uc),
        [k] => {
            let ((a, b), (c, d)) = (opposite(t, tc, k), opposite(u, uc, k));
            segment_meets_triangle(a, b, uc) || segment_meets_triangle(c, d, tc)
        }
        [k, l] => {
            let apex = |x: [u32; 3], xc: &Triangle| xc[(0..3).find(|&j| x[j] != t[k] && x[j] != t[l]).unwrap_or(0)];
            let (a, b) = (apex(t, tc), apex(u, uc));
            let [p2, q2, a2, b2] = flatten(tc, [tc[k], tc[l], a, b]);
            orient3d(tc[k], tc[l], a, b) == Equal && orient2d(p2, q2, a2) == orient2d(p2, q2, b2)
        }
        _ => true,
    }
}

/// Drops the coordinate along which the triangle's normal is largest (a projection that keeps
/// the triangle non-degenerate).
fn flatten<const N: usize>(t: &Triangle, points: [[f64; 3]; N]) -> [[f64; 2]; N] {
    let n = normal(t);
    let drop = (0..3).max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(2);
    let (i, j) = ((drop + 1) % 3, (drop + 2) % 3);
    points.map(|x| [x[i], x[j]])
}

/// The coplanar case, in the coordinate plane where the triangle's projection is largest.
fn coplanar_segment_meets_triangle(p: [f64; 3], q: [f64; 3], t: &Triangle) -> bool {
    let [p, q, t0, t1, t2] = flatten(t, [p, q, t[0], t[1], t[2]]);
    let t = [t0, t1, t2];
    point_in_triangle_2d(p, &t)
        || point_in_triangle_2d(q, &t)
        || (0..3).any(|k| segments_meet_2d(p, q, t[k], t[(k + 1) % 3]))
}

fn point_in_triangle_2d(p: [f64; 2], t: &[[f64; 2]; 3]) -> bool {
    let sides = [0, 1, 2].map(|k| orient2d(t[k], t[(k + 1) % 3], p));
    !(sides.contains(&Greater) && sides.contains(&Less))
}

/// Whether the closed segments [a, b] and [c, d] share a point.
fn segments_meet_2d(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orient2d(a, b, c), orient2d(a, b, d));
    let (o3, o4) = (orient2d(c, d, a), orient2d(c, d, b));
    let opposite = |x: Ordering, y: Ordering| x != y && x != Equal && y != Equal;
    if opposite(o1, o2) && opposite(o3, o4) {
        return true;
    }
    // Touching or collinear: an endpoint lies on the other segment.
    let on = |o: Ordering, s: [f64; 2], e: [f64; 2], x: [f64; 2]| {
        o == Equal && (0..2).all(|k| s[k].min(e[k]) <= x[k] && x[k] <= s[k].max(e[k]))
    };
    on(o1, a, b, c) || on(o2, a, b, d) || on(o3, c, d, a) || on(o4, c, d, b)
}

fn normal(t: &Triangle) -> [f64; 3] {
    let u = [0, 1, 2].map(|k| t[1][k] - t[0][k]);
    let v = [0, 1, 2].map(|k| t[2][k] - t[0][k]);
    [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
}

/// The axis-aligned bounding box of a triangle.
pub(crate) fn triangle_box(c: &Triangle) -> AABB<[f64; 3]> {
    let lo = [0, 1, 2].map(|k| c[0][k].min(c[1][k]).min(c[2][k]));
    let hi = [0, 1, 2].map(|k| c[0][k].max(c[1][k]).max(c[2][k]));
    AABB::from_corners(lo, hi)
}

/// An R-tree of triangle bounding boxes, each tagged with the triangle's index. Entries are
/// only added: callers re-insert a triangle whose corners changed and check candidates against
/// its current corners, so stale boxes cost a little time and never hide a triangle.
pub(crate) struct TriangleIndex(RTree<GeomWithData<Rectangle<[f64; 3]>, u32>>);

impl TriangleIndex {
    pub(crate) fn new(boxes: impl Iterator<Item = (u32, AABB<[f64; 3]>)>) -> Self {
        Self(RTree::bulk_load(
            boxes.map(|(t, b)| GeomWithData::new(Rectangle::from_corners(b.lower(), b.upper()), t)).collect(),
        ))
    }

    pub(crate) fn insert(&mut self, t: u32, b: AABB<[f64; 3]>) {
        self.0.insert(GeomWithData::new(Rectangle::from_corners(b.lower(), b.upper()), t));
    }

    /// Indices whose (possibly stale) box meets `b`, each once.
    pub(crate) fn candidates(&self, b: AABB<[f64; 3]>) -> Vec<u32> {
        let mut c: Vec<u32> = self.0.locate_in_envelope_intersecting(b).map(|e| e.data).collect();
        c.sort_unstable();
        c.dedup();
        c
    }
}

/// Every pair (t, u), t < u, sorted, of triangles without a common corner that intersect.
/// Pairs with a common corner are left out: on planar and gently curved regions their exact
/// test is mostly a (costly) proof of coplanarity, and folds between neighbours are what the
/// callers' own orientation checks exclude.
pub(crate) fn intersecting_pairs(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<(usize, usize)> {
    let corners = |t: usize| triangles[t].map(|v| vertices[v as usize]);
    let index = TriangleIndex::new((0..triangles.len()).map(|t| (t as u32, triangle_box(&corners(t)))));
    (0..triangles.len())
        .into_par_iter()
        .flat_map_iter(|t| {
            let tri = corners(t);
            index
                .candidates(triangle_box(&tri))
                .into_iter()
                .map(|u| u as usize)
                .filter(move |&u| u > t && !triangles[u].iter().any(|v| triangles[t].contains(v)))
                .filter(move |&u| triangles_intersect(&tri, &corners(u)))
                .map(move |u| (t, u))
                .collect::<Vec<_>>()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: Triangle = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    fn moved(t: &Triangle, by: [f64; 3]) -> Triangle {
        t.map(|p| [p[0] + by[0], p[1] + by[1], p[2] + by[2]])
    }

    #[test]
    fn crossing_touching_and_separate_triangles() {
        let piercing = [[0.2, 0.2, -1.0], [0.2, 0.2, 1.0], [0.3, 0.9, 0.5]];
        assert!(triangles_intersect(&T, &piercing));
        assert!(triangles_intersect(&piercing, &T));
        // Above the plane: no contact; a corner exactly on T's edge: contact.
        assert!(!triangles_intersect(&T, &moved(&piercing, [0.0, 0.0, 1.5])));
        let touching = [[0.5, 0.0, 0.0], [0.5, -1.0, 1.0], [0.5, -1.0, -1.0]];
        assert!(triangles_intersect(&T, &touching));
        assert!(!triangles_intersect(&T, &moved(&touching, [0.0, -1e-12, 0.0])));
    }

    #[test]
    fn coplanar_triangles() {
        assert!(triangles_intersect(&T, &moved(&T, [0.4, 0.4, 0.0])));
        assert!(!triangles_intersect(&T, &moved(&T, [0.6, 0.6, 0.0])));
        // One inside the other, no edges crossing.
        let small = [[0.1, 0.1, 0.0], [0.3, 0.1, 0.0], [0.1, 0.3, 0.0]];
        assert!(triangles_intersect(&T, &small) && triangles_intersect(&small, &T));
        // Sharing only a corner point, but as distinct vertices.
        assert!(triangles_intersect(&T, &moved(&T, [1.0, 0.0, 0.0])));
    }

    #[test]
    fn neighbours_overlap_only_when_folded_or_pierced() {
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.3, 0.3, 0.0],
            [0.5, 0.5, 1.0],
            [-1.0, 0.5, 1.0],
        ];
        let c = |t: [u32; 3]| t.map(|i| v[i as usize]);
        let pair = |t: [u32; 3], u: [u32; 3]| triangles_overlap(t, &c(t), u, &c(u));
        // Shared edge 1–2: unfolded (apexes 0 and 3 on opposite sides) or folded onto one side.
        assert!(!pair([0, 1, 2], [1, 3, 2]));
        assert!(pair([0, 1, 2], [1, 2, 4]));
        // Shared corner 0: the other triangle rises out of the plane (touching at 0 only), cuts
        // through along its edge 0–3, or lies inside.
        assert!(!pair([0, 1, 2], [0, 5, 6]));
        assert!(pair([0, 1, 2], [0, 5, 3]));
        assert!(pair([0, 1, 2], [0, 4, 3]));
    }

    #[test]
    fn intersecting_pairs_are_found() {
        let vertices = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.2, 0.2, -1.0],
            [0.2, 0.2, 1.0],
            [0.3, 0.9, 0.5],
        ];
        let triangles = vec![[0, 1, 2], [1, 3, 2], [4, 5, 6]];
        assert_eq!(intersecting_pairs(&vertices, &triangles[..2]), []);
        assert_eq!(intersecting_pairs(&vertices, &triangles), [(0, 2)]);
    }
}
