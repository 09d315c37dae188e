//! Galleries: a grid of mesh pictures (flat 2D meshes, or 3D surfaces from a viewpoint) on one
//! colour scale, composed into one PNG.

use std::path::Path;

use amber_mesh::{Mesh2, Mesh3};

use crate::render::{render_rgb, render_surface_rgb};
use crate::{PlotError, RenderOptions, View, write_png};

/// One picture of a gallery: a mesh coloured by per-element values.
pub struct Tile<'m> {
    pub title: String,
    pub mesh: TileMesh<'m>,
    pub values: Vec<f64>,
}

/// The mesh of a tile: drawn flat (2D), or as its boundary surface from a viewpoint (3D).
pub enum TileMesh<'m> {
    Flat(&'m Mesh2),
    Solid(&'m Mesh3, View),
}

/// A grid of mesh pictures (rows of tiles), every tile on the same logarithmic colour range so
/// the pictures compare.
pub fn mesh_gallery(path: &Path, rows: &[Vec<Tile<'_>>], tile: (u32, u32)) -> Result<(), PlotError> {
    let positive =
        || rows.iter().flatten().flat_map(|t| t.values.iter().copied()).filter(|v| *v > 0.0 && v.is_finite());
    let range = (positive().fold(f64::INFINITY, f64::min), positive().fold(0.0, f64::max));
    let columns = rows.iter().map(Vec::len).max().unwrap_or(0) as u32;
    let (width, height) = (tile.0 * columns.max(1), tile.1 * rows.len().max(1) as u32);
    let mut rgb = vec![255u8; 3 * (width * height) as usize];
    for (r, row) in rows.iter().enumerate() {
        for (c, t) in row.iter().enumerate() {
            let options = RenderOptions {
                width: tile.0,
                height: tile.1,
                title: Some(t.title.clone()),
                log_scale: true,
                range: Some(range),
                edges: true,
            };
            let image = match t.mesh {
                TileMesh::Flat(mesh) => render_rgb(mesh, &t.values, &options, path)?,
                TileMesh::Solid(mesh, view) => render_surface_rgb(mesh, &t.values, &options, view, path)?,
            };
            for y in 0..tile.1 as usize {
                let src = &image[3 * y * tile.0 as usize..3 * (y + 1) * tile.0 as usize];
                let dst_row = r * tile.1 as usize + y;
                let dst = 3 * (dst_row * width as usize + c * tile.0 as usize);
                rgb[dst..dst + src.len()].copy_from_slice(src);
            }
        }
    }
    write_png(path, width, height, &rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn galleries_are_written_as_one_png_of_tiles() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]], vec![0, 1, 2, 1, 3, 2]).unwrap();
        let tile = |title: &str| Tile { title: title.into(), mesh: TileMesh::Flat(&mesh), values: mesh.sizes() };
        let path = dir.path().join("gallery.png");
        mesh_gallery(&path, &[vec![tile("a"), tile("b"), tile("c")], vec![tile("d")]], (200, 150)).unwrap();
        let reader =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap())).read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (600, 300));
    }
}
