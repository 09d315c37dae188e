//! Adaptive isotropic surface remeshing (Botsch & Kobbelt 2004) of a CAD-face-labelled
//! reference surface toward a sizing field, so that TetGen — which never coarsens its input
//! surface — gets a boundary that already has the target sizes (spec §2, 3D).
//!
//! Every iteration splits edges longer than 4/3·h, collapses edges shorter than 4/5·h, flips
//! edges toward valence 6 (or toward better-shaped triangles), smooths tangentially and
//! projects back onto the reference; h is evaluated at the vertices and an edge's target is
//! the mean of its ends. CAD faces are never merged: every vertex stays on its own face
//! (projection onto that face only, which keeps the two sides of a thin sheet apart), vertices
//! on the curve between two faces stay on that curve, and corners (vertices of three or more
//! faces) never move. No operation may make the surface intersect itself or turn a triangle
//! over: collapses and flips whose new triangles would cross another are refused, and vertices
//! whose move (split or smoothing) made triangles cross go back to where they were safe. Inside
//! a planar face the orientation check is enough — a planar triangulation with a fixed boundary
//! whose triangles all keep their orientation cannot overlap itself — so the costly crossing
//! tests run only on curved faces.

use std::collections::{BTreeMap, HashMap};

use nalgebra::Vector3;
use rstar::primitives::Line;
use rstar::{AABB, Envelope, RTree};

use super::distance::RefTriangle;
use super::intersect::{TriangleIndex, triangle_box, triangles_intersect, triangles_overlap};
use super::surface::{Surface, SurfaceDefect};
use crate::SizingField;

/// Remeshing settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RemeshParams {
    /// Split–collapse–flip–smooth–project rounds (the literature uses 5–10).
    pub iterations: usize,
    /// How far, as a fraction of the local size, the midpoint of an edge that a collapse or
    /// flip creates may lie from its CAD face or curve. Keeps curved faces resolved and stops
    /// edges from cutting across holes and concave corners.
    pub max_relative_deviation: f64,
    /// Stop with an error rather than grow beyond this many triangles (sizes far too small).
    pub max_triangles: usize,
}

impl Default for RemeshParams {
    fn default() -> Self {
        Self { iterations: 6, max_relative_deviation: 0.1, max_triangles: 2_000_000 }
    }
}

/// Remeshing failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RemeshError {
    /// The sizing field returned a size that is not positive and finite.
    #[error("the sizing field returned {value} at {at:?}; sizes must be positive and finite")]
    InvalidSize { at: [f64; 3], value: f64 },
    /// The sizes are so small that the surface would exceed the triangle cap.
    #[error("the surface would exceed {cap} triangles (sizes too small?)")]
    TooManyTriangles { cap: usize },
    /// The remeshed surface failed validation: a self-intersection that moving vertices back
    /// could not undo, or a bug; reported rather than handed to TetGen.
    #[error("the remeshed surface is invalid: {0}")]
    InvalidResult(#[from] SurfaceDefect),
}

/// Remeshes a validated (closed, outward) `reference` surface so that its edges follow `sizing`,
/// keeping every CAD face, curve and corner. The result is validated.
///
/// Sizes are evaluated at the vertices (when they are created or moved) and an edge's target is
/// the mean of its two ends, so the field is queried about once per vertex and iteration.
pub fn remesh<S: SizingField<3>>(
    reference: &Surface,
    sizing: &S,
    params: &RemeshParams,
) -> Result<Surface, RemeshError> {
    let context = Context { sizing, projector: Projector::new(reference), params: *params };
    let mut mesh = WorkMesh::new(reference, &context)?;
    // Refuse at once a field that would need more triangles than the cap.
    if mesh.estimated_triangles() > params.max_triangles as f64 {
        return Err(RemeshError::TooManyTriangles { cap: params.max_triangles });
    }
    for _ in 0..params.iterations {
        mesh.split_long_edges(&context)?;
        mesh.collapse_short_edges(&context);
        mesh.flip_edges(&context);
        mesh.smooth_and_project(&context)?;
    }
    let mut surface = mesh.into_surface()?;
    surface.validate()?;
    Ok(surface)
}

/// What the mesh operations measure against: the sizing field and the reference surface.
struct Context<'a, S> {
    sizing: &'a S,
    projector: Projector,
    params: RemeshParams,
}

impl<S: SizingField<3>> Context<'_, S> {
    fn size(&self, p: [f64; 3]) -> Result<f64, RemeshError> {
        let value = self.sizing.size_at(p);
        if value.is_finite() && value > 0.0 { Ok(value) } else { Err(RemeshError::InvalidSize { at: p, value }) }
    }

    /// Whether an edge p–q of target size `h` on `kind` (a face, or the curve of a feature
    /// edge) stays close enough to the reference at its midpoint.
    fn follows_reference(&self, p: [f64; 3], q: [f64; 3], kind: Kind, h: f64) -> bool {
        let mid = [0, 1, 2].map(|k| 0.5 * (p[k] + q[k]));
        let deviation = (Vector3::from(self.projector.project(mid, kind)) - Vector3::from(mid)).norm();
        deviation <= self.params.max_relative_deviation * h
    }
}

