//! PNG pictures of meshes coloured by a per-element scalar, with a colour bar: 2D meshes as
//! they are, 3D meshes as their shaded boundary surface seen from a viewpoint.
//!
//! Triangles are filled straight into an RGB buffer (a pixel takes the colour of the element
//! containing its centre), edges are drawn as darkened lines, and plotters draws only the text,
//! with the vendored DejaVu Sans so no system font is needed. Surfaces are drawn back to front
//! (painter's algorithm on the front-facing boundary triangles) and their edges are found in a
//! buffer of which triangle each pixel shows, so hidden edges never show through.

use nalgebra::Vector3;
use std::path::Path;

use amber_mesh::{FacetAdjacency, Mesh2, Mesh3, MeshError, signed_volume};
use plotters::prelude::{BitMapBackend, DrawingBackend, IntoFont, RGBColor};
use plotters::style::TextStyle;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::draw_error;
use crate::font::{FONT_FAMILY, register_default_font};
use crate::{PlotError, write_png};

/// How to draw a mesh picture.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Text above the mesh.
    pub title: Option<String>,
    /// Colour by log10 of the values; non-positive values are then drawn as missing.
    pub log_scale: bool,
    /// Value range of the colour bar; `None` (or an empty or, on a log scale, non-positive
    /// range) spans the values. Fix it to compare pictures.
    pub range: Option<(f64, f64)>,
    /// Draw element edges. They fade out with element size and vanish for elements thinner
    /// than about 2 pixels, where lines would hide the colours.
    pub edges: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { width: 1000, height: 800, title: None, log_scale: false, range: None, edges: true }
    }
}

/// Colour of elements whose value is NaN, infinite, or non-positive on a log scale.
pub const MISSING_COLOUR: [u8; 3] = [190, 190, 190];

const BACKGROUND: [u8; 3] = [255, 255, 255];
const INK: [u8; 3] = [0, 0, 0];
/// Edge pixels are the fill colour scaled by this factor, so edges stay visible on any colour.
const EDGE_SHADE: f64 = 0.55;
/// Element thickness (smallest height, in pixels) below which its edges are hidden, and above
/// which they are drawn at full strength; in between they fade.
const EDGE_FADE: (f64, f64) = (2.0, 8.0);
/// Smallest and largest picture side, in pixels.
pub(crate) const MIN_SIZE: u32 = 64;
pub(crate) const MAX_SIZE: u32 = 16_384;

/// Viridis at `t` in [0, 1]: Matt Zucker's degree-6 polynomial fit of matplotlib's table
/// (shadertoy WlfXRN, CC0), within 3/255 of it.
pub fn viridis(t: f64) -> [u8; 3] {
    const C: [[f64; 3]; 7] = [
        [0.277_727_327_223_417_7, 0.005_407_344_544_966_578, 0.334_099_805_335_306_1],
        [0.105_093_043_108_577_4, 1.404_613_529_898_575, 1.384_590_162_594_685],
        [-0.330_861_828_725_556_3, 0.214_847_559_468_213, 0.095_095_163_028_236_59],
        [-4.634_230_498_983_486, -5.799_100_973_351_585, -19.332_440_956_279_87],
        [6.228_269_936_347_081, 14.179_933_366_805_09, 56.690_552_600_681_05],
        [4.776_384_997_670_288, -13.745_145_377_746_01, -65.353_032_633_372_34],
        [-5.435_455_855_934_631, 4.645_852_612_178_535, 26.312_435_249_583_2],
    ];
    let t = t.clamp(0.0, 1.0);
    std::array::from_fn(|k| {
        let v = C.iter().rev().fold(0.0, |acc, c| acc * t + c[k]);
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    })
}

/// Writes a PNG of `mesh` with element `e` coloured by `values[e]` on the viridis scale, a colour
/// bar with tick labels on the right and the optional title on top. The mesh keeps its aspect
/// ratio. The file appears atomically.
///
/// ```no_run
/// # let mesh = amber_mesh::Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap();
/// let options = amber_plot::RenderOptions { title: Some("h".into()), log_scale: true, ..Default::default() };
/// amber_plot::render_png(&mesh, &mesh.sizes(), &options, "sizes.png")?;
/// # Ok::<(), amber_plot::PlotError>(())
/// ```
pub fn render_png(
    mesh: &Mesh2,
    values: &[f64],
    options: &RenderOptions,
    path: impl AsRef<Path>,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    let image = render_rgb(mesh, values, options, path)?;
    write_png(path, options.width, options.height, &image)
}

