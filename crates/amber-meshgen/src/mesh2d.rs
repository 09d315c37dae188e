//! The 2D sizing-field mesh generator (spec §2) on spade's constrained Delaunay triangulation.
//!
//! 1. Every boundary edge is split into pieces of equal ∫ds/h, never longer than the field asks.
//! 2. Delaunay refinement: a triangle whose circumradius exceeds `size_factor`·h(centroid), or
//!    whose smallest angle is below `min_angle_deg`, gets its circumcentre inserted. A
//!    circumcentre that encroaches a boundary segment (lies in its diametral circle) or falls
//!    outside the domain splits that segment at its midpoint instead (Ruppert).
//! 3. Quality-guarded Laplacian smoothing of interior vertices (a move is kept only if the
//!    smallest angle of the vertex's star does not drop).
//! 4. Edge flips restore the constrained Delaunay property the smoothing broke (Lawson): the
//!    smoothed mesh is still a valid triangulation of the domain, so flipping every edge whose
//!    opposite vertex lies in the other triangle's circumcircle ends at the constrained
//!    Delaunay triangulation of the smoothed vertices, without triangulating them anew.

use std::cmp::Ordering;
use std::collections::VecDeque;

use amber_mesh::{Mesh2, VertexElements};
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{
    ConstrainedDelaunayTriangulation, Intersection, LineIntersectionIterator, Point2, PositionInTriangulation,
    Triangulation,
};

use crate::predicates::incircle;
use crate::{ConstantSize, MeshgenError, PolygonDomain, SizingField};

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// Knobs of the 2D generator.
#[derive(Clone, Debug)]
pub struct Mesh2dParams {
    /// Refuse to build meshes with more triangles than this.
    pub max_elements: usize,
    /// A triangle is refined while its circumradius exceeds `size_factor`·h. Calibrated so that
    /// element sizes (spec §0) centre on h after smoothing.
    pub size_factor: f64,
    /// Triangles with a smaller angle are refined (Ruppert; terminates for ≤ ~30°), unless
    /// their shortest edge is already below `quality_floor` times the smallest target size at
    /// their corners and centroid: features of the geometry smaller than the field asks for
    /// (a short boundary edge in a coarse mesh) are then kept rather than refined around, as
    /// gmsh does.
    pub min_angle_deg: f64,
    /// See `min_angle_deg`.
    pub quality_floor: f64,
    /// Quality-guarded Laplacian smoothing passes.
    pub smoothing_passes: usize,
}

impl Default for Mesh2dParams {
    fn default() -> Self {
        Self {
            max_elements: 5_000_000,
            size_factor: 0.78,
            min_angle_deg: 25.0,
            quality_floor: 0.5,
            smoothing_passes: 2,
        }
    }
}

impl Mesh2dParams {
    /// Sets the element cap.
    pub fn with_max_elements(mut self, max_elements: usize) -> Self {
        self.max_elements = max_elements;
        self
    }
}

/// Meshes `domain` with triangles whose edge lengths follow `field`.
pub fn generate_2d<F: SizingField<2> + ?Sized>(
    domain: &PolygonDomain,
    field: &F,
    params: &Mesh2dParams,
) -> Result<Mesh2, MeshgenError> {
    let size = |p: [f64; 2]| {
        let h = field.size_at(p);
        if h.is_finite() && h > 0.0 { Ok(h) } else { Err(MeshgenError::InvalidSize { at: p.to_vec(), value: h }) }
    };
    // A field over the cap is refused before any work (once one size is known to be valid);
    // 2× leaves room for the estimate's error.
    size(domain.outer()[0])?;
    if field.estimated_elements(domain.area()).is_some_and(|n| !n.is_finite() || n > 2.0 * params.max_elements as f64) {
        return Err(MeshgenError::TooManyElements { cap: params.max_elements });
    }
    let (points, segments) = discretise_boundary(domain, &size, params.max_elements)?;
    let mut cdt = bulk_load(points, segments)?;
    let side = refine(&mut cdt, &size, params)?;
    let Exported { vertices, mut triangles, mut neighbours, segments } = export(&cdt, &side);
    drop(cdt);
    // Spatially coherent numbering: smoothing, the flips and every consumer of the mesh (FEM
    // assembly, graphs) touch neighbours that are near in memory.
    let (mut vertices, segments) = morton_order(vertices, &mut triangles, segments);
    smooth(&mut vertices, &triangles, &segments, params.smoothing_passes);
    restore_delaunay(&vertices, &mut triangles, &mut neighbours);
    Ok(Mesh2::new(vertices, triangles_in_vertex_order(triangles))?)
}

