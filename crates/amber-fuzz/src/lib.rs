//! The bodies of the fuzz targets: each takes arbitrary bytes, feeds them to one of amber's
//! entry points for outside input (mesh files of every format, surface files, polygon domains
//! and the meshers behind them here; Poisson problem files in `tasks`; model directories and
//! training configurations in `train`), and panics only where amber broke a promise: a reader
//! that panics, an error that does not name the file, a mesh that breaks the invariants its type
//! guarantees, a mesher that exceeds its element cap, an accepted value outside the documented
//! bounds. `fuzz/` wraps them for cargo-fuzz (libFuzzer); `tests/replay.rs` replays the
//! committed corpus on stable in CI.

mod tasks;
mod train;

pub use tasks::problem_file;
pub use train::{model_dir, training_config};

use std::path::{Path, PathBuf};

use amber_mesh::{
    AnyMesh, ElementOrder, Mesh, MeshData, StlFaceIds, WriteOptions, parse_any_mesh, parse_surface,
    read_mesh_with_data, write_mesh_as,
};
use amber_meshgen::mesh3d::{Mesh3dParams, Surface, generate_3d};
use amber_meshgen::{ConstantSize, Mesh2dParams, PolygonDomain, uniform_mesh_2d};

/// A target's body: panics where amber broke a promise on `data`.
pub type Target = fn(data: &[u8]);

/// Every target by name, as `fuzz/fuzz_targets/<name>.rs` and `fuzz/corpus/<name>/` know it.
pub const TARGETS: [(&str, Target); 6] = [
    ("mesh_file", mesh_file),
    ("surface_file", surface_file),
    ("polygon_domain", polygon_domain),
    ("problem_file", problem_file),
    ("model_dir", model_dir),
    ("training_config", training_config),
];

/// The extensions [`mesh_file`] chooses from with the input's first byte.
const MESH_EXTENSIONS: [&str; 7] = ["msh", "vtu", "vtk", "nas", "inp", "mesh", "json"];

/// Meshes made by the targets stay this small, so that an input runs in milliseconds.
pub(crate) const ELEMENT_CAP: usize = 20_000;

/// A mesh file: the first byte picks the format, the rest is the file. A mesh read is checked,
/// written back in every format and element order, and its boundary made into a geometry (as a
/// folder dataset without geometry files does).
pub fn mesh_file(data: &[u8]) {
    let Some((&format, contents)) = data.split_first() else { return };
    let path = format!("fuzz.{}", MESH_EXTENSIONS[format as usize % MESH_EXTENSIONS.len()]);
    match parse_any_mesh(Path::new(&path), contents.to_vec()) {
        Ok(AnyMesh::Two(mesh, data)) => {
            assert_valid(&mesh);
            assert_written_back(&mesh, &data);
            if let Ok(domain) = PolygonDomain::from_mesh_boundary(&mesh) {
                assert!(domain.area() > 0.0 && domain.area().is_finite(), "area {}", domain.area());
            }
        }
        Ok(AnyMesh::Three(mesh, data)) => {
            assert_valid(&mesh);
            assert_written_back(&mesh, &data);
            if let Ok(mut surface) = Surface::from_mesh_boundary(&mesh, &data.facet_tags) {
                surface.split_faces_at_feature_edges(30.0);
                let _ = surface.validate();
            }
        }
        Err(e) => assert_names(&e.to_string(), &path),
    }
}

/// A surface file (the first byte picks STL or OBJ): read, welded, validated as the boundary of
/// a solid, and, when it is one, tetrahedralised at a uniform size under the element cap.
pub fn surface_file(data: &[u8]) {
    let Some((&format, contents)) = data.split_first() else { return };
    let path = if format % 2 == 0 { "fuzz.stl" } else { "fuzz.obj" };
    let soup = match parse_surface(Path::new(path), contents, StlFaceIds::FromFile) {
        Ok(soup) => soup,
        Err(e) => return assert_names(&e.to_string(), path),
    };
    assert_eq!(soup.corners.len(), 3 * soup.face_ids.len());
    let Ok(mut surface) = Surface::from_triangle_soup(&soup.corners, soup.face_ids, 0.0) else { return };
    if surface.validate().is_err() || surface.triangles().len() > 2_000 {
        return;
    }
    // About 30 tets' worth of the volume each: the size a part's M⁰ has.
    let size = surface.enclosed_volume().cbrt() / 3.0;
    let params = Mesh3dParams { max_elements: ELEMENT_CAP, ..Mesh3dParams::default() };
    if let Ok(mesh) = generate_3d(&surface, &ConstantSize(size), &params) {
        assert_valid(&mesh);
        assert!(mesh.num_elements() <= ELEMENT_CAP, "{} tets over the cap", mesh.num_elements());
    }
}

