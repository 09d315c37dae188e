//! Geometry-only domains, with no task inputs beyond the geometry of their meshes: a solid
//! bounded by a validated, CAD-face-labelled surface ([`SolidPart`]) and a planar polygon with
//! holes ([`PlanarPart`]). A geometry-only model (Console's, or one trained on a folder of expert
//! meshes) meshes any part of its dimension; every problem of a folder dataset is one with its
//! expert's mesh.

use std::collections::BTreeMap;
use std::path::Path;

use amber_graph::FeatureSet;
use amber_mesh::{AnyMesh, FacetAdjacency, Mesh, Mesh2, Mesh3, MeshError, StlFaceIds, read_any_mesh, read_surface};
use amber_meshgen::mesh3d::{Mesh3dError, Mesh3dParams, Surface, SurfaceDistance, generate_3d};
use amber_meshgen::{
    ConstantSize, Mesh2dParams, MeshSizing, MeshgenError, PolygonDistance, PolygonDomain, generate_2d, uniform_mesh_2d,
};
use rayon::prelude::*;

use crate::TaskError;
use crate::cad::{Gmsh, TESSELLATION_SIZE_PER_INITIAL_SIZE, is_cad};
use crate::problem::{Column, Domain, ProblemError};

/// The dihedral angle above which an edge of a surface without CAD faces separates two faces:
/// sheet-metal bends and flanges meet at 90°, and a faceted curved face turns by far less per
/// edge at the resolutions a part is exported with.
pub const FEATURE_ANGLE_DEGREES: f64 = 30.0;

/// The validated surface of a solid from a geometry file: a surface (`.stl`, `.obj`) whose CAD
/// faces come from the file (the STL facet attribute or `solid` blocks, OBJ groups), a CAD file
/// (STEP, IGES, BREP; tessellated by gmsh with triangles up to
/// [`TESSELLATION_SIZE_PER_INITIAL_SIZE`] × `initial_size`, M⁰'s element size), or the boundary
/// of a tet mesh in any format amber reads (its faces the file's boundary groups). A surface
/// with a single face (a plain STL, a mesh boundary without groups) is split into faces at
/// edges sharper than `feature_angle` degrees and at tangent edges (where a flat face meets a
/// curved one), since the generator keeps vertices on their own
/// face and curves. The solid's name is a mesh file's domain group's, or the name of a surface's
/// single face (an STL of one `solid NAME`, as CAD exporters write a part).
pub fn read_solid_surface(path: &Path, feature_angle: f64, initial_size: f64) -> Result<Surface, TaskError> {
    let geometry = |message: String| TaskError::Geometry { path: path.into(), message };
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let soup = match extension.as_deref() {
        Some("stl" | "obj") => Some(read_surface(path, StlFaceIds::FromFile).map_err(|e| unreadable(path, e, ""))?),
        _ if is_cad(path) => Some(Gmsh::default().tessellate(path, TESSELLATION_SIZE_PER_INITIAL_SIZE * initial_size)?),
        _ => None,
    };
    match soup {
        Some(soup) => {
            let surface = Surface::from_triangle_soup(&soup.corners, soup.face_ids, 0.0)
                .map_err(|e| geometry(e.to_string()))?
                .with_face_names(soup.face_names);
            // One named face is a CAD exporter's `solid PART` (an OBJ's one group): the name of
            // the part, whose pieces after the split at feature edges get numbers.
            let single_face_name = single_face(&surface).and_then(|face| surface.face_names().get(&face).cloned());
            validated_solid(path, surface, feature_angle).map(|surface| surface.with_solid_name(single_face_name))
        }
        None => match read_any_mesh(path).map_err(|e| unreadable(path, e, "neither a surface nor a tet mesh: "))? {
            AnyMesh::Three(mesh, data) => {
                solid_surface_of_mesh(path, &mesh, &data.facet_tags, data.facet_names, feature_angle)
                    .map(|surface| surface.with_solid_name(data.domain_name))
            }
            AnyMesh::Two(..) => Err(geometry("holds triangles (a 2D geometry), not a solid".into())),
        },
    }
}