/// The picture [`render_png`] writes, as row-major RGB bytes (`3 × width × height`); errors name
/// `path`, the file the picture is for.
pub(crate) fn render_rgb(
    mesh: &Mesh2,
    values: &[f64],
    options: &RenderOptions,
    path: &Path,
) -> Result<Vec<u8>, PlotError> {
    check_request(mesh.num_elements(), values, options, path)?;
    Ok(render(mesh, values, None, options, path)?.0)
}

/// Checks that there is one value per element and that the picture size is sensible.
fn check_request(elements: usize, values: &[f64], options: &RenderOptions, path: &Path) -> Result<(), PlotError> {
    if values.len() != elements {
        return Err(PlotError::ValueCount { path: path.to_owned(), len: values.len(), expected: elements });
    }
    let (width, height) = (options.width, options.height);
    if !(MIN_SIZE..=MAX_SIZE).contains(&width) || !(MIN_SIZE..=MAX_SIZE).contains(&height) {
        return Err(PlotError::ImageSize { path: path.to_owned(), width, height });
    }
    Ok(())
}

/// Where the camera looks from, for pictures of 3D meshes: `azimuth_deg` around the z axis
/// from +x, `elevation_deg` above the xy plane. The projection is orthographic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
}

/// The picture [`render_surface_png`] writes, as row-major RGB bytes; errors name `path`, the
/// file the picture is for.
pub(crate) fn render_surface_rgb(
    mesh: &Mesh3,
    values: &[f64],
    options: &RenderOptions,
    view: View,
    path: &Path,
) -> Result<Vec<u8>, PlotError> {
    check_request(mesh.num_elements(), values, options, path)?;
    let (projected, face_values, shades) =
        visible_surface(mesh, values, view).map_err(|source| PlotError::Surface { path: path.to_owned(), source })?;
    Ok(render(&projected, &face_values, Some(&shades), options, path)?.0)
}

/// Writes a PNG of a tetrahedral mesh's boundary surface seen from `view`, each boundary
/// triangle coloured by its tetrahedron's value (as [`render_png`] colours elements) and shaded
/// by its angle to the light. The file appears atomically.
pub fn render_surface_png(
    mesh: &Mesh3,
    values: &[f64],
    options: &RenderOptions,
    view: View,
    path: impl AsRef<Path>,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    let image = render_surface_rgb(mesh, values, options, view, path)?;
    write_png(path, options.width, options.height, &image)
}

/// The front-facing boundary triangles of `mesh` projected onto the view plane, ordered back
/// to front, with their tetrahedra's values and their shading factors in (0, 1].
fn visible_surface(mesh: &Mesh3, values: &[f64], view: View) -> Result<(Mesh2, Vec<f64>, Vec<f64>), MeshError> {
    let (az, el) = (view.azimuth_deg.to_radians(), view.elevation_deg.to_radians());
    let eye = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
    let right = Vector3::new(-az.sin(), az.cos(), 0.0);
    let up = eye.cross(&right);
    let light = normalised(eye + 0.4 * up + 0.3 * right);
    let adjacency = FacetAdjacency::new(mesh)?;
    let vertices: Vec<Vector3<f64>> = mesh.vertices().iter().map(|&p| Vector3::from(p)).collect();
    let mut faces: Vec<(f64, [u32; 3], f64, f64)> = Vec::new();
    for (element, local) in adjacency.boundary_facets() {
        let cell = mesh.element(element);
        let mut tri: Vec<u32> = (0..4).filter(|&k| k != local).map(|k| cell[k]).collect();
        let [a, b, c] = [0, 1, 2].map(|k| vertices[tri[k] as usize]);
        let mut normal = (b - a).cross(&(c - a));
        if normal.dot(&(vertices[cell[local] as usize] - a)) > 0.0 {
            normal = -normal;
            tri.swap(1, 2);
        }
        let normal = normalised(normal);
        if normal.dot(&eye) <= 0.0 {
            continue;
        }
        let depth = ((a + b + c) / 3.0).dot(&eye);
        let shade = 0.35 + 0.65 * normal.dot(&light).max(0.0);
        faces.push((depth, [tri[0], tri[1], tri[2]], values[element], shade));
    }
    faces.sort_by(|x, y| x.0.total_cmp(&y.0));
    let points: Vec<[f64; 2]> = vertices.iter().map(|p| [p.dot(&right), p.dot(&up)]).collect();
    let extent = points.iter().fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs())).max(f64::MIN_POSITIVE);
    // Triangles seen edge-on have no area to draw (and are no valid 2D elements).
    faces.retain(|(_, t, _, _)| signed_volume::<2>(&points, t) > 1e-12 * extent * extent);
    let cells = faces.iter().flat_map(|f| f.1).collect();
    let projected = Mesh2::new(points, cells)?;
    Ok((projected, faces.iter().map(|f| f.2).collect(), faces.iter().map(|f| f.3).collect()))
}

