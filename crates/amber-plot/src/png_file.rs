//! Writing RGB pixels as a PNG file, atomically (temporary file beside the target, then rename).

use std::io::Write;
use std::path::Path;

use amber_mesh::MeshError;
use amber_stdx::write_atomic_with;

use crate::PlotError;

/// Writes row-major RGB bytes (`3 × width × height`) as a PNG file, atomically.
pub fn write_png(path: impl AsRef<Path>, width: u32, height: u32, rgb: &[u8]) -> Result<(), PlotError> {
    let path = path.as_ref();
    if rgb.len() != 3 * width as usize * height as usize {
        return Err(PlotError::BufferSize { path: path.to_owned(), len: rgb.len(), width, height });
    }
    write_atomic_with(path, |out| {
        encode_png(out, width, height, rgb).map_err(|source| MeshError::Io { path: path.to_owned(), source })
    })
    .map_err(PlotError::Write)
}

fn encode_png(out: &mut impl Write, w: u32, h: u32, rgb: &[u8]) -> std::io::Result<()> {
    let mut encoder = png::Encoder::new(out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer.write_image_data(rgb).map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}