/// The error of a geometry file `path` that amber could not read as a mesh or surface: a file
/// that cannot be opened is an I/O error, anything else says what the file was expected to be.
fn unreadable(path: &Path, error: MeshError, expected: &str) -> TaskError {
    match error {
        MeshError::Io { source, .. } => TaskError::Io { path: path.into(), source },
        error => TaskError::Geometry { path: path.into(), message: format!("{expected}{error}") },
    }
}

/// The boundary of the tet mesh `mesh` (read from `path`) as a validated surface, its faces the
/// file's `facet_tags` (physical groups, skin properties) named by `facet_names` when they name
/// more than one, else found at edges sharper than `feature_angle` degrees and at tangent edges.
pub(crate) fn solid_surface_of_mesh(
    path: &Path,
    mesh: &Mesh3,
    facet_tags: &BTreeMap<Vec<u32>, i32>,
    facet_names: BTreeMap<i32, String>,
    feature_angle: f64,
) -> Result<Surface, TaskError> {
    let surface = Surface::from_mesh_boundary(mesh, facet_tags)
        .map_err(|e| TaskError::Geometry { path: path.into(), message: format!("boundary of the tet mesh: {e}") })?;
    validated_solid(path, surface.with_face_names(facet_names), feature_angle)
}

/// `surface` (from `path`) split at feature edges when it has a single face, and validated.
fn validated_solid(path: &Path, mut surface: Surface, feature_angle: f64) -> Result<Surface, TaskError> {
    if single_face(&surface).is_some() {
        surface.split_faces_at_feature_edges(feature_angle);
    }
    surface
        .validate()
        .map_err(|e| TaskError::Geometry { path: path.into(), message: format!("does not bound a solid: {e}") })?;
    Ok(surface)
}

/// The one face of a surface whose triangles all lie on the same face.
fn single_face(surface: &Surface) -> Option<i32> {
    match surface.face_ids() {
        [first, rest @ ..] if rest.iter().all(|id| id == first) => Some(*first),
        _ => None,
    }
}

/// A planar domain from a geometry file: a polygon JSON `{"outer": [[x, y], ...], "holes":
/// [...]}`, or the boundary of a triangle mesh in any format amber reads.
pub fn read_polygon_domain(path: &Path) -> Result<PolygonDomain, TaskError> {
    let geometry = |message: String| TaskError::Geometry { path: path.into(), message };
    let is_json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
    if is_json {
        let bytes = std::fs::read(path).map_err(|source| TaskError::Io { path: path.into(), source })?;
        let value: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|source| TaskError::Json { path: path.into(), source })?;
        if value.get("outer").is_some() {
            return serde_json::from_value(value).map_err(|e| geometry(format!("not a valid polygon domain: {e}")));
        }
    }
    match read_any_mesh(path).map_err(|e| unreadable(path, e, "neither a polygon nor a triangle mesh: "))? {
        AnyMesh::Two(mesh, _) => polygon_domain_of_mesh(path, &mesh),
        AnyMesh::Three(..) => Err(geometry("holds tetrahedra (a 3D geometry), not a planar domain".into())),
    }
}

/// The domain the triangle mesh `mesh` (read from `path`) covers.
pub(crate) fn polygon_domain_of_mesh(path: &Path, mesh: &Mesh2) -> Result<PolygonDomain, TaskError> {
    PolygonDomain::from_mesh_boundary(mesh)
        .map_err(|e| TaskError::Geometry { path: path.into(), message: format!("boundary of the mesh: {e}") })
}

/// The optional node inputs a geometry-only domain offers (see [`Domain::optional_inputs`]):
/// the log distance from each element's midpoint to the boundary and to the nearest feature (a
/// curve where two CAD faces meet in 3D, a corner in 2D), and how far the boundary turns at that
/// feature (radians), and the log radius of curvature of the boundary nearest to the midpoint
/// (within a CAD face in 3D, between corners in 2D; capped at the geometry's extent: a round hole
/// shows its radius, a flat face or straight edge the cap), and the log thickness of the wall
/// through the midpoint (the chord along the nearest boundary's normal; capped at the extent).
/// They come from the geometry alone, so every dataset has them.
pub const GEOMETRY_INPUTS: [&str; 5] =
    ["log_boundary_distance", "log_feature_distance", "feature_turn", "log_curvature_radius", "log_wall_thickness"];

