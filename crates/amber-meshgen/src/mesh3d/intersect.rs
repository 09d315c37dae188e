//! Exact intersection tests between closed triangles and the search for intersecting pairs in a
//! triangle surface (an R-tree of triangle bounding boxes).

use std::cmp::Ordering::{self, Equal, Greater, Less};

use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use nalgebra::Vector3;
use rstar::{AABB, Envelope};

use crate::predicates::{orient2d, orient3d};

type Triangle = [[f64; 3]; 3];

/// Whether two closed triangles share at least one point. Both must be non-degenerate.
///
/// Two triangles intersect iff an edge of one meets the other: if they are not coplanar, each
/// end of the intersection segment lies on an edge of one of them; if they are coplanar, either
/// edges cross or one triangle holds an edge of the other.
pub(crate) fn triangles_intersect(t: &Triangle, u: &Triangle) -> bool {
    !clearly_apart(t, u)
        && (0..3)
            .any(|i| segment_meets_triangle(t[i], t[(i + 1) % 3], u) || segment_meets_triangle(u[i], u[(i + 1) % 3], t))
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
            (!clearly_apart(&[a, b], uc) && segment_meets_triangle(a, b, uc))
                || (!clearly_apart(&[c, d], tc) && segment_meets_triangle(c, d, tc))
        }
        [k, l] => {
            let apex = |x: [u32; 3], xc: &Triangle| xc[(0..3).find(|&j| x[j] != t[k] && x[j] != t[l]).unwrap_or(0)];
            let (a, b) = (apex(t, tc), apex(u, uc));
            let [p2, q2, a2, b2] = flatten(tc, [tc[k], tc[l], a, b]);
            // The side test first: it settles the common unfolded case without the (for
            // coplanar neighbours always exact, hence slow) orientation test.
            orient2d(p2, q2, a2) == orient2d(p2, q2, b2) && orient3d(tc[k], tc[l], a, b) == Equal
        }
        _ => true,
    }
}

/// A floating-point separating-axis test with a safety margin: `true` proves that the convex
/// hulls of `p` and `q` (segments or triangles) are disjoint; `false` proves nothing. It spares
/// the exact predicates the nearly coplanar pairs of a flat surface, where their floating-point
/// filters always fail. Axes: the normals of the triangles, the cross products of all edge
/// pairs, and each normal crossed with every edge (the in-plane separations).
fn clearly_apart(p: &[[f64; 3]], q: &[[f64; 3]]) -> bool {
    let edges = |x: &[[f64; 3]]| -> Vec<Vector3<f64>> {
        let edge = |i: usize| Vector3::from(x[(i + 1) % x.len()]) - Vector3::from(x[i]);
        (0..x.len()).filter(|&i| x.len() > 2 || i == 0).map(edge).collect()
    };
    let (ep, eq) = (edges(p), edges(q));
    let scale = p.iter().chain(q).flatten().fold(1.0f64, |m, &c| m.max(c.abs()));
    let separates = |axis: Vector3<f64>| {
        let length = axis.norm();
        if length == 0.0 || !length.is_finite() {
            return false;
        }
        let range = |x: &[[f64; 3]]| {
            x.iter()
                .map(|&v| axis.dot(&Vector3::from(v)))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)))
        };
        let ((plo, phi), (qlo, qhi)) = (range(p), range(q));
        // Rounding in the dot products is a few ulps of length × scale; 1e-10 is far above it.
        let margin = 1e-10 * length * scale;
        plo > qhi + margin || qlo > phi + margin
    };
    let normals: Vec<Vector3<f64>> =
        [(p, &ep), (q, &eq)].iter().filter(|(x, _)| x.len() == 3).map(|(_, e)| e[0].cross(&e[1])).collect();
    normals.iter().any(|&n| separates(n))
        || ep.iter().any(|a| eq.iter().any(|b| separates(a.cross(b))))
        || normals.iter().any(|n| ep.iter().chain(&eq).any(|e| separates(n.cross(e))))
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

