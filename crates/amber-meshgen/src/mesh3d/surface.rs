//! Closed triangle surfaces with a CAD-face id per triangle: built from the triangles of an
//! STL or OBJ file (which amber-mesh reads), welding duplicate vertices, and the checks TetGen
//! needs of its input — closed, 2-manifold, consistently oriented with outward normals, free of
//! self-intersections.
//!
//! The Console reference surfaces (`data/console/reference_surface/*/NNN.stl`) are binary STL
//! in mm whose 2-byte facet attribute holds the 1-based CAD face id: load them with
//! [`StlFaceIds::FromFile`].

use std::cmp::Ordering;
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::path::{Path, PathBuf};

pub use amber_mesh::StlFaceIds;
use amber_mesh::{FacetAdjacency, Mesh3, MeshError, read_surface};
use nalgebra::Vector3;

use super::intersect::intersecting_pairs;
use super::tetgen::Plc;
use crate::predicates::orient2d;

/// A triangle surface: vertices, triangles (zero-based vertex indices) and the CAD face id of
/// every triangle. Indices are in range and vertices finite ([`Surface::new`] checks); whether
/// the surface bounds a solid is what [`Surface::validate`] checks (and remembers).
#[derive(Clone, Debug)]
pub struct Surface {
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    face_ids: Vec<i32>,
    /// Names of face ids, where the geometry gives them.
    face_names: BTreeMap<i32, String>,
    /// The name of the solid the surface bounds, where the geometry gives one.
    solid_name: Option<String>,
    /// Whether [`Surface::validate`] succeeded (nothing can change the surface afterwards).
    valid: bool,
}

impl PartialEq for Surface {
    /// Same vertices, triangles and face ids (validated or not).
    fn eq(&self, other: &Self) -> bool {
        (&self.vertices, &self.triangles, &self.face_ids) == (&other.vertices, &other.triangles, &other.face_ids)
    }
}

/// What [`Surface::validate`] found and did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceReport {
    /// Connected components (separate closed shells).
    pub components: usize,
    /// Triangles whose orientation was reversed to make all normals point outward.
    pub flipped_triangles: usize,
    /// Enclosed volume (positive).
    pub enclosed_volume: f64,
    /// V − E + F.
    pub euler_characteristic: i64,
}

impl SurfaceReport {
    /// Number of handles (through-holes), summed over components: (2·components − χ) / 2.
    pub fn genus(&self) -> i64 {
        (2 * self.components as i64 - self.euler_characteristic) / 2
    }
}

/// Reading or validating a surface file failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceError {
    /// The file could not be read, is malformed, or its extension names no surface format
    /// (the error names the file).
    #[error(transparent)]
    Read(#[from] MeshError),
    /// The file was read but the surface does not bound a solid.
    #[error("{path}: {source}")]
    Defect { path: PathBuf, source: SurfaceDefect },
}

/// Why a surface does not bound a solid (or is malformed).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceDefect {
    /// No triangles.
    #[error("the surface has no triangles")]
    Empty,
    /// Array lengths disagree.
    #[error("{what} has {found} entries, expected {expected}")]
    LengthMismatch { what: &'static str, expected: usize, found: usize },
    /// A coordinate is NaN or infinite (`vertex` indexes the input points, or corners of a soup).
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex { vertex: usize },
    /// A triangle references a missing vertex.
    #[error("triangle {triangle} references vertex {vertex}, but there are {num_vertices} vertices")]
    VertexOutOfRange { triangle: usize, vertex: u32, num_vertices: usize },
    /// Two corners coincide or all three are collinear.
    #[error("triangle {triangle} (face {face}) near {at:?} is degenerate (repeated or collinear corners)")]
    DegenerateTriangle { triangle: usize, face: i32, at: [f64; 3] },
    /// A vertex belongs to no triangle (TetGen would insert it as a free point).
    #[error("vertex {vertex} at {at:?} belongs to no triangle")]
    UnusedVertex { vertex: usize, at: [f64; 3] },
    /// Edges with one triangle: the surface has holes or cracks.
    #[error("not closed: {count} edges have only one triangle, e.g. {edge:?} at {at:?}")]
    OpenEdges { count: usize, edge: [u32; 2], at: [f64; 3] },
    /// Edges with three or more triangles.
    #[error(
        "not manifold: {count} edges have more than two triangles, e.g. {edge:?} at {at:?} ({triangles} triangles)"
    )]
    NonManifoldEdges { count: usize, edge: [u32; 2], at: [f64; 3], triangles: usize },
    /// Two or more fans of triangles meet only at a vertex.
    #[error("not manifold: vertex {vertex} at {at:?} joins {fans} separate fans of triangles")]
    NonManifoldVertex { vertex: usize, at: [f64; 3], fans: usize },
    /// A component cannot be oriented consistently (a Möbius-like surface).
    #[error("not orientable: the component of triangle {triangle} cannot be oriented consistently")]
    NonOrientable { triangle: usize },
    /// A closed component encloses no volume.
    #[error("the component of triangle {triangle} encloses no volume ({volume:e})")]
    ZeroVolume { triangle: usize, volume: f64 },
    /// Two triangles without a common vertex intersect.
    #[error(
        "self-intersection: triangle {first} (face {first_face}) and triangle {second} (face {second_face}) intersect near {at:?}"
    )]
    SelfIntersection { first: usize, first_face: i32, second: usize, second_face: i32, at: [f64; 3] },
}