/// The columns of [`GEOMETRY_INPUTS`] for elements with midpoints `midpoints`, given the distance
/// to the boundary of a point with the boundary's radius of curvature there, its distance to
/// the nearest feature with the feature's turn, and the wall's thickness there. Lengths are
/// clamped to [10⁻⁶, 1] × the geometry's extent `extent` before the logarithm; without
/// features, the feature lies at `extent` and turns by 0.
fn geometry_columns<const D: usize>(
    midpoints: &[[f64; D]],
    extent: f64,
    to_boundary: impl Fn([f64; D]) -> (f64, f64) + Sync,
    to_feature: impl Fn([f64; D]) -> Option<(f64, f64)> + Sync,
    wall_thickness: impl Fn([f64; D]) -> f64 + Sync,
) -> Vec<Column> {
    let floor = 1e-6 * extent;
    let log_length = |x: f64| x.clamp(floor, extent).ln();
    let rows: Vec<[f64; 5]> = midpoints
        .par_iter()
        .map(|&p| {
            let (to_boundary, radius) = to_boundary(p);
            let (to_feature, turn) = to_feature(p).unwrap_or((extent, 0.0));
            [
                to_boundary.max(floor).ln(),
                to_feature.max(floor).ln(),
                turn,
                log_length(radius),
                log_length(wall_thickness(p)),
            ]
        })
        .collect();
    GEOMETRY_INPUTS
        .iter()
        .enumerate()
        .map(|(i, name)| Column { name: (*name).into(), values: rows.iter().map(|row| row[i]).collect() })
        .collect()
}

/// The file beside a part's expert mesh (or geometry) that holds its inputs: `<stem>.inputs.json`.
pub const PART_INPUTS_SUFFIX: &str = ".inputs.json";

/// Inputs a part has beyond its geometry, from `<stem>.inputs.json`: named scalars (a load, a
/// material constant) and named points (an inlet, a clamp) that decide where an expert refines.
/// Each becomes a node input of every element, a scalar as it is and a point `p` as
/// `log_distance_to_<p>`, the log distance from the element's midpoint.
///
/// ```json
/// {"pressure": 2.5, "inlet": [10.0, 0.0, 42.0]}
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PartInputs<const D: usize> {
    scalars: BTreeMap<String, f64>,
    points: BTreeMap<String, [f64; D]>,
}

impl<const D: usize> PartInputs<D> {
    /// Reads a part's inputs file: a JSON object whose values are finite numbers or points of `D`
    /// finite coordinates.
    pub fn read(path: &Path) -> Result<Self, TaskError> {
        let value: serde_json::Value = amber_stdx::read_json(path)?;
        let invalid = |message: String| TaskError::Dataset { path: path.into(), message };
        let serde_json::Value::Object(entries) = value else {
            return Err(invalid("part inputs must be a JSON object of named numbers and points".into()));
        };
        let mut inputs = Self::default();
        for (name, value) in entries {
            let number = |v: &serde_json::Value| v.as_f64().filter(|x| x.is_finite());
            match &value {
                serde_json::Value::Array(coordinates) if coordinates.len() == D => {
                    let point: Option<Vec<f64>> = coordinates.iter().map(number).collect();
                    let point = point.ok_or_else(|| invalid(format!("`{name}`: a point of finite coordinates")))?;
                    inputs.points.insert(name, std::array::from_fn(|k| point[k]));
                }
                _ => match number(&value) {
                    Some(x) => {
                        inputs.scalars.insert(name, x);
                    }
                    None => {
                        return Err(invalid(format!("`{name}`: {value} is neither a finite number nor a {D}D point")));
                    }
                },
            }
        }
        Ok(inputs)
    }

    /// The names of the columns these inputs give, in the order [`Self::columns`] gives them.
    pub fn names(&self) -> Vec<String> {
        let points = self.points.keys().map(|name| format!("log_distance_to_{name}"));
        self.scalars.keys().cloned().chain(points).collect()
    }