/// A mesh of `domain` with uniform target size `size` (e.g. the initial mesh M⁰, spec §1).
pub fn uniform_mesh_2d(domain: &PolygonDomain, size: f64, params: &Mesh2dParams) -> Result<Mesh2, MeshgenError> {
    generate_2d(domain, &ConstantSize(size), params)
}

/// The boundary's points and the segments between them (indices into the points).
type BoundarySegments = (Vec<[f64; 2]>, Vec<[usize; 2]>);

/// Splits every boundary edge into `ceil(∫ds/h)` pieces of equal ∫ds/h (never longer than the
/// field asks, as gmsh does). Returns the points and the boundary segments between them.
fn discretise_boundary(
    domain: &PolygonDomain,
    size: &impl Fn([f64; 2]) -> Result<f64, MeshgenError>,
    max_elements: usize,
) -> Result<BoundarySegments, MeshgenError> {
    let mut points = Vec::new();
    let mut segments = Vec::new();
    let mut samples: Vec<(f64, f64)> = Vec::new();
    for ring in domain.rings() {
        let first = points.len();
        for i in 0..ring.len() {
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            let at = |t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            let length = (b[0] - a[0]).hypot(b[1] - a[1]);
            // Cumulative ∫ds/h by the midpoint rule, steps of a quarter of the local size.
            samples.clear();
            samples.push((0.0, 0.0));
            let (mut t, mut integral) = (0.0, 0.0);
            while t < 1.0 {
                let dt = (0.25 * size(at(t))? / length).min(1.0 - t);
                integral += dt * length / size(at(t + 0.5 * dt))?;
                t += dt;
                samples.push((t, integral));
                // A step too small to advance t (a size far below the edge length) counts as
                // over the cap too: the loop could not end.
                if !integral.is_finite() || integral > max_elements as f64 || dt <= 0.0 {
                    return Err(MeshgenError::TooManyElements { cap: max_elements });
                }
            }
            let pieces = ((integral - 1e-9).ceil() as usize).max(1);
            points.push(a);
            let mut k = 0;
            for j in 1..pieces {
                let target = integral * j as f64 / pieces as f64;
                while samples[k + 1].1 < target {
                    k += 1;
                }
                let ((t0, i0), (t1, i1)) = (samples[k], samples[k + 1]);
                points.push(at(t0 + (t1 - t0) * (target - i0) / (i1 - i0)));
            }
        }
        let n = points.len() - first;
        segments.extend((0..n).map(|j| [first + j, first + (j + 1) % n]));
    }
    Ok((points, segments))
}

fn bulk_load(points: Vec<[f64; 2]>, segments: Vec<[usize; 2]>) -> Result<Cdt, MeshgenError> {
    let n = points.len();
    let points = points.into_iter().map(|p| Point2::new(p[0], p[1])).collect();
    let cdt = Cdt::bulk_load_cdt(points, segments).map_err(|e| MeshgenError::Triangulation(format!("{e:?}")))?;
    if cdt.num_vertices() != n {
        return Err(MeshgenError::Triangulation(format!("{} of {n} points coincide", n - cdt.num_vertices())));
    }
    Ok(cdt)
}

const OUTSIDE: u8 = 0;
const INSIDE: u8 = 1;
const UNKNOWN: u8 = 2;

/// Inside/outside flag per face index, by flood fill from the convex hull: crossing a
/// boundary segment toggles the side. Exact (no geometric predicates).
fn classify_faces(cdt: &Cdt) -> Vec<u8> {
    let mut side = vec![UNKNOWN; cdt.num_all_faces()];
    side[cdt.outer_face().fix().index()] = OUTSIDE;
    let mut stack = Vec::new();
    for edge in cdt.convex_hull() {
        for (e, f) in [(edge, edge.rev().face()), (edge.rev(), edge.face())] {
            if let Some(inner) = f.as_inner() {
                let s = if e.is_constraint_edge() { INSIDE } else { OUTSIDE };
                if side[inner.fix().index()] == UNKNOWN {
                    side[inner.fix().index()] = s;
                    stack.push(inner.fix());
                }
            }
        }
    }
    while let Some(f) = stack.pop() {
        let s = side[f.index()];
        for edge in cdt.face(f).adjacent_edges() {
            if let Some(next) = edge.rev().face().as_inner()
                && side[next.fix().index()] == UNKNOWN
            {
                side[next.fix().index()] = s ^ u8::from(edge.is_constraint_edge());
                stack.push(next.fix());
            }
        }
    }
    side
}

