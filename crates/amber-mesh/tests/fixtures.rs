//! The files gmsh 4.15, meshio 5.3 and VTK 9 write (tests/data, made by tests/data/generate.py):
//! every encoding reads to the same square, and damaged copies fail with an error that names the
//! file instead of panicking or allocating what a corrupt header announces.

use std::path::{Path, PathBuf};

use amber_mesh::{Mesh2, MeshError, read_mesh_with_data};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

/// The square meshio and the hand-assembled VTK file hold: 4 triangles around the centre.
const MESHIO: [&str; 11] = [
    "meshio-ascii.vtu",
    "meshio-binary.vtu",
    "meshio-zlib-uint64.vtu",
    "vtk-appended-zlib.vtu",
    "meshio-ascii.vtk",
    "meshio-binary.vtk",
    "meshio-binary.msh",
    "meshio-22-binary.msh",
    "meshio.nas",
    "meshio.inp",
    "meshio.mesh",
];

#[test]
fn every_meshio_and_vtk_encoding_reads_to_the_same_square() {
    let expected = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]];
    for name in MESHIO {
        let (mesh, fields): (Mesh2, _) = read_mesh_with_data(data(name)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(mesh.vertices(), &expected, "{name}");
        assert_eq!(mesh.num_elements(), 4, "{name}");
        assert!((mesh.total_volume() - 1.0).abs() < 1e-15, "{name}");
        let has_size = !matches!(name, "meshio.nas" | "meshio.inp" | "meshio.mesh");
        if has_size {
            assert_eq!(fields.cell["size"], vec![1.0, 2.0, 3.0, 4.0], "{name}");
        }
        if name != "meshio-binary.msh" {
            let lines = fields.dropped.values().sum::<usize>() + fields.facet_tags.len();
            assert_eq!(lines, 4, "{name}: the boundary lines are dropped, or facet tags where tagged");
        }
    }
}

#[test]
fn every_gmsh_encoding_reads_the_same_mesh_with_its_physical_groups() {
    let reference: (Mesh2, _) = read_mesh_with_data(data("gmsh-4.1-ascii.msh")).unwrap();
    assert_eq!(reference.0.num_elements(), 14);
    assert_eq!(reference.1.facet_tags.len(), 8);
    assert!(reference.1.facet_tags.values().all(|&t| t == 2), "the boundary is physical group 2");
    assert!(reference.1.dropped.is_empty(), "tagged lines are facet tags, not dropped: {:?}", reference.1.dropped);
    for name in ["gmsh-4.1-binary.msh", "gmsh-2.2-ascii.msh", "gmsh-2.2-binary.msh"] {
        let (mesh, fields): (Mesh2, _) = read_mesh_with_data(data(name)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((mesh.cells(), &fields), (reference.0.cells(), &reference.1), "{name}");
        // gmsh's ASCII keeps 16 significant digits, one short of binary's bits.
        let close = mesh
            .vertices()
            .iter()
            .zip(reference.0.vertices())
            .all(|(a, b)| (0..2).all(|k| (a[k] - b[k]).abs() < 1e-15));
        assert!(close, "{name}");
    }
    let vtk: Mesh2 = amber_mesh::read_mesh(data("gmsh-ascii.vtk")).unwrap();
    assert_eq!(vtk.cells(), reference.0.cells());
}

/// Writes `bytes` under `name` in a scratch directory and reads it as a 2D mesh.
fn read_damaged(name: &str, bytes: &[u8]) -> Result<Mesh2, MeshError> {
    let dir = std::env::temp_dir().join(format!("amber-mesh-fixtures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let result = amber_mesh::read_mesh(&path);
    std::fs::remove_file(&path).unwrap();
    result
}

fn replaced(name: &str, from: &[u8], to: &[u8]) -> Vec<u8> {
    let bytes = std::fs::read(data(name)).unwrap();
    let at = bytes.windows(from.len()).position(|w| w == from).unwrap_or_else(|| panic!("{name}: no {from:?}"));
    [&bytes[..at], to, &bytes[at + from.len()..]].concat()
}

#[test]
fn damaged_files_are_errors_that_name_the_file() {
    // Every truncation of binary files, a few bytes apart.
    for name in ["gmsh-4.1-binary.msh", "gmsh-2.2-binary.msh", "meshio-binary.vtk", "vtk-appended-zlib.vtu"] {
        let bytes = std::fs::read(data(name)).unwrap();
        for cut in (0..bytes.len() - 40).step_by(7) {
            if let Err(err) = read_damaged(name, &bytes[..cut]) {
                assert!(err.to_string().contains(name), "{err}");
            }
        }
    }
    let cases: [(&str, Vec<u8>, &str); 6] = [
        (
            "meshio-binary.vtu",
            replaced("meshio-binary.vtu", b"NumberOfPoints=\"5\"", b"NumberOfPoints=\"6\""),
            "expected 18",
        ),
        (
            "meshio-binary.vtu",
            replaced("meshio-binary.vtu", b"format=\"binary\">", b"format=\"binary\">!"),
            "bad base64",
        ),
        ("vtk-appended-zlib.vtu", replaced("vtk-appended-zlib.vtu", b"_\x01\x00", b"_\x01\x01"), "compressed blocks"),
        ("vtk-appended-zlib.vtu", replaced("vtk-appended-zlib.vtu", b"x\x9c", b"x\x00"), "zlib"),
        // A node count of 2^40 in a binary $Nodes header must not be allocated.
        (
            "gmsh-4.1-binary.msh",
            replaced("gmsh-4.1-binary.msh", b"$Nodes\n", b"$Nodes\n\x01\x00\x00\x00\x00\x01"),
            "announced",
        ),
        ("meshio-ascii.vtk", replaced("meshio-ascii.vtk", b"POINTS 5", b"POINTS 5000000000"), "announced"),
    ];
    for (name, bytes, needle) in cases {
        let message = read_damaged(name, &bytes).unwrap_err().to_string();
        assert!(message.contains(name) && message.contains(needle), "{message}");
    }
}