    /// The columns on the elements with midpoints `midpoints`; distances are floored at 10⁻⁶ of
    /// the geometry's extent `extent` before the logarithm.
    fn columns(&self, midpoints: &[[f64; D]], extent: f64) -> Vec<Column> {
        let scalars = self.scalars.values().map(|&x| vec![x; midpoints.len()]);
        let points = self.points.values().map(|q| {
            let distance = |p: &[f64; D]| p.iter().zip(q).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
            midpoints.iter().map(|p| distance(p).max(1e-6 * extent).ln()).collect()
        });
        self.names().into_iter().zip(scalars.chain(points)).map(|(name, values)| Column { name, values }).collect()
    }
}

/// The length of the diagonal of a bounding box.
fn diagonal<const D: usize>((min, max): ([f64; D], [f64; D])) -> f64 {
    min.iter().zip(&max).map(|(a, b)| (b - a) * (b - a)).sum::<f64>().sqrt()
}

/// A solid to mesh: its bounding surface and M⁰.
#[derive(Clone, Debug)]
pub struct SolidPart {
    /// What errors and reports call it (a file stem, or `split/NNN` for Console parts).
    pub name: String,
    /// The validated surface (CAD face ids per triangle) every new mesh is made from.
    pub surface: Surface,
    /// M⁰: a uniform mesh of the solid.
    pub initial_mesh: Mesh3,
    /// The part's own inputs (none unless given).
    pub inputs: PartInputs<3>,
    distance: SurfaceDistance,
    /// The diagonal of the surface's bounding box.
    extent: f64,
}

impl SolidPart {
    /// Meshes M⁰ uniformly with size `initial_size` (no curvature cap, size factor 1: the Console
    /// reference's uniform gmsh mesh, see `console::INITIAL_MESH_RECIPE`).
    pub fn new(name: String, surface: Surface, initial_size: f64) -> Result<Self, Mesh3dError> {
        let params = Mesh3dParams { curvature_tolerance: f64::INFINITY, size_factor: 1.0, ..Mesh3dParams::default() };
        let initial_mesh = generate_3d(&surface, &ConstantSize(initial_size), &params)?;
        let distance = SurfaceDistance::new(&surface);
        let extent = amber_mesh::bounding_box(surface.vertices()).map_or(1.0, diagonal);
        Ok(Self { name, surface, initial_mesh, inputs: PartInputs::default(), distance, extent })
    }
}

impl Domain<3> for SolidPart {
    /// Geometric features only: node [volume], edge [3D midpoint difference].
    fn feature_set(&self) -> FeatureSet {
        FeatureSet::console()
    }

    fn optional_inputs(&self) -> Vec<String> {
        GEOMETRY_INPUTS.iter().map(|name| (*name).to_owned()).chain(self.inputs.names()).collect()
    }

    fn initial_mesh(&self) -> &Mesh<3> {
        &self.initial_mesh
    }

    /// The [`GEOMETRY_INPUTS`] and the part's inputs; the feature set's own features are
    /// computed by the graph.
    fn columns(&self, mesh: &Mesh<3>) -> Result<Vec<Column>, ProblemError> {
        let (midpoints, distance, extent) = (mesh.midpoints(), &self.distance, self.extent);
        let mut columns = geometry_columns(
            &midpoints,
            extent,
            |p| distance.to_surface(p),
            |p| distance.to_feature_curve(p),
            |p| distance.wall_thickness(p),
        );
        columns.extend(self.inputs.columns(&midpoints, extent));
        Ok(columns)
    }

    fn remesh(&self, mesh: &Mesh<3>, sizes: Vec<f64>, max_elements: usize) -> Result<Mesh<3>, ProblemError> {
        let params = Mesh3dParams::default().with_max_elements(max_elements);
        generate_3d(&self.surface, &MeshSizing::new(mesh, sizes), &params)
            .map_err(|e| ProblemError::Meshing(MeshgenError::from(e)))
    }

