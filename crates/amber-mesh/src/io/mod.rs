//! Reading and writing meshes, one entry point per direction, dispatching on the file extension:
//! `.vtu` (VTK XML, binary), `.msh` (gmsh 4.1 ASCII), `.json`, and `.nas` (NASTRAN bulk data,
//! read only); and reading triangle surfaces, `.stl` (binary or ASCII) and `.obj`, as the plain
//! triangles the file lists ([`TriangleSoup`]).
//!
//! Every mesh reader keeps only the simplices of the mesh dimension, drops vertices no kept
//! element uses (a stray vertex would make an FEM system singular) and flips negatively oriented
//! elements. Surfaces are read as they are: welding and checking them is the mesher's job. Every
//! writer writes to a temporary file beside the target, fsyncs it and renames it (amber-stdx's
//! `write_atomic_with`), so a reader never sees a half-written file.

mod json;
mod msh;
mod nastran;
mod obj;
mod stl;
mod vtu;

use std::collections::BTreeMap;
use std::path::Path;

use crate::{Mesh, MeshError};

/// Named scalar fields on a mesh: one value per element (`cell`) or per vertex (`point`).
///
/// `.vtu`, `.msh` and `.json` store them; `.nas` has none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Per-element fields, by name.
    pub cell: BTreeMap<String, Vec<f64>>,
    /// Per-vertex fields, by name.
    pub point: BTreeMap<String, Vec<f64>>,
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

    /// Whether there are no fields at all.
    pub fn is_empty(&self) -> bool {
        self.cell.is_empty() && self.point.is_empty()
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
    Msh,
    Json,
    Nastran,
}

const READ_FORMATS: &str = ".vtu, .msh, .json, .nas";
const WRITE_FORMATS: &str = ".vtu, .msh, .json";

fn format_of(path: &Path) -> Option<Format> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "vtu" => Some(Format::Vtu),
        "msh" => Some(Format::Msh),
        "json" => Some(Format::Json),
        "nas" => Some(Format::Nastran),
        _ => None,
    }
}

/// Reads a mesh, choosing the format by extension (`.vtu`, `.msh`, `.json`, `.nas`).
///
/// ```no_run
/// let mesh: amber_mesh::Mesh3 = amber_mesh::read_mesh("expert.nas")?;
/// # Ok::<(), amber_mesh::MeshError>(())
/// ```
pub fn read_mesh<const D: usize>(path: impl AsRef<Path>) -> Result<Mesh<D>, MeshError> {
    read_mesh_with_data(path).map(|(mesh, _)| mesh)
}

/// Reads a mesh and the scalar fields stored with it (none for `.nas`).
pub fn read_mesh_with_data<const D: usize>(path: impl AsRef<Path>) -> Result<(Mesh<D>, MeshData), MeshError> {
    let path = path.as_ref();
    let format = format_of(path)
        .ok_or_else(|| MeshError::UnsupportedFormat { path: path.to_owned(), expected: READ_FORMATS })?;
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io { path: path.to_owned(), source })?;
    match format {
        Format::Vtu => vtu::read(path, &bytes),
        Format::Msh => msh::read(path, &bytes),
        Format::Json => json::read(path, &bytes),
        Format::Nastran => nastran::read(path, &bytes),
    }
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
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let is_stl = match extension.as_deref() {
        Some("stl") => true,
        Some("obj") => false,
        _ => return Err(MeshError::UnsupportedFormat { path: path.to_owned(), expected: SURFACE_FORMATS }),
    };
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io { path: path.to_owned(), source })?;
    if is_stl { stl::read(path, &bytes, stl_face_ids) } else { obj::read(path, &bytes) }
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

/// Writes a mesh with optional scalar fields, choosing the format by extension (`.vtu`, `.msh`,
/// `.json`). The file appears atomically: it is written beside `path` and renamed.
///
/// ```no_run
/// # let mesh = amber_mesh::Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2])?;
/// let data = amber_mesh::MeshData::new().with_cell("h", mesh.sizes());
/// amber_mesh::write_mesh(&mesh, "step-03.vtu", &data)?;
/// # Ok::<(), amber_mesh::MeshError>(())
/// ```
pub fn write_mesh<const D: usize>(mesh: &Mesh<D>, path: impl AsRef<Path>, data: &MeshData) -> Result<(), MeshError> {
    let path = path.as_ref();
    let unsupported = || MeshError::UnsupportedFormat { path: path.to_owned(), expected: WRITE_FORMATS };
    let format = format_of(path).ok_or_else(unsupported)?;
    data.check_lengths(path, mesh.num_elements(), mesh.num_vertices())?;
    match format {
        Format::Vtu => write_atomic(path, |w| vtu::write(mesh, data, w, path)),
        Format::Msh => write_atomic(path, |w| msh::write(mesh, data, w, path)),
        Format::Json => write_atomic(path, |w| json::write(mesh, data, w, path)),
        Format::Nastran => Err(unsupported()),
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
    let (vertices, cells) = if kept.len() == vertices.len() {
        (vertices, cells)
    } else {
        for (new, &old) in kept.iter().enumerate() {
            new_index[old] = new as u32;
        }
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

    #[test]
    fn every_writable_format_round_trips_mesh_and_data() {
        let dir = test_dir("round-trip");
        let m2 = square();
        let d2 = MeshData::new().with_cell("h", m2.sizes()).with_point("u", vec![0.0, 0.5, 1.0, 0.1 + 0.2]);
        let m3 = tet();
        let d3 = MeshData::new().with_cell("h", m3.sizes());
        for ext in ["vtu", "msh", "json", "VTU"] {
            let p2 = dir.join(format!("m2.{ext}"));
            write_mesh(&m2, &p2, &d2).unwrap();
            assert_eq!(read_mesh_with_data::<2>(&p2).unwrap(), (m2.clone(), d2.clone()), "{ext}");
            let p3 = dir.join(format!("m3.{ext}"));
            write_mesh(&m3, &p3, &d3).unwrap();
            assert_eq!(read_mesh_with_data::<3>(&p3).unwrap(), (m3.clone(), d3.clone()), "{ext}");
        }
        let leftovers: Vec<_> =
            std::fs::read_dir(&dir).unwrap().filter_map(|e| e.ok()).map(|e| e.file_name()).collect();
        assert!(leftovers.iter().all(|n| !n.to_string_lossy().ends_with(".tmp")), "{leftovers:?}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn unknown_extensions_and_nastran_writes_are_unsupported() {
        let dir = test_dir("unsupported");
        let err = write_mesh(&square(), dir.join("m.stl"), &MeshData::new()).unwrap_err();
        assert!(matches!(err, MeshError::UnsupportedFormat { .. }), "{err}");
        assert!(err.to_string().contains("m.stl"));
        let err = write_mesh(&tet(), dir.join("m.nas"), &MeshData::new()).unwrap_err();
        assert!(matches!(err, MeshError::UnsupportedFormat { .. }), "{err}");
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
            TriangleSoup { corners: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], face_ids: vec![1] }
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
