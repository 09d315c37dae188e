//! What every mixed-element reader (`.msh`, `.vtu`, `.vtk`, `.nas`, `.inp`, `.mesh`) produces
//! before a mesh is built: points in 3D and cells of any kind in file order. [`RawMesh::finish`]
//! is the one place that decides the dimension, keeps the simplices of it (quadratic ones by
//! their corner nodes), turns tagged facets into [`MeshData::facet_tags`] and counts what it
//! dropped.

use std::collections::BTreeMap;
use std::path::Path;

use super::{MeshData, assemble};
use crate::{Mesh, MeshError};

/// A cell kind: its topological dimension and whether it is the linear simplex of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Kind {
    pub(super) dim: usize,
    pub(super) name: &'static str,
}

impl Kind {
    pub(super) const VERTEX: Kind = Kind { dim: 0, name: "vertex" };
    pub(super) const LINE: Kind = Kind { dim: 1, name: "line" };
    pub(super) const TRIANGLE: Kind = Kind { dim: 2, name: "triangle" };
    pub(super) const TETRA: Kind = Kind { dim: 3, name: "tetra" };
    pub(super) const LINE3: Kind = Kind { dim: 1, name: "line3" };
    pub(super) const TRIANGLE6: Kind = Kind { dim: 2, name: "triangle6" };
    pub(super) const TETRA10: Kind = Kind { dim: 3, name: "tetra10" };

    /// The linear simplex of dimension `dim` (0 to 3).
    pub(super) fn simplex(dim: usize) -> Kind {
        [Self::VERTEX, Self::LINE, Self::TRIANGLE, Self::TETRA][dim]
    }

    /// The quadratic simplex of dimension `dim` (1 to 3): corner nodes first, then one node per
    /// edge, in every format amber reads.
    fn quadratic(dim: usize) -> Option<Kind> {
        [None, Some(Self::LINE3), Some(Self::TRIANGLE6), Some(Self::TETRA10)].get(dim).copied().flatten()
    }

    fn is_simplex(self) -> bool {
        self == Self::simplex(self.dim)
    }

    fn is_quadratic(self) -> bool {
        Self::quadratic(self.dim) == Some(self)
    }

    /// The nodes a cell of this kind may list: a linear simplex its corners; a quadratic one its
    /// corners and edge nodes, or its corners alone (NASTRAN's edge grids sit on continuation
    /// lines, which the reader does not need); `None` for any other kind.
    fn node_counts(self) -> Option<[usize; 2]> {
        let corners = self.dim + 1;
        if self.is_simplex() {
            Some([corners; 2])
        } else if self.is_quadratic() {
            Some([corners, corners * (corners + 1) / 2])
        } else {
            None
        }
    }
}

#[derive(Default)]
pub(super) struct RawMesh {
    pub(super) points: Vec<[f64; 3]>,
    pub(super) kinds: Vec<Kind>,
    /// Point indices of every cell, cell after cell.
    pub(super) nodes: Vec<u32>,
    /// End of every cell's nodes in `nodes`.
    pub(super) ends: Vec<usize>,
    /// A tag per cell (gmsh physical group, medit reference, 0 for none), or empty when the
    /// format has none.
    pub(super) tags: Vec<i32>,
    /// Names of tags by dimension and tag (gmsh's `$PhysicalNames`).
    pub(super) tag_names: Vec<(usize, i32, String)>,
    /// Per-cell fields over all cells, in file order.
    pub(super) cell_data: BTreeMap<String, Vec<f64>>,
    pub(super) point_data: BTreeMap<String, Vec<f64>>,
}

impl RawMesh {
    pub(super) fn push_cell(&mut self, kind: Kind, nodes: impl IntoIterator<Item = u32>) {
        self.kinds.push(kind);
        self.nodes.extend(nodes);
        self.ends.push(self.nodes.len());
    }

    fn cell(&self, i: usize) -> &[u32] {
        &self.nodes[if i == 0 { 0 } else { self.ends[i - 1] }..self.ends[i]]
    }

    /// Cell `i`'s tag (0: none).
    fn tag(&self, i: usize) -> i32 {
        self.tags.get(i).copied().unwrap_or(0)
    }

    /// The highest dimension of the cells (0 without cells).
    pub(super) fn dimension(&self) -> usize {
        self.kinds.iter().map(|k| k.dim).max().unwrap_or(0)
    }