/// Where a vertex may move: on one CAD face, on the curve between two faces, or nowhere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Face(i32),
    Curve(i32, i32),
    Corner,
}

/// The kind implied by the CAD faces around a vertex.
fn kind_of(faces: &mut Vec<i32>) -> Kind {
    faces.sort_unstable();
    faces.dedup();
    match faces[..] {
        [f] => Kind::Face(f),
        [f, g] => Kind::Curve(f, g),
        _ => Kind::Corner,
    }
}

/// Closest points on the reference surface, restricted to one CAD face or one curve. Planar
/// faces (most of a sheet-metal part) project onto their plane: a vertex inside a planar face
/// whose triangles keep their orientation cannot leave the face, so the plane is enough.
struct Projector {
    /// The triangles of every curved face.
    faces: HashMap<i32, RTree<RefTriangle>>,
    /// Point and unit normal of every planar face.
    planes: HashMap<i32, (Vector3<f64>, Vector3<f64>)>,
    curves: HashMap<(i32, i32), RTree<Line<[f64; 3]>>>,
}

impl Projector {
    fn new(reference: &Surface) -> Self {
        let (v, t, ids) = (reference.vertices(), reference.triangles(), reference.face_ids());
        let mut faces: BTreeMap<i32, Vec<RefTriangle>> = BTreeMap::new();
        for (tri, &id) in t.iter().zip(ids) {
            faces.entry(id).or_default().push(RefTriangle(tri.map(|i| v[i as usize])));
        }
        let mut curves: BTreeMap<(i32, i32), Vec<Line<[f64; 3]>>> = BTreeMap::new();
        for ([a, b], [k, l]) in reference.feature_edges() {
            let (f, g) = (ids[k], ids[l]);
            curves.entry((f.min(g), f.max(g))).or_default().push(Line::new(v[a as usize], v[b as usize]));
        }
        let planes: HashMap<i32, (Vector3<f64>, Vector3<f64>)> =
            faces.iter().filter_map(|(&id, tris)| Some((id, plane_of(tris)?))).collect();
        Self {
            faces: faces
                .into_iter()
                .filter(|(id, _)| !planes.contains_key(id))
                .map(|(id, tris)| (id, RTree::bulk_load(tris)))
                .collect(),
            planes,
            curves: curves.into_iter().map(|(key, lines)| (key, RTree::bulk_load(lines))).collect(),
        }
    }

    fn project(&self, p: [f64; 3], kind: Kind) -> [f64; 3] {
        match kind {
            Kind::Face(f) => match self.planes.get(&f) {
                Some(&(origin, n)) => {
                    let p = Vector3::from(p);
                    (p + n * -(p - origin).dot(&n)).into()
                }
                None => self.faces.get(&f).and_then(|tree| tree.nearest_neighbor(p)).map_or(p, |t| t.closest(p)),
            },
            Kind::Curve(f, g) => {
                self.curves.get(&(f, g)).and_then(|tree| tree.nearest_neighbor(p)).map_or(p, |l| l.nearest_point(&p))
            }
            Kind::Corner => p,
        }
    }

    fn is_planar(&self, face: i32) -> bool {
        self.planes.contains_key(&face)
    }
}

/// The plane of a face whose triangles all lie in one (within 10⁻⁵ of the face's extent,
/// which float32 STL coordinates respect and any real bend or hole wall exceeds).
fn plane_of(triangles: &[RefTriangle]) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let corners = || triangles.iter().flat_map(|t| t.0).map(Vector3::from);
    let count = 3.0 * triangles.len() as f64;
    let origin = corners().fold(Vector3::zeros(), |acc, c| acc + c) / count;
    let n = triangles.iter().fold(Vector3::zeros(), |acc, t| {
        let [a, b, c] = t.0.map(Vector3::from);
        acc + (b - a).cross(&(c - a))
    });
    let length = n.norm();
    if length == 0.0 {
        return None;
    }
    let n = n / length;
    let extent = corners().map(|c| (c - origin).norm()).fold(0.0, f64::max);
    corners().all(|c| (c - origin).dot(&n).abs() <= 1e-5 * extent).then_some((origin, n))
}

/// The surface being remeshed: triangles with their CAD faces, vertex → triangle lists and the
/// target size at every vertex. Removed triangles and vertices stay as tombstones until
/// [`WorkMesh::into_surface`].
struct WorkMesh {
    pos: Vec<[f64; 3]>,
    kind: Vec<Kind>,
    /// Target size at each vertex, and where it was evaluated.
    h: Vec<f64>,
    sized_at: Vec<[f64; 3]>,
    vertex_alive: Vec<bool>,
    triangles: Vec<[u32; 3]>,
    face: Vec<i32>,
    triangle_alive: Vec<bool>,
    live_triangles: usize,
    around: Vec<Vec<u32>>,
}

