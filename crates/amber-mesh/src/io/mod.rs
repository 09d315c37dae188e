//! Reading and writing meshes, one entry point per direction, dispatching on the file extension:
//! `.vtu` (VTK XML), `.vtk` (legacy VTK), `.msh` (gmsh 2.2 and 4.1), `.json`, `.nas` (NASTRAN
//! bulk data), `.inp` (Abaqus) and `.mesh` (medit), in ASCII or binary wherever the format has
//! both; and reading triangle surfaces, `.stl` (binary or ASCII) and `.obj`, as the plain
//! triangles the file lists ([`TriangleSoup`]).
//!
//! Every mesh reader keeps only the simplices of the mesh dimension, quadratic ones (`tetra10`,
//! `triangle6`) as the linear simplices of their corner nodes (and says in
//! [`MeshData::linearised`] and [`MeshData::dropped`] what the file held beside linear ones), drops vertices no kept element uses (a stray
//! vertex would make an FEM system singular) and flips negatively oriented elements. Surfaces
//! are read as they are: welding and checking them is the mesher's job. Every writer writes to a
//! temporary file beside the target, fsyncs it and renames it (amber-stdx's
//! `write_atomic_with`), so a reader never sees a half-written file.

mod abaqus;
mod cursor;
mod json;
mod medit;
mod msh;
mod nastran;
mod nodes;
mod obj;
mod raw;
mod stl;
mod vtk;
mod vtu;

use std::collections::BTreeMap;
use std::path::Path;

pub use self::nodes::ElementOrder;
use self::nodes::Nodes;
use crate::{Mesh, Mesh2, Mesh3, MeshError};

/// What travels with a mesh in a file: named scalar fields with one value per element (`cell`)
/// or per vertex (`point`), tags on boundary facets, and what a reader left out.
///
/// `.vtu`, `.vtk`, `.msh` and `.json` store the fields; `.nas`, `.inp` and `.mesh` none. `.msh`
/// and `.mesh` store the facet tags (`.msh` with their names); `.inp` writes them as named node
/// sets and element-side surfaces (and reads the surfaces, and element sets of facet elements,
/// as named groups), and `.nas` (3D) as skin triangles under one property per tag.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Per-element fields, by name.
    pub cell: BTreeMap<String, Vec<f64>>,
    /// Per-vertex fields, by name.
    pub point: BTreeMap<String, Vec<f64>>,
    /// Tags of facets (edges in 2D, triangles in 3D), keyed by their sorted vertex indices: CAD
    /// face ids or boundary segment ids from the caller, or the physical groups (`.msh`) and
    /// references (`.mesh`) of a file's lower-dimensional elements. The `.msh` writer makes one
    /// physical group per tag (tags must be positive); without tags it writes one group for the
    /// whole boundary.
    pub facet_tags: BTreeMap<Vec<u32>, i32>,
    /// Names of facet tags (gmsh's `$PhysicalNames`), which the `.msh` and `.inp` writers give
    /// their boundary groups: a solver setup refers to `inlet`, not to tag 7. A tag without a
    /// name is written as `boundary_<tag>` (`boundary` when it is the only group).
    pub facet_names: BTreeMap<i32, String>,
    /// The name of the domain's element group when every element carries the same named one (a
    /// `.msh` physical group's, an Abaqus element set's, which its section assignment refers to,
    /// a NASTRAN solid property's comment); writers call the domain so, else `domain`.
    pub domain_name: Option<String>,
    /// Elements a reader dropped because they are neither simplices of the mesh dimension nor
    /// tagged facets (those are in `facet_tags`), counted by kind (`line`, `quad`, `hexahedron`,
    /// ...). Writers ignore it.
    pub dropped: BTreeMap<String, usize>,
    /// Quadratic simplices of the mesh dimension (`tetra10`, `triangle6`) a reader kept as the
    /// linear simplices of their corners, their edge nodes dropped, counted by kind. Writers
    /// ignore it.
    pub linearised: BTreeMap<String, usize>,
}

impl MeshData {
    /// No fields.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds (or replaces) a per-element field.
    pub fn with_cell(mut self, name: impl Into<String>, values: impl Into<Vec<f64>>) -> Self {
        self.cell.insert(name.into(), values.into());
        self
    }

    /// Adds (or replaces) a per-vertex field.
    pub fn with_point(mut self, name: impl Into<String>, values: impl Into<Vec<f64>>) -> Self {
        self.point.insert(name.into(), values.into());
        self
    }

