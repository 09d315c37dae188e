//! Metrics that compare a generated mesh with an expert mesh (spec §7): the density-aware Chamfer
//! distance (DCD) and plain Chamfer distance between element midpoints, the normalised DCD, the
//! symmetric volume difference and the element-count delta, and where a generated mesh is coarser
//! or finer than the expert's (the log size ratio per element).
//!
//! Depends on the mesh crate (and amber-stdx's quantiles) only; it knows nothing of graphs, networks
//! or training. Nearest
//! neighbours come from a kiddo k-d tree, queried in parallel with rayon; results do not depend
//! on the thread count.

mod compare;
mod dcd;
mod error;
mod size;
mod volume;

pub use compare::{MeshComparison, compare_meshes, midpoint_distance};
pub use dcd::{PointSetDistance, normalised_dcd, point_set_distance};
pub use error::MetricsError;
pub use size::{SizeRatios, log_size_ratios};
pub use volume::{VolumeDifference, volume_difference};