    fn boundary_tags(&self, mesh: &Mesh<3>) -> BTreeMap<Vec<u32>, i32> {
        cad_face_tags(&self.distance, mesh)
    }

    fn boundary_names(&self) -> BTreeMap<i32, String> {
        self.surface.face_names().clone()
    }

    fn domain_name(&self) -> Option<String> {
        self.surface.solid_name().map(str::to_owned)
    }
}

/// Every boundary triangle of `mesh` (a mesh of the solid `distance` measures), keyed by its
/// sorted vertices, tagged with the CAD face nearest its centroid: the generator keeps every
/// surface vertex on its own face and every triangle within one face, so this is the face it
/// was made on. Empty for a mesh whose facets do not pair up (not a generated mesh).
pub fn cad_face_tags(distance: &SurfaceDistance, mesh: &Mesh3) -> BTreeMap<Vec<u32>, i32> {
    boundary_facet_tags(mesh, |centroid| distance.nearest_face(centroid))
}

/// Every boundary edge of `mesh` (a mesh of the polygon `distance` measures), keyed by its sorted
/// vertices, tagged with the side of the polygon nearest its midpoint
/// ([`PolygonDistance::nearest_side`]: the stretches between corners). The generator splits the
/// polygon's edges, so each mesh edge lies on one side. Empty as [`cad_face_tags`].
pub fn polygon_side_tags(distance: &PolygonDistance, mesh: &Mesh2) -> BTreeMap<Vec<u32>, i32> {
    boundary_facet_tags(mesh, |midpoint| distance.nearest_side(midpoint))
}

/// The boundary facets of `mesh`, keyed by their sorted vertices, tagged by `piece` of their
/// centroids.
fn boundary_facet_tags<const D: usize>(
    mesh: &Mesh<D>,
    piece: impl Fn([f64; D]) -> Option<i32> + Sync,
) -> BTreeMap<Vec<u32>, i32> {
    let Ok(adjacency) = FacetAdjacency::new(mesh) else { return BTreeMap::new() };
    let vertices = mesh.vertices();
    (adjacency.oriented_boundary_facets(mesh).par_iter())
        .filter_map(|facet| {
            let centroid = amber_mesh::centroid::<D>(vertices, facet);
            let mut key = facet.to_vec();
            key.sort_unstable();
            piece(centroid).map(|tag| (key, tag))
        })
        .collect()
}

/// A planar domain to mesh: its polygon with holes and M⁰, meshed by the 2D generator.
#[derive(Clone, Debug)]
pub struct PlanarPart {
    /// What errors and reports call it (e.g. `split/stem` of a folder dataset).
    pub name: String,
    /// The polygon with holes every new mesh is made of.
    pub domain: PolygonDomain,
    /// M⁰: a uniform mesh of the domain.
    pub initial_mesh: Mesh2,
    /// The part's own inputs (none unless given).
    pub inputs: PartInputs<2>,
    geometry: PlanarGeometry,
}

impl PlanarPart {
    /// Meshes M⁰ uniformly with size `initial_size`.
    pub fn new(name: String, domain: PolygonDomain, initial_size: f64) -> Result<Self, MeshgenError> {
        let initial_mesh = uniform_mesh_2d(&domain, initial_size, &Mesh2dParams::default())?;
        let geometry = PlanarGeometry::new(&domain);
        Ok(Self { name, domain, initial_mesh, inputs: PartInputs::default(), geometry })
    }
}

/// What the [`GEOMETRY_INPUTS`] of a polygon with holes are measured with: a planar part's, and
/// the Poisson task's, whose domains are polygons too.
#[derive(Clone, Debug)]
pub(crate) struct PlanarGeometry {
    distance: PolygonDistance,
    /// The diagonal of the domain's bounding box.
    extent: f64,
}

impl PlanarGeometry {
    pub(crate) fn new(domain: &PolygonDomain) -> Self {
        Self { distance: PolygonDistance::new(domain), extent: diagonal(domain.bounding_box()) }
    }

