//! Running mean/variance normalisation of node and edge features (spec §4; reference notes §4.4).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::{FeatureSet, GraphBatch, GraphError, MeshGraph};

/// Normalised features are clipped to ±`CLIP`.
pub const CLIP: f64 = 20.0;
/// Added to the variance before the square root.
pub const VARIANCE_EPSILON: f64 = 1e-6;
/// Pseudo-count of the initial moments (mean 0, variance 1), so the first update dominates.
pub const INITIAL_COUNT: f64 = 1e-6;

/// Per-column running mean and variance of feature rows, merged batch by batch (Chan et al.).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunningMoments {
    count: f64,
    mean: Vec<f64>,
    var: Vec<f64>,
}

impl RunningMoments {
    /// Moments of `dim` columns before any data: mean 0, variance 1, count [`INITIAL_COUNT`].
    pub fn new(dim: usize) -> Self {
        Self { count: INITIAL_COUNT, mean: vec![0.0; dim], var: vec![1.0; dim] }
    }

    /// Number of columns.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Rows merged so far (plus [`INITIAL_COUNT`]).
    pub fn count(&self) -> f64 {
        self.count
    }

    /// Running mean per column.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Running variance per column.
    pub fn variance(&self) -> &[f64] {
        &self.var
    }

    /// Merges the rows of `rows` (row-major, [`Self::dim`] columns). As in the reference code the
    /// batch variance is the unbiased one (0 for a single row); an empty batch changes nothing.
    pub fn update(&mut self, rows: &[f32]) -> Result<(), GraphError> {
        self.check_rows(rows)?;
        let dim = self.dim();
        if dim == 0 || rows.is_empty() {
            return Ok(());
        }
        let n = (rows.len() / dim) as f64;
        let mut batch_mean = vec![0.0; dim];
        for row in rows.chunks_exact(dim) {
            for (m, &x) in batch_mean.iter_mut().zip(row) {
                *m += f64::from(x);
            }
        }
        batch_mean.iter_mut().for_each(|m| *m /= n);
        let mut batch_var = vec![0.0; dim];
        for row in rows.chunks_exact(dim) {
            for ((v, &x), m) in batch_var.iter_mut().zip(row).zip(&batch_mean) {
                *v += (f64::from(x) - m).powi(2);
            }
        }
        batch_var.iter_mut().for_each(|v| *v = if n > 1.0 { *v / (n - 1.0) } else { 0.0 });

        let total = self.count + n;
        for k in 0..dim {
            let delta = batch_mean[k] - self.mean[k];
            let m2 = self.var[k] * self.count + batch_var[k] * n + delta * delta * self.count * n / total;
            self.mean[k] += delta * n / total;
            self.var[k] = m2 / total;
        }
        self.count = total;
        Ok(())
    }

    /// Replaces every value x of column k by clip((x − μ_k)/√(σ²_k + ε), ±[`CLIP`]).
    pub fn normalise(&self, rows: &mut [f32]) -> Result<(), GraphError> {
        self.check_rows(rows)?;
        let dim = self.dim();
        if dim == 0 {
            return Ok(());
        }
        let scale: Vec<f64> = self.var.iter().map(|v| 1.0 / (v + VARIANCE_EPSILON).sqrt()).collect();
        for row in rows.chunks_exact_mut(dim) {
            for ((x, m), s) in row.iter_mut().zip(&self.mean).zip(&scale) {
                *x = ((f64::from(*x) - m) * s).clamp(-CLIP, CLIP) as f32;
            }
        }
        Ok(())
    }

    fn check_rows(&self, rows: &[f32]) -> Result<(), GraphError> {
        let dim = self.dim();
        if (dim == 0 && !rows.is_empty()) || (dim > 0 && !rows.len().is_multiple_of(dim)) {
            return Err(GraphError::RaggedFeatures { len: rows.len(), dim });
        }
        Ok(())
    }

    /// Checks moments read from a file: as many means as variances, a finite positive count
    /// (the merge divides by it), finite means and finite non-negative variances (the square
    /// root of a negative one is NaN). The message names the field and column at fault.
    pub fn validate(&self) -> Result<(), String> {
        if self.mean.len() != self.var.len() {
            return Err(format!("{} means but {} variances", self.mean.len(), self.var.len()));
        }
        if !(self.count.is_finite() && self.count > 0.0) {
            return Err(format!("count {} is not positive", self.count));
        }
        if let Some((k, m)) = self.mean.iter().enumerate().find(|(_, m)| !m.is_finite()) {
            return Err(format!("mean of column {k} is {m}"));
        }
        if let Some((k, v)) = self.var.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v >= 0.0)) {
            return Err(format!("variance of column {k} is {v}"));
        }
        Ok(())
    }
}