/// `a` scaled to unit length (a zero vector stays zero).
fn normalised(a: Vector3<f64>) -> Vector3<f64> {
    a / a.norm().max(f64::MIN_POSITIVE)
}

/// Maps values to [0, 1] along the colour bar.
#[derive(Clone, Copy, Debug)]
struct Scale {
    lo: f64,
    hi: f64,
    log: bool,
}

impl Scale {
    fn new(values: &[f64], options: &RenderOptions) -> Self {
        let log = options.log_scale;
        let valid = |v: f64| v.is_finite() && (!log || v > 0.0);
        let (mut lo, mut hi) = options.range.filter(|&(a, b)| valid(a) && valid(b) && a < b).unwrap_or_else(|| {
            values
                .iter()
                .copied()
                .filter(|&v| valid(v))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)))
        });
        if lo > hi {
            (lo, hi) = if log { (1.0, 10.0) } else { (0.0, 1.0) };
        } else if lo == hi {
            (lo, hi) =
                if log { (lo / 2.0, hi * 2.0) } else { (lo - lo.abs().max(1.0) * 0.5, hi + hi.abs().max(1.0) * 0.5) };
        }
        Self { lo, hi, log }
    }

    /// Position in [0, 1] (clamped), or `None` for a missing value.
    fn position(&self, v: f64) -> Option<f64> {
        if !v.is_finite() || (self.log && v <= 0.0) {
            return None;
        }
        let t = if self.log {
            (v / self.lo).log10() / (self.hi / self.lo).log10()
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        Some(t.clamp(0.0, 1.0))
    }

    fn colour(&self, v: f64) -> [u8; 3] {
        self.position(v).map_or(MISSING_COLOUR, viridis)
    }

    /// Tick values with their labels: "nice" steps of 1, 2 or 5 × 10^k.
    fn ticks(&self) -> Vec<(f64, String)> {
        let (lo, hi) = (self.lo, self.hi);
        if self.log {
            let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
            // Every decade up to about eight of them, then every second, third, ...
            let stride = ((last - first) / 8).max(1);
            let decades = (first..=last).filter(|k| k.rem_euclid(stride) == 0);
            for mantissas in [&[1][..], &[1, 2, 5], &[1, 2, 3, 4, 5, 6, 7, 8, 9]] {
                let ticks: Vec<(f64, String)> = decades
                    .clone()
                    .flat_map(|k| {
                        mantissas.iter().map(move |&m| (m as f64 * 10f64.powi(k), label(m as f64 * 10f64.powi(k), k)))
                    })
                    .filter(|&(v, _)| v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9))
                    .collect();
                if ticks.len() >= 3 {
                    return ticks;
                }
            }
        }
        // Linear ticks, also the fallback for a log range narrower than a few ticks: the step
        // of 1, 2 or 5 × 10^k that gives closest to five ticks. (Dividing first keeps the
        // width finite for any finite range.)
        let k0 = ((hi / 5.0 - lo / 5.0).log10().floor() as i32).clamp(-330, 310);
        let Some((step, k)) = (k0 - 1..=k0 + 1)
            .flat_map(|k| [1.0, 2.0, 5.0].map(|m| (m * 10f64.powi(k), k)))
            .filter(|&(step, _)| step.is_normal() && (hi / step).is_finite() && (lo / step).is_finite())
            .min_by_key(|&(step, _)| ((hi / step).floor() - (lo / step).ceil() + 1.0 - 5.0).abs() as i64)
        else {
            return Vec::new();
        };
        let first = (lo / step - 1e-9).ceil() as i64;
        let last = (hi / step + 1e-9).floor() as i64;
        (first..=last).map(|i| i as f64 * step).map(|v| (v, label(v, k))).collect()
    }
}