    /// Adds (or replaces) the tag of the facet with these vertices (in any order).
    pub fn with_facet_tag(mut self, facet: impl Into<Vec<u32>>, tag: i32) -> Self {
        let mut facet = facet.into();
        facet.sort_unstable();
        self.facet_tags.insert(facet, tag);
        self
    }

    /// Adds (or replaces) the name of the facets tagged `tag`.
    pub fn with_facet_name(mut self, tag: i32, name: impl Into<String>) -> Self {
        self.facet_names.insert(tag, name.into());
        self
    }

    /// The name the writers give the boundary group of `tag`, one of `groups`: its name in
    /// [`MeshData::facet_names`], else `boundary` for a lone group and `boundary_<tag>` otherwise.
    fn group_name(&self, tag: i32, groups: usize) -> String {
        match self.facet_names.get(&tag) {
            Some(name) => name.clone(),
            None if groups == 1 => "boundary".to_owned(),
            None => format!("boundary_{tag}"),
        }
    }

    /// The name the writers give the domain's element group.
    fn domain_group_name(&self) -> &str {
        self.domain_name.as_deref().unwrap_or("domain")
    }

    /// Whether there are no fields and no facet tags.
    pub fn is_empty(&self) -> bool {
        self.cell.is_empty() && self.point.is_empty() && self.facet_tags.is_empty()
    }

    /// Checks that every field has one value per element or vertex.
    fn check_lengths(&self, path: &Path, num_elements: usize, num_vertices: usize) -> Result<(), MeshError> {
        let kinds = [("element", &self.cell, num_elements), ("vertex", &self.point, num_vertices)];
        for (kind, fields, expected) in kinds {
            if let Some((name, values)) = fields.iter().find(|(_, v)| v.len() != expected) {
                return Err(MeshError::DataLength {
                    path: path.to_owned(),
                    field: format!("{kind} field `{name}`"),
                    len: values.len(),
                    expected,
                });
            }
        }
        Ok(())
    }
}

/// The formats, named by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Vtu,
    Vtk,
    Msh,
    Json,
    Nastran,
    Abaqus,
    Medit,
}

/// The extensions of the mesh files amber reads and writes, for messages.
pub const MESH_FORMATS: &str = ".vtu, .vtk, .msh, .json, .nas, .inp, .mesh";

fn format_of(path: &Path) -> Option<Format> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "vtu" => Some(Format::Vtu),
        "vtk" => Some(Format::Vtk),
        "msh" => Some(Format::Msh),
        "json" => Some(Format::Json),
        "nas" | "bdf" => Some(Format::Nastran),
        "inp" => Some(Format::Abaqus),
        "mesh" => Some(Format::Medit),
        _ => None,
    }
}

/// How a format that has both writes its numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// Text.
    Ascii,
    /// Binary: `.msh` little-endian sections, `.vtu` inline base64, `.vtk` big-endian.
    Binary,
}

/// Reads a mesh, choosing the format by extension (`.vtu`, `.vtk`, `.msh`, `.json`, `.nas`,
/// `.inp`, `.mesh`). A file whose highest-dimensional elements are not `D`-dimensional is a
/// [`MeshError::DimensionMismatch`], so a caller that does not know the dimension can try 3, then 2.
///
/// ```no_run
/// let mesh: amber_mesh::Mesh3 = amber_mesh::read_mesh("expert.nas")?;
/// # Ok::<(), amber_mesh::MeshError>(())
/// ```
pub fn read_mesh<const D: usize>(path: impl AsRef<Path>) -> Result<Mesh<D>, MeshError> {
    read_mesh_with_data(path).map(|(mesh, _)| mesh)
}

/// Reads a mesh with the fields and facet tags stored with it, and what was dropped.
pub fn read_mesh_with_data<const D: usize>(path: impl AsRef<Path>) -> Result<(Mesh<D>, MeshData), MeshError> {
    let path = path.as_ref();
    match parse_raw(path, read_mesh_file(path)?)? {
        Parsed::Json(bytes) => json::read(path, &bytes),
        Parsed::Raw(raw) => raw.finish(path),
    }
}

/// A mesh in the dimension its file holds, with its data.
#[derive(Clone, Debug, PartialEq)]
pub enum AnyMesh {
    Two(Mesh2, MeshData),
    Three(Mesh3, MeshData),
}