    /// Builds the `D`-dimensional mesh: fails with [`MeshError::DimensionMismatch`] when the
    /// highest cell dimension is not `D` (so a caller can try the other), keeps the
    /// `D`-simplices with their cell data (a quadratic one as the linear simplex of its corners,
    /// counted in [`MeshData::linearised`]), records tagged `(D-1)`-simplices as facet tags and
    /// counts every other cell (untagged facets among them) in [`MeshData::dropped`]; the names
    /// of the `(D-1)`-dimensional tags some facet carries become [`MeshData::facet_names`], and the
    /// name of the `D`-dimensional tag every kept simplex carries [`MeshData::domain_name`].
    pub(super) fn finish<const D: usize>(self, path: &Path) -> Result<(Mesh<D>, MeshData), MeshError> {
        let found = self.dimension();
        if found != D {
            return Err(MeshError::DimensionMismatch { path: path.to_owned(), expected: D, found });
        }
        let format_error = |message: String| MeshError::Format { path: path.to_owned(), message };
        if D == 2
            && let Some((i, p)) = self.points.iter().enumerate().find(|(_, p)| p[2] != 0.0)
        {
            return Err(format_error(format!("point {i} has z = {}; a 2D mesh must lie in the plane z = 0", p[2])));
        }
        if let Some((i, _)) = self.points.iter().enumerate().find(|(_, p)| p.iter().any(|x| !x.is_finite())) {
            return Err(format_error(format!("point {i} has a non-finite coordinate")));
        }
        let mut data = MeshData::new();
        let mut kept = Vec::new();
        let mut cells = Vec::new();
        for (i, &kind) in self.kinds.iter().enumerate() {
            let nodes = self.cell(i);
            if let Some(counts) = kind.node_counts()
                && !counts.contains(&nodes.len())
            {
                return Err(format_error(format!("cell {i} is a {} with {} nodes", kind.name, nodes.len())));
            }
            // Corner nodes come first in a quadratic simplex.
            let corners = &nodes[..nodes.len().min(kind.dim + 1)];
            if kind.dim == D && kind.node_counts().is_some() {
                kept.push(i);
                cells.extend_from_slice(corners);
                if kind.is_quadratic() {
                    *data.linearised.entry(kind.name.to_owned()).or_default() += 1;
                }
                continue;
            }
            let tag = self.tag(i);
            if kind.dim + 1 == D && kind.node_counts().is_some() && tag != 0 {
                let mut facet = corners.to_vec();
                facet.sort_unstable();
                data.facet_tags.insert(facet, tag);
            } else {
                *data.dropped.entry(kind.name.to_owned()).or_default() += 1;
            }
        }
        let domain_tags: std::collections::BTreeSet<i32> = kept.iter().map(|&i| self.tag(i)).collect();
        if let [tag] = domain_tags.into_iter().collect::<Vec<_>>()[..] {
            data.domain_name =
                (self.tag_names.iter()).find(|(dim, t, _)| *dim == D && *t == tag).map(|(.., n)| n.clone());
        }
        let used: std::collections::BTreeSet<i32> = data.facet_tags.values().copied().collect();
        data.facet_names = (self.tag_names.into_iter())
            .filter(|(dim, tag, _)| dim + 1 == D && used.contains(tag))
            .map(|(_, tag, name)| (tag, name))
            .collect();
        for (name, values) in self.cell_data {
            if values.len() != self.kinds.len() {
                let field = format!("element field `{name}`");
                return Err(MeshError::DataLength {
                    path: path.to_owned(),
                    field,
                    len: values.len(),
                    expected: self.kinds.len(),
                });
            }
            data.cell.insert(name, kept.iter().map(|&i| values[i]).collect());
        }
        data.point = self.point_data;
        let vertices = self.points.iter().map(|p| std::array::from_fn(|k| p[k])).collect();
        assemble(path, vertices, cells, data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_simplices_of_the_dimension_and_counts_the_rest() {
        let mut raw = RawMesh {
            points: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
            ..Default::default()
        };
        raw.push_cell(Kind::LINE, [0, 1]);
        raw.push_cell(Kind::TRIANGLE, [0, 1, 2]);
        raw.push_cell(Kind { dim: 2, name: "quad" }, [0, 1, 3, 2]);
        raw.push_cell(Kind::VERTEX, [3]);
        raw.tags = vec![7, 1, 1, 0];
        raw.tag_names = vec![(1, 7, "inlet".into()), (1, 8, "unused".into()), (2, 7, "domain".into())];
        raw.cell_data.insert("h".into(), vec![0.0, 1.0, 2.0, 3.0]);
        let (mesh, data) = raw.finish::<2>(Path::new("x")).unwrap();
        assert_eq!(mesh.num_elements(), 1);
        assert_eq!(data.cell["h"], vec![1.0]);
        assert_eq!(data.dropped, BTreeMap::from([("quad".into(), 1), ("vertex".into(), 1)]));
        assert_eq!(data.facet_tags, BTreeMap::from([(vec![0, 1], 7)]));
        assert_eq!(data.facet_names, BTreeMap::from([(7, "inlet".into())]));
        let raw = RawMesh { points: vec![[0.0; 3]], kinds: vec![Kind::LINE], ..Default::default() };
        let err = raw.finish::<2>(Path::new("x")).unwrap_err();
        assert!(matches!(err, MeshError::DimensionMismatch { found: 1, .. }), "{err}");
    }

    /// A quadratic triangle is the linear triangle of its corners (its edge nodes dropped with
    /// the vertices nothing else uses, the rest renumbered), a tagged quadratic edge tags the
    /// facet of its ends, and a quadratic simplex with a node count of neither kind is an error.
    #[test]
    fn keeps_quadratic_simplices_by_their_corners() {
        let corners = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let edges = [[0.5, 0.0, 0.0], [0.5, 0.5, 0.0], [0.0, 0.5, 0.0]];
        // An edge node first, so that dropping it renumbers the corners.
        let points = [edges[0]].iter().chain(&corners).chain(&edges[1..]).copied().collect();
        let mut raw = RawMesh { points, ..Default::default() };
        raw.push_cell(Kind::TRIANGLE6, [1, 2, 3, 0, 4, 5]);
        raw.push_cell(Kind::LINE3, [1, 2, 0]);
        raw.tags = vec![1, 4];
        let (mesh, data) = raw.finish::<2>(Path::new("x")).unwrap();
        assert_eq!(mesh.vertices(), &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        assert_eq!(mesh.cells(), &[0, 1, 2]);
        assert_eq!(data.linearised, BTreeMap::from([("triangle6".into(), 1)]));
        assert!(data.dropped.is_empty(), "{:?}", data.dropped);
        assert_eq!(data.facet_tags, BTreeMap::from([(vec![0, 1], 4)]));
        let mut raw = RawMesh { points: corners.to_vec(), ..Default::default() };
        raw.push_cell(Kind::TRIANGLE6, [0, 1, 2, 0]);
        let err = raw.finish::<2>(Path::new("x")).unwrap_err().to_string();
        assert!(err.contains("triangle6 with 4 nodes"), "{err}");
    }
}