/// A tick label showing `value` to the precision of 10^`exponent`: fixed-point for moderate
/// magnitudes, scientific otherwise.
fn label(value: f64, exponent: i32) -> String {
    let magnitude = value.abs();
    if magnitude < 10f64.powi(exponent) * 1e-6 {
        "0".into()
    } else if (1e-3..1e5).contains(&magnitude) {
        format!("{:.*}", (-exponent).max(0) as usize, value)
    } else {
        let e = magnitude.log10().floor() as i32;
        format!("{:.*e}", (e - exponent).max(0) as usize, value)
    }
}

/// Where things go on the canvas, in pixels.
#[derive(Clone, Copy, Debug)]
struct Layout {
    /// World → pixel: `px = x0 + (x - xmin) * scale`, `py = y0 - (y - ymin) * scale` (y up).
    x0: f64,
    y0: f64,
    xmin: f64,
    ymin: f64,
    scale: f64,
    /// Colour bar rectangle `[left, top, right, bottom)`.
    bar: [i64; 4],
    font: f64,
    title_font: f64,
}

impl Layout {
    fn new(mesh: &Mesh2, options: &RenderOptions, label_width: f64) -> Self {
        let (w, h) = (options.width as f64, options.height as f64);
        let margin = (w.min(h) / 40.0).max(6.0);
        let font = (h / 40.0).clamp(10.0, 20.0);
        let title_font = (h / 28.0).clamp(12.0, 28.0);
        let top = margin + if options.title.is_some() { 1.6 * title_font } else { font / 2.0 };
        let bottom = h - margin - font / 2.0;
        let bar_width = (w / 40.0).clamp(10.0, 28.0);
        let bar_right = w - margin - label_width - font;
        let bar_left = bar_right - bar_width;
        let plot_right = bar_left - 2.0 * margin;
        let (plot_w, plot_h) = ((plot_right - margin).max(1.0), (bottom - top).max(1.0));
        let ([xmin, ymin], [xmax, ymax]) = mesh.bounding_box().unwrap_or(([0.0, 0.0], [1.0, 1.0]));
        let (dx, dy) = ((xmax - xmin).max(f64::MIN_POSITIVE), (ymax - ymin).max(f64::MIN_POSITIVE));
        let scale = (plot_w / dx).min(plot_h / dy);
        Self {
            x0: margin + (plot_w - dx * scale) / 2.0,
            y0: bottom - (plot_h - dy * scale) / 2.0,
            xmin,
            ymin,
            scale,
            bar: [bar_left as i64, top as i64, bar_right as i64, bottom as i64],
            font,
            title_font,
        }
    }

    fn pixel(&self, p: [f64; 2]) -> [f64; 2] {
        [self.x0 + (p[0] - self.xmin) * self.scale, self.y0 - (p[1] - self.ymin) * self.scale]
    }
}

/// An RGB canvas.
struct Canvas {
    w: i64,
    h: i64,
    rgb: Vec<u8>,
}

impl Canvas {
    fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if (0..self.w).contains(&x) && (0..self.h).contains(&y) {
            let i = 3 * (y * self.w + x) as usize;
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }

