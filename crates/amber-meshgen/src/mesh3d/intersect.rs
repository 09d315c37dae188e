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

/// The coplanar case, in the coordinate plane where the triangle's projection is largest.
fn coplanar_segment_meets_triangle(p: [f64; 3], q: [f64; 3], t: &Triangle) -> bool {
    let n = normal(t);
    let drop = (0..3).max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs())).unwrap_or(2);
    let (i, j) = ((drop + 1) % 3, (drop + 2) % 3);
    let flat = |x: [f64; 3]| [x[i], x[j]];
    let (p, q, t) = (flat(p), flat(q), t.map(flat));
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

/// The first pair (by the lower index, then the higher) of triangles that intersect without
/// sharing a vertex. Triangles that share a vertex are not tested: in a closed manifold surface
/// they meet at that vertex or edge by construction.
pub(crate) fn first_intersecting_pair(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Option<(usize, usize)> {
    let corners = |t: usize| triangles[t].map(|v| vertices[v as usize]);
    let boxes: Vec<AABB<[f64; 3]>> = (0..triangles.len())
        .map(|t| {
            let c = corners(t);
            let lo = [0, 1, 2].map(|k| c[0][k].min(c[1][k]).min(c[2][k]));
            let hi = [0, 1, 2].map(|k| c[0][k].max(c[1][k]).max(c[2][k]));
            AABB::from_corners(lo, hi)
        })
        .collect();
    let tree = RTree::bulk_load(
        boxes.iter().enumerate().map(|(t, b)| GeomWithData::new(Rectangle::from_corners(b.lower(), b.upper()), t)).collect(),
    );
    boxes.par_iter().enumerate().find_map_first(|(t, b)| {
        tree.locate_in_envelope_intersecting(*b)
            .map(|other| other.data)
            .filter(|&u| u > t && !triangles[u].iter().any(|v| triangles[t].contains(v)))
            .filter(|&u| triangles_intersect(&corners(t), &corners(u)))
            .min()
            .map(|u| (t, u))
    })
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
    fn pairs_sharing_a_vertex_are_skipped_and_others_found() {
        let vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.2, 0.2, -1.0], [0.2, 0.2, 1.0], [0.3, 0.9, 0.5]];
        let triangles = vec![[0, 1, 2], [1, 3, 2], [4, 5, 6]];
        assert_eq!(first_intersecting_pair(&vertices, &triangles[..2]), None);
        assert_eq!(first_intersecting_pair(&vertices, &triangles), Some((0, 2)));
    }
}
