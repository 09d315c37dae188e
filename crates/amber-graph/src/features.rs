//! Which node and edge features a graph carries, as data (spec §4).
//!
//! Geometric features are computed here from the mesh; everything else (FEM solution statistics,
//! load function, ...) comes from the caller as named per-element columns.

use serde::{Deserialize, Serialize};

/// One node feature column.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NodeFeature {
    /// Element volume (area in 2D).
    Volume,
    /// A per-element value supplied by the caller under this name (see [`ElementColumn`]).
    Column(String),
}

/// One edge feature (of an edge `src → dst`; self-loops get zeros).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EdgeFeature {
    /// Euclidean distance between the element midpoints (1 column).
    MidpointDistance,
    /// Midpoint difference vector `c_dst − c_src` (D columns).
    MidpointDifference,
}

impl EdgeFeature {
    /// Number of columns this feature takes in a `D`-dimensional mesh.
    pub fn width(self, dim: usize) -> usize {
        match self {
            EdgeFeature::MidpointDistance => 1,
            EdgeFeature::MidpointDifference => dim,
        }
    }
}

/// The node and edge feature columns of a graph, in order.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FeatureSet {
    pub node: Vec<NodeFeature>,
    pub edge: Vec<EdgeFeature>,
}

impl FeatureSet {
    /// Poisson task: node [area, mean u, std u, f(midpoint)] with the caller's columns
    /// `solution_mean`, `solution_std` (population std over the element's vertices) and `load`;
    /// edge [midpoint distance].
    pub fn poisson() -> Self {
        Self {
            node: vec![
                NodeFeature::Volume,
                NodeFeature::Column("solution_mean".into()),
                NodeFeature::Column("solution_std".into()),
                NodeFeature::Column("load".into()),
            ],
            edge: vec![EdgeFeature::MidpointDistance],
        }
    }

    /// Console task: node [volume], edge [3D midpoint difference vector].
    pub fn console() -> Self {
        Self { node: vec![NodeFeature::Volume], edge: vec![EdgeFeature::MidpointDifference] }
    }

    /// Width of a node feature row.
    pub fn node_dim(&self) -> usize {
        self.node.len()
    }

    /// Width of an edge feature row in a `dim`-dimensional mesh.
    pub fn edge_dim(&self, dim: usize) -> usize {
        self.edge.iter().map(|f| f.width(dim)).sum()
    }

    /// Whether an edge feature is a vector, which turns with the mesh (the other features do not).
    pub fn has_edge_vectors(&self) -> bool {
        self.edge.contains(&EdgeFeature::MidpointDifference)
    }

    /// Turns every edge vector of `rows` (edge feature rows of a `D`-dimensional mesh) by the
    /// orthogonal matrix `q`: the features of the same mesh rotated or reflected by `q`.
    pub fn transform_edge_vectors<const D: usize>(&self, rows: &mut [f32], q: &[[f64; D]; D]) {
        let dim = self.edge_dim(D);
        let mut column = 0;
        let mut starts = Vec::new();
        for feature in &self.edge {
            if *feature == EdgeFeature::MidpointDifference {
                starts.push(column);
            }
            column += feature.width(D);
        }
        for row in rows.chunks_exact_mut(dim) {
            for &start in &starts {
                let v: [f64; D] = std::array::from_fn(|k| f64::from(row[start + k]));
                for (i, out) in row[start..start + D].iter_mut().enumerate() {
                    *out = (0..D).map(|k| q[i][k] * v[k]).sum::<f64>() as f32;
                }
            }
        }
    }
}

/// A caller-provided per-element feature column, matched to [`NodeFeature::Column`] by name.
#[derive(Clone, Copy, Debug)]
pub struct ElementColumn<'a> {
    pub name: &'a str,
    /// One value per element, in element order.
    pub values: &'a [f64],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_follow_the_spec() {
        assert_eq!((FeatureSet::poisson().node_dim(), FeatureSet::poisson().edge_dim(2)), (4, 1));
        assert_eq!((FeatureSet::console().node_dim(), FeatureSet::console().edge_dim(3)), (1, 3));
    }

    #[test]
    fn only_edge_vectors_turn() {
        let features = FeatureSet {
            node: vec![NodeFeature::Volume],
            edge: vec![EdgeFeature::MidpointDistance, EdgeFeature::MidpointDifference],
        };
        assert!(features.has_edge_vectors() && !FeatureSet::poisson().has_edge_vectors());
        // A quarter turn about z, then a reflection of x.
        let quarter = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let mut rows = vec![3.0, 1.0, 2.0, 2.0, 5.0, 0.0, 0.0, 5.0];
        features.transform_edge_vectors(&mut rows, &quarter);
        assert_eq!(rows, vec![3.0, -2.0, 1.0, 2.0, 5.0, 0.0, 0.0, 5.0]);
        features.transform_edge_vectors(&mut rows, &[[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        assert_eq!(rows, vec![3.0, 2.0, 1.0, 2.0, 5.0, 0.0, 0.0, 5.0]);
    }

    #[test]
    fn feature_sets_are_plain_json() {
        let json = serde_json::to_string(&FeatureSet::poisson()).unwrap();
        assert_eq!(
            json,
            r#"{"node":["volume",{"column":"solution_mean"},{"column":"solution_std"},{"column":"load"}],"edge":["midpoint_distance"]}"#
        );
        assert_eq!(serde_json::from_str::<FeatureSet>(&json).unwrap(), FeatureSet::poisson());
    }
}