/// Reads a mesh whose dimension is not known in advance: the highest dimension of the file's
/// elements decides (3: tetrahedra, 2: triangles). The file is parsed once.
pub fn read_any_mesh(path: impl AsRef<Path>) -> Result<AnyMesh, MeshError> {
    let path = path.as_ref();
    parse_any_mesh(path, read_mesh_file(path)?)
}

/// [`read_any_mesh`] of a file's contents: `path` chooses the format by its extension and names
/// the file in errors (the fuzz targets and their replay test feed arbitrary bytes through it).
pub fn parse_any_mesh(path: &Path, bytes: Vec<u8>) -> Result<AnyMesh, MeshError> {
    match parse_raw(path, bytes)? {
        Parsed::Json(bytes) => match json::read::<3>(path, &bytes) {
            Err(MeshError::DimensionMismatch { found: 2, .. }) => {
                json::read(path, &bytes).map(|(mesh, data)| AnyMesh::Two(mesh, data))
            }
            read => read.map(|(mesh, data)| AnyMesh::Three(mesh, data)),
        },
        Parsed::Raw(raw) => match raw.dimension() {
            2 => raw.finish(path).map(|(mesh, data)| AnyMesh::Two(mesh, data)),
            // Anything else is a DimensionMismatch from `finish`, naming what the file holds.
            _ => raw.finish(path).map(|(mesh, data)| AnyMesh::Three(mesh, data)),
        },
    }
}

/// A file parsed up to the point where the mesh dimension matters.
enum Parsed {
    Json(Vec<u8>),
    Raw(raw::RawMesh),
}

/// The bytes of a mesh file, once its extension names a format amber reads.
fn read_mesh_file(path: &Path) -> Result<Vec<u8>, MeshError> {
    if format_of(path).is_none() {
        return Err(MeshError::UnsupportedFormat { path: path.to_owned(), expected: MESH_FORMATS });
    }
    std::fs::read(path).map_err(|source| MeshError::Io { path: path.to_owned(), source })
}

fn parse_raw(path: &Path, bytes: Vec<u8>) -> Result<Parsed, MeshError> {
    let format = format_of(path)
        .ok_or_else(|| MeshError::UnsupportedFormat { path: path.to_owned(), expected: MESH_FORMATS })?;
    Ok(Parsed::Raw(match format {
        Format::Json => return Ok(Parsed::Json(bytes)),
        Format::Vtu => vtu::read(path, &bytes)?,
        Format::Vtk => vtk::read(path, &bytes)?,
        Format::Msh => msh::read(path, &bytes)?,
        Format::Nastran => nastran::read(path, &bytes)?,
        Format::Abaqus => abaqus::read(path, &bytes)?,
        Format::Medit => medit::read(path, &bytes)?,
    }))
}

/// Where the face ids of an STL file come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StlFaceIds {
    /// Binary STL: the 2-byte facet attribute (as gmsh-made reference surfaces store it);
    /// ASCII STL: the 1-based index of the `solid` block.
    FromFile,
    /// Every triangle gets face id 1 (plain STL, attribute ignored).
    Single,
}

/// The triangles of a surface file as it lists them: three corners per triangle (shared
/// vertices repeated, nothing welded or checked) and a face id per triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleSoup {
    /// `3 × face_ids.len()` corner positions, triangle after triangle.
    pub corners: Vec<[f64; 3]>,
    /// The face id of every triangle: from the STL file as `stl_face_ids` says, or the 1-based
    /// `g`/`o` group of an OBJ file in order of appearance.
    pub face_ids: Vec<i32>,
    /// The names of face ids where the file gives them: an ASCII STL's `solid NAME` blocks (with
    /// face ids from the file), an OBJ file's groups.
    pub face_names: BTreeMap<i32, String>,
}

const SURFACE_FORMATS: &str = ".stl, .obj";

/// Reads the triangles of a surface file, choosing the format by extension: `.stl` (binary when
/// the file size matches its facet count, else ASCII; face ids as `stl_face_ids` says) or
/// `.obj` (polygons fanned into triangles, one face id per `g`/`o` group). Errors name the file
/// and, for text, the line.
///
/// ```no_run
/// use amber_mesh::{StlFaceIds, read_surface};
/// let soup = read_surface("part.stl", StlFaceIds::FromFile)?;
/// assert_eq!(soup.corners.len(), 3 * soup.face_ids.len());
/// # Ok::<(), amber_mesh::MeshError>(())
/// ```
pub fn read_surface(path: impl AsRef<Path>, stl_face_ids: StlFaceIds) -> Result<TriangleSoup, MeshError> {
    let path = path.as_ref();
    let format = SurfaceFormat::of(path)?;
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io { path: path.to_owned(), source })?;
    format.parse(path, &bytes, stl_face_ids)
}