/// Extends `side` to the faces around a newly inserted vertex: new faces take the side of
/// their neighbour around the vertex, toggled across boundary segments.
fn classify_star(cdt: &Cdt, v: FixedVertexHandle, side: &mut Vec<u8>) {
    side.resize(cdt.num_all_faces(), UNKNOWN);
    let star: Vec<_> = cdt.vertex(v).out_edges().collect();
    for _ in 0..star.len() {
        let mut progress = false;
        for e in &star {
            let f = e.face().fix().index();
            if side[f] != UNKNOWN {
                continue;
            }
            // The faces left and right of an edge out of v are both in v's star.
            let before = e.rev().face().fix().index();
            if side[before] != UNKNOWN {
                side[f] = side[before] ^ u8::from(e.is_constraint_edge());
                progress = true;
            }
        }
        if !progress {
            break;
        }
    }
}

fn refine(
    cdt: &mut Cdt,
    size: &impl Fn([f64; 2]) -> Result<f64, MeshgenError>,
    params: &Mesh2dParams,
) -> Result<Vec<u8>, MeshgenError> {
    let mut side = classify_faces(cdt);
    let mut vertex_size =
        cdt.vertices().map(|v| size([v.position().x, v.position().y])).collect::<Result<Vec<_>, _>>()?;
    let mut queue: VecDeque<FixedFaceHandle<InnerTag>> =
        cdt.fixed_inner_faces().filter(|f| side[f.index()] == INSIDE).collect();
    let shape_limit = 1.0 / (2.0 * params.min_angle_deg.to_radians().sin());
    while let Some(fh) = queue.pop_front() {
        if side[fh.index()] != INSIDE {
            continue;
        }
        let face = cdt.face(fh);
        let [a, b, c] = face.positions().map(|p| [p.x, p.y]);
        let (centre, radius2) = circumcircle(a, b, c);
        let centroid = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
        let h = size(centroid)?;
        let shortest2 = dist2(a, b).min(dist2(b, c)).min(dist2(c, a));
        let too_large = radius2 > (params.size_factor * h).powi(2);
        let smallest_h = face.vertices().iter().map(|v| vertex_size[v.fix().index()]).fold(h, f64::min);
        let badly_shaped =
            radius2 > shape_limit * shape_limit * shortest2 && shortest2 > (params.quality_floor * smallest_h).powi(2);
        if !(too_large || badly_shaped) || !radius2.is_finite() {
            continue;
        }
        if cdt.num_inner_faces() > params.max_elements {
            return Err(MeshgenError::TooManyElements { cap: params.max_elements });
        }
        let hint = face.vertices()[0].fix();
        let target = Point2::new(centre[0], centre[1]);
        let encroached = match cdt.locate_with_hint(target, hint) {
            PositionInTriangulation::OnFace(landing) if side[landing.index()] == INSIDE => cdt
                .face(landing)
                .adjacent_edges()
                .into_iter()
                .find(|e| e.is_constraint_edge() && encroaches(e.positions(), centre))
                .map(|e| e.fix()),
            PositionInTriangulation::OnEdge(e) if !cdt.directed_edge(e).is_constraint_edge() => None,
            PositionInTriangulation::OnVertex(_) => continue,
            _ => {
                // Beyond the boundary: split the first boundary segment between the face and
                // its circumcentre.
                let from = Point2::new(centroid[0], centroid[1]);
                let crossed = LineIntersectionIterator::new(cdt, from, target).find_map(|i| match i {
                    Intersection::EdgeIntersection(e) | Intersection::EdgeOverlap(e) if e.is_constraint_edge() => {
                        Some(e.fix())
                    }
                    _ => None,
                });
                match crossed {
                    Some(e) => Some(e),
                    None => continue,
                }
            }
        };
        let inserted = match encroached {
            Some(segment) => {
                let segment = cdt.directed_edge(segment);
                let [p, q] = segment.positions();
                let midpoint = Point2::new(0.5 * (p.x + q.x), 0.5 * (p.y + q.y));
                // Only split where the midpoint lies exactly on the segment, or spade would
                // leave the segment whole beside a new vertex.
                match cdt.locate_with_hint(midpoint, segment.from().fix()) {
                    PositionInTriangulation::OnEdge(e) if e.as_undirected() == segment.fix().as_undirected() => {
                        Some(midpoint)
                    }
                    _ => None,
                }
            }
            None => Some(target),
        };
        let Some(point) = inserted else { continue };
        let v = cdt.insert_with_hint(point, hint).map_err(|e| MeshgenError::Triangulation(format!("{e:?}")))?;
        vertex_size.push(size([point.x, point.y])?);
        classify_star(cdt, v, &mut side);
        for e in cdt.vertex(v).out_edges() {
            if let Some(f) = e.face().as_inner()
                && side[f.fix().index()] == INSIDE
            {
                queue.push_back(f.fix());
            }
        }
        if encroached.is_some() {
            // The triangle that asked for the split is still there and may still be bad.
            queue.push_back(fh);
        }
    }
    Ok(side)
}