    fn get(&self, x: i64, y: i64) -> [u8; 3] {
        let i = 3 * (y * self.w + x) as usize;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    fn rect(&mut self, [x0, y0, x1, y1]: [i64; 4], c: [u8; 3]) {
        for y in y0.max(0)..y1.min(self.h) {
            for x in x0.max(0)..x1.min(self.w) {
                self.put(x, y, c);
            }
        }
    }

    /// Fills the pixels whose centres lie in the triangle (inclusive, so shared edges leave no gaps).
    fn triangle(&mut self, p: [[f64; 2]; 3], c: [u8; 3]) {
        for (x, y) in self.covered(p) {
            self.put(x, y, c);
        }
    }

    /// The pixels whose centres lie in the triangle, inside the canvas.
    fn covered(&self, p: [[f64; 2]; 3]) -> Vec<(i64, i64)> {
        let cross =
            |a: [f64; 2], b: [f64; 2], q: [f64; 2]| (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]);
        let area = cross(p[0], p[1], p[2]);
        if area == 0.0 || !area.is_finite() {
            return Vec::new();
        }
        let sign = area.signum();
        let lo = |k: usize| (p[0][k].min(p[1][k]).min(p[2][k]) - 0.5).ceil() as i64;
        let hi = |k: usize| (p[0][k].max(p[1][k]).max(p[2][k]) - 0.5).floor() as i64;
        let mut pixels = Vec::new();
        for y in lo(1).max(0)..=hi(1).min(self.h - 1) {
            for x in lo(0).max(0)..=hi(0).min(self.w - 1) {
                let q = [x as f64 + 0.5, y as f64 + 0.5];
                if (0..3).all(|i| sign * cross(p[i], p[(i + 1) % 3], q) >= 0.0) {
                    pixels.push((x, y));
                }
            }
        }
        pixels
    }

    /// Draws a 1-pixel line whose pixels are the `fill` canvas's colour darkened by `strength`
    /// in [0, 1], so every edge pixel looks the same however many edges cross it.
    fn edge(&mut self, fill: &Canvas, a: [f64; 2], b: [f64; 2], strength: f64) {
        let shade = 1.0 - strength * (1.0 - EDGE_SHADE);
        let steps = (b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil().max(1.0) as usize;
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            let (x, y) = ((a[0] + t * (b[0] - a[0])).floor() as i64, (a[1] + t * (b[1] - a[1])).floor() as i64);
            if (0..self.w).contains(&x) && (0..self.h).contains(&y) {
                self.put(x, y, fill.get(x, y).map(|v| (v as f64 * shade) as u8));
            }
        }
    }
}

/// How strongly to draw the edges of a triangle (in pixels): 0 below [`EDGE_FADE`], 1 above.
/// Thickness is the smallest height, so slivers thin in one direction count as small.
fn edge_strength(p: [[f64; 2]; 3]) -> f64 {
    let length = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let longest = length(p[0], p[1]).max(length(p[1], p[2])).max(length(p[2], p[0]));
    let doubled_area = ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0])).abs();
    let thickness = doubled_area / longest;
    ((thickness - EDGE_FADE.0) / (EDGE_FADE.1 - EDGE_FADE.0)).clamp(0.0, 1.0)
}

/// Draws every element edge once, as strongly as the thicker of its two elements asks for.
fn draw_edges(canvas: &mut Canvas, mesh: &Mesh2, pixels: &[[f64; 2]]) {
    let corners = |cell: &[u32]| [pixels[cell[0] as usize], pixels[cell[1] as usize], pixels[cell[2] as usize]];
    let mut edges: Vec<((u32, u32), f64)> = Vec::with_capacity(3 * mesh.num_elements());
    for cell in mesh.elements() {
        let strength = edge_strength(corners(cell));
        if strength > 0.0 {
            for (a, b) in [(cell[0], cell[1]), (cell[1], cell[2]), (cell[2], cell[0])] {
                edges.push(((a.min(b), a.max(b)), strength));
            }
        }
    }
    edges.sort_unstable_by(|x, y| x.0.cmp(&y.0).then(y.1.total_cmp(&x.1)));
    edges.dedup_by_key(|e| e.0);
    let fill = Canvas { w: canvas.w, h: canvas.h, rgb: canvas.rgb.clone() };
    for ((a, b), strength) in edges {
        canvas.edge(&fill, pixels[a as usize], pixels[b as usize], strength);
    }
}

