//! Sizing fields: a target element edge length h(x) at every point of the domain (spec §0).

use amber_mesh::{Mesh, PointLocator};

/// A target element size (edge length of the regular simplex, spec §0) at every point.
///
/// Generators call [`SizingField::size_at`] many times; implementations must be cheap and
/// thread-safe. Non-finite or non-positive answers are rejected by the generators with a typed
/// error, so implementations need not check.
pub trait SizingField<const D: usize>: Sync {
    /// The target size at `x`.
    fn size_at(&self, x: [f64; D]) -> f64;

    /// ∫ 1/V(h) over a domain of volume `volume`: about the element count a mesh of the field
    /// has, where the field can tell it without sampling (generators refuse a field over their
    /// cap before any work). `None`: unknown.
    fn estimated_elements(&self, _volume: f64) -> Option<f64> {
        None
    }
}

/// The same size everywhere.
#[derive(Clone, Copy, Debug)]
pub struct ConstantSize(pub f64);

impl<const D: usize> SizingField<D> for ConstantSize {
    fn size_at(&self, _: [f64; D]) -> f64 {
        self.0
    }

    fn estimated_elements(&self, volume: f64) -> Option<f64> {
        Some(volume / amber_mesh::volume_from_size::<D>(self.0))
    }
}

/// A size given by a closure.
pub struct FnSize<F>(pub F);

impl<const D: usize, F: Fn([f64; D]) -> f64 + Sync> SizingField<D> for FnSize<F> {
    fn size_at(&self, x: [f64; D]) -> f64 {
        (self.0)(x)
    }
}

/// A piecewise-constant field on a mesh: the value of the element containing `x`, or of the
/// element with the nearest midpoint when `x` lies outside the mesh.
pub struct MeshSizing<'m, const D: usize> {
    locator: PointLocator<'m, D>,
    sizes: Vec<f64>,
}

impl<'m, const D: usize> MeshSizing<'m, D> {
    /// One size per element of `mesh`.
    ///
    /// # Panics
    /// If `sizes.len()` differs from the number of elements (a programming error, not input).
    pub fn new(mesh: &'m Mesh<D>, sizes: Vec<f64>) -> Self {
        assert_eq!(sizes.len(), mesh.num_elements(), "one size per element");
        Self { locator: PointLocator::new(mesh), sizes }
    }

    /// The expert's own sizing field: each element's size h(K) (used for the reconstruction M̂).
    pub fn from_element_sizes(mesh: &'m Mesh<D>) -> Self {
        Self::new(mesh, mesh.sizes())
    }

    /// The per-element sizes.
    pub fn sizes(&self) -> &[f64] {
        &self.sizes
    }
}

impl<const D: usize> SizingField<D> for MeshSizing<'_, D> {
    fn size_at(&self, x: [f64; D]) -> f64 {
        self.sizes[self.locator.locate_or_nearest(x).element()]
    }

    /// The estimate over the field's own mesh (which covers the domain being meshed).
    fn estimated_elements(&self, _volume: f64) -> Option<f64> {
        Some(estimated_element_count(self.locator.mesh(), &self.sizes))
    }
}

/// A field on a regular pixel (2D) or voxel (3D) grid, evaluated at the nearest pixel centre
/// (points outside the grid take the nearest border pixel). Used by the CNN baseline.
#[derive(Clone, Debug)]
pub struct PixelGridSizing<const D: usize> {
    /// Lower corner of the grid's bounding box.
    pub origin: [f64; D],
    /// Extent of one pixel along each axis.
    pub spacing: [f64; D],
    /// Pixels along each axis.
    pub shape: [usize; D],
    /// Row-major values, the last axis fastest.
    pub values: Vec<f64>,
}

impl<const D: usize> SizingField<D> for PixelGridSizing<D> {
    fn size_at(&self, x: [f64; D]) -> f64 {
        let mut index = 0;
        for (k, &xk) in x.iter().enumerate() {
            let i = ((xk - self.origin[k]) / self.spacing[k]).floor();
            let i = if i.is_nan() { 0 } else { (i.max(0.0) as usize).min(self.shape[k] - 1) };
            index = index * self.shape[k] + i;
        }
        self.values[index]
    }
}

/// Clamps another field to `[min, max]` (spec §2: predictions are clipped at h_min).
pub struct ClampedSize<F> {
    pub inner: F,
    pub min: f64,
    pub max: f64,
}

impl<const D: usize, F: SizingField<D>> SizingField<D> for ClampedSize<F> {
    fn size_at(&self, x: [f64; D]) -> f64 {
        let h = self.inner.size_at(x);
        // NaN stays NaN so that the generator reports it instead of silently meshing with `min`.
        if h.is_nan() { h } else { h.clamp(self.min, self.max) }
    }
}

/// Expected number of elements if each element `i` of `mesh` were meshed with size `sizes[i]`:
/// Σ |K_i| / V(h_i) (the element-budget guard of spec §6).
pub fn estimated_element_count<const D: usize>(mesh: &Mesh<D>, sizes: &[f64]) -> f64 {
    mesh.volumes().iter().zip(sizes).map(|(v, &h)| v / amber_mesh::volume_from_size::<D>(h)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::Mesh2;

    #[test]
    fn mesh_sizing_is_piecewise_constant_with_nearest_fallback() {
        let m = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
        let f = MeshSizing::new(&m, vec![0.1, 0.2]);
        assert_eq!(f.size_at([0.9, 0.1]), 0.1);
        assert_eq!(f.size_at([0.1, 0.9]), 0.2);
        assert_eq!(f.size_at([5.0, -1.0]), 0.1);
    }

    #[test]
    fn pixel_grid_uses_the_nearest_pixel_and_clamps_to_the_border() {
        let g = PixelGridSizing {
            origin: [0.0, 0.0],
            spacing: [0.5, 0.5],
            shape: [2, 2],
            values: vec![1.0, 2.0, 3.0, 4.0],
        };
        assert_eq!(g.size_at([0.1, 0.1]), 1.0);
        assert_eq!(g.size_at([0.1, 0.9]), 2.0);
        assert_eq!(g.size_at([0.9, 0.1]), 3.0);
        assert_eq!(g.size_at([7.0, 7.0]), 4.0);
    }

    #[test]
    fn clamping_keeps_nan_visible() {
        let c = ClampedSize { inner: FnSize(|x: [f64; 2]| x[0]), min: 0.5, max: 2.0 };
        assert_eq!(c.size_at([0.1, 0.0]), 0.5);
        assert_eq!(c.size_at([3.0, 0.0]), 2.0);
        assert!(c.size_at([f64::NAN, 0.0]).is_nan());
    }

    #[test]
    fn element_estimate_counts_regular_simplices() {
        let m = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap();
        let h = 0.1;
        let expected = 1.0 / amber_mesh::volume_from_size::<2>(h);
        assert!((estimated_element_count(&m, &[h, h]) - expected).abs() < 1e-9);
    }
}
