//! Meshes onto pixel grids and back (spec §8): a regular grid of rᴰ cells over a bounding box,
//! the element of a mesh under every cell centre, per-element values copied to the cells, the
//! inside/outside mask, and the per-cell field as a sizing field for the mesh generator.

use std::collections::VecDeque;

use amber_mesh::{Mesh, PointLocator};
use amber_meshgen::PixelGridSizing;
use rayon::prelude::*;

use crate::error::{CnnError, Result};

/// A regular grid of cells over an axis-aligned box, sampled at the cell centres; cells are
/// numbered row-major, the last axis fastest (the layout of a `(spatial...)` tensor).
#[derive(Clone, Debug, PartialEq)]
pub struct PixelGrid<const D: usize> {
    /// Lower corner of the box.
    pub origin: [f64; D],
    /// Extent of one cell along each axis.
    pub spacing: [f64; D],
    /// Cells along each axis.
    pub shape: [usize; D],
}

impl<const D: usize> PixelGrid<D> {
    /// `resolution` cells along every axis of `mesh`'s bounding box (cells are not square when
    /// the box is not, as in the reference).
    pub fn over_mesh(mesh: &Mesh<D>, resolution: usize) -> Result<Self> {
        let (lo, hi) = mesh.bounding_box().ok_or_else(|| CnnError::EmptyMesh("the mesh has no vertices".into()))?;
        // `<=` would let NaN extents through.
        if resolution == 0 || (0..D).any(|k| hi[k].partial_cmp(&lo[k]) != Some(std::cmp::Ordering::Greater)) {
            return Err(CnnError::EmptyMesh(format!(
                "a grid of {resolution} cells per axis over the box {lo:?}–{hi:?} has no cells"
            )));
        }
        Ok(Self {
            origin: lo,
            spacing: std::array::from_fn(|k| (hi[k] - lo[k]) / resolution as f64),
            shape: [resolution; D],
        })
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// Whether the grid has no cells (never, for a grid built by [`Self::over_mesh`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Volume (area in 2D) of one cell.
    pub fn cell_volume(&self) -> f64 {
        self.spacing.iter().product()
    }

    /// Centre of cell `index`.
    pub fn centre(&self, mut index: usize) -> [f64; D] {
        let mut x = [0.0; D];
        for k in (0..D).rev() {
            x[k] = self.origin[k] + ((index % self.shape[k]) as f64 + 0.5) * self.spacing[k];
            index /= self.shape[k];
        }
        x
    }

    /// The nearest-cell sizing field of per-cell `values` (points outside the grid take the
    /// nearest border cell).
    pub fn sizing(&self, values: Vec<f64>) -> PixelGridSizing<D> {
        PixelGridSizing { origin: self.origin, spacing: self.spacing, shape: self.shape, values }
    }
}

/// A mesh rasterised onto a grid: the element under every cell centre.
#[derive(Clone, Debug)]
pub struct Raster<const D: usize> {
    pub grid: PixelGrid<D>,
    /// The element containing each cell centre; `None` outside the mesh.
    pub owners: Vec<Option<u32>>,
}

impl<const D: usize> Raster<D> {
    /// Locates every cell centre of `grid` in `mesh` (exact point location, in parallel).
    pub fn new(grid: PixelGrid<D>, mesh: &Mesh<D>) -> Result<Self> {
        if mesh.num_elements() == 0 {
            return Err(CnnError::EmptyMesh("the mesh has no elements".into()));
        }
        let locator = PointLocator::new(mesh);
        let owners: Vec<Option<u32>> = (0..grid.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(|i| locator.locate(grid.centre(i)).map(|e| e as u32))
            .collect();
        if owners.iter().all(Option::is_none) {
            return Err(CnnError::EmptyMesh("no cell centre lies inside the mesh".into()));
        }
        Ok(Self { grid, owners })
    }

    /// The mask channel: +1 inside the mesh, −1 outside.
    pub fn mask(&self) -> Vec<f32> {
        self.owners.iter().map(|o| if o.is_some() { 1.0 } else { -1.0 }).collect()
    }

    /// Number of cells inside the mesh.
    pub fn inside_count(&self) -> usize {
        self.owners.iter().filter(|o| o.is_some()).count()
    }

    /// Per-element `values` copied to the cells whose centre the element contains; `outside`
    /// elsewhere.
    pub fn per_cell(&self, values: &[f64], outside: f64) -> Result<Vec<f64>> {
        if let Some(bad) = self.owners.iter().flatten().find(|&&e| e as usize >= values.len()) {
            return Err(CnnError::Shape(format!("{} element values, but cell owner {bad}", values.len())));
        }
        Ok(self.owners.iter().map(|o| o.map_or(outside, |e| values[e as usize])).collect())
    }

    /// The network input of this raster, channel-major `(columns + 1) × cells`: each column's
    /// value of the element under the cell (0 outside), then the mask.
    pub fn channels(&self, columns: &[&[f64]]) -> Result<Vec<f32>> {
        let mut out = Vec::with_capacity((columns.len() + 1) * self.grid.len());
        for column in columns {
            out.extend(self.per_cell(column, 0.0)?.into_iter().map(|v| v as f32));
        }
        out.extend(self.mask());
        Ok(out)
    }

    /// Overwrites every outside cell of `values` with the value of a nearest inside cell (in
    /// steps between face neighbours), so that a nearest-cell lookup near the boundary never
    /// reads a cell the network was not trained on.
    pub fn fill_outside(&self, values: &mut [f64]) -> Result<()> {
        if values.len() != self.grid.len() {
            return Err(CnnError::Shape(format!("{} values for {} cells", values.len(), self.grid.len())));
        }
        let mut done: Vec<bool> = self.owners.iter().map(Option::is_some).collect();
        let mut queue: VecDeque<usize> = (0..values.len()).filter(|&i| done[i]).collect();
        let shape = self.grid.shape;
        let mut strides = [1usize; D];
        for k in (0..D.saturating_sub(1)).rev() {
            strides[k] = strides[k + 1] * shape[k + 1];
        }
        while let Some(i) = queue.pop_front() {
            for k in 0..D {
                let at = (i / strides[k]) % shape[k];
                let neighbours = [(at > 0).then(|| i - strides[k]), (at + 1 < shape[k]).then(|| i + strides[k])];
                for j in neighbours.into_iter().flatten() {
                    if !done[j] {
                        done[j] = true;
                        values[j] = values[i];
                        queue.push_back(j);
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::Mesh2;
    use amber_meshgen::SizingField;

    /// The L-shape [0,1]² ∖ [0.5,1]² as 6 triangles.
    fn lshape() -> Mesh2 {
        let v = vec![[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [0.0, 0.5], [0.5, 0.5], [1.0, 0.5], [0.0, 1.0], [0.5, 1.0]];
        Mesh2::new(v, vec![0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 3, 4, 7, 3, 7, 6]).unwrap()
    }

    #[test]
    fn cells_inside_take_their_elements_values_and_the_mask_marks_the_notch() {
        let mesh = lshape();
        let raster = Raster::new(PixelGrid::over_mesh(&mesh, 4).unwrap(), &mesh).unwrap();
        assert_eq!(raster.inside_count(), 12);
        // Cell (row 3, column 3) has centre (0.875, 0.875): in the notch.
        assert_eq!(raster.grid.centre(15), [0.875, 0.875]);
        assert_eq!(raster.owners[15], None);
        let values: Vec<f64> = (0..6).map(f64::from).collect();
        let channels = raster.channels(&[&values]).unwrap();
        assert_eq!(channels.len(), 32);
        // Cell 0 (centre (0.125, 0.125)) lies in element 0 or 1; its mask is +1.
        assert!(channels[0] == 0.0 || channels[0] == 1.0);
        assert_eq!(channels[16], 1.0);
        assert_eq!(channels[16 + 15], -1.0);
        assert_eq!(channels[15], 0.0);
    }

    #[test]
    fn outside_cells_are_filled_from_their_nearest_inside_neighbour() {
        let mesh = lshape();
        let raster = Raster::new(PixelGrid::over_mesh(&mesh, 4).unwrap(), &mesh).unwrap();
        let mut values: Vec<f64> = (0..16).map(|i| if raster.owners[i].is_some() { i as f64 } else { -1.0 }).collect();
        raster.fill_outside(&mut values).unwrap();
        assert!(values.iter().all(|&v| v >= 0.0));
        // (row 2, column 2) borders (row 1, column 2) = 6 and (row 2, column 1) = 9.
        assert!(values[10] == 6.0 || values[10] == 9.0);
        let sizing = raster.grid.sizing(values.clone());
        assert_eq!(sizing.size_at([0.1, 0.1]), values[0]);
        assert_eq!(sizing.size_at([0.6, 0.1]), values[8]);
    }

    #[test]
    fn voxel_grids_locate_tetrahedra() {
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let tet = amber_mesh::Mesh3::new_reoriented(v, vec![0, 1, 2, 3]).unwrap();
        let raster = Raster::new(PixelGrid::over_mesh(&tet, 4).unwrap(), &tet).unwrap();
        // Centres (i + 0.5)/4 with i + j + k + 1.5 ≤ 4, i.e. i + j + k ≤ 2: 10 cells.
        assert_eq!(raster.inside_count(), 10);
        assert!((raster.grid.cell_volume() - 1.0 / 64.0).abs() < 1e-15);
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        let mesh = lshape();
        assert!(PixelGrid::over_mesh(&mesh, 0).is_err());
        let raster = Raster::new(PixelGrid::over_mesh(&mesh, 4).unwrap(), &mesh).unwrap();
        assert!(raster.per_cell(&[1.0], 0.0).is_err());
        assert!(raster.fill_outside(&mut [0.0; 3]).is_err());
    }
}