/// [`read_surface`] of a file's contents: `path` chooses the format and names the file in errors.
pub fn parse_surface(path: &Path, bytes: &[u8], stl_face_ids: StlFaceIds) -> Result<TriangleSoup, MeshError> {
    SurfaceFormat::of(path)?.parse(path, bytes, stl_face_ids)
}

enum SurfaceFormat {
    Stl,
    Obj,
}

impl SurfaceFormat {
    fn of(path: &Path) -> Result<Self, MeshError> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("stl") => Ok(Self::Stl),
            Some("obj") => Ok(Self::Obj),
            _ => Err(MeshError::UnsupportedFormat { path: path.to_owned(), expected: SURFACE_FORMATS }),
        }
    }

    fn parse(self, path: &Path, bytes: &[u8], stl_face_ids: StlFaceIds) -> Result<TriangleSoup, MeshError> {
        match self {
            Self::Stl => stl::read(path, bytes, stl_face_ids),
            Self::Obj => obj::read(path, bytes),
        }
    }
}

/// Three whitespace-separated coordinates; the error says which word is wrong.
fn parse_point<'a>(mut words: impl Iterator<Item = &'a str>) -> Result<[f64; 3], String> {
    let mut p = [0.0; 3];
    for x in &mut p {
        let word = words.next().ok_or("expected 3 coordinates")?;
        *x = word.parse().map_err(|_| format!("`{word}` is not a number"))?;
    }
    Ok(p)
}

/// Writes a mesh with optional scalar fields, choosing the format by extension (`.vtu`, `.vtk`,
/// `.msh`, `.json`, `.nas`, `.inp`, `.mesh`) in its default encoding: binary `.vtu`, ASCII for
/// the rest. The file appears atomically: it is written beside `path` and renamed.
///
/// ```no_run
/// # let mesh = amber_mesh::Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2])?;
/// let data = amber_mesh::MeshData::new().with_cell("h", mesh.sizes());
/// amber_mesh::write_mesh(&mesh, "step-03.vtu", &data)?;
/// # Ok::<(), amber_mesh::MeshError>(())
/// ```
pub fn write_mesh<const D: usize>(mesh: &Mesh<D>, path: impl AsRef<Path>, data: &MeshData) -> Result<(), MeshError> {
    write_mesh_as(mesh, path, data, WriteOptions::default())
}

/// How [`write_mesh_as`] writes: the encoding (`None`: the format's default; `.msh`, `.vtu` and
/// `.vtk` have both, asking a text-only format for binary is an error) and the element order
/// (second order in `.msh`, `.vtu`, `.vtk`, `.nas` and `.inp`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WriteOptions {
    pub encoding: Option<Encoding>,
    pub order: ElementOrder,
}

/// [`write_mesh`] with [`WriteOptions`].
///
/// ```no_run
/// # let mesh = amber_mesh::Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2])?;
/// // Edges 0-1 and 1-2 in physical group 3, edge 2-0 in group 4.
/// let data = amber_mesh::MeshData::new().with_facet_tag([0, 1], 3).with_facet_tag([1, 2], 3).with_facet_tag([2, 0], 4);
/// let options = amber_mesh::WriteOptions { encoding: Some(amber_mesh::Encoding::Binary), ..Default::default() };
/// amber_mesh::write_mesh_as(&mesh, "solver.msh", &data, options)?;
/// // 10-node tetrahedra for Abaqus.
/// # let mesh = amber_mesh::Mesh3::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], vec![0, 1, 2, 3])?;
/// let options = amber_mesh::WriteOptions { order: amber_mesh::ElementOrder::Quadratic, ..Default::default() };
/// amber_mesh::write_mesh_as(&mesh, "part.inp", &amber_mesh::MeshData::new(), options)?;
/// # Ok::<(), amber_mesh::MeshError>(())
/// ```
pub fn write_mesh_as<const D: usize>(
    mesh: &Mesh<D>,
    path: impl AsRef<Path>,
    data: &MeshData,
    options: WriteOptions,
) -> Result<(), MeshError> {
    let path = path.as_ref();
    let (format, binary) = output_format(path, options)?;
    data.check_lengths(path, mesh.num_elements(), mesh.num_vertices())?;
    let nodes = Nodes::new(mesh, options.order);
    match format {
        Format::Vtu => write_atomic(path, |w| vtu::write(&nodes, data, binary, w).map_err(write_error(path))),
        Format::Vtk => write_atomic(path, |w| vtk::write(&nodes, data, binary, w, path)),
        Format::Msh => write_atomic(path, |w| msh::write(&nodes, data, binary, w, path)),
        Format::Json => write_atomic(path, |w| json::write(mesh, data, w, path)),
        Format::Nastran => write_atomic(path, |w| nastran::write(&nodes, data, w, path)),
        Format::Abaqus => write_atomic(path, |w| abaqus::write(&nodes, data, w, path)),
        Format::Medit => write_atomic(path, |w| medit::write(mesh, data, w, path)),
    }
}