/// Whether `p` lies strictly inside the diametral circle of the segment.
fn encroaches(segment: [Point2<f64>; 2], p: [f64; 2]) -> bool {
    let [a, b] = segment;
    let mid = [0.5 * (a.x + b.x), 0.5 * (a.y + b.y)];
    dist2(mid, p) < 0.25 * dist2([a.x, a.y], [b.x, b.y])
}

fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

/// Circumcentre and squared circumradius.
fn circumcircle(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> ([f64; 2], f64) {
    let (bx, by, cx, cy) = (b[0] - a[0], b[1] - a[1], c[0] - a[0], c[1] - a[1]);
    let d = 2.0 * (bx * cy - by * cx);
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    let ux = (cy * b2 - by * c2) / d;
    let uy = (bx * c2 - cx * b2) / d;
    ([a[0] + ux, a[1] + uy], ux * ux + uy * uy)
}

/// Across a boundary segment: no triangle, and no flip.
const NO_NEIGHBOUR: u32 = u32::MAX;

/// The inside of a triangulation as flat arrays.
struct Exported {
    /// In spade's order.
    vertices: Vec<[f64; 2]>,
    /// Counter-clockwise, three vertex indices each.
    triangles: Vec<u32>,
    /// Per triangle corner k, the triangle across the edge opposite k, or `NO_NEIGHBOUR` across
    /// a boundary segment.
    neighbours: Vec<u32>,
    /// The boundary segments.
    segments: Vec<[usize; 2]>,
}

fn export(cdt: &Cdt, side: &[u8]) -> Exported {
    let ((vertices, segments), (triangles, neighbours)) = rayon::join(
        || {
            let vertices = cdt.vertices().map(|v| [v.position().x, v.position().y]).collect();
            let segments = cdt
                .undirected_edges()
                .filter(|e| e.is_constraint_edge())
                .map(|e| e.vertices().map(|v| v.fix().index()))
                .collect();
            (vertices, segments)
        },
        || inside_triangles(cdt, side),
    );
    Exported { vertices, triangles, neighbours, segments }
}

/// The inside triangles and their neighbours, numbered in face order.
fn inside_triangles(cdt: &Cdt, side: &[u8]) -> (Vec<u32>, Vec<u32>) {
    let mut inside = 0;
    let triangle_of_face: Vec<u32> = side
        .iter()
        .map(|&s| {
            inside += u32::from(s == INSIDE);
            if s == INSIDE { inside - 1 } else { NO_NEIGHBOUR }
        })
        .collect();
    let mut triangles = Vec::with_capacity(3 * inside as usize);
    let mut neighbours = Vec::with_capacity(3 * inside as usize);
    for face in cdt.inner_faces().filter(|f| side[f.fix().index()] == INSIDE) {
        // Edge i runs from corner i to corner i + 1, opposite corner i + 2.
        let edges = face.adjacent_edges();
        triangles.extend(edges.map(|e| e.from().fix().index() as u32));
        neighbours.extend([edges[1], edges[2], edges[0]].map(|e| {
            if e.is_constraint_edge() { NO_NEIGHBOUR } else { triangle_of_face[e.rev().face().fix().index()] }
        }));
    }
    (triangles, neighbours)
}

/// Renumbers vertices along a Morton (Z-order) curve, in the triangles and segments too.
fn morton_order(
    vertices: Vec<[f64; 2]>,
    triangles: &mut [u32],
    segments: Vec<[usize; 2]>,
) -> (Vec<[f64; 2]>, Vec<[usize; 2]>) {
    let (lo, hi) = vertices.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
        ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
    });
    let scale = ((1u64 << 31) as f64 - 1.0) / (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE);
    let spread = |x: f64| {
        let mut v = x as u64 & 0x7fff_ffff;
        v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
        v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    };
    let mut order: Vec<(u64, u32)> = vertices
        .iter()
        .enumerate()
        .map(|(i, p)| (spread((p[0] - lo[0]) * scale) | (spread((p[1] - lo[1]) * scale) << 1), i as u32))
        .collect();
    // Stable: vertices sharing a code keep spade's order, as the sort of the pairs kept it.
    radsort::sort_by_key(&mut order, |&(code, _)| code);
    let mut new_index = vec![0u32; vertices.len()];
    for (new, &(_, old)) in order.iter().enumerate() {
        new_index[old as usize] = new as u32;
    }
    let sorted = order.iter().map(|&(_, old)| vertices[old as usize]).collect();
    for v in triangles {
        *v = new_index[*v as usize];
    }
    let segments = segments.into_iter().map(|s| s.map(|v| new_index[v] as usize)).collect();
    (sorted, segments)
}