/// Running normalisation of node and edge features, kept separately. Update it with every
/// training graph that enters the replay buffer (never validation or test graphs) and apply it
/// to every batch before the network sees it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeatureNormaliser {
    pub node: RunningMoments,
    pub edge: RunningMoments,
}

impl FeatureNormaliser {
    /// A normaliser for graphs with these feature widths.
    pub fn new(node_dim: usize, edge_dim: usize) -> Self {
        Self { node: RunningMoments::new(node_dim), edge: RunningMoments::new(edge_dim) }
    }

    /// Merges all node rows and all edge rows (self-loops included) of `graph`.
    pub fn update(&mut self, graph: &MeshGraph) -> Result<(), GraphError> {
        self.check_dims(graph.node_dim(), graph.edge_dim())?;
        self.node.update(graph.node_features())?;
        self.edge.update(graph.edge_features())
    }

    /// Merges `graph` as [`Self::update`] does, its edge vectors once along each cyclic
    /// permutation of the axes of its `D`-dimensional mesh: every component of a vector then
    /// has the same mean and variance, as in a training that turns each graph at random
    /// ([`FeatureSet::transform_edge_vectors`]), so the normaliser favours no axis.
    pub fn update_all_axes_alike<const D: usize>(
        &mut self,
        graph: &MeshGraph,
        features: &FeatureSet,
    ) -> Result<(), GraphError> {
        self.check_dims(graph.node_dim(), graph.edge_dim())?;
        self.node.update(graph.node_features())?;
        for shift in 0..D {
            let permutation: [[f64; D]; D] =
                std::array::from_fn(|i| std::array::from_fn(|k| f64::from((i + shift) % D == k)));
            let mut rows = graph.edge_features().to_vec();
            features.transform_edge_vectors(&mut rows, &permutation);
            self.edge.update(&rows)?;
        }
        Ok(())
    }

    /// Normalises the features of `batch` in place.
    pub fn normalise(&self, batch: &mut GraphBatch) -> Result<(), GraphError> {
        self.check_dims(batch.node_dim, batch.edge_dim)?;
        self.node.normalise(&mut batch.node_features)?;
        self.edge.normalise(&mut batch.edge_features)
    }

    /// Writes the normaliser as JSON.
    pub fn save(&self, path: &Path) -> Result<(), GraphError> {
        let json =
            serde_json::to_string_pretty(self).map_err(|source| GraphError::Json { path: path.into(), source })?;
        std::fs::write(path, json).map_err(|source| GraphError::Io { path: path.into(), source })
    }

    /// Reads a normaliser written by [`Self::save`], checking its consistency.
    pub fn load(path: &Path) -> Result<Self, GraphError> {
        let text = std::fs::read_to_string(path).map_err(|source| GraphError::Io { path: path.into(), source })?;
        let normaliser: Self =
            serde_json::from_str(&text).map_err(|source| GraphError::Json { path: path.into(), source })?;
        normaliser.validate().map_err(|reason| GraphError::InvalidNormaliser { path: path.into(), reason })?;
        Ok(normaliser)
    }

    /// [`RunningMoments::validate`] of both moments; the message starts with `node` or `edge`.
    pub fn validate(&self) -> Result<(), String> {
        for (name, moments) in [("node", &self.node), ("edge", &self.edge)] {
            moments.validate().map_err(|reason| format!("{name}: {reason}"))?;
        }
        Ok(())
    }