/// A triangle quality below which no operation may push a triangle (unless it was worse before).
const MIN_QUALITY: f64 = 0.15;

impl WorkMesh {
    fn new<S: SizingField<3>>(s: &Surface, context: &Context<S>) -> Result<Self, RemeshError> {
        let n = s.vertices().len();
        let mut around: Vec<Vec<u32>> = vec![Vec::with_capacity(6); n];
        for (t, tri) in s.triangles().iter().enumerate() {
            tri.iter().for_each(|&v| around[v as usize].push(t as u32));
        }
        let kind =
            around.iter().map(|ts| kind_of(&mut ts.iter().map(|&t| s.face_ids()[t as usize]).collect())).collect();
        let h = s.vertices().iter().map(|&p| context.size(p)).collect::<Result<_, _>>()?;
        Ok(Self {
            pos: s.vertices().to_vec(),
            kind,
            h,
            sized_at: s.vertices().to_vec(),
            vertex_alive: vec![true; n],
            triangles: s.triangles().to_vec(),
            face: s.face_ids().to_vec(),
            triangle_alive: vec![true; s.triangles().len()],
            live_triangles: s.triangles().len(),
            around,
        })
    }

    /// The triangle count if every triangle were covered by equilateral triangles of the mean
    /// size at its corners.
    fn estimated_triangles(&self) -> f64 {
        let live = (0..self.triangles.len()).filter(|&t| self.triangle_alive[t]);
        live.map(|t| {
            let tri = self.triangles[t];
            let h = tri.iter().map(|&v| self.h[v as usize]).sum::<f64>() / 3.0;
            0.5 * self.normal(tri).norm() / (3f64.sqrt() / 4.0 * h * h)
        })
        .sum()
    }