/// Paints shaded surface triangles back to front, remembering which triangle each pixel shows,
/// then darkens the pixels where the shown triangle changes (visible edges and silhouettes).
fn draw_surface(
    canvas: &mut Canvas,
    mesh: &Mesh2,
    values: &[f64],
    shades: &[f64],
    scale: &Scale,
    pixels: &[[f64; 2]],
    edges: bool,
) {
    const NONE: u32 = u32::MAX;
    let corners = |cell: &[u32]| [pixels[cell[0] as usize], pixels[cell[1] as usize], pixels[cell[2] as usize]];
    let mut shown = vec![NONE; (canvas.w * canvas.h) as usize];
    let mut strength = Vec::with_capacity(mesh.num_elements());
    for (k, ((cell, &v), &shade)) in mesh.elements().zip(values).zip(shades).enumerate() {
        let colour = scale.colour(v).map(|c| (c as f64 * shade).round() as u8);
        for (x, y) in canvas.covered(corners(cell)) {
            canvas.put(x, y, colour);
            shown[(y * canvas.w + x) as usize] = k as u32;
        }
        strength.push(edge_strength(corners(cell)));
    }
    if !edges {
        return;
    }
    let fill = canvas.rgb.clone();
    let at = |x: i64, y: i64| shown[(y * canvas.w + x) as usize];
    for y in 0..canvas.h {
        for x in 0..canvas.w {
            let here = at(x, y);
            let differs = |other: u32| other != here && (here != NONE || other != NONE);
            let right = if x + 1 < canvas.w { at(x + 1, y) } else { here };
            let below = if y + 1 < canvas.h { at(x, y + 1) } else { here };
            let neighbour = [right, below].into_iter().find(|&o| differs(o));
            if let Some(other) = neighbour {
                let s = [here, other].iter().filter(|&&t| t != NONE).map(|&t| strength[t as usize]).fold(0.0, f64::max);
                // Silhouettes are drawn whatever the triangle size.
                let s = if here == NONE || other == NONE { 1.0 } else { s };
                let i = 3 * (y * canvas.w + x) as usize;
                let shade = 1.0 - s * (1.0 - EDGE_SHADE);
                for k in 0..3 {
                    canvas.rgb[i + k] = (fill[i + k] as f64 * shade).round() as u8;
                }
            }
        }
    }
}