/// Checks before any work that [`write_mesh_as`] can write `path` with `options`: a mesh format
/// by extension, with the encoding and element order asked for. The error names the file.
pub fn check_output(path: &Path, options: WriteOptions) -> Result<(), MeshError> {
    output_format(path, options).map(|_| ())
}

/// The format of `path` and whether it is written in binary, or why it cannot be written so.
fn output_format(path: &Path, options: WriteOptions) -> Result<(Format, bool), MeshError> {
    let format = format_of(path)
        .ok_or_else(|| MeshError::UnsupportedFormat { path: path.to_owned(), expected: MESH_FORMATS })?;
    let binary = match (format, options.encoding) {
        (Format::Vtu, None) | (_, Some(Encoding::Binary)) => true,
        (_, None | Some(Encoding::Ascii)) => false,
    };
    let refuse = |message: &str| Err(MeshError::Format { path: path.to_owned(), message: message.to_owned() });
    if binary && !matches!(format, Format::Vtu | Format::Vtk | Format::Msh) {
        return refuse("this format has no binary encoding");
    }
    if options.order == ElementOrder::Quadratic && matches!(format, Format::Json | Format::Medit) {
        return refuse("second-order elements are written to .msh, .vtu, .vtk, .nas and .inp only");
    }
    Ok((format, binary))
}

/// The facet adjacency of a mesh a writer groups the boundary of; a mesh without one (elements
/// that overlap) is an error naming the file.
fn writer_adjacency<const D: usize>(mesh: &Mesh<D>, path: &Path) -> Result<crate::FacetAdjacency, MeshError> {
    crate::FacetAdjacency::new(mesh)
        .map_err(|source| MeshError::InvalidMesh { path: path.to_owned(), source: Box::new(source) })
}

/// The facets a writer stores with their tags: every tagged facet, and the untagged boundary
/// facets (of `adjacency`, the mesh's) with `untagged` (one past the largest tag, or 1 when
/// nothing is tagged).
fn tagged_facets<const D: usize>(
    mesh: &Mesh<D>,
    adjacency: &crate::FacetAdjacency,
    data: &MeshData,
    path: &Path,
) -> Result<Vec<(Vec<u32>, i32)>, MeshError> {
    if let Some(facet) =
        data.facet_tags.keys().find(|k| k.len() != D || k.iter().any(|&v| v as usize >= mesh.num_vertices()))
    {
        let message = format!("facet tag on {facet:?}, which is not {D} vertices of the mesh");
        return Err(MeshError::Format { path: path.to_owned(), message });
    }
    let untagged = data.facet_tags.values().max().map_or(1, |&t| t.saturating_add(1));
    let mut facets: Vec<(Vec<u32>, i32)> = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for facet in adjacency.oriented_boundary_facets(mesh) {
        let facet = facet.to_vec();
        let mut key = facet.clone();
        key.sort_unstable();
        facets.push((facet, data.facet_tags.get(&key).copied().unwrap_or(untagged)));
        seen.insert(key);
    }
    facets.extend(data.facet_tags.iter().filter(|(k, _)| !seen.contains(*k)).map(|(k, &t)| (k.clone(), t)));
    facets.sort_by_key(|&(_, t)| t);
    Ok(facets)
}

