//! Pictures of what the pipeline made, as PNG files: meshes coloured by a per-element scalar
//! with a colour bar ([`render_png`] for 2D meshes, [`render_surface_png`] for the shaded
//! boundary surface of a 3D mesh from a [`View`]), bar and line charts ([`bar_chart`],
//! [`line_chart`]) and galleries of mesh pictures on one colour scale ([`mesh_gallery`]). Text is
//! drawn in the vendored DejaVu Sans, so no system font is needed, and every file appears
//! atomically. This crate draws the numbers it is given: it depends on no amber crate but
//! amber-mesh and knows nothing of sizing fields, mesh generation, FEM, graphs, learning or
//! experiment results.

mod charts;
mod error;
mod font;
mod gallery;
mod png_file;
mod render;

pub use charts::{Bar, Series, bar_chart, line_chart};
pub use error::PlotError;
pub use gallery::{Tile, TileMesh, mesh_gallery};
pub use png_file::write_png;
pub use render::{MISSING_COLOUR, RenderOptions, View, render_png, render_surface_png, viridis};