impl Surface {
    /// Builds a surface from indexed triangles, checking lengths, indices, finiteness and that
    /// no triangle repeats a vertex.
    pub fn new(vertices: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>, face_ids: Vec<i32>) -> Result<Self, SurfaceDefect> {
        if triangles.is_empty() {
            return Err(SurfaceDefect::Empty);
        }
        if face_ids.len() != triangles.len() {
            return Err(SurfaceDefect::LengthMismatch {
                what: "face_ids",
                expected: triangles.len(),
                found: face_ids.len(),
            });
        }
        if let Some(vertex) = vertices.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(SurfaceDefect::NonFiniteVertex { vertex });
        }
        let num_vertices = vertices.len();
        for (triangle, t) in triangles.iter().enumerate() {
            if let Some(&vertex) = t.iter().find(|&&v| v as usize >= num_vertices) {
                return Err(SurfaceDefect::VertexOutOfRange { triangle, vertex, num_vertices });
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(SurfaceDefect::DegenerateTriangle {
                    triangle,
                    face: face_ids[triangle],
                    at: vertices[t[0] as usize],
                });
            }
        }
        Ok(Self { vertices, triangles, face_ids, face_names: BTreeMap::new(), solid_name: None, valid: false })
    }

    /// Builds a surface from a triangle soup (3 corners per triangle, as in STL), merging
    /// corners closer than `weld_tolerance` (0: only bit-identical positions) into one vertex.
    pub fn from_triangle_soup(
        corners: &[[f64; 3]],
        face_ids: Vec<i32>,
        weld_tolerance: f64,
    ) -> Result<Self, SurfaceDefect> {
        if corners.len() != 3 * face_ids.len() {
            return Err(SurfaceDefect::LengthMismatch {
                what: "corners",
                expected: 3 * face_ids.len(),
                found: corners.len(),
            });
        }
        if let Some(vertex) = corners.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(SurfaceDefect::NonFiniteVertex { vertex });
        }
        let (vertices, index) = weld(corners, weld_tolerance);
        let triangles = index.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Self::new(vertices, triangles, face_ids)
    }

    /// Reads an `.stl` or `.obj` file ([`amber_mesh::read_surface`]), welds bit-identical
    /// corners and [validates](Surface::validate) the surface; every error names the file.
    pub fn load(path: impl AsRef<Path>, stl_face_ids: StlFaceIds) -> Result<(Self, SurfaceReport), SurfaceError> {
        let path = path.as_ref();
        let soup = read_surface(path, stl_face_ids)?;
        let defect = |source| SurfaceError::Defect { path: path.into(), source };
        let mut surface = Self::from_triangle_soup(&soup.corners, soup.face_ids, 0.0)
            .map_err(defect)?
            .with_face_names(soup.face_names);
        let report = surface.validate().map_err(defect)?;
        Ok((surface, report))
    }

    /// The boundary surface of a tet mesh: its boundary triangles, oriented outwards, over its
    /// boundary vertices; not yet validated. A triangle's face is its tag in `facet_tags` (keyed
    /// by sorted mesh vertex indices, as [`amber_mesh::MeshData::facet_tags`]: a file's physical
    /// groups or skin properties); the untagged ones share one face numbered after the largest
    /// tag, face 1 without tags (see [`Surface::split_faces_at_feature_edges`]). A mesh whose
    /// facets do not pair up (three tets on one triangle) is an error.
    pub fn from_mesh_boundary(mesh: &Mesh3, facet_tags: &BTreeMap<Vec<u32>, i32>) -> Result<Self, SurfaceError> {
        let facets = FacetAdjacency::new(mesh)?.oriented_boundary_facets(mesh);
        let mut index = vec![u32::MAX; mesh.num_vertices()];
        let mut vertices = Vec::new();
        let triangles: Vec<[u32; 3]> = facets
            .iter()
            .map(|facet| {
                facet.map(|v| {
                    if index[v as usize] == u32::MAX {
                        index[v as usize] = vertices.len() as u32;
                        vertices.push(mesh.vertices()[v as usize]);
                    }
                    index[v as usize]
                })
            })
            .collect();
        let untagged = facet_tags.values().max().map_or(1, |&largest| largest.max(0) + 1);
        let face_ids = facets
            .iter()
            .map(|facet| {
                let mut key = facet.to_vec();
                key.sort_unstable();
                facet_tags.get(&key).copied().unwrap_or(untagged)
            })
            .collect();
        Self::new(vertices, triangles, face_ids).map_err(|source| SurfaceError::Defect { path: PathBuf::new(), source })
    }

    /// Finds faces as a CAD model would have them, for surfaces whose files carry none: two
    /// triangles across an edge share a face when they were in one face, their normals differ by
    /// at most `angle_degrees`, and the edge is not where a flat region meets a curved one (the
    /// tangent edge of a fillet, a bend or a hole, which no angle shows). Faces are renumbered
    /// from 1 in the order of their first triangle, without names. The surface must be
    /// validated again.
    ///
    /// A flat region is a patch of triangles joined across edges below [`FLAT_EDGE_DEGREES`] that
    /// is wider than [`FLAT_PATCH_WIDTH_RATIO`] × its narrowest neighbour across a bent edge: a
    /// curved face's patches (single triangles of an irregular mesh, the coplanar strips of a
    /// tessellated cylinder) are about as wide as their neighbours, a plane beside a fillet is
    /// many times wider than the fillet's patches.
    pub fn split_faces_at_feature_edges(&mut self, angle_degrees: f64) {
        let cross = |t: &[u32; 3]| {
            let p = |k: usize| Vector3::from(self.vertices[t[k] as usize]);
            (p(1) - p(0)).cross(&(p(2) - p(0)))
        };
        let crosses: Vec<Vector3<f64>> = self.triangles.iter().map(cross).collect();
        let normals: Vec<Vector3<f64>> = crosses.iter().map(|c| c.normalize()).collect();
        // Every edge inside one of the given faces: its triangles, length and the angle between
        // their normals (NaN for a sliver, which then joins nothing).
        let edges: Vec<([usize; 2], f64, f64)> = self
            .edge_triangles()
            .into_iter()
            .filter_map(|([a, b], around)| match around[..] {
                [k, l] if self.face_ids[k] == self.face_ids[l] => {
                    let length =
                        (Vector3::from(self.vertices[a as usize]) - Vector3::from(self.vertices[b as usize])).norm();
                    Some(([k, l], length, normals[k].dot(&normals[l]).clamp(-1.0, 1.0).acos()))
                }
                _ => None,
            })
            .collect();
        let limit = angle_degrees.to_radians();
        let flat_limit = FLAT_EDGE_DEGREES.to_radians();
        let patch = components(self.triangles.len(), edges.iter().filter(|e| e.2 <= flat_limit).map(|e| e.0));
        let patches = patch.iter().max().map_or(0, |&p| p + 1);
        let mut patch_area = vec![0.0; patches];
        for (t, c) in crosses.iter().enumerate() {
            patch_area[patch[t]] += 0.5 * c.norm();
        }
        let mut bent_length = vec![0.0; patches];
        let bent = |&&(_, _, angle): &&([usize; 2], f64, f64)| angle > flat_limit && angle <= limit;
        for &([k, l], length, _) in edges.iter().filter(bent) {
            bent_length[patch[k]] += length;
            bent_length[patch[l]] += length;
        }
        let width: Vec<f64> = patch_area.iter().zip(&bent_length).map(|(a, b)| 2.0 * a / b).collect();
        let mut narrowest_neighbour = vec![f64::INFINITY; patches];
        for &([k, l], _, _) in edges.iter().filter(bent) {
            let (p, q) = (patch[k], patch[l]);
            narrowest_neighbour[p] = narrowest_neighbour[p].min(width[q]);
            narrowest_neighbour[q] = narrowest_neighbour[q].min(width[p]);
        }
        let flat: Vec<bool> =
            (0..patches).map(|p| width[p] > FLAT_PATCH_WIDTH_RATIO * narrowest_neighbour[p]).collect();
        let joined = edges.iter().filter(|&&([k, l], _, angle)| {
            let (p, q) = (patch[k], patch[l]);
            p == q || (angle <= limit && !flat[p] && !flat[q])
        });
        let face = components(self.triangles.len(), joined.map(|e| e.0));
        self.face_ids = face.into_iter().map(|f| f as i32 + 1).collect();
        self.face_names.clear();
        self.valid = false;
    }

    /// The triangles around every edge (its vertices in increasing order), edges in order.
    fn edge_triangles(&self) -> BTreeMap<[u32; 2], Vec<usize>> {
        let mut by_edge: BTreeMap<[u32; 2], Vec<usize>> = BTreeMap::new();
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                by_edge.entry([a.min(b), a.max(b)]).or_default().push(t);
            }
        }
        by_edge
    }

    /// The edges inside a CAD face (two triangles of the same face around them), in order, each
    /// with its two triangles.
    pub fn smooth_edges(&self) -> impl Iterator<Item = ([u32; 2], [usize; 2])> + '_ {
        self.edge_triangles().into_iter().filter_map(|(edge, around)| match around[..] {
            [k, l] if self.face_ids[k] == self.face_ids[l] => Some((edge, [k, l])),
            _ => None,
        })
    }

    /// The edges between two CAD faces (the feature curves' pieces), in order: each edge's
    /// vertices and its two triangles.
    pub fn feature_edges(&self) -> impl Iterator<Item = ([u32; 2], [usize; 2])> + '_ {
        self.edge_triangles().into_iter().filter_map(|(edge, around)| match around[..] {
            [k, l] if self.face_ids[k] != self.face_ids[l] => Some((edge, [k, l])),
            _ => None,
        })
    }

    /// Whether [`Surface::validate`] has succeeded on this surface.
    pub fn is_validated(&self) -> bool {
        self.valid
    }

    /// Vertex positions.
    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.vertices
    }

    /// Triangles as zero-based vertex indices.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// CAD face id of every triangle.
    pub fn face_ids(&self) -> &[i32] {
        &self.face_ids
    }

    /// The surface with these names of its face ids (a file's STL solids, OBJ groups, gmsh
    /// physical groups), which meshes of it give their boundary groups.
    pub fn with_face_names(mut self, names: BTreeMap<i32, String>) -> Self {
        self.face_names = names;
        self
    }

    /// Names of face ids, where the geometry gives them.
    pub fn face_names(&self) -> &BTreeMap<i32, String> {
        &self.face_names
    }

    /// The surface as the boundary of the solid called `name` (a mesh file's domain group),
    /// which meshes of it give their element group.
    pub fn with_solid_name(mut self, name: Option<String>) -> Self {
        self.solid_name = name;
        self
    }

    /// The name of the solid the surface bounds, where the geometry gives one.
    pub fn solid_name(&self) -> Option<&str> {
        self.solid_name.as_deref()
    }

    /// Signed enclosed volume (divergence theorem; positive for a closed outward surface).
    pub fn enclosed_volume(&self) -> f64 {
        self.volume_of(0..self.triangles.len())
    }

    /// The surface as TetGen input: one facet per triangle, marker = CAD face id.
    pub fn to_plc(&self) -> Plc {
        Plc { points: self.vertices.clone(), triangles: self.triangles.clone(), face_markers: self.face_ids.clone() }
    }

    /// Checks that the surface bounds a solid: no degenerate triangles or unused vertices,
    /// closed (every edge in exactly two triangles), 2-manifold at every vertex, orientable,
    /// free of self-intersections (no two triangles without a common corner meet).
    /// Re-orients triangles so that every component encloses positive volume (so nested
    /// shells — cavities — are not supported).
    pub fn validate(&mut self) -> Result<SurfaceReport, SurfaceDefect> {
        self.check_triangles_and_vertices()?;
        let edges = self.manifold_edges()?;
        self.check_vertex_fans(&edges)?;
        let (components, flipped_triangles) = self.orient(&edges)?;
        if let Some(&(first, second)) = intersecting_pairs(&self.vertices, &self.triangles).first() {
            let at = self.vertices[self.triangles[first][0] as usize];
            let (first_face, second_face) = (self.face_ids[first], self.face_ids[second]);
            return Err(SurfaceDefect::SelfIntersection { first, first_face, second, second_face, at });
        }
        let euler_characteristic = self.vertices.len() as i64 - edges.len() as i64 + self.triangles.len() as i64;
        self.valid = true;
        Ok(SurfaceReport {
            components,
            flipped_triangles,
            enclosed_volume: self.enclosed_volume(),
            euler_characteristic,
        })
    }

    fn check_triangles_and_vertices(&self) -> Result<(), SurfaceDefect> {
        // Exactly collinear corners have collinear projections onto all three coordinate planes.
        let flat = |p: [f64; 3], i: usize| [p[i], p[(i + 1) % 3]];
        for (triangle, t) in self.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|v| self.vertices[v as usize]);
            if (0..3).all(|i| orient2d(flat(a, i), flat(b, i), flat(c, i)) == Ordering::Equal) {
                return Err(SurfaceDefect::DegenerateTriangle { triangle, face: self.face_ids[triangle], at: a });
            }
        }
        let mut used = vec![false; self.vertices.len()];
        self.triangles.iter().flatten().for_each(|&v| used[v as usize] = true);
        match used.iter().position(|&u| !u) {
            Some(vertex) => Err(SurfaceDefect::UnusedVertex { vertex, at: self.vertices[vertex] }),
            None => Ok(()),
        }
    }

    /// Every undirected edge with its two triangles, or the first open / non-manifold edge.
    fn manifold_edges(&self) -> Result<Vec<SharedEdge>, SurfaceDefect> {
        let mut uses: Vec<([u32; 2], u32)> = Vec::with_capacity(3 * self.triangles.len());
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                uses.push(([a.min(b), a.max(b)], t as u32));
            }
        }
        uses.sort_unstable();
        let groups: Vec<&[([u32; 2], u32)]> = uses.chunk_by(|x, y| x.0 == y.0).collect();
        let midpoint = |[a, b]: [u32; 2]| {
            let (p, q) = (self.vertices[a as usize], self.vertices[b as usize]);
            [0, 1, 2].map(|k| 0.5 * (p[k] + q[k]))
        };
        let open: Vec<_> = groups.iter().filter(|g| g.len() == 1).collect();
        if let Some(g) = open.first() {
            return Err(SurfaceDefect::OpenEdges { count: open.len(), edge: g[0].0, at: midpoint(g[0].0) });
        }
        let crowded: Vec<_> = groups.iter().filter(|g| g.len() > 2).collect();
        if let Some(g) = crowded.first() {
            let (edge, triangles) = (g[0].0, g.len());
            return Err(SurfaceDefect::NonManifoldEdges { count: crowded.len(), edge, at: midpoint(edge), triangles });
        }
        Ok(groups.iter().map(|g| SharedEdge { vertices: g[0].0, triangles: [g[0].1, g[1].1] }).collect())
    }

    /// With every edge in two triangles, a vertex is manifold iff its triangles form a single
    /// fan, i.e. they are connected through the edges at that vertex. Union-find over corners.
    fn check_vertex_fans(&self, edges: &[SharedEdge]) -> Result<(), SurfaceDefect> {
        let corner =
            |t: u32, v: u32| 3 * t as usize + self.triangles[t as usize].iter().position(|&x| x == v).unwrap_or(0);
        let mut parent: Vec<usize> = (0..3 * self.triangles.len()).collect();
        for e in edges {
            for v in e.vertices {
                let (x, y) =
                    (find(&mut parent, corner(e.triangles[0], v)), find(&mut parent, corner(e.triangles[1], v)));
                parent[x] = y;
            }
        }
        let mut fans = vec![0usize; self.vertices.len()];
        for c in 0..parent.len() {
            // Only corners of the same vertex were joined, so each root is one fan of its vertex.
            if find(&mut parent, c) == c {
                fans[self.triangles[c / 3][c % 3] as usize] += 1;
            }
        }
        match fans.iter().position(|&n| n > 1) {
            Some(vertex) => {
                Err(SurfaceDefect::NonManifoldVertex { vertex, at: self.vertices[vertex], fans: fans[vertex] })
            }
            None => Ok(()),
        }
    }

    /// Makes neighbouring triangles agree (breadth-first over shared edges), then turns every
    /// component that encloses negative volume. Returns (components, flipped triangles).
    fn orient(&mut self, edges: &[SharedEdge]) -> Result<(usize, usize), SurfaceDefect> {
        let n = self.triangles.len();
        let mut neighbours: Vec<Vec<(u32, bool)>> = vec![Vec::with_capacity(3); n];
        for e in edges {
            let [t, u] = e.triangles;
            // Consistent neighbours run through their shared edge in opposite directions.
            let same = self.runs_forward(t, e.vertices) == self.runs_forward(u, e.vertices);
            neighbours[t as usize].push((u, same));
            neighbours[u as usize].push((t, same));
        }
        let mut flip: Vec<Option<bool>> = vec![None; n];
        let mut components = 0;
        let mut flipped = 0;
        for seed in 0..n {
            if flip[seed].is_some() {
                continue;
            }
            components += 1;
            flip[seed] = Some(false);
            let mut members = vec![seed];
            let mut queue = VecDeque::from([seed]);
            while let Some(t) = queue.pop_front() {
                let ft = flip[t].unwrap_or(false);
                for &(u, same) in &neighbours[t] {
                    let want = ft ^ same;
                    match flip[u as usize] {
                        None => {
                            flip[u as usize] = Some(want);
                            members.push(u as usize);
                            queue.push_back(u as usize);
                        }
                        Some(have) if have != want => return Err(SurfaceDefect::NonOrientable { triangle: seed }),
                        Some(_) => {}
                    }
                }
            }
            for &t in &members {
                if flip[t] == Some(true) {
                    self.triangles[t].swap(1, 2);
                }
            }
            let volume = self.volume_of(members.iter().copied());
            if volume == 0.0 || !volume.is_finite() {
                return Err(SurfaceDefect::ZeroVolume { triangle: seed, volume });
            }
            let outward = volume > 0.0;
            if !outward {
                members.iter().for_each(|&t| self.triangles[t].swap(1, 2));
            }
            flipped += members.iter().filter(|&&t| flip[t] == Some(outward)).count();
        }
        Ok((components, flipped))
    }

    /// Whether triangle `t` lists edge [a, b] as a → b.
    fn runs_forward(&self, t: u32, [a, b]: [u32; 2]) -> bool {
        let tri = self.triangles[t as usize];
        (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b)
    }

    /// Signed volume enclosed by the given triangles, relative to their first vertex to keep
    /// the sum well conditioned away from the origin.
    fn volume_of(&self, triangles: impl Iterator<Item = usize>) -> f64 {
        let mut triangles = triangles.peekable();
        let Some(&first) = triangles.peek() else { return 0.0 };
        let r = self.vertices[self.triangles[first][0] as usize];
        triangles
            .map(|t| {
                let [a, b, c] = self.triangles[t].map(|v| {
                    let p = self.vertices[v as usize];
                    [p[0] - r[0], p[1] - r[1], p[2] - r[2]]
                });
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum()
    }
}

/// An undirected edge (sorted vertices) and the two triangles that share it.
struct SharedEdge {
    vertices: [u32; 2],
    triangles: [u32; 2],
}

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

/// The angle (degrees) below which two triangles count as coplanar when faces are found
/// ([`Surface::split_faces_at_feature_edges`]): far above the rounding of coordinates printed
/// with six digits, below a curved face's angle between neighbouring triangles.
pub const FLAT_EDGE_DEGREES: f64 = 0.5;

/// How many times wider than its narrowest bent neighbour a coplanar patch is to count as a flat
/// face of its own ([`Surface::split_faces_at_feature_edges`]).
pub const FLAT_PATCH_WIDTH_RATIO: f64 = 4.0;

/// The connected components of `nodes` nodes joined by `links`: each node's component, numbered
/// from 0 in the order of their smallest node.
fn components(nodes: usize, links: impl Iterator<Item = [usize; 2]>) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..nodes).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for [a, b] in links {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        parent[ra.max(rb)] = ra.min(rb);
    }
    let mut number = vec![usize::MAX; nodes];
    let mut next = 0;
    (0..nodes)
        .map(|x| {
            let r = root(&mut parent, x);
            if number[r] == usize::MAX {
                number[r] = next;
                next += 1;
            }
            number[r]
        })
        .collect()
}