/// Quality-guarded Laplacian smoothing: each interior vertex moves to the mean of its
/// neighbours unless that lowers the smallest angle of its star (Gauss–Seidel order).
fn smooth(vertices: &mut [[f64; 2]], triangles: &[u32], segments: &[[usize; 2]], passes: usize) {
    if passes == 0 {
        return;
    }
    let n = vertices.len();
    let mut fixed = vec![false; n];
    for s in segments {
        fixed[s[0]] = true;
        fixed[s[1]] = true;
    }
    let star = VertexElements::new(n, triangles, 3);
    for _ in 0..passes {
        for v in 0..n {
            let around = star.around(v);
            if fixed[v] || around.is_empty() {
                continue;
            }
            let old = vertices[v];
            let before = star_quality(vertices, triangles, around);
            // Every vertex off the boundary segments is interior, so its ring of neighbours is
            // closed: each neighbour is a corner of exactly two of its triangles.
            let weight = 0.5 / around.len() as f64;
            let mut mean = [0.0, 0.0];
            for &t in around {
                for &w in triangles[3 * t as usize..3 * t as usize + 3].iter().filter(|&&w| w as usize != v) {
                    let p = vertices[w as usize];
                    mean = [mean[0] + p[0] * weight, mean[1] + p[1] * weight];
                }
            }
            vertices[v] = mean;
            if star_quality(vertices, triangles, around) < before {
                vertices[v] = old;
            }
        }
    }
}

/// Flips interior edges until every one is locally Delaunay (Lawson). Each flip turns the
/// quadrilateral a, b, d, c of triangles t = (a, b, c) and u = (d, c, b) into (a, b, d) and
/// (a, d, c); the exact in-circle test keeps it finite.
fn restore_delaunay(vertices: &[[f64; 2]], triangles: &mut [u32], neighbours: &mut [u32]) {
    let mut stack: Vec<(u32, u8)> = (0..neighbours.len())
        .filter(|&i| neighbours[i] != NO_NEIGHBOUR && (i / 3) < neighbours[i] as usize)
        .map(|i| ((i / 3) as u32, (i % 3) as u8))
        .collect();
    while let Some((t, k)) = stack.pop() {
        let (t, k) = (t as usize, k as usize);
        let u = neighbours[3 * t + k];
        if u == NO_NEIGHBOUR {
            continue;
        }
        let u = u as usize;
        let corner = |tri: usize, i: usize| triangles[3 * tri + i % 3];
        let (a, b, c) = (corner(t, k), corner(t, k + 1), corner(t, k + 2));
        let j = (0..3).find(|&j| corner(u, j) != b && corner(u, j) != c).expect("neighbours share an edge");
        let d = corner(u, j);
        let at = |v: u32| vertices[v as usize];
        if incircle(at(a), at(b), at(c), at(d)) != Ordering::Greater {
            continue;
        }
        let (ab, ca) = (neighbours[3 * t + (k + 2) % 3], neighbours[3 * t + (k + 1) % 3]);
        let (bd, dc) = (neighbours[3 * u + (j + 1) % 3], neighbours[3 * u + (j + 2) % 3]);
        triangles[3 * t..3 * t + 3].copy_from_slice(&[a, b, d]);
        triangles[3 * u..3 * u + 3].copy_from_slice(&[a, d, c]);
        neighbours[3 * t..3 * t + 3].copy_from_slice(&[bd, u as u32, ab]);
        neighbours[3 * u..3 * u + 3].copy_from_slice(&[dc, ca, t as u32]);
        for (moved, from, to) in [(bd, u, t), (ca, t, u)] {
            if moved != NO_NEIGHBOUR {
                let moved = moved as usize;
                let slot = (0..3).find(|&i| neighbours[3 * moved + i] == from as u32).expect("adjacency is symmetric");
                neighbours[3 * moved + slot] = to as u32;
            }
        }
        stack.extend([(t, 0), (t, 2), (u, 0), (u, 1)].map(|(tri, i)| (tri as u32, i as u8)));
    }
}

