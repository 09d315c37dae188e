//! The 3D mesh generator: closed CAD-face-labelled surfaces in, tetrahedral meshes out.
//!
//! [`surface`] reads and validates the geometry (STL with CAD face ids, plain STL, OBJ);
//! [`mod@remesh`] adapts the surface to a sizing field, keeping CAD faces, curves and corners;
//! [`tetgen`] fills a closed surface with tets following the same field; [`generate_3d`] runs
//! both, capped by curvature and by an element budget. Exact predicates and triangle
//! intersection tests are private helpers.

mod generate;
mod intersect;
mod predicates;
pub mod remesh;
pub mod surface;
pub mod tetgen;

pub use generate::{Mesh3dError, Mesh3dParams, adapt_surface, fill_surface, generate_3d};
pub use remesh::{RemeshError, RemeshParams, remesh};
pub use surface::{StlFaceIds, Surface, SurfaceDefect, SurfaceError, SurfaceReport};
pub use tetgen::{
    Optimization, Plc, Quality, TetgenError, TetgenMesh, TetgenSwitches, convex_background, delaunay, tetrahedralize,
};

/// The shipped Console reference surfaces (19 train + 2 val), or `None` when the data is absent.
#[cfg(test)]
fn console_reference_surfaces() -> Option<Vec<std::path::PathBuf>> {
    use std::path::{Path, PathBuf};
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/console/reference_surface");
    let root = if root.is_dir() { root } else { Path::new("/work/shared/data/console/reference_surface").to_owned() };
    if !root.is_dir() {
        println!("skipping: {} not found", root.display());
        return None;
    }
    let mut files: Vec<PathBuf> = ["train", "val"]
        .iter()
        .filter_map(|split| std::fs::read_dir(root.join(split)).ok())
        .flatten()
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "stl"))
        .collect();
    files.sort();
    assert!(files.len() >= 21, "expected 19 train + 2 val surfaces, found {}", files.len());
    Some(files)
}