    /// Every edge once, as (smaller, larger) vertex index.
    fn edges(&self) -> Vec<[u32; 2]> {
        let mut edges: Vec<[u32; 2]> = (0..self.triangles.len())
            .filter(|&t| self.triangle_alive[t])
            .flat_map(|t| {
                let tri = self.triangles[t];
                (0..3).map(move |k| [tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3])])
            })
            .collect();
        edges.sort_unstable();
        edges.dedup();
        edges
    }

    /// The two triangles of edge (a, b), or `None` if it is no longer an edge.
    fn edge_triangles(&self, a: u32, b: u32) -> Option<[u32; 2]> {
        let mut it = self.around[a as usize].iter().copied().filter(|&t| self.triangles[t as usize].contains(&b));
        Some([it.next()?, it.next()?])
    }

    fn neighbours(&self, v: u32) -> Vec<u32> {
        let mut n: Vec<u32> =
            self.around[v as usize].iter().flat_map(|&t| self.triangles[t as usize]).filter(|&x| x != v).collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    /// The corner of triangle `t` opposite edge (a, b).
    fn apex(&self, t: u32, a: u32, b: u32) -> u32 {
        self.triangles[t as usize].into_iter().find(|&x| x != a && x != b).unwrap_or(a)
    }

    fn length(&self, a: u32, b: u32) -> f64 {
        (Vector3::from(self.pos[a as usize]) - Vector3::from(self.pos[b as usize])).norm()
    }

    /// The target length of edge (a, b): the mean of the sizes at its ends.
    fn edge_size(&self, a: u32, b: u32) -> f64 {
        0.5 * (self.h[a as usize] + self.h[b as usize])
    }

    fn normal(&self, tri: [u32; 3]) -> Vector3<f64> {
        let [a, b, c] = tri.map(|v| Vector3::from(self.pos[v as usize]));
        (b - a).cross(&(c - a))
    }

    fn quality(&self, tri: [u32; 3]) -> f64 {
        quality(tri.map(|v| self.pos[v as usize]))
    }

    /// Splits every edge longer than 4/3 of its target, repeating on the new edges until none
    /// is (or for at most 16 rounds, which halve edges 2^16-fold).
    fn split_long_edges<S: SizingField<3>>(&mut self, context: &Context<S>) -> Result<(), RemeshError> {
        let first_new = self.pos.len() as u32;
        // Where each new vertex is safe: the midpoint of its edge's safe ends, which lies in
        // the plane of an old triangle (the surface before splitting did not cross itself).
        let mut safe: Vec<[f64; 3]> = Vec::new();
        let mut candidates = self.edges();
        for _ in 0..16 {
            let mut created = Vec::new();
            for [a, b] in candidates {
                if self.length(a, b) > 4.0 / 3.0 * self.edge_size(a, b)
                    && let Some(m) = self.split(a, b, context)?
                {
                    let safe_of =
                        |v: u32| if v < first_new { self.pos[v as usize] } else { safe[(v - first_new) as usize] };
                    let (p, q) = (safe_of(a), safe_of(b));
                    safe.push([0, 1, 2].map(|k| 0.5 * (p[k] + q[k])));
                    created.push(m);
                }
            }
            let cap = context.params.max_triangles;
            if self.live_triangles > cap {
                return Err(RemeshError::TooManyTriangles { cap });
            }
            if created.is_empty() {
                break;
            }
            candidates = created.iter().flat_map(|&m| self.neighbours(m).into_iter().map(move |x| [m, x])).collect();
        }
        let moved: Vec<u32> = (first_new..self.pos.len() as u32).collect();
        let safe_of = |v: u32| if v < first_new { self.pos[v as usize] } else { safe[(v - first_new) as usize] };
        let safe_positions: Vec<[f64; 3]> = moved.iter().map(|&v| safe_of(v)).collect();
        self.untangle(&moved, |v| safe_positions[(v - first_new) as usize], &context.projector);
        Ok(())
    }

    /// Inserts the midpoint of edge (a, b), projected onto the reference, and splits both
    /// triangles of the edge in two. Refuses (returns `None`) when the projection moves the
    /// midpoint by more than a quarter of the edge: such an edge does not follow its face and
    /// splitting it would not shorten it. Keeps the straight midpoint when the projected one
    /// would turn a new triangle over.
    fn split<S: SizingField<3>>(&mut self, a: u32, b: u32, context: &Context<S>) -> Result<Option<u32>, RemeshError> {
        let Some([t1, t2]) = self.edge_triangles(a, b) else { return Ok(None) };
        let kind = self.edge_kind(t1, t2);
        let (p, q) = (self.pos[a as usize], self.pos[b as usize]);
        let mid = [0, 1, 2].map(|k| 0.5 * (p[k] + q[k]));
        let projected = context.projector.project(mid, kind);
        if (Vector3::from(projected) - Vector3::from(mid)).norm() > 0.25 * self.length(a, b) {
            return Ok(None);
        }
        let halves = [t1, t2].map(|t| {
            let tri = self.triangles[t as usize];
            let k = (0..3).find(|&k| [a, b].contains(&tri[k]) && [a, b].contains(&tri[(k + 1) % 3])).unwrap_or(0);
            (t, tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3])
        });
        let keeps_side = halves.iter().all(|&(t, x, y, c)| {
            let old = self.normal(self.triangles[t as usize]);
            let [px, py, pc] = [x, y, c].map(|v| Vector3::from(self.pos[v as usize]));
            let pm = Vector3::from(projected);
            (pm - px).cross(&(pc - px)).dot(&old) > 0.0 && (py - pm).cross(&(pc - pm)).dot(&old) > 0.0
        });
        let at = if keeps_side { projected } else { mid };
        let m = self.pos.len() as u32;
        self.pos.push(at);
        self.kind.push(kind);
        self.h.push(context.size(at)?);
        self.sized_at.push(at);
        self.vertex_alive.push(true);
        self.around.push(Vec::with_capacity(6));
        for (t, x, y, c) in halves {
            let new = self.triangles.len() as u32;
            self.triangles[t as usize] = [x, m, c];
            self.triangles.push([m, y, c]);
            self.face.push(self.face[t as usize]);
            self.triangle_alive.push(true);
            let at_y = &mut self.around[y as usize];
            at_y.retain(|&s| s != t);
            at_y.push(new);
            self.around[c as usize].push(new);
            self.around[m as usize].extend([t, new]);
        }
        self.live_triangles += 2;
        Ok(Some(m))
    }

    /// A new vertex on edge t1 ∩ t2 lies on their CAD face, or on the curve between their faces.
    fn edge_kind(&self, t1: u32, t2: u32) -> Kind {
        let (f, g) = (self.face[t1 as usize], self.face[t2 as usize]);
        if f == g { Kind::Face(f) } else { Kind::Curve(f.min(g), f.max(g)) }
    }

    /// Collapses edges shorter than 4/5 of their target, shortest first, where allowed.
    fn collapse_short_edges<S: SizingField<3>>(&mut self, context: &Context<S>) {
        let mut short: Vec<(f64, u32, u32)> = self
            .edges()
            .into_iter()
            .map(|[a, b]| (self.length(a, b), a, b))
            .filter(|&(length, a, b)| length < 0.8 * self.edge_size(a, b))
            .collect();
        short.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut index = self.index();
        for (_, a, b) in short {
            if !(self.vertex_alive[a as usize] && self.vertex_alive[b as usize]) {
                continue;
            }
            for (from, to) in [(a, b), (b, a)] {
                if self.collapse_allowed(from, to, context, &index) {
                    for t in self.collapse(from, to) {
                        index.insert(t, self.triangle_box(t));
                    }
                    break;
                }
            }
        }
    }

    /// Whether vertex `from` may be merged into `to`: CAD structure kept, topology stays a
    /// closed manifold (link condition), no triangle turns over or degenerates, no new edge is
    /// too long or strays from the reference, no new triangle crosses another.
    fn collapse_allowed<S: SizingField<3>>(
        &self,
        from: u32,
        to: u32,
        context: &Context<S>,
        index: &TriangleIndex,
    ) -> bool {
        let Some([t1, t2]) = self.edge_triangles(from, to) else { return false };
        let structure_kept = match self.kind[from as usize] {
            Kind::Corner => false,
            Kind::Face(_) => true,
            Kind::Curve(..) => {
                self.face[t1 as usize] != self.face[t2 as usize]
                    && (self.kind[to as usize] == self.kind[from as usize] || self.kind[to as usize] == Kind::Corner)
            }
        };
        if !structure_kept {
            return false;
        }
        let (n_from, n_to) = (self.neighbours(from), self.neighbours(to));
        let common = n_from.iter().filter(|v| n_to.binary_search(v).is_ok()).count();
        if common != 2 || n_from.len() <= 3 || n_to.len() <= 3 {
            return false;
        }
        let target = self.pos[to as usize];
        let moved: Vec<(u32, [u32; 3])> = self.around[from as usize]
            .iter()
            .map(|&t| (t, self.triangles[t as usize]))
            .filter(|(_, tri)| !tri.contains(&to))
            .map(|(t, tri)| (t, tri.map(|v| if v == from { to } else { v })))
            .collect();
        let new_edges: Vec<u32> =
            n_from.iter().copied().filter(|&x| x != to && n_to.binary_search(&x).is_err()).collect();
        // Cheap checks first: lengths, orientation and shape.
        if new_edges.iter().any(|&x| self.length(x, to) > 4.0 / 3.0 * self.edge_size(x, to)) {
            return false;
        }
        for &(t, new) in &moved {
            let old = self.triangles[t as usize];
            let q = self.quality(new);
            if self.normal(old).dot(&self.normal(new)) <= 0.0 || (q < MIN_QUALITY && q < self.quality(old)) {
                return false;
            }
        }
        for &x in &new_edges {
            let Some([s, t]) = self.edge_triangles(from, x) else { return false };
            if !context.follows_reference(target, self.pos[x as usize], self.edge_kind(s, t), self.edge_size(x, to)) {
                return false;
            }
        }
        // Inside planar faces, triangles that keep their orientation cannot cross anything.
        let around = &self.around[from as usize];
        let new: Vec<[u32; 3]> = moved.iter().map(|&(_, tri)| tri).collect();
        around.iter().all(|&t| context.projector.is_planar(self.face[t as usize])) || !self.crosses(index, &new, around)
    }

    /// Merges `from` into `to`; returns the triangles that changed corners.
    fn collapse(&mut self, from: u32, to: u32) -> Vec<u32> {
        let mut moved = Vec::new();
        for t in std::mem::take(&mut self.around[from as usize]) {
            let tri = self.triangles[t as usize];
            if tri.contains(&to) {
                self.triangle_alive[t as usize] = false;
                self.live_triangles -= 1;
                for v in tri.into_iter().filter(|&v| v != from) {
                    self.around[v as usize].retain(|&s| s != t);
                }
            } else {
                self.triangles[t as usize] = tri.map(|v| if v == from { to } else { v });
                self.around[to as usize].push(t);
                moved.push(t);
            }
        }
        self.vertex_alive[from as usize] = false;
        moved
    }

    /// Flips edges inside a CAD face that bring the four vertices closer to valence 6 without
    /// making the worst of the two triangles much worse, or that make it clearly better.
    fn flip_edges<S: SizingField<3>>(&mut self, context: &Context<S>) {
        let mut index = self.index();
        for [a, b] in self.edges() {
            let Some([t1, t2]) = self.edge_triangles(a, b) else { continue };
            if self.face[t1 as usize] != self.face[t2 as usize] {
                continue;
            }
            let (c, d) = (self.apex(t1, a, b), self.apex(t2, a, b));
            if c == d || self.around[c as usize].iter().any(|&t| self.triangles[t as usize].contains(&d)) {
                continue;
            }
            let valence = |v: u32| self.around[v as usize].len() as i64;
            let deviation =
                |va: i64, vb: i64, vc: i64, vd: i64| [va, vb, vc, vd].iter().map(|v| (v - 6) * (v - 6)).sum::<i64>();
            let (va, vb, vc, vd) = (valence(a), valence(b), valence(c), valence(d));
            if va <= 3 || vb <= 3 {
                continue;
            }
            // Orient so that t1 = (x, y, c) runs x → y; then t2 runs y → x with apex d.
            let tri = self.triangles[t1 as usize];
            let k = (0..3).find(|&k| tri[(k + 2) % 3] == c).unwrap_or(0);
            let (x, y) = (tri[k], tri[(k + 1) % 3]);
            let (new1, new2) = ([x, d, c], [y, c, d]);
            let old_quality = self.quality(self.triangles[t1 as usize]).min(self.quality(self.triangles[t2 as usize]));
            let new_quality = self.quality(new1).min(self.quality(new2));
            let better_valence = deviation(va - 1, vb - 1, vc + 1, vd + 1) < deviation(va, vb, vc, vd);
            if !(better_valence && new_quality >= 0.9 * old_quality || new_quality >= 1.25 * old_quality) {
                continue;
            }
            let old = self.normal(self.triangles[t1 as usize]) + self.normal(self.triangles[t2 as usize]);
            let (n1, n2) = (self.normal(new1), self.normal(new2));
            if n1.dot(&old) <= 0.0 || n2.dot(&old) <= 0.0 || n1.dot(&n2) <= 0.0 {
                continue;
            }
            let kind = Kind::Face(self.face[t1 as usize]);
            let curved = !context.projector.is_planar(self.face[t1 as usize]);
            if !context.follows_reference(self.pos[c as usize], self.pos[d as usize], kind, self.edge_size(c, d))
                || curved && self.crosses(&index, &[new1, new2], &[t1, t2])
            {
                continue;
            }
            self.triangles[t1 as usize] = new1;
            self.triangles[t2 as usize] = new2;
            self.around[y as usize].retain(|&s| s != t1);
            self.around[x as usize].retain(|&s| s != t2);
            self.around[d as usize].push(t1);
            self.around[c as usize].push(t2);
            index.insert(t1, self.triangle_box(t1));
            index.insert(t2, self.triangle_box(t2));
        }
    }

    /// One Gauss–Seidel pass of tangential smoothing (face vertices toward the centroid of
    /// their neighbours within the tangent plane, curve vertices toward the mean of their two
    /// curve neighbours), each result projected onto its own face or curve of the reference.
    /// A move that would turn a triangle over or degenerate it is skipped; the sizes of moved
    /// vertices are re-evaluated.
    fn smooth_and_project<S: SizingField<3>>(&mut self, context: &Context<S>) -> Result<(), RemeshError> {
        let safe = self.pos.clone();
        let mut moved = Vec::new();
        for v in 0..self.pos.len() as u32 {
            let p = self.pos[v as usize];
            let kind = self.kind[v as usize];
            if !self.vertex_alive[v as usize] || kind == Kind::Corner {
                continue;
            }
            let neighbours: Vec<u32> = self
                .neighbours(v)
                .into_iter()
                .filter(|&x| {
                    matches!(kind, Kind::Face(_))
                        || self
                            .edge_triangles(v, x)
                            .is_some_and(|[s, t]| self.face[s as usize] != self.face[t as usize])
                })
                .collect();
            if neighbours.is_empty() {
                continue;
            }
            let centroid =
                neighbours.iter().fold(Vector3::zeros(), |acc, &x| acc + Vector3::from(self.pos[x as usize]))
                    / neighbours.len() as f64;
            let mut step = centroid - Vector3::from(p);
            let around = &self.around[v as usize];
            if let Kind::Face(_) = kind {
                let n = around.iter().fold(Vector3::zeros(), |acc, &t| acc + self.normal(self.triangles[t as usize]));
                let nn = n.dot(&n);
                if nn > 0.0 {
                    step += n * (-step.dot(&n) / nn);
                }
            }
            let target = context.projector.project((Vector3::from(p) + step).into(), kind);
            let before: Vec<(Vector3<f64>, f64)> = around
                .iter()
                .map(|&t| (self.normal(self.triangles[t as usize]), self.quality(self.triangles[t as usize])))
                .collect();
            self.pos[v as usize] = target;
            let acceptable = around.iter().zip(&before).all(|(&t, &(normal, q))| {
                let tri = self.triangles[t as usize];
                let q_new = self.quality(tri);
                self.normal(tri).dot(&normal) > 0.0 && (q_new >= MIN_QUALITY || q_new >= q)
            });
            if acceptable {
                moved.push(v);
            } else {
                self.pos[v as usize] = p;
            }
        }
        self.untangle(&moved, |v| safe[v as usize], &context.projector);
        // Sizes follow their vertex once it has moved by a tenth of its size.
        for v in moved {
            let p = self.pos[v as usize];
            if (Vector3::from(p) - Vector3::from(self.sized_at[v as usize])).norm() > 0.1 * self.h[v as usize] {
                self.h[v as usize] = context.size(p)?;
                self.sized_at[v as usize] = p;
            }
        }
        Ok(())
    }

    fn triangle_box(&self, t: u32) -> AABB<[f64; 3]> {
        triangle_box(&self.triangles[t as usize].map(|v| self.pos[v as usize]))
    }

    /// An index of the live triangles' boxes.
    fn index(&self) -> TriangleIndex {
        TriangleIndex::new(
            (0..self.triangles.len() as u32)
                .filter(|&t| self.triangle_alive[t as usize])
                .map(|t| (t, self.triangle_box(t))),
        )
    }

    /// Whether any of the triangles `new` would cross a live triangle other than the
    /// `replaced` ones (one index query for all of them).
    fn crosses(&self, index: &TriangleIndex, new: &[[u32; 3]], replaced: &[u32]) -> bool {
        let corners: Vec<[[f64; 3]; 3]> = new.iter().map(|tri| tri.map(|v| self.pos[v as usize])).collect();
        let boxes: Vec<AABB<[f64; 3]>> = corners.iter().map(triangle_box).collect();
        let all = boxes.iter().fold(AABB::new_empty(), |acc: AABB<[f64; 3]>, b| acc.merged(b));
        index.candidates(all).into_iter().any(|u| {
            let other = self.triangles[u as usize];
            if !self.triangle_alive[u as usize] || replaced.contains(&u) {
                return false;
            }
            let other_corners = other.map(|v| self.pos[v as usize]);
            let other_box = triangle_box(&other_corners);
            new.iter()
                .zip(&corners)
                .zip(&boxes)
                .any(|((&tri, c), b)| b.intersects(&other_box) && triangles_overlap(tri, c, other, &other_corners))
        })
    }

    /// Sends `moved` vertices of crossing triangles back to their `safe` positions (where the
    /// surface did not cross itself), repeating around the vertices sent back since a move
    /// back can expose another crossing. Only triangles around moved vertices are checked, and
    /// only against triangles they share no corner with (moves were checked against turning
    /// their own triangles over), and only on curved faces (inside a planar face, triangles
    /// that keep their orientation cannot cross anything).
    fn untangle(&mut self, moved: &[u32], safe: impl Fn(u32) -> [f64; 3], projector: &Projector) {
        let mut index = self.index();
        let mut is_moved = vec![false; self.pos.len()];
        moved.iter().for_each(|&v| is_moved[v as usize] = true);
        let mut check: Vec<u32> = moved.iter().flat_map(|&v| self.around[v as usize].iter().copied()).collect();
        while !check.is_empty() {
            check.retain(|&t| !projector.is_planar(self.face[t as usize]));
            check.sort_unstable();
            check.dedup();
            let mut back = Vec::new();
            for &t in &check {
                let tri = self.triangles[t as usize];
                let corners = tri.map(|v| self.pos[v as usize]);
                for u in index.candidates(triangle_box(&corners)) {
                    let other = self.triangles[u as usize];
                    if self.triangle_alive[u as usize]
                        && !other.iter().any(|v| tri.contains(v))
                        && triangles_intersect(&corners, &other.map(|v| self.pos[v as usize]))
                    {
                        back.extend(tri.iter().chain(&other).copied().filter(|&v| is_moved[v as usize]));
                    }
                }
            }
            check.clear();
            for v in back {
                if is_moved[v as usize] {
                    is_moved[v as usize] = false;
                    self.pos[v as usize] = safe(v);
                    for &t in &self.around[v as usize] {
                        index.insert(t, self.triangle_box(t));
                        check.push(t);
                    }
                }
            }
        }
    }

    /// The live part as a [`Surface`], renumbered.
    fn into_surface(self) -> Result<Surface, SurfaceDefect> {
        let mut index = vec![u32::MAX; self.pos.len()];
        let mut vertices = Vec::new();
        for (v, &alive) in self.vertex_alive.iter().enumerate() {
            if alive {
                index[v] = vertices.len() as u32;
                vertices.push(self.pos[v]);
            }
        }
        let live = (0..self.triangles.len()).filter(|&t| self.triangle_alive[t]);
        let triangles = live.clone().map(|t| self.triangles[t].map(|v| index[v as usize])).collect();
        let face_ids = live.map(|t| self.face[t]).collect();
        Surface::new(vertices, triangles, face_ids)
    }
}