    /// The [`GEOMETRY_INPUTS`] of elements with midpoints `midpoints`.
    pub(crate) fn columns(&self, midpoints: &[[f64; 2]]) -> Vec<Column> {
        let distance = &self.distance;
        geometry_columns(
            midpoints,
            self.extent,
            |p| distance.to_boundary(p),
            |p| distance.to_corner(p),
            |p| distance.wall_thickness(p),
        )
    }
}

impl Domain<2> for PlanarPart {
    /// Geometric features only: node [area], edge [2D midpoint difference].
    fn feature_set(&self) -> FeatureSet {
        FeatureSet::console()
    }

    fn optional_inputs(&self) -> Vec<String> {
        GEOMETRY_INPUTS.iter().map(|name| (*name).to_owned()).chain(self.inputs.names()).collect()
    }

    fn initial_mesh(&self) -> &Mesh<2> {
        &self.initial_mesh
    }

    /// The [`GEOMETRY_INPUTS`] and the part's inputs; the feature set's own features are
    /// computed by the graph.
    fn columns(&self, mesh: &Mesh<2>) -> Result<Vec<Column>, ProblemError> {
        let midpoints = mesh.midpoints();
        let mut columns = self.geometry.columns(&midpoints);
        columns.extend(self.inputs.columns(&midpoints, self.geometry.extent));
        Ok(columns)
    }

    fn remesh(&self, mesh: &Mesh<2>, sizes: Vec<f64>, max_elements: usize) -> Result<Mesh<2>, ProblemError> {
        let params = Mesh2dParams::default().with_max_elements(max_elements);
        Ok(generate_2d(&self.domain, &MeshSizing::new(mesh, sizes), &params)?)
    }

