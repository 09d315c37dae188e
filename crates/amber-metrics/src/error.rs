//! Errors of the metrics.

/// Everything that can make a metric undefined. `which` names the offending argument
/// (`"first"`/`"second"` for point sets and meshes).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MetricsError {
    /// A point set is empty: nearest neighbours and means are undefined.
    #[error("the {which} point set is empty")]
    EmptyPointSet { which: &'static str },
    /// A point has a NaN or infinite coordinate.
    #[error("point {index} of the {which} point set has a non-finite coordinate")]
    NonFinitePoint { which: &'static str, index: usize },
    /// A point set has more points than a `u32` index reaches.
    #[error("the {which} point set has {len} points, more than {} can be indexed", u32::MAX)]
    TooManyPoints { which: &'static str, len: usize },
    /// The k-d tree could not index the points.
    #[error("cannot index the {which} point set: {source}")]
    KdTree { which: &'static str, source: kiddo::kd_tree::ConstructionError },
    /// The normalised DCD divides by d(M⁰) − d(M̂), which is zero or not finite here.
    #[error("normalised DCD undefined: d(M⁰) = {initial} and d(M̂) = {reconstruction} do not differ")]
    DegenerateNormalisation { initial: f64, reconstruction: f64 },
}
