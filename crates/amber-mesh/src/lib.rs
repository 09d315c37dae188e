//! Simplicial meshes in 2D and 3D, the layer every other amber crate stands on.
//!
//! A [`Mesh<D>`] holds vertices and positively oriented simplices (triangles for `D = 2`,
//! tetrahedra for `D = 3`). It answers per-element geometry (volume, midpoint, the element size
//! h(K) of spec §0), facet adjacency ([`FacetAdjacency`]) and point location ([`PointLocator`]).
//! It reads and writes meshes ([`read_mesh`], [`write_mesh`]: `.vtu`, `.vtk`, gmsh `.msh`,
//! NASTRAN `.nas`, Abaqus `.inp`, medit `.mesh`, JSON; second-order elements with
//! [`write_mesh_as`]) and reads the triangles of surface files ([`read_surface`]: binary and ASCII
//! STL, OBJ).
//!
//! This crate knows nothing of sizing fields, mesh generation, FEM, graphs or learning.

mod adjacency;
mod error;
mod io;
mod locate;
mod mesh;

pub use adjacency::{FacetAdjacency, VertexElements};
pub use error::MeshError;
pub use io::{
    AnyMesh, ElementOrder, Encoding, MESH_FORMATS, MeshData, StlFaceIds, TriangleSoup, WriteOptions, check_output,
    parse_any_mesh, parse_surface, read_any_mesh, read_mesh, read_mesh_with_data, read_surface, write_mesh,
    write_mesh_as,
};
pub use locate::{Location, PointLocator};
pub use mesh::{Mesh, Mesh2, Mesh3, bounding_box, centroid, signed_volume, size_from_volume, volume_from_size};