    fn boundary_tags(&self, mesh: &Mesh<2>) -> BTreeMap<Vec<u32>, i32> {
        polygon_side_tags(&self.geometry.distance, mesh)
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::FRAC_PI_2;

    use super::*;

    /// The L-shape meshed: every boundary edge is tagged with one of its six sides, and each
    /// side's edges lie on one line.
    #[test]
    fn boundary_edges_are_tagged_with_their_side_of_the_polygon() {
        let part = PlanarPart::new("l".into(), PolygonDomain::lshape([0.4, 0.6]).unwrap(), 0.05).unwrap();
        let mesh = &part.initial_mesh;
        let tags = part.boundary_tags(mesh);
        assert_eq!(tags.len(), FacetAdjacency::new(mesh).unwrap().boundary_facets().count());
        let mut sides: BTreeMap<i32, Vec<[f64; 2]>> = BTreeMap::new();
        for (edge, tag) in &tags {
            sides.entry(*tag).or_default().extend(edge.iter().map(|&v| mesh.vertices()[v as usize]));
        }
        assert_eq!(sides.keys().copied().collect::<Vec<_>>(), [1, 2, 3, 4, 5, 6]);
        for points in sides.values() {
            let (a, b) = (points[0], points[1]);
            let off_line = |p: &[f64; 2]| ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])).abs();
            assert!(points.iter().all(|p| off_line(p) < 1e-12), "{points:?}");
        }
    }

    /// M⁰ of the boundary of an expert mesh (reads `../shared/data/console`) at the sizes where
    /// TetGen failed on every remeshed surface with the background mesh of its vertices: filled,
    /// its tets the solid's volume (within the chords' loss on curved faces).
    #[test]
    fn an_expert_mesh_boundary_fills_at_every_initial_size() {
        let Some(data) = amber_testdata::shared("data/console") else { return };
        let path = data.join("train/015.nas");
        for h in [4.75, 5.45] {
            let surface = read_solid_surface(&path, FEATURE_ANGLE_DEGREES, h).unwrap();
            let volume = surface.enclosed_volume();
            let part = SolidPart::new("015".into(), surface, h).unwrap_or_else(|e| panic!("M⁰ at {h}: {e}"));
            let filled = part.initial_mesh.total_volume();
            assert!((filled / volume - 1.0).abs() < 5e-3, "M⁰ at {h}: {filled} for {volume}");
        }
    }

    /// The unit cube with its six sides as CAD faces 1..=6 (z = 0, z = 1, y = 0, y = 1, x = 0,
    /// x = 1), meshed at size 0.3.
    fn unit_cube_part() -> SolidPart {
        let v: Vec<[f64; 3]> = (0..8).map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64]).collect();
        let sides = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let triangles = sides.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        let faces = (1..=6).flat_map(|f| [f; 2]).collect();
        SolidPart::new("cube".into(), Surface::new(v, triangles, faces).unwrap(), 0.3).unwrap()
    }

    /// A cube of six CAD faces, meshed: every boundary triangle is tagged with the face it lies
    /// on (the coordinate that is 0 or 1 across its corners says which).
    #[test]
    fn boundary_triangles_are_tagged_with_their_cad_face() {
        let part = unit_cube_part();
        let mesh = &part.initial_mesh;
        let tags = part.boundary_tags(mesh);
        assert_eq!(tags.len(), FacetAdjacency::new(mesh).unwrap().boundary_facets().count());
        let plane =
            |face: i32| ([2, 2, 1, 1, 0, 0][face as usize - 1], [0.0, 1.0, 0.0, 1.0, 0.0, 1.0][face as usize - 1]);
        for (facet, &face) in &tags {
            let (axis, value) = plane(face);
            assert!(facet.iter().all(|&i| mesh.vertices()[i as usize][axis] == value), "{facet:?} on face {face}");
        }
        assert_eq!(tags.values().copied().collect::<std::collections::BTreeSet<_>>().len(), 6);
    }

    /// A geometry file that is not there is reported as such, once, whatever its format.
    #[test]
    fn a_missing_geometry_file_is_an_io_error() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["part.nas", "part.stl"] {
            let path = dir.path().join(name);
            let err = read_solid_surface(&path, FEATURE_ANGLE_DEGREES, 1.0).unwrap_err();
            assert!(matches!(err, TaskError::Io { .. }), "{name}: {err}");
            assert_eq!(err.to_string().matches(name).count(), 1, "{err}");
        }
        let err = read_polygon_domain(&dir.path().join("plate.msh")).unwrap_err();
        assert!(matches!(err, TaskError::Io { .. }), "{err}");
    }

    /// A tet mesh given as the geometry keeps its file's boundary groups as its faces: z = 0 and
    /// z = 1 in group 7, the other four sides in group 3, two faces where a split at its edges
    /// would make six; then meshing it tags its boundary with those groups, and its elements
    /// with the file's domain name.
    #[test]
    fn a_mesh_file_as_geometry_keeps_its_boundary_groups() {
        let part = unit_cube_part();
        let mesh = &part.initial_mesh;
        let group = |face: i32| if face <= 2 { 7 } else { 3 };
        let facet_tags = part.boundary_tags(mesh).into_iter().map(|(facet, face)| (facet, group(face))).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cube.msh");
        let data = amber_mesh::MeshData { facet_tags, domain_name: Some("block".into()), ..Default::default() }
            .with_facet_name(7, "ends");
        amber_mesh::write_mesh(mesh, &path, &data).unwrap();

        let surface = read_solid_surface(&path, FEATURE_ANGLE_DEGREES, 0.3).unwrap();
        let on_a_z_side = |t: &[u32; 3]| {
            let z = t.map(|i| surface.vertices()[i as usize][2]);
            z.iter().all(|&z| z == 0.0) || z.iter().all(|&z| z == 1.0)
        };
        for (t, &face) in surface.triangles().iter().zip(surface.face_ids()) {
            assert_eq!(face, if on_a_z_side(t) { 7 } else { 3 }, "{t:?}");
        }
        // The named group keeps its name; the other gets the writer's.
        let names = BTreeMap::from([(3, "boundary_3".into()), (7, "ends".into())]);
        assert_eq!(surface.face_names(), &names);
        let remeshed = SolidPart::new("cube".into(), surface, 0.3).unwrap();
        let tags = remeshed.boundary_tags(&remeshed.initial_mesh);
        assert_eq!(tags.values().copied().collect::<std::collections::BTreeSet<_>>(), [3, 7].into());
        assert_eq!(remeshed.boundary_names(), names);
        assert_eq!(remeshed.domain_name().as_deref(), Some("block"));
    }

    /// An STL of one named solid, as a CAD exporter writes a part, names the solid: its faces
    /// after the split at feature edges are numbered, and meshes of it put their elements in a
    /// group of the part's name. Two named solids are two faces, and name no solid.
    #[test]
    fn a_single_named_stl_solid_names_the_part() {
        let cube = unit_cube_part().surface;
        let dir = tempfile::tempdir().unwrap();
        // The cube's faces in one solid per name, face f in solid f mod `names.len()`.
        let read_stl = |names: &[&str]| {
            let mut text = String::new();
            for (solid, name) in names.iter().enumerate() {
                text += &format!("solid {name}\n");
                for (triangle, _) in
                    cube.triangles().iter().zip(cube.face_ids()).filter(|&(_, &f)| f as usize % names.len() == solid)
                {
                    text += "facet normal 0 0 0\nouter loop\n";
                    for &[x, y, z] in triangle.map(|i| cube.vertices()[i as usize]).iter() {
                        text += &format!("vertex {x} {y} {z}\n");
                    }
                    text += "endloop\nendfacet\n";
                }
                text += &format!("endsolid {name}\n");
            }
            let path = dir.path().join(format!("{}.stl", names.len()));
            std::fs::write(&path, text).unwrap();
            read_solid_surface(&path, FEATURE_ANGLE_DEGREES, 0.3).unwrap()
        };
        let one = read_stl(&["Bracket"]);
        assert_eq!(one.solid_name(), Some("Bracket"));
        assert_eq!(one.face_ids().iter().collect::<std::collections::BTreeSet<_>>().len(), 6);
        assert!(one.face_names().is_empty(), "{:?}", one.face_names());
        assert_eq!(SolidPart::new("cube".into(), one, 0.3).unwrap().domain_name().as_deref(), Some("Bracket"));
        let two = read_stl(&["even", "odd"]);
        assert_eq!(two.solid_name(), None);
        assert_eq!(two.face_names().values().map(String::as_str).collect::<Vec<_>>(), ["even", "odd"]);
    }

    /// Every element of an L-shaped plate gets the geometry inputs, no element is farther from
    /// the boundary than from the nearest corner, and the element nearest to the re-entrant
    /// corner sees the boundary turn a quarter right there.
    #[test]
    fn an_l_shaped_plate_has_its_geometry_inputs() {
        let part = PlanarPart::new("l".into(), PolygonDomain::lshape([0.5, 0.5]).unwrap(), 0.05).unwrap();
        let columns = part.columns(&part.initial_mesh).unwrap();
        let names: Vec<&str> = columns.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, GEOMETRY_INPUTS);
        let [boundary, feature, turn, radius, thickness] = [0, 1, 2, 3, 4].map(|i| &columns[i].values);
        // The upper arm of the L is 0.5 wide: near its left side the chord crosses it.
        let arm = part.initial_mesh.midpoints().iter().position(|&[x, y]| x < 0.15 && (y - 0.75).abs() < 0.1);
        let arm = arm.expect("an element in the upper arm");
        assert!((thickness[arm] - 0.5f64.ln()).abs() < 1e-9, "{}", thickness[arm].exp());
        // The L-shape's sides are straight: its curvature radius is the cap everywhere.
        assert!(radius.iter().all(|&r| (r - part.geometry.extent.ln()).abs() < 1e-12));
        assert!(boundary.iter().all(|v| v.is_finite()) && boundary.len() == part.initial_mesh.num_elements());
        assert!(boundary.iter().zip(feature).all(|(b, f)| b <= f));
        let distance_to_reentrant = |e: usize| {
            let [x, y] = part.initial_mesh.midpoint(e);
            (x - 0.5).hypot(y - 0.5)
        };
        let nearest =
            (0..boundary.len()).min_by(|&a, &b| distance_to_reentrant(a).total_cmp(&distance_to_reentrant(b)));
        let nearest = nearest.unwrap();
        assert!((turn[nearest] + FRAC_PI_2).abs() < 1e-12);
        assert!((feature[nearest] - distance_to_reentrant(nearest).ln()).abs() < 1e-12);
    }
}