/// 4√3·area / Σ edge²: 1 for an equilateral triangle, 0 for a degenerate one.
fn quality(corners: [[f64; 3]; 3]) -> f64 {
    let [a, b, c] = corners.map(Vector3::from);
    let sum = (a - b).norm_squared() + (b - c).norm_squared() + (c - a).norm_squared();
    if sum > 0.0 { 2.0 * 3f64.sqrt() * (b - a).cross(&(c - a)).norm() / sum } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ConstantSize, FnSize};

    use crate::mesh3d::unit_cube as cube;

    /// Median and 5th/95th percentile of edge length / size at the edge midpoint.
    fn edge_ratios(s: &Surface, h: impl Fn([f64; 3]) -> f64) -> (f64, f64, f64) {
        let v = s.vertices();
        let mut r: Vec<f64> = s
            .triangles()
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .map(|(a, b)| {
                let (p, q) = (v[a as usize], v[b as usize]);
                (Vector3::from(p) - Vector3::from(q)).norm() / h([0, 1, 2].map(|k| 0.5 * (p[k] + q[k])))
            })
            .collect();
        r.sort_by(f64::total_cmp);
        (r[r.len() / 2], r[r.len() / 20], r[r.len() * 19 / 20])
    }

    #[test]
    fn cube_is_refined_to_a_uniform_size_with_its_edges_and_corners_kept() {
        let out = remesh(&cube(), &ConstantSize(0.1), &RemeshParams::default()).unwrap();
        let (median, p5, p95) = edge_ratios(&out, |_| 0.1);
        assert!((0.8..1.2).contains(&median) && p5 > 0.5 && p95 < 1.5, "ratios {median} [{p5}, {p95}]");
        assert!((out.enclosed_volume() - 1.0).abs() < 1e-12, "volume {}", out.enclosed_volume());
        // Vertices stay on the cube; the 8 corners survive; six CAD faces remain.
        let on_cube =
            |p: &[f64; 3]| p.iter().any(|&x| x == 0.0 || x == 1.0) && p.iter().all(|&x| (0.0..=1.0).contains(&x));
        assert!(out.vertices().iter().all(on_cube));
        let corners = out.vertices().iter().filter(|p| p.iter().all(|&x| x == 0.0 || x == 1.0)).count();
        assert_eq!(corners, 8);
        let mut ids = out.face_ids().to_vec();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids, [1, 2, 3, 4, 5, 6]);
    }

    #[test]
    fn graded_size_gives_graded_triangles_and_coarsening_works() {
        let h = |p: [f64; 3]| 0.03 + 0.2 * p[0];
        let fine = remesh(&cube(), &FnSize(h), &RemeshParams::default()).unwrap();
        let (median, p5, p95) = edge_ratios(&fine, h);
        assert!((0.75..1.25).contains(&median) && p5 > 0.4 && p95 < 1.6, "ratios {median} [{p5}, {p95}]");
        // Coarsening the fine mesh back to 0.25 everywhere.
        let coarse = remesh(&fine, &ConstantSize(0.25), &RemeshParams::default()).unwrap();
        assert!(
            coarse.triangles().len() * 5 < fine.triangles().len(),
            "{} vs {}",
            coarse.triangles().len(),
            fine.triangles().len()
        );
        assert!((coarse.enclosed_volume() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_sizes_are_typed_errors() {
        assert!(matches!(
            remesh(&cube(), &ConstantSize(f64::NAN), &RemeshParams::default()),
            Err(RemeshError::InvalidSize { .. })
        ));
        let params = RemeshParams { max_triangles: 1000, ..RemeshParams::default() };
        assert!(matches!(
            remesh(&cube(), &ConstantSize(1e-3), &params),
            Err(RemeshError::TooManyTriangles { cap: 1000 })
        ));
    }

    /// Console reference surfaces remeshed to 2 mm and 4 mm, then filled by TetGen with the
    /// project's switches: edges follow the size, the volume stays within 0.5 %, and the
    /// remeshed surface is a valid TetGen input (`remesh` validates it).
    #[test]
    fn console_surfaces_are_remeshed_to_the_size_and_tetrahedralize() {
        use crate::mesh3d::tetgen::{TetgenSwitches, tetrahedralize};
        use crate::mesh3d::{console_reference_surfaces, surface::StlFaceIds};
        let Some(files) = console_reference_surfaces() else { return };
        for path in files.iter().filter(|p| p.ends_with("train/015.stl") || p.ends_with("val/002.stl")) {
            let (reference, report) = Surface::load(path, StlFaceIds::FromFile).unwrap();
            for h in [2.0, 4.0] {
                let start = std::time::Instant::now();
                let out = remesh(&reference, &ConstantSize(h), &RemeshParams::default()).unwrap();
                let seconds = start.elapsed().as_secs_f64();
                let (median, p5, p95) = edge_ratios(&out, |_| h);
                let volume_change = out.enclosed_volume() / report.enclosed_volume - 1.0;
                let sizes = vec![h; out.vertices().len()];
                let tets = tetrahedralize(&out.to_plc(), Some(&sizes), None, &TetgenSwitches::default()).unwrap();
                println!(
                    "{} h = {h}: {} -> {} triangles in {seconds:.2} s, edge/h median {median:.2} [p5 {p5:.2}, p95 \
                     {p95:.2}], volume {volume_change:+.1e}, {} tets",
                    path.display(),
                    reference.triangles().len(),
                    out.triangles().len(),
                    tets.mesh.num_elements()
                );
                assert!((0.85..1.1).contains(&median) && p5 > 0.5 && p95 < 1.35, "{}", path.display());
                assert!(volume_change.abs() < 5e-3, "{}", path.display());
                assert!((tets.mesh.total_volume() / out.enclosed_volume() - 1.0).abs() < 1e-9);
            }
        }
    }
}