/// The triangles ordered by their smallest vertex index, so that on a Morton-numbered
/// mesh nearby triangles are near in memory.
fn triangles_in_vertex_order(triangles: Vec<u32>) -> Vec<u32> {
    // Keys (smallest vertex, triangle) are distinct: the sort is deterministic.
    let mut keys: Vec<u64> = triangles
        .chunks_exact(3)
        .enumerate()
        .map(|(t, c)| (u64::from(c[0].min(c[1]).min(c[2])) << 32) | t as u64)
        .collect();
    radsort::sort(&mut keys);
    let mut ordered = Vec::with_capacity(triangles.len());
    for key in keys {
        let t = 3 * (key as u32) as usize;
        ordered.extend_from_slice(&triangles[t..t + 3]);
    }
    ordered
}

/// A monotone measure of the smallest angle over the triangles of a star: sin²(min angle),
/// negated for inverted triangles.
fn star_quality(vertices: &[[f64; 2]], triangles: &[u32], star: &[u32]) -> f64 {
    star.iter()
        .map(|&t| {
            let t = t as usize;
            let [a, b, c] = [0, 1, 2].map(|k| vertices[triangles[3 * t + k] as usize]);
            let twice_area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            let (l0, l1, l2) = (dist2(a, b), dist2(b, c), dist2(c, a));
            // The smallest angle lies opposite the shortest edge, between the two longer ones.
            let longer_product = (l0 * l1 * l2) / l0.min(l1).min(l2);
            twice_area * twice_area.abs() / longer_product
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FnSize, QualityReport};
    use amber_mesh::FacetAdjacency;
    use proptest::prelude::*;

    /// Checks conformity, orientation, area and that the boundary of the mesh is exactly the
    /// boundary of the domain.
    fn assert_valid(mesh: &Mesh2, domain: &PolygonDomain) {
        let adjacency = FacetAdjacency::new(mesh).expect("every edge shared by at most two triangles");
        assert!(mesh.volumes().iter().all(|&a| a > 0.0));
        let area = mesh.total_volume();
        assert!((area - domain.area()).abs() <= 1e-12 * domain.area(), "area {area} vs {}", domain.area());
        let on_domain_edge = |p: [f64; 2], q: [f64; 2]| {
            domain.rings().any(|ring| {
                (0..ring.len()).any(|i| {
                    let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
                    let cross = |r: [f64; 2]| ((b[0] - a[0]) * (r[1] - a[1]) - (b[1] - a[1]) * (r[0] - a[0])).abs();
                    let tol = 1e-12 * dist2(a, b);
                    let within = |r: [f64; 2]| {
                        let t = ((r[0] - a[0]) * (b[0] - a[0]) + (r[1] - a[1]) * (b[1] - a[1])) / dist2(a, b);
                        (-1e-12..=1.0 + 1e-12).contains(&t)
                    };
                    cross(p) <= tol && cross(q) <= tol && within(p) && within(q)
                })
            })
        };
        let mut boundary_length = 0.0;
        for (e, local) in adjacency.boundary_facets() {
            let cell = mesh.element(e);
            let (p, q) =
                (mesh.vertices()[cell[(local + 1) % 3] as usize], mesh.vertices()[cell[(local + 2) % 3] as usize]);
            assert!(on_domain_edge(p, q), "boundary edge {p:?}-{q:?} is not on the domain boundary");
            boundary_length += dist2(p, q).sqrt();
        }
        let perimeter: f64 =
            domain.rings().map(|r| (0..r.len()).map(|i| dist2(r[i], r[(i + 1) % r.len()]).sqrt()).sum::<f64>()).sum();
        assert!((boundary_length - perimeter).abs() < 1e-9 * perimeter);
    }

    /// A star-shaped polygon: vertices at sorted angles with random radii.
    fn star_polygon() -> impl Strategy<Value = Vec<[f64; 2]>> {
        (5usize..12).prop_flat_map(|n| {
            (proptest::collection::vec(0.0..1.0f64, n), proptest::collection::vec(0.4..1.0f64, n)).prop_map(
                move |(jitter, radii)| {
                    (0..n)
                        .map(|i| {
                            let angle = (i as f64 + 0.8 * jitter[i]) * std::f64::consts::TAU / n as f64;
                            [radii[i] * angle.cos(), radii[i] * angle.sin()]
                        })
                        .collect()
                },
            )
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        #[test]
        fn random_polygons_and_fields_give_valid_meshes(outer in star_polygon(), h0 in 0.04..0.2f64, wave in 0.0..0.8f64) {
            let domain = PolygonDomain::new(outer, vec![]).unwrap();
            let field = FnSize(move |x: [f64; 2]| h0 * (1.0 + wave * (5.0 * x[0]).sin() * (3.0 * x[1]).cos()));
            let mesh = generate_2d(&domain, &field, &Mesh2dParams::default()).unwrap();
            assert_valid(&mesh, &domain);
            assert_constrained_delaunay(&mesh);
        }

        #[test]
        fn lshapes_meet_the_quality_bounds(px in 0.2..0.8f64, py in 0.2..0.8f64, h0 in 0.01..0.1f64, grading in 0.0..2.0f64) {
            let domain = PolygonDomain::lshape([px, py]).unwrap();
            let field = FnSize(move |x: [f64; 2]| h0 * (0.2 + grading * ((x[0] - px).powi(2) + (x[1] - py).powi(2)).sqrt()).min(1.0));
            let mesh = generate_2d(&domain, &field, &Mesh2dParams::default()).unwrap();
            assert_valid(&mesh, &domain);
            let report = QualityReport::measure(&mesh, &field);
            prop_assert!(report.min_angle >= 20.0, "min angle {}", report.min_angle);
            prop_assert!(report.mean_min_angle >= 45.0, "mean min angle {}", report.mean_min_angle);
        }
    }

    /// The mesh's triangles as a set, each a sorted triple.
    fn triangle_set(triangles: &[u32]) -> Vec<[u32; 3]> {
        let mut set: Vec<[u32; 3]> = triangles
            .chunks_exact(3)
            .map(|c| {
                let mut t = [c[0], c[1], c[2]];
                t.sort_unstable();
                t
            })
            .collect();
        set.sort_unstable();
        set
    }

    /// The flips end where a triangulation from scratch does: at the constrained Delaunay
    /// triangulation (by spade) of the final vertices and boundary segments.
    fn assert_constrained_delaunay(mesh: &Mesh2) {
        let adjacency = FacetAdjacency::new(mesh).unwrap();
        let segments = adjacency
            .boundary_facets()
            .map(|(e, local)| {
                let cell = mesh.element(e);
                [cell[(local + 1) % 3] as usize, cell[(local + 2) % 3] as usize]
            })
            .collect();
        let cdt = bulk_load(mesh.vertices().to_vec(), segments).unwrap();
        let delaunay = export(&cdt, &classify_faces(&cdt));
        assert_eq!(triangle_set(mesh.cells()), triangle_set(&delaunay.triangles));
    }

    #[test]
    fn a_flip_makes_a_quadrilateral_delaunay() {
        // A rhombus split along its long diagonal b–c, which is not Delaunay: d lies in the
        // circumcircle of a, b, c (the angles opposite b–c sum to 254°).
        let vertices = [[0.0, 0.0], [1.0, -2.0], [1.0, 2.0], [2.0, 0.0]];
        let mut triangles = vec![0, 1, 2, 3, 2, 1];
        let mut neighbours = vec![1, NO_NEIGHBOUR, NO_NEIGHBOUR, 0, NO_NEIGHBOUR, NO_NEIGHBOUR];
        restore_delaunay(&vertices, &mut triangles, &mut neighbours);
        assert_eq!(triangle_set(&triangles), vec![[0, 1, 3], [0, 2, 3]]);
        let mesh = Mesh2::new(vertices.to_vec(), triangles.clone()).expect("flipped triangles stay counter-clockwise");
        assert_constrained_delaunay(&mesh);
        // Both triangles still name each other across the new diagonal.
        assert_eq!(neighbours, vec![NO_NEIGHBOUR, 1, NO_NEIGHBOUR, NO_NEIGHBOUR, NO_NEIGHBOUR, 0]);
    }

    #[test]
    fn holes_are_left_empty() {
        let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let hole = vec![[0.3, 0.3], [0.6, 0.35], [0.5, 0.7]];
        let domain = PolygonDomain::new(square, vec![hole]).unwrap();
        let mesh = generate_2d(&domain, &ConstantSize(0.05), &Mesh2dParams::default()).unwrap();
        assert_valid(&mesh, &domain);
        assert_constrained_delaunay(&mesh);
        assert!(mesh.midpoints().iter().all(|&m| domain.contains(m)));
    }

    #[test]
    fn uniform_initial_lshape_mesh_is_coarse() {
        // The Poisson task's M⁰ (h₀ = 0.9467): the reference has 6–12 triangles.
        for corner in [[0.2, 0.2], [0.5, 0.5], [0.8, 0.3], [0.8, 0.8]] {
            let domain = PolygonDomain::lshape(corner).unwrap();
            let mesh = uniform_mesh_2d(&domain, 0.9467, &Mesh2dParams::default()).unwrap();
            assert!((4..=12).contains(&mesh.num_elements()), "{} triangles for corner {corner:?}", mesh.num_elements());
            assert_valid(&mesh, &domain);
        }
    }

    #[test]
    fn same_input_gives_the_same_mesh_at_any_thread_count() {
        let domain = PolygonDomain::lshape([0.4, 0.6]).unwrap();
        let field = FnSize(|x: [f64; 2]| 0.01 + 0.1 * x[0]);
        let a = generate_2d(&domain, &field, &Mesh2dParams::default()).unwrap();
        let b = generate_2d(&domain, &field, &Mesh2dParams::default()).unwrap();
        assert_eq!(a, b);
        let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let c = one_thread.install(|| generate_2d(&domain, &field, &Mesh2dParams::default())).unwrap();
        assert_eq!(a, c);
    }

    #[test]
    fn invalid_sizes_are_typed_errors() {
        let domain = PolygonDomain::lshape([0.5, 0.5]).unwrap();
        for bad in [f64::NAN, 0.0, -0.1, f64::INFINITY] {
            let result = generate_2d(&domain, &ConstantSize(bad), &Mesh2dParams::default());
            assert!(matches!(result, Err(MeshgenError::InvalidSize { .. })), "{bad}: {result:?}");
        }
        // NaN only in part of the domain is caught too.
        let patchy = FnSize(|x: [f64; 2]| if x[0] > 0.25 && x[1] < 0.25 { f64::NAN } else { 0.05 });
        assert!(matches!(
            generate_2d(&domain, &patchy, &Mesh2dParams::default()),
            Err(MeshgenError::InvalidSize { .. })
        ));
    }

    #[test]
    fn sizes_too_small_for_the_cap_are_refused() {
        let domain = PolygonDomain::lshape([0.5, 0.5]).unwrap();
        let params = Mesh2dParams::default().with_max_elements(10_000);
        // A field that knows its element count is refused before any work.
        let result = generate_2d(&domain, &ConstantSize(1e-9), &params);
        assert!(matches!(result, Err(MeshgenError::TooManyElements { cap: 10_000 })));
        // One that does not: the boundary alone exceeds the cap.
        let result = generate_2d(&domain, &FnSize(|_| 1e-9), &params);
        assert!(matches!(result, Err(MeshgenError::TooManyElements { cap: 10_000 })));
        // The boundary fits, the interior does not.
        let result = generate_2d(&domain, &FnSize(|_| 0.003), &params);
        assert!(matches!(result, Err(MeshgenError::TooManyElements { cap: 10_000 })));
        // Sizes 100 orders of magnitude below the edges: refused, not looped over.
        let huge = vec![[0.0, 0.0], [1e60, 0.0], [1e60, 1e60], [0.0, 1e60]];
        let domain = PolygonDomain::new(huge, vec![]).unwrap();
        let result = generate_2d(&domain, &FnSize(|_| 1e-40), &params);
        assert!(matches!(result, Err(MeshgenError::TooManyElements { cap: 10_000 })));
    }
}