/// Merges corners into vertices: bit-identical positions for `tolerance == 0`, else any two
/// within `tolerance` (grid hashing with cells of that size; the first vertex found wins).
fn weld(corners: &[[f64; 3]], tolerance: f64) -> (Vec<[f64; 3]>, Vec<u32>) {
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut index = Vec::with_capacity(corners.len());
    if tolerance <= 0.0 {
        // `+ 0.0` turns −0.0 into +0.0 so that both hash alike.
        let mut seen: HashMap<[u64; 3], u32> = HashMap::with_capacity(corners.len() / 2);
        for p in corners {
            let id = *seen.entry(p.map(|x| (x + 0.0).to_bits())).or_insert_with(|| {
                vertices.push(*p);
                vertices.len() as u32 - 1
            });
            index.push(id);
        }
        return (vertices, index);
    }
    let cell = |p: &[f64; 3]| p.map(|x| (x / tolerance).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    for p in corners {
        let c = cell(p);
        let near = (0..27).find_map(|k: i64| {
            let key = [c[0] + k % 3 - 1, c[1] + (k / 3) % 3 - 1, c[2] + k / 9 - 1];
            grid.get(&key)?.iter().copied().find(|&v| {
                let q = vertices[v as usize];
                (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>() <= tolerance * tolerance
            })
        });
        let id = near.unwrap_or_else(|| {
            vertices.push(*p);
            let id = vertices.len() as u32 - 1;
            grid.entry(c).or_default().push(id);
            id
        });
        index.push(id);
    }
    (vertices, index)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh3d::{console_reference_surfaces, unit_cube_triangles};

    /// The unit cube as a triangle soup, one face id per side, with its top side inside out.
    fn cube() -> Surface {
        let (vertices, mut triangles, ids) = unit_cube_triangles();
        triangles[2..4].iter_mut().for_each(|t| t.swap(1, 2));
        let corners: Vec<[f64; 3]> = triangles.iter().flat_map(|t| t.map(|v| vertices[v as usize])).collect();
        Surface::from_triangle_soup(&corners, ids, 0.0).unwrap()
    }

    fn soup(s: &Surface) -> Vec<[f64; 3]> {
        s.triangles().iter().flat_map(|t| t.map(|v| s.vertices()[v as usize])).collect()
    }

    #[test]
    fn cube_soup_is_welded_validated_and_turned_outward() {
        let mut s = cube();
        assert_eq!((s.vertices().len(), s.triangles().len()), (8, 12));
        let mut ids = s.face_ids().to_vec();
        ids.dedup();
        assert_eq!(ids, [1, 2, 3, 4, 5, 6]);
        let report = s.validate().unwrap();
        assert_eq!(report.components, 1);
        assert_eq!(report.flipped_triangles, 2);
        assert_eq!((report.euler_characteristic, report.genus()), (2, 0));
        assert!((report.enclosed_volume - 1.0).abs() < 1e-15);
    }

    /// A cube's surface with one face id gets its six sides back from the feature edges (90°),
    /// and none at an angle above 90°; a tet mesh of the cube gives back a closed surface of the
    /// cube's volume with the same six faces.
    #[test]
    fn feature_edges_split_faces_and_mesh_boundaries_bound_the_mesh() {
        let mut s = cube();
        s.face_ids.iter_mut().for_each(|id| *id = 7);
        s.split_faces_at_feature_edges(30.0);
        let mut ids = s.face_ids().to_vec();
        ids.sort();
        ids.dedup();
        assert_eq!(ids, [1, 2, 3, 4, 5, 6]);
        assert!(s.triangles().chunks(2).zip(s.face_ids().chunks(2)).all(|(_, f)| f[0] == f[1]));
        // Splitting never merges faces; from one face, no edge of a cube is sharper than 95°.
        s.face_ids.iter_mut().for_each(|id| *id = 7);
        s.split_faces_at_feature_edges(95.0);
        assert!(s.face_ids().iter().all(|&id| id == 1));

        let mut cube = cube();
        cube.validate().unwrap();
        let mesh = crate::mesh3d::generate_3d(&cube, &crate::ConstantSize(0.3), &Default::default()).unwrap();
        let mut boundary = Surface::from_mesh_boundary(&mesh, &BTreeMap::new()).unwrap();
        assert!(boundary.face_ids().iter().all(|&id| id == 1));
        boundary.split_faces_at_feature_edges(30.0);
        assert_eq!(*boundary.face_ids().iter().max().unwrap(), 6);
        let report = boundary.validate().unwrap();
        assert_eq!(report.flipped_triangles, 0, "mesh boundaries come out oriented");
        assert!((report.enclosed_volume - mesh.total_volume()).abs() < 1e-12);
    }

    /// A box of 3 × 1 × 2 whose edge between the top and the side x = 3 is a fillet of radius
    /// 0.5 in `strips` flat strips, as a CAD exporter tessellates it; one face id throughout.
    fn filleted_box(strips: u32) -> Surface {
        let (r, w) = (0.5, 1.0);
        // The profile in the xz-plane, counter-clockwise from the origin; y is the extrusion.
        let mut profile = vec![[0.0, 0.0], [3.0, 0.0]];
        profile.extend((0..=strips).map(|k| {
            let angle = std::f64::consts::FRAC_PI_2 * f64::from(k) / f64::from(strips);
            [3.0 - r + r * angle.cos(), 2.0 - r + r * angle.sin()]
        }));
        profile.push([0.0, 2.0]);
        let n = profile.len() as u32;
        let mut vertices: Vec<[f64; 3]> =
            [0.0, w].iter().flat_map(|&y| profile.iter().map(move |p| [p[0], y, p[1]])).collect();
        vertices.extend([[1.5, 0.0, 1.0], [1.5, w, 1.0]]);
        let mut triangles = Vec::new();
        for k in 0..n {
            let (a0, a1, b0, b1) = (k, (k + 1) % n, n + k, n + (k + 1) % n);
            triangles.extend([[a0, b1, a1], [a0, b0, b1], [2 * n, a0, a1], [2 * n + 1, b1, b0]]);
        }
        let faces = vec![1; triangles.len()];
        Surface::new(vertices, triangles, faces).unwrap()
    }

    /// The fillet's tangent edges have no angle, yet they bound faces as in the CAD model: the
    /// fillet is one face between the top and the side, whether in one strip or in twelve, and
    /// every face is a side of the box, the fillet or a cap.
    #[test]
    fn tangent_edges_bound_faces() {
        for strips in [1, 3, 12] {
            let mut s = filleted_box(strips);
            s.split_faces_at_feature_edges(30.0);
            let mut faces = s.face_ids().to_vec();
            faces.sort();
            faces.dedup();
            assert_eq!(faces.len(), 7, "{strips} strips: {:?}", s.face_ids());
            let n = strips + 4;
            let fillet: Vec<i32> = (2..2 + strips).map(|k| s.face_ids()[4 * k as usize]).collect();
            assert!(fillet.iter().all(|&f| f == fillet[0]), "{strips} strips: {fillet:?}");
            let (side, top) = (s.face_ids()[4], s.face_ids()[4 * (n as usize - 2)]);
            assert!(side != fillet[0] && top != fillet[0] && side != top, "{strips} strips: {:?}", s.face_ids());
            s.validate().unwrap();
        }
    }

    /// A mesh file's facet tags become the faces of its boundary; untagged facets share the
    /// face after the largest tag.
    #[test]
    fn mesh_boundary_faces_follow_the_facet_tags() {
        let mut cube = cube();
        cube.validate().unwrap();
        let mesh = crate::mesh3d::generate_3d(&cube, &crate::ConstantSize(0.5), &Default::default()).unwrap();
        let facets = FacetAdjacency::new(&mesh).unwrap().oriented_boundary_facets(&mesh);
        let on_plane = |facet: &[u32; 3], axis: usize| facet.iter().all(|&v| mesh.vertices()[v as usize][axis] == 0.0);
        let mut tags = BTreeMap::new();
        for facet in &facets {
            let mut key = facet.to_vec();
            key.sort_unstable();
            if on_plane(facet, 0) {
                tags.insert(key, 4);
            } else if on_plane(facet, 1) {
                tags.insert(key, 9);
            }
        }
        let boundary = Surface::from_mesh_boundary(&mesh, &tags).unwrap();
        let count = |id| boundary.face_ids().iter().filter(|&&f| f == id).count();
        assert_eq!(count(4), facets.iter().filter(|f| on_plane(f, 0)).count());
        assert_eq!(count(9), facets.iter().filter(|f| on_plane(f, 1) && !on_plane(f, 0)).count());
        assert_eq!(count(4) + count(9) + count(10), facets.len(), "the rest in face 10");
        assert!(count(4) > 0 && count(9) > 0 && count(10) > 0);
    }

    #[test]
    fn inside_out_surface_is_reversed_whole() {
        let mut s = cube();
        s.validate().unwrap();
        s.triangles.iter_mut().for_each(|t| t.swap(0, 1));
        assert!(s.enclosed_volume() < 0.0);
        assert_eq!(s.validate().unwrap().flipped_triangles, 12);
        assert!((s.enclosed_volume() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn file_errors_name_the_file() {
        let dir = std::env::temp_dir().join(format!("amber-surface-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("bad.obj");
        std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
        let err = Surface::load(&bad, StlFaceIds::Single).unwrap_err();
        assert!(matches!(err, SurfaceError::Read(MeshError::Parse { line: 3, .. })), "{err}");
        assert!(err.to_string().contains("bad.obj"), "{err}");
        // A cube missing one triangle of its bottom: readable, but not closed.
        let open = dir.join("open.obj");
        std::fs::write(
            &open,
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
            f 1 4 3\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
        )
        .unwrap();
        let err = Surface::load(&open, StlFaceIds::FromFile).unwrap_err();
        assert!(
            matches!(&err, SurfaceError::Defect { source: SurfaceDefect::OpenEdges { count: 3, .. }, .. }),
            "{err}"
        );
        assert!(err.to_string().contains("open.obj"));
        let missing = Surface::load(dir.join("missing.stl"), StlFaceIds::FromFile).unwrap_err();
        assert!(matches!(missing, SurfaceError::Read(MeshError::Io { .. })));
        assert!(matches!(
            Surface::load(dir.join("x.ply"), StlFaceIds::FromFile),
            Err(SurfaceError::Read(MeshError::UnsupportedFormat { .. }))
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn tolerance_welding_closes_cracks() {
        let mut corners = soup(&cube());
        corners[0][0] += 1e-9;
        let mut exact = Surface::from_triangle_soup(&corners, vec![1; 12], 0.0).unwrap();
        assert_eq!(exact.vertices().len(), 9);
        assert!(matches!(exact.validate(), Err(SurfaceDefect::OpenEdges { .. })));
        let mut welded = Surface::from_triangle_soup(&corners, vec![1; 12], 1e-6).unwrap();
        assert_eq!(welded.vertices().len(), 8);
        welded.validate().unwrap();
    }

    #[test]
    fn non_manifold_and_degenerate_surfaces_are_rejected() {
        let cube = cube();
        let corners = soup(&cube);
        // Two cubes sharing one corner vertex: every edge is fine, the vertex is not.
        let mut two = corners.clone();
        two.extend(corners.iter().map(|p| [p[0] + 1.0, p[1] + 1.0, p[2] + 1.0]));
        let mut s = Surface::from_triangle_soup(&two, vec![1; 24], 0.0).unwrap();
        assert!(matches!(s.validate(), Err(SurfaceDefect::NonManifoldVertex { fans: 2, .. })), "{:?}", s.validate());
        // The same triangle twice: three triangles on each of its edges.
        let mut three = corners.clone();
        three.extend_from_slice(&corners[..3]);
        let mut s = Surface::from_triangle_soup(&three, vec![1; 13], 0.0).unwrap();
        assert!(matches!(s.validate(), Err(SurfaceDefect::NonManifoldEdges { count: 3, .. })));
        // A collinear triangle.
        let mut flat = corners.clone();
        flat.extend([[0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.25, 0.25, 0.25]]);
        let mut s = Surface::from_triangle_soup(&flat, vec![1; 13], 0.0).unwrap();
        assert!(matches!(s.validate(), Err(SurfaceDefect::DegenerateTriangle { triangle: 12, .. })));
        assert!(matches!(
            Surface::new(vec![[0.0; 3]; 3], vec![[0, 1, 1]], vec![1]),
            Err(SurfaceDefect::DegenerateTriangle { .. })
        ));
    }

    #[test]
    fn overlapping_shells_are_a_self_intersection() {
        let corners = soup(&cube());
        let mut two = corners.clone();
        two.extend(corners.iter().map(|p| [p[0] + 0.5, p[1] + 0.25, p[2] + 0.125]));
        let mut s = Surface::from_triangle_soup(&two, (0..24).map(|t| t / 12 + 1).collect(), 0.0).unwrap();
        let err = s.validate().unwrap_err();
        assert!(matches!(err, SurfaceDefect::SelfIntersection { first_face: 1, second_face: 2, .. }), "{err}");
        // Apart, they are two valid components.
        let mut apart = corners.clone();
        apart.extend(corners.iter().map(|p| [p[0] + 2.0, p[1], p[2]]));
        let mut s = Surface::from_triangle_soup(&apart, vec![1; 24], 0.0).unwrap();
        let report = s.validate().unwrap();
        assert_eq!((report.components, report.genus()), (2, 0));
        assert!((report.enclosed_volume - 2.0).abs() < 1e-14);
    }

    /// A number from the flat JSON beside each surface (`"key": value`).
    fn json_number(path: &Path, key: &str) -> f64 {
        let text = std::fs::read_to_string(path.with_extension("json")).unwrap();
        let rest = &text[text.find(&format!("\"{key}\":")).unwrap_or_else(|| panic!("{key} in {}", path.display()))..];
        let value = rest[key.len() + 3..].trim_start();
        value[..value.find([',', '\n', '}']).unwrap_or(value.len())].trim().parse().unwrap()
    }

    #[test]
    fn shipped_console_surfaces_are_closed_manifold_outward_and_intersection_free() {
        use rayon::prelude::*;
        let Some(files) = console_reference_surfaces() else { return };
        let lines: Vec<String> = files
            .par_iter()
            .map(|path| {
                let start = std::time::Instant::now();
                let (surface, report) = Surface::load(path, StlFaceIds::FromFile).unwrap_or_else(|e| panic!("{e}"));
                let expected_volume = json_number(path, "enclosed_volume_mm3");
                assert_eq!(report.components, 1, "{}", path.display());
                assert_eq!(report.genus(), json_number(path, "genus") as i64, "{}", path.display());
                assert!(report.enclosed_volume > 0.0);
                assert!((report.enclosed_volume / expected_volume - 1.0).abs() < 1e-6, "{}", path.display());
                assert!(surface.face_ids().iter().all(|&id| id >= 1));
                format!(
                    "{}: {} triangles, {} CAD faces, {} flipped, genus {}, {:.1} mm³ (json {expected_volume:.1}), {:.0} ms",
                    path.display(),
                    surface.triangles().len(),
                    surface.face_ids().iter().max().unwrap_or(&0),
                    report.flipped_triangles,
                    report.genus(),
                    report.enclosed_volume,
                    start.elapsed().as_secs_f64() * 1e3
                )
            })
            .collect();
        lines.iter().for_each(|l| println!("{l}"));
    }

    /// TetGen on an un-adapted reference surface with `-pq1.4` and a coarse 5 mm size at every
    /// surface point: the tets fill the enclosed volume and the boundary keeps its face ids.
    /// Returns a one-line summary with tets and time.
    fn tetrahedralize_reference_surface(path: &Path) -> String {
        use crate::mesh3d::tetgen::{TetgenSwitches, tetrahedralize};
        let (surface, report) = Surface::load(path, StlFaceIds::FromFile).unwrap_or_else(|e| panic!("{e}"));
        let sizes = vec![5.0; surface.vertices().len()];
        let start = std::time::Instant::now();
        let out = tetrahedralize(&surface.to_plc(), Some(&sizes), None, &TetgenSwitches::plain_quality(1.4))
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let seconds = start.elapsed().as_secs_f64();
        assert!((out.mesh.total_volume() / report.enclosed_volume - 1.0).abs() < 1e-9, "{}", path.display());
        let ids: std::collections::HashSet<i32> = surface.face_ids().iter().copied().collect();
        assert!(out.boundary_markers.iter().all(|m| ids.contains(m)));
        let min_dihedral = out.mesh.min_angles().into_iter().fold(f64::INFINITY, f64::min);
        format!(
            "{}: {} surface triangles -> {} tets, {} boundary triangles, {:.2} s, min dihedral {min_dihedral:.1}°",
            path.display(),
            surface.triangles().len(),
            out.mesh.num_elements(),
            out.boundary.len(),
            seconds
        )
    }

    #[test]
    fn small_console_surfaces_tetrahedralize() {
        let Some(files) = console_reference_surfaces() else { return };
        for path in files.iter().filter(|p| p.ends_with("train/002.stl") || p.ends_with("val/002.stl")) {
            println!("{}", tetrahedralize_reference_surface(path));
        }
    }
}