/// Fails unless every tag of `facets` is positive, which `what` (the format's groups) needs.
fn require_positive_tags(facets: &[(Vec<u32>, i32)], path: &Path, what: &str) -> Result<(), MeshError> {
    match facets.iter().find(|(_, t)| *t <= 0) {
        Some((_, tag)) => Err(MeshError::Format {
            path: path.to_owned(),
            message: format!("facet tag {tag}: {what} need positive tags"),
        }),
        None => Ok(()),
    }
}

/// Every file this crate writes goes through amber-stdx's atomic writer (temporary file,
/// fsync, rename); its file errors become [`MeshError::Io`].
pub(crate) use amber_stdx::write_atomic_with as write_atomic;

/// Maps an io error while writing `path`.
fn write_error(path: &Path) -> impl Fn(std::io::Error) -> MeshError + '_ {
    move |source| MeshError::Io { path: path.to_owned(), source }
}

/// Builds the mesh a reader parsed: checks the field lengths against what was parsed, drops
/// unused vertices (remapping per-vertex fields) and reorients negative elements.
fn assemble<const D: usize>(
    path: &Path,
    vertices: Vec<[f64; D]>,
    cells: Vec<u32>,
    mut data: MeshData,
) -> Result<(Mesh<D>, MeshData), MeshError> {
    let invalid = |source| MeshError::InvalidMesh { path: path.to_owned(), source: Box::new(source) };
    if !cells.len().is_multiple_of(D + 1) {
        return Err(invalid(MeshError::Connectivity { len: cells.len(), nodes_per_element: D + 1 }));
    }
    data.check_lengths(path, cells.len() / (D + 1), vertices.len())?;
    let mut new_index = vec![u32::MAX; vertices.len()];
    for (element, cell) in cells.chunks_exact(D + 1).enumerate() {
        for &v in cell {
            let slot = new_index.get_mut(v as usize).ok_or_else(|| {
                invalid(MeshError::VertexOutOfRange { element, vertex: v, num_vertices: vertices.len() })
            })?;
            *slot = 0;
        }
    }
    let kept: Vec<usize> = (0..vertices.len()).filter(|&v| new_index[v] == 0).collect();
    for (new, &old) in kept.iter().enumerate() {
        new_index[old] = new as u32;
    }
    // Facets on vertices no element uses (or outside the file's points) go with them.
    let renumber = |v: &u32| new_index.get(*v as usize).copied().filter(|&i| i != u32::MAX);
    data.facet_tags = std::mem::take(&mut data.facet_tags)
        .into_iter()
        .filter_map(|(facet, tag)| {
            let mut facet = facet.iter().map(renumber).collect::<Option<Vec<u32>>>()?;
            facet.sort_unstable();
            Some((facet, tag))
        })
        .collect();
    let (vertices, cells) = if kept.len() == vertices.len() {
        (vertices, cells)
    } else {
        for values in data.point.values_mut() {
            *values = kept.iter().map(|&old| values[old]).collect();
        }
        (kept.iter().map(|&old| vertices[old]).collect(), cells.iter().map(|&v| new_index[v as usize]).collect())
    };
    let mesh = Mesh::new_reoriented(vertices, cells).map_err(invalid)?;
    Ok((mesh, data))
}

/// Line-by-line reading of a text file with 1-based line numbers for error messages. Lines may
/// end in LF or CRLF; each line is checked for UTF-8 only when it is read, so a binary file fails
/// at its first binary line rather than up front.
struct Lines<'a> {
    path: &'a Path,
    rest: &'a [u8],
    line: usize,
}

impl<'a> Lines<'a> {
    fn new(path: &'a Path, bytes: &'a [u8]) -> Self {
        Self { path, rest: bytes, line: 0 }
    }

    /// The next line without its line ending, or `None` at the end of the file.
    fn next(&mut self) -> Result<Option<&'a str>, MeshError> {
        if self.rest.is_empty() {
            return Ok(None);
        }
        let (line, rest) = match self.rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&self.rest[..i], &self.rest[i + 1..]),
            None => (self.rest, &self.rest[self.rest.len()..]),
        };
        self.rest = rest;
        self.line += 1;
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        std::str::from_utf8(line).map(Some).map_err(|_| self.error("not a text line (binary data?)"))
    }

    /// The next line, which must exist.
    fn expect(&mut self, what: &str) -> Result<&'a str, MeshError> {
        self.next()?.ok_or_else(|| MeshError::Parse {
            path: self.path.to_owned(),
            line: self.line + 1,
            message: format!("unexpected end of file, expected {what}"),
        })
    }

    /// An error at the current line.
    fn error(&self, message: impl Into<String>) -> MeshError {
        MeshError::Parse { path: self.path.to_owned(), line: self.line, message: message.into() }
    }

    /// Parses one whitespace-separated token of the current line.
    fn parse<T: std::str::FromStr>(&self, token: Option<&str>, what: &str) -> Result<T, MeshError> {
        let token = token.ok_or_else(|| self.error(format!("missing {what}")))?;
        token.parse().map_err(|_| self.error(format!("bad {what} `{token}`")))
    }
}