fn normal(t: &Triangle) -> Vector3<f64> {
    let [a, b, c] = t.map(Vector3::from);
    (b - a).cross(&(c - a))
}

/// The axis-aligned bounding box of a triangle.
pub(crate) fn triangle_box(c: &Triangle) -> AABB<[f64; 3]> {
    let lo = [0, 1, 2].map(|k| c[0][k].min(c[1][k]).min(c[2][k]));
    let hi = [0, 1, 2].map(|k| c[0][k].max(c[1][k]).max(c[2][k]));
    AABB::from_corners(lo, hi)
}

/// A uniform grid of triangle bounding boxes (cells twice as large as the mean box, hashed),
/// holding each triangle's latest box. Re-inserting a triangle whose corners changed records
/// its new box and cells; the old cells keep listing it, which costs a little time and never
/// hides a triangle (candidates are filtered by the latest box).
pub(crate) struct TriangleIndex {
    cell: f64,
    boxes: Vec<Option<AABB<[f64; 3]>>>,
    cells: HashMap<[i64; 3], Vec<u32>, BuildHasherDefault<CellHasher>>,
}

impl TriangleIndex {
    pub(crate) fn new(boxes: impl Iterator<Item = (u32, AABB<[f64; 3]>)>) -> Self {
        let boxes: Vec<(u32, AABB<[f64; 3]>)> = boxes.collect();
        let extent = |b: &AABB<[f64; 3]>| (0..3).map(|k| b.upper()[k] - b.lower()[k]).fold(0.0, f64::max);
        let mean = boxes.iter().map(|(_, b)| extent(b)).sum::<f64>() / boxes.len().max(1) as f64;
        // Twice the mean: most boxes then touch at most two cells per axis, also after the
        // remesher has made triangles larger.
        let cell = if mean.is_finite() && mean > 0.0 { 2.0 * mean } else { 1.0 };
        let mut index = Self { cell, boxes: Vec::new(), cells: HashMap::default() };
        index.cells.reserve(boxes.len());
        boxes.into_iter().for_each(|(t, b)| index.insert(t, b));
        index
    }

    /// The cells a box covers, as an inclusive index range per axis.
    fn range(&self, b: &AABB<[f64; 3]>) -> ([i64; 3], [i64; 3]) {
        let cell = |x: f64| (x / self.cell).floor() as i64;
        (b.lower().map(cell), b.upper().map(cell))
    }

    pub(crate) fn insert(&mut self, t: u32, b: AABB<[f64; 3]>) {
        if self.boxes.len() <= t as usize {
            self.boxes.resize(t as usize + 1, None);
        }
        self.boxes[t as usize] = Some(b);
        let (lo, hi) = self.range(&b);
        for i in lo[0]..=hi[0] {
            for j in lo[1]..=hi[1] {
                for k in lo[2]..=hi[2] {
                    let cell = self.cells.entry([i, j, k]).or_default();
                    if cell.last() != Some(&t) {
                        cell.push(t);
                    }
                }
            }
        }
    }

    /// Indices whose latest box meets `b`, each once, sorted.
    pub(crate) fn candidates(&self, b: AABB<[f64; 3]>) -> Vec<u32> {
        let (lo, hi) = self.range(&b);
        let mut c = Vec::new();
        for i in lo[0]..=hi[0] {
            for j in lo[1]..=hi[1] {
                for k in lo[2]..=hi[2] {
                    if let Some(entries) = self.cells.get(&[i, j, k]) {
                        c.extend(
                            entries
                                .iter()
                                .copied()
                                .filter(|&t| self.boxes[t as usize].is_some_and(|e| e.intersects(&b))),
                        );
                    }
                }
            }
        }
        c.sort_unstable();
        c.dedup();
        c
    }
}

/// A multiplicative hash of grid cell indices (the default SipHash costs more than the
/// lookups it serves).
#[derive(Default)]
pub(crate) struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        bytes.iter().for_each(|&b| self.write_u64(b as u64));
    }

    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
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