    fn check_dims(&self, node_dim: usize, edge_dim: usize) -> Result<(), GraphError> {
        if node_dim != self.node.dim() {
            return Err(GraphError::DimensionMismatch {
                what: "node features",
                expected: self.node.dim(),
                found: node_dim,
            });
        }
        if edge_dim != self.edge.dim() {
            return Err(GraphError::DimensionMismatch {
                what: "edge features",
                expected: self.edge.dim(),
                found: edge_dim,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_moments_equal_the_moments_of_all_rows() {
        // Chan's merge is exact up to the initial pseudo-count and the unbiased batch variances.
        let a: Vec<f32> = (0..500).map(|i| (i as f32 * 0.37).sin() * 3.0 + 1.0).collect();
        let b: Vec<f32> = (0..700).map(|i| (i as f32 * 0.11).cos() * 0.5 - 2.0).collect();
        let mut m = RunningMoments::new(1);
        m.update(&a).unwrap();
        m.update(&b).unwrap();
        let all: Vec<f64> = a.iter().chain(&b).map(|&x| f64::from(x)).collect();
        let mean = all.iter().sum::<f64>() / all.len() as f64;
        let var = all.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / all.len() as f64;
        assert!((m.mean()[0] - mean).abs() < 1e-9);
        assert!((m.variance()[0] - var).abs() < 2.5e-3 * var);
    }

    #[test]
    fn columns_are_normalised_separately_and_clipped() {
        let mut m = RunningMoments::new(2);
        let rows = [0.0f32, 10.0, 2.0, 10.0, 4.0, 10.0];
        m.update(&rows).unwrap();
        let mut x = [2.0f32, 10.0, 1e6, -1e6];
        m.normalise(&mut x).unwrap();
        // The constant column's variance is ~0, so the pseudo-count's pull on the mean shows.
        assert!(x[0].abs() < 1e-6 && x[1].abs() < 1e-2);
        assert_eq!((x[2], x[3]), (CLIP as f32, -CLIP as f32));
        assert!(matches!(m.update(&[1.0; 3]), Err(GraphError::RaggedFeatures { len: 3, dim: 2 })));
    }

    #[test]
    fn a_batch_of_the_training_graph_comes_out_centred() {
        use crate::FeatureSet;
        let m = amber_mesh::Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.3, 0.6]],
            vec![0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4],
        )
        .unwrap();
        let graph = MeshGraph::new(&m, &FeatureSet::console(), &[]).unwrap();
        let mut normaliser = FeatureNormaliser::new(1, 2);
        normaliser.update(&graph).unwrap();
        let mut batch = GraphBatch::from_graphs([&graph]).unwrap();
        normaliser.normalise(&mut batch).unwrap();
        let mean = batch.node_features.iter().sum::<f32>() / batch.num_nodes as f32;
        assert!(mean.abs() < 1e-5);
        assert!(matches!(FeatureNormaliser::new(2, 2).update(&graph), Err(GraphError::DimensionMismatch { .. })));
    }

    #[test]
    fn all_axes_alike_pools_the_moments_of_a_vector_s_components() {
        use crate::{EdgeFeature, FeatureSet, NodeFeature};
        // A strip of triangles along x: its midpoint differences are longer along x than y.
        let strip = amber_mesh::Mesh2::new(
            (0..=10).flat_map(|i| [[f64::from(i), 0.0], [f64::from(i), 1.0]]).collect(),
            (0..10u32).flat_map(|i| [2 * i, 2 * i + 2, 2 * i + 1, 2 * i + 1, 2 * i + 2, 2 * i + 3]).collect(),
        )
        .unwrap();
        let features = FeatureSet {
            node: vec![NodeFeature::Volume],
            edge: vec![EdgeFeature::MidpointDistance, EdgeFeature::MidpointDifference],
        };
        let graph = MeshGraph::new(&strip, &features, &[]).unwrap();
        let mut plain = FeatureNormaliser::new(1, 3);
        plain.update(&graph).unwrap();
        let mut alike = FeatureNormaliser::new(1, 3);
        alike.update_all_axes_alike::<2>(&graph, &features).unwrap();
        let (p, a) = (plain.edge.variance(), alike.edge.variance());
        assert!(p[1] > 2.0 * p[2], "{p:?}");
        // The distance keeps its moments; x and y each get the pooled ones.
        assert!((a[0] - p[0]).abs() < 1e-6 * p[0]);
        assert!((a[1] - a[2]).abs() < 1e-9 && (a[1] - 0.5 * (p[1] + p[2])).abs() < 1e-3 * a[1], "{a:?} {p:?}");
        assert_eq!(alike.node, plain.node);
    }

    #[test]
    fn save_and_load_round_trip_and_reject_bad_files() {
        let dir = std::env::temp_dir().join(format!("amber-graph-normaliser-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut n = FeatureNormaliser::new(2, 1);
        n.node.update(&[1.0, 2.0, 3.0, 5.0]).unwrap();
        let path = dir.join("normaliser.json");
        n.save(&path).unwrap();
        assert_eq!(FeatureNormaliser::load(&path).unwrap(), n);

        let bad = dir.join("bad.json");
        std::fs::write(&bad, r#"{"node":{"count":1.0,"mean":[0.0],"var":[]},"edge":{"count":1.0,"mean":[],"var":[]}}"#)
            .unwrap();
        assert!(matches!(FeatureNormaliser::load(&bad), Err(GraphError::InvalidNormaliser { .. })));
        assert!(matches!(FeatureNormaliser::load(&dir.join("missing.json")), Err(GraphError::Io { .. })));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