/// A unique scratch directory for one test, removed by the caller.
#[cfg(test)]
pub(crate) fn test_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("amber-mesh-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Mesh2, Mesh3};

    fn square() -> Mesh2 {
        Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap()
    }

    fn tet() -> Mesh3 {
        Mesh3::new(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], vec![0, 1, 2, 3]).unwrap()
    }

    /// Every writer through the matching reader, in every encoding: the same mesh bit for bit,
    /// the fields where the format stores them, the boundary as facet tags where it has them.
    #[test]
    fn every_writable_format_round_trips_mesh_and_data() {
        let dir = test_dir("round-trip");
        let m2 = square();
        let d2 = MeshData::new().with_cell("h", m2.sizes()).with_point("u", vec![0.0, 0.5, 1.0, 0.1 + 0.2]);
        let m3 = tet();
        let d3 = MeshData::new().with_cell("h", m3.sizes());
        let encodings = [None, Some(Encoding::Ascii), Some(Encoding::Binary)];
        for ext in ["vtu", "vtk", "msh", "json", "nas", "inp", "mesh", "VTU"] {
            for encoding in encodings {
                let p2 = dir.join(format!("m2.{ext}"));
                let written = write_mesh_as(&m2, &p2, &d2, WriteOptions { encoding, ..Default::default() });
                if encoding == Some(Encoding::Binary) && !matches!(ext, "vtu" | "vtk" | "msh" | "VTU") {
                    assert!(written.unwrap_err().to_string().contains("no binary encoding"), "{ext}");
                    continue;
                }
                written.unwrap();
                let (back, data) = read_mesh_with_data::<2>(&p2).unwrap();
                assert_eq!(back, m2, "{ext} {encoding:?}");
                let has_fields = matches!(ext, "vtu" | "vtk" | "msh" | "json" | "VTU");
                assert_eq!(
                    (data.cell, data.point),
                    if has_fields { (d2.cell.clone(), d2.point.clone()) } else { Default::default() }
                );
                let boundary_edges = if matches!(ext, "msh" | "mesh" | "inp") { 4 } else { 0 };
                assert_eq!(data.facet_tags.len(), boundary_edges, "{ext}");
                let p3 = dir.join(format!("m3.{ext}"));
                write_mesh_as(&m3, &p3, &d3, WriteOptions { encoding, ..Default::default() }).unwrap();
                let (back, data) = read_mesh_with_data::<3>(&p3).unwrap();
                assert_eq!(back, m3, "{ext} {encoding:?}");
                assert_eq!(data.cell, if has_fields { d3.cell.clone() } else { Default::default() });
                assert!(matches!(read_mesh::<2>(&p3), Err(MeshError::DimensionMismatch { found: 3, .. })), "{ext}");
            }
        }
        let leftovers: Vec<_> =
            std::fs::read_dir(&dir).unwrap().filter_map(|e| e.ok()).map(|e| e.file_name()).collect();
        assert!(leftovers.iter().all(|n| !n.to_string_lossy().ends_with(".tmp")), "{leftovers:?}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    /// Second-order output through amber's own readers, which keep the corners: the same mesh bit
    /// for bit, every element counted as linearised, the fields and boundary groups kept; the
    /// formats without second-order elements refuse it.
    #[test]
    fn second_order_output_reads_back_as_its_corner_mesh() {
        let dir = test_dir("second-order");
        let m2 = square();
        let d2 = MeshData::new().with_cell("h", m2.sizes()).with_point("u", vec![0.0, 0.5, 1.0, 0.1 + 0.2]);
        let m3 = tet();
        let d3 = MeshData::new().with_cell("h", m3.sizes()).with_facet_tag([0, 1, 2], 7);
        for ext in ["vtu", "vtk", "msh", "nas", "inp", "json", "mesh"] {
            for encoding in [Some(Encoding::Ascii), Some(Encoding::Binary)] {
                if encoding == Some(Encoding::Binary) && !matches!(ext, "vtu" | "vtk" | "msh") {
                    continue;
                }
                let options = WriteOptions { encoding, order: ElementOrder::Quadratic };
                let p2 = dir.join(format!("m2.{ext}"));
                let written = write_mesh_as(&m2, &p2, &d2, options);
                if matches!(ext, "json" | "mesh") {
                    assert!(written.unwrap_err().to_string().contains("second-order"), "{ext}");
                    continue;
                }
                written.unwrap();
                let (back, data) = read_mesh_with_data::<2>(&p2).unwrap();
                assert_eq!(back, m2, "{ext} {encoding:?}");
                assert_eq!(data.linearised, BTreeMap::from([("triangle6".to_owned(), 2)]), "{ext}");
                if matches!(ext, "vtu" | "vtk" | "msh") {
                    assert_eq!((&data.cell, &data.point), (&d2.cell, &d2.point), "{ext}");
                }
                let p3 = dir.join(format!("m3.{ext}"));
                write_mesh_as(&m3, &p3, &d3, options).unwrap();
                let (back, data) = read_mesh_with_data::<3>(&p3).unwrap();
                assert_eq!(back, m3, "{ext} {encoding:?}");
                assert_eq!(data.linearised, BTreeMap::from([("tetra10".to_owned(), 1)]), "{ext}");
                if ext == "msh" {
                    assert_eq!(data.facet_tags.len(), 4);
                    assert_eq!(data.facet_tags[&vec![0, 1, 2]], 7);
                }
            }
        }
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn unknown_extensions_are_unsupported() {
        let dir = test_dir("unsupported");
        let err = write_mesh(&square(), dir.join("m.stl"), &MeshData::new()).unwrap_err();
        assert!(matches!(err, MeshError::UnsupportedFormat { .. }), "{err}");
        assert!(err.to_string().contains("m.stl"));
        assert!(matches!(read_mesh::<2>(dir.join("m")), Err(MeshError::UnsupportedFormat { .. })));
        assert!(matches!(read_mesh::<2>(dir.join("missing.vtu")), Err(MeshError::Io { .. })));
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn surfaces_are_read_by_extension_and_errors_name_the_file() {
        let dir = test_dir("surface");
        let path = dir.join("tri.OBJ");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let soup = read_surface(&path, StlFaceIds::FromFile).unwrap();
        assert_eq!(
            soup,
            TriangleSoup {
                corners: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                face_ids: vec![1],
                face_names: BTreeMap::new()
            }
        );
        let bad = dir.join("bad.obj");
        std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
        let err = read_surface(&bad, StlFaceIds::Single).unwrap_err();
        assert!(matches!(err, MeshError::Parse { line: 3, .. }) && err.to_string().contains("bad.obj"), "{err}");
        let err = read_surface(dir.join("missing.stl"), StlFaceIds::FromFile).unwrap_err();
        assert!(matches!(err, MeshError::Io { .. }) && err.to_string().contains("missing.stl"), "{err}");
        let err = read_surface(dir.join("x.ply"), StlFaceIds::FromFile).unwrap_err();
        assert!(matches!(err, MeshError::UnsupportedFormat { .. }) && err.to_string().contains("x.ply"), "{err}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn fields_of_the_wrong_length_are_rejected_before_writing() {
        let dir = test_dir("data-length");
        let path = dir.join("m.vtu");
        let err = write_mesh(&square(), &path, &MeshData::new().with_cell("h", vec![1.0])).unwrap_err();
        assert!(matches!(err, MeshError::DataLength { len: 1, expected: 2, .. }), "{err}");
        assert!(!path.exists());
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn assemble_drops_unused_vertices_and_reorients() {
        let vertices = vec![[9.0, 9.0], [0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let data = MeshData::new().with_point("u", vec![-1.0, 1.0, 2.0, 3.0]).with_cell("h", vec![5.0]);
        let (mesh, data) = assemble::<2>(Path::new("x"), vertices, vec![1, 3, 2], data).unwrap();
        assert_eq!(mesh.vertices(), &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        assert!(mesh.volume(0) > 0.0);
        assert_eq!(data.point["u"], vec![1.0, 2.0, 3.0]);
        let err = assemble::<2>(Path::new("x"), vec![[0.0, 0.0]], vec![0, 1, 2], MeshData::new()).unwrap_err();
        assert!(matches!(err, MeshError::InvalidMesh { .. }), "{err}");
    }
}