/// Draws the picture for the file `path` into an RGB buffer and says where the mesh went; errors
/// are text-drawing failures. With `shades` (a projected surface, triangles back to front) each colour is
/// darkened by its triangle's factor and edges are drawn only where they are seen.
fn render(
    mesh: &Mesh2,
    values: &[f64],
    shades: Option<&[f64]>,
    options: &RenderOptions,
    path: &Path,
) -> Result<(Vec<u8>, Layout), PlotError> {
    register_default_font();
    let (w, h) = (options.width, options.height);
    let scale = Scale::new(values, options);
    let ticks = scale.ticks();
    let font_size = (h as f64 / 40.0).clamp(10.0, 20.0);
    let text = |size: f64, pos: Pos| {
        TextStyle::from((FONT_FAMILY, size).into_font()).color(&RGBColor(INK[0], INK[1], INK[2])).pos(pos)
    };
    let label_style = text(font_size, Pos::new(HPos::Left, VPos::Center));
    let mut canvas = Canvas { w: w as i64, h: h as i64, rgb: BACKGROUND.repeat((w * h) as usize) };

    // Measure the tick labels first: their width decides how much room the mesh gets.
    let label_width = {
        let backend = BitMapBackend::with_buffer(&mut canvas.rgb, (w, h));
        let mut widest = 0;
        for (_, label) in &ticks {
            widest = widest.max(backend.estimate_text_size(label, &label_style).map_err(draw_error(path))?.0);
        }
        widest as f64
    };
    let layout = Layout::new(mesh, options, label_width);

    let pixels: Vec<[f64; 2]> = mesh.vertices().iter().map(|&p| layout.pixel(p)).collect();
    match shades {
        None => {
            for (cell, &v) in mesh.elements().zip(values) {
                let corners = [pixels[cell[0] as usize], pixels[cell[1] as usize], pixels[cell[2] as usize]];
                canvas.triangle(corners, scale.colour(v));
            }
            if options.edges {
                draw_edges(&mut canvas, mesh, &pixels);
            }
        }
        Some(shades) => draw_surface(&mut canvas, mesh, values, shades, &scale, &pixels, options.edges),
    }

    // Colour bar: a gradient from the bottom (low) to the top (high), framed, with ticks.
    let [left, top, right, bottom] = layout.bar;
    let bar_height = (bottom - top - 1).max(1) as f64;
    for y in top..bottom {
        canvas.rect([left, y, right, y + 1], viridis((bottom - 1 - y) as f64 / bar_height));
    }
    for frame in [[left - 1, top - 1, right + 1, top], [left - 1, bottom, right + 1, bottom + 1]] {
        canvas.rect(frame, INK);
    }
    for frame in [[left - 1, top - 1, left, bottom + 1], [right, top - 1, right + 1, bottom + 1]] {
        canvas.rect(frame, INK);
    }
    let tick_y = |v: f64| bottom - 1 - (scale.position(v).unwrap_or(0.0) * bar_height).round() as i64;
    let tick_length = (layout.font / 3.0).round() as i64;
    for &(v, _) in &ticks {
        canvas.rect([right, tick_y(v), right + tick_length, tick_y(v) + 1], INK);
    }

    let mut backend = BitMapBackend::with_buffer(&mut canvas.rgb, (w, h));
    let label_x = (right + tick_length + 3) as i32;
    for (v, label) in &ticks {
        backend.draw_text(label, &label_style, (label_x, tick_y(*v) as i32)).map_err(draw_error(path))?;
    }
    if let Some(title) = &options.title {
        let style = text(layout.title_font, Pos::new(HPos::Center, VPos::Top));
        let y = (layout.title_font * 0.4) as i32;
        backend.draw_text(title, &style, (w as i32 / 2, y)).map_err(draw_error(path))?;
    }
    backend.present().map_err(draw_error(path))?;
    drop(backend);
    Ok((canvas.rgb, layout))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
        let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        (info.width, info.height, buf)
    }

    /// A 2×1 rectangle split into four triangles around its centre.
    fn fan() -> Mesh2 {
        let v = vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0], [1.0, 0.5]];
        Mesh2::new(v, vec![0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4]).unwrap()
    }

    #[test]
    fn element_centres_have_their_colour() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fan.png");
        let mesh = fan();
        let values = [1.0, 2.0, 3.0, f64::NAN];
        let options = RenderOptions { width: 400, height: 300, title: Some("fan".into()), ..Default::default() };
        render_png(&mesh, &values, &options, &path).unwrap();
        let (w, h, rgb) = decode(&path);
        assert_eq!((w, h), (400, 300));
        let (_, layout) = render(&mesh, &values, None, &options, &path).unwrap();
        for (e, expected) in [viridis(0.0), viridis(0.5), viridis(1.0), MISSING_COLOUR].into_iter().enumerate() {
            let [x, y] = layout.pixel(mesh.midpoint(e));
            let i = 3 * (y as usize * w as usize + x as usize);
            assert_eq!(rgb[i..i + 3], expected, "element {e} at pixel ({x:.0}, {y:.0})");
        }
        // The mesh keeps its 2:1 aspect ratio.
        let [x0, y0] = layout.pixel([0.0, 0.0]);
        let [x1, y1] = layout.pixel([2.0, 1.0]);
        assert!(((x1 - x0) / (y0 - y1) - 2.0).abs() < 1e-12);
    }

    /// Two unit cubes of 6 tetrahedra each, at x ∈ [0, 1] (value 1) and x ∈ [3, 4] (value 2).
    fn two_cubes() -> (Mesh3, Vec<f64>) {
        let mut vertices = Vec::new();
        let mut cells = Vec::new();
        let mut values = Vec::new();
        for (offset, value) in [(0.0, 1.0), (3.0, 2.0)] {
            let base = vertices.len() as u32;
            for k in 0..8 {
                vertices.push([offset + (k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64]);
            }
            // Kuhn's triangulation along the diagonal 0 → 7.
            for path in [[1, 3], [1, 5], [2, 3], [2, 6], [4, 5], [4, 6]] {
                cells.extend([base, base + path[0], base + path[1], base + 7]);
                values.push(value);
            }
        }
        (Mesh3::new_reoriented(vertices, cells).unwrap(), values)
    }

    #[test]
    fn surfaces_show_the_nearest_front_faces_shaded() {
        let (mesh, values) = two_cubes();
        let options = RenderOptions { width: 300, height: 200, edges: false, ..Default::default() };
        let path = Path::new("cubes.png");
        let pixel = |view: View| {
            let rgb = render_surface_rgb(&mesh, &values, &options, view, path).unwrap();
            // The cubes' square outline is centred vertically; sample a pixel inside it.
            let (_, layout) = {
                let (projected, v, s) = visible_surface(&mesh, &values, view).unwrap();
                render(&projected, &v, Some(&s), &options, path).unwrap()
            };
            let [x, y] = layout.pixel([0.5 * if view.azimuth_deg == 0.0 { 1.0 } else { -1.0 }, 0.5]);
            let i = 3 * (y as usize * 300 + x as usize);
            [rgb[i], rgb[i + 1], rgb[i + 2]]
        };
        // Face-on, the face normal is the eye direction: shade 0.35 + 0.65 · cos(light, eye).
        let shade = 0.35 + 0.65 / (1.0f64 + 0.16 + 0.09).sqrt();
        let expected = |t: f64| viridis(t).map(|c| (c as f64 * shade).round() as u8);
        // From +x the cube at x ∈ [3, 4] hides the other; from −x it is the other way round.
        assert_eq!(pixel(View { azimuth_deg: 0.0, elevation_deg: 0.0 }), expected(1.0));
        assert_eq!(pixel(View { azimuth_deg: 180.0, elevation_deg: 0.0 }), expected(0.0));
    }

    #[test]
    fn surface_pictures_are_written_and_bad_requests_are_errors() {
        let (mesh, values) = two_cubes();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cubes.png");
        let view = View { azimuth_deg: 30.0, elevation_deg: 25.0 };
        render_surface_png(&mesh, &values, &RenderOptions::default(), view, &path).unwrap();
        assert_eq!(decode(&path).0, 1000);
        let err = render_surface_png(&mesh, &values[1..], &RenderOptions::default(), view, &path).unwrap_err();
        assert!(matches!(err, PlotError::ValueCount { len: 11, expected: 12, .. }), "{err}");
        assert!(err.to_string().contains("cubes.png"), "{err}");
    }

    #[test]
    fn bad_requests_are_errors() {
        let path = Path::new("/nonexistent-dir/x.png");
        let err = render_png(&fan(), &[1.0], &RenderOptions::default(), path).unwrap_err();
        assert!(matches!(err, PlotError::ValueCount { len: 1, expected: 4, .. }), "{err}");
        let tiny = RenderOptions { width: 10, ..Default::default() };
        let err = render_png(&fan(), &[1.0; 4], &tiny, path).unwrap_err();
        assert!(matches!(err, PlotError::ImageSize { width: 10, .. }), "{err}");
        let err = render_png(&fan(), &[1.0; 4], &RenderOptions::default(), path).unwrap_err();
        assert!(matches!(err, PlotError::Write(MeshError::Io { .. })), "{err}");
        assert!(err.to_string().contains("x.png"), "{err}");
    }

    #[test]
    fn viridis_matches_matplotlib_anchors() {
        // matplotlib's viridis at i/7 (as tabulated in plotters' ViridisRGB).
        let anchors = [
            [68, 1, 84],
            [70, 50, 127],
            [54, 92, 141],
            [39, 127, 143],
            [31, 162, 136],
            [74, 194, 110],
            [160, 219, 57],
            [254, 232, 37],
        ];
        for (i, a) in anchors.iter().enumerate() {
            let c = viridis(i as f64 / 7.0);
            assert!((0..3).all(|k| (c[k] as i32 - a[k]).abs() <= 4), "{i}: {c:?} vs {a:?}");
        }
    }

    #[test]
    fn ticks_are_round_numbers_inside_the_range() {
        let linear = Scale { lo: 0.013, hi: 0.087, log: false }.ticks();
        let labels: Vec<&str> = linear.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0.02", "0.04", "0.06", "0.08"]);
        let log = Scale { lo: 3e-5, hi: 0.2, log: true }.ticks();
        let labels: Vec<&str> = log.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["1e-4", "0.001", "0.01", "0.1"]);
        let narrow = Scale { lo: 2.0, hi: 3.0, log: true }.ticks();
        assert!(narrow.len() >= 2, "{narrow:?}");
        assert!(Scale { lo: 1e-300, hi: 1e300, log: true }.ticks().len() <= 10);
        for (lo, hi) in [(-f64::MAX, f64::MAX), (1.0, 1.0 + f64::EPSILON), (0.0, 5e-324)] {
            assert!(Scale { lo, hi, log: false }.ticks().len() <= 10, "{lo} {hi}");
        }
        assert_eq!(label(-2.5e-7, -8), "-2.5e-7");
        assert_eq!(label(1500.0, 2), "1500");
    }
}