/// A polygon domain JSON (`{"outer": ..., "holes": ..., "size": h}`), meshed uniformly at `h`
/// under the element cap: a size far too small for the domain must be refused, not attempted.
pub fn polygon_domain(data: &[u8]) {
    let Ok(mut value) = serde_json::from_slice::<serde_json::Value>(data) else { return };
    let size = value.as_object_mut().and_then(|o| o.remove("size")).and_then(|s| s.as_f64()).unwrap_or(0.1);
    let Ok(domain) = serde_json::from_value::<PolygonDomain>(value) else { return };
    let params = Mesh2dParams::default().with_max_elements(ELEMENT_CAP);
    if let Ok(mesh) = uniform_mesh_2d(&domain, size, &params) {
        assert_valid(&mesh);
        assert!(mesh.num_elements() <= ELEMENT_CAP, "{} triangles over the cap", mesh.num_elements());
        let (area, covered) = (domain.area(), mesh.total_volume());
        assert!((covered - area).abs() <= 1e-6 * area.abs().max(1e-300), "mesh area {covered} for domain {area}");
    }
}

/// Every writer, in both element orders, on a mesh a reader accepted, with the fields and facet
/// tags it read: a refusal names the file, and a written file reads back as the same mesh (the
/// corners of a second-order one, each element counted as linearised; NASTRAN's coordinates to
/// the 16 characters of a large field).
fn assert_written_back<const D: usize>(mesh: &Mesh<D>, data: &MeshData) {
    let dir = scratch_dir();
    for extension in MESH_EXTENSIONS {
        for order in [ElementOrder::Linear, ElementOrder::Quadratic] {
            let path = dir.join(format!("written.{extension}"));
            let options = WriteOptions { order, ..WriteOptions::default() };
            if let Err(e) = write_mesh_as(mesh, &path, data, options) {
                assert_names(&e.to_string(), &path.display().to_string());
                continue;
            }
            let (back, back_data) =
                read_mesh_with_data::<D>(&path).unwrap_or_else(|e| panic!("{extension} {order:?}: {e}"));
            let same = if extension == "nas" {
                // 5e-11 relative where the exponent has one or two digits, 5e-9 with three.
                let close = |a: f64, b: f64| (a - b).abs() <= 5e-9 * a.abs();
                back.cells() == mesh.cells()
                    && back
                        .vertices()
                        .iter()
                        .flatten()
                        .zip(mesh.vertices().iter().flatten())
                        .all(|(&a, &b)| close(a, b))
            } else {
                &back == mesh
            };
            assert!(same, "{extension} {order:?}: read back as another mesh");
            if order == ElementOrder::Quadratic {
                assert_eq!(back_data.linearised.values().sum::<usize>(), mesh.num_elements(), "{extension}");
            }
        }
    }
}

/// What `Mesh` promises: finite vertices, elements that index them, positive volumes.
pub(crate) fn assert_valid<const D: usize>(mesh: &Mesh<D>) {
    assert!(mesh.num_elements() > 0);
    assert!(mesh.vertices().iter().flatten().all(|x| x.is_finite()));
    assert!(mesh.volumes().iter().all(|&v| v > 0.0), "a non-positive element volume");
}

/// Errors about a file name it.
pub(crate) fn assert_names(message: &str, path: &str) {
    assert!(message.contains(path), "error without the file name: {message}");
}

thread_local! {
    /// The scratch directory of this thread, removed when a test's thread ends (libFuzzer exits
    /// without running destructors and leaves its one directory behind).
    static SCRATCH: tempfile::TempDir =
        tempfile::Builder::new().prefix("amber-fuzz-").tempdir().expect("a temporary directory");
}

/// A directory of this thread for the targets whose readers take a path.
pub(crate) fn scratch_dir() -> PathBuf {
    SCRATCH.with(|dir| dir.path().to_owned())
}
