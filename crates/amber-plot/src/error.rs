//! Errors of drawing and writing pictures, each naming the output file.

use std::path::{Path, PathBuf};

use amber_mesh::MeshError;

use crate::render::{MAX_SIZE, MIN_SIZE};

/// Everything that can go wrong drawing a picture or chart; every variant names the file it was
/// meant for.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// The values to colour by are not one per element.
    #[error("{path}: {len} values for {expected} elements")]
    ValueCount { path: PathBuf, len: usize, expected: usize },
    /// The requested picture is too small or too large.
    #[error("{path}: image size {width}×{height} is outside {min}..={max} pixels per side", min = MIN_SIZE, max = MAX_SIZE)]
    ImageSize { path: PathBuf, width: u32, height: u32 },
    /// An RGB buffer does not hold `width × height` pixels.
    #[error("{path}: {len} bytes are not a {width}×{height} RGB image")]
    BufferSize { path: PathBuf, len: usize, width: u32, height: u32 },
    /// The boundary surface of a 3D mesh cannot be projected (e.g. it is not manifold).
    #[error("{path}: {source}")]
    Surface { path: PathBuf, source: MeshError },
    /// plotters failed to draw text or a chart element.
    #[error("{path}: drawing failed: {message}")]
    Draw { path: PathBuf, message: String },
    /// The file could not be written (the error names it).
    #[error(transparent)]
    Write(MeshError),
}

/// Maps a plotters error while drawing the picture for `path`.
pub(crate) fn draw_error<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> PlotError + '_ {
    move |e| PlotError::Draw { path: path.to_owned(), message: e.to_string() }
}
