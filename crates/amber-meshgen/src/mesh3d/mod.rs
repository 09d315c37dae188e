//! The 3D mesh generator: closed CAD-face-labelled surfaces in, tetrahedral meshes out.
//!
//! [`surface`] welds and validates the geometry whose triangles amber-mesh reads (STL with CAD
//! face ids, plain STL, OBJ); [`mod@remesh`] adapts the surface to a sizing field, keeping CAD
//! faces, curves and corners; [`tetgen`] fills a closed surface with tets following the same
//! field; [`generate_3d`] runs both, capped by curvature and by an element budget. Triangle
//! intersection tests are private helpers; the exact predicates are the crate's.

mod distance;
mod generate;
mod intersect;
pub mod remesh;
pub mod surface;
pub mod tetgen;

pub use distance::SurfaceDistance;
pub use generate::{Mesh3dError, Mesh3dParams, adapt_surface, fill_surface, generate_3d};
pub use remesh::{RemeshError, RemeshParams, remesh};
pub use surface::{StlFaceIds, Surface, SurfaceDefect, SurfaceError, SurfaceReport};
pub use tetgen::{
    BackgroundMesh, Optimization, Plc, Quality, TetgenError, TetgenMesh, TetgenSwitches, convex_background, delaunay,
    tetrahedralize,
};

/// The shipped Console reference surfaces (19 train + 2 val), or `None` when the data is absent.
#[cfg(test)]
fn console_reference_surfaces() -> Option<Vec<std::path::PathBuf>> {
    let root = amber_testdata::shared("data/console/reference_surface")?;
    let mut files: Vec<std::path::PathBuf> = ["train", "val"]
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

/// The unit cube as 12 triangles, one CAD face per side (corners (i&1, i>>1&1, i>>2&1)).
#[cfg(test)]
fn unit_cube_triangles() -> (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<i32>) {
    let v: Vec<[f64; 3]> = (0..8).map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64]).collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let mut triangles = Vec::new();
    let mut ids = Vec::new();
    for (side, q) in quads.iter().enumerate() {
        triangles.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
        ids.extend([side as i32 + 1; 2]);
    }
    (v, triangles, ids)
}

/// The unit cube as a validated surface, one CAD face per side.
#[cfg(test)]
fn unit_cube() -> Surface {
    let (v, triangles, ids) = unit_cube_triangles();
    let mut s = Surface::new(v, triangles, ids).expect("the unit cube is a surface");
    s.validate().expect("the unit cube bounds a solid");
    s
}
