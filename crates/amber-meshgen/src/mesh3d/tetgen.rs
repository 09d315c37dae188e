//! Safe wrapper around the vendored TetGen 1.5 (`tetgen-sys`): a closed triangle surface (PLC)
//! plus target edge lengths in, a positively oriented [`Mesh3`] and its marked boundary out.
//!
//! TetGen never coarsens its input surface: the tets next to the boundary are as fine as the
//! surface handed in, so the surface must already follow the sizing field (spec §2, 3D).
//! Linking this module makes the program AGPL-3.0 (see `crates/tetgen-sys/tetgen/NOTICE.md`).

use std::cmp::Ordering;
use std::collections::HashMap;
use std::ffi::{CString, c_int};
use std::ptr::{null, null_mut};

use amber_mesh::{Mesh3, MeshError, bounding_box, signed_volume};
use nalgebra::Vector3;
use rstar::RTree;
use rstar::primitives::GeomWithData;
use tetgen_sys as sys;

use crate::predicates::orient3d;

/// A piecewise linear complex made of triangles: every triangle is one facet of TetGen's input,
/// carrying a marker (the CAD face id) that reappears on the output boundary triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Plc {
    /// Vertex positions.
    pub points: Vec<[f64; 3]>,
    /// Zero-based point indices, any orientation.
    pub triangles: Vec<[u32; 3]>,
    /// One marker per triangle.
    pub face_markers: Vec<i32>,
}

/// TetGen's quality bound (`-q`): refine tets whose radius-edge ratio or minimum dihedral
/// angle is worse than these.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quality {
    /// Maximum circumradius / shortest edge (TetGen's default 2.0; ≥ 1.2 is safe, less may not terminate).
    pub max_radius_edge_ratio: f64,
    /// Minimum dihedral angle in degrees (0 = no bound).
    pub min_dihedral_deg: f64,
}

/// TetGen's mesh optimisation (`-O` and `-o/`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Optimization {
    /// Optimisation passes, 0–9 (`-O<level>`).
    pub level: u8,
    /// Bit set of operations, 0–7 (`-O<level>/<scheme>`): 1 flips, 2 vertex smoothing,
    /// 4 vertex insertion and deletion.
    pub scheme: u8,
    /// Dihedral angle in degrees above which a tet is optimised (`-o/<angle>`).
    pub max_dihedral_deg: f64,
}

/// The TetGen switches amber exposes; rendered to TetGen's letter syntax by
/// [`TetgenSwitches::to_command`]. `p` (mesh a PLC), `m` (use sizes, added when sizes or a
/// background mesh are given) and `Q` (quiet) are implied.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TetgenSwitches {
    /// `-q`: quality refinement, or none.
    pub quality: Option<Quality>,
    /// `-Y`: keep the input surface as it is (no Steiner points on the boundary).
    pub keep_boundary: bool,
    /// `-O`/`-o`: optimisation, or TetGen's default.
    pub optimization: Option<Optimization>,
    /// `-S`: stop inserting points after this many Steiner points (none: no limit).
    pub max_steiner_points: Option<usize>,
}

impl Default for TetgenSwitches {
    /// The project's switches `-pYq1.4/20mO7/7o/150` (spec §2, 3D).
    fn default() -> Self {
        Self {
            quality: Some(Quality { max_radius_edge_ratio: 1.4, min_dihedral_deg: 20.0 }),
            keep_boundary: true,
            optimization: Some(Optimization { level: 7, scheme: 7, max_dihedral_deg: 150.0 }),
            max_steiner_points: None,
        }
    }
}

impl TetgenSwitches {
    /// Plain quality meshing, `-pq<ratio>`: TetGen may split boundary triangles, default optimisation.
    pub fn plain_quality(max_radius_edge_ratio: f64) -> Self {
        Self {
            quality: Some(Quality { max_radius_edge_ratio, min_dihedral_deg: 0.0 }),
            keep_boundary: false,
            optimization: None,
            max_steiner_points: None,
        }
    }

    /// The switch string without dash, e.g. `"pYq1.4/20mO7/7o/150Q"` for the default with sizes.
    pub fn to_command(&self, with_sizes: bool) -> Result<String, TetgenError> {
        let mut s = String::from("p");
        if self.keep_boundary {
            s.push('Y');
        }
        if let Some(q) = self.quality {
            let ratio_ok = q.max_radius_edge_ratio.is_finite() && q.max_radius_edge_ratio > 0.0;
            if !ratio_ok || !(0.0..90.0).contains(&q.min_dihedral_deg) {
                return Err(TetgenError::InvalidSwitches(format!("{q:?}")));
            }
            s += &format!("q{}/{}", q.max_radius_edge_ratio, q.min_dihedral_deg);
        }
        if with_sizes {
            s.push('m');
        }
        if let Some(o) = self.optimization {
            if o.level > 9 || o.scheme > 7 || !(0.0..180.0).contains(&o.max_dihedral_deg) {
                return Err(TetgenError::InvalidSwitches(format!("{o:?}")));
            }
            s += &format!("O{}/{}o/{}", o.level, o.scheme, o.max_dihedral_deg);
        }
        if let Some(n) = self.max_steiner_points {
            // TetGen reads the count into an `int`; 0 would mean "no limit".
            s += &format!("S{}", n.clamp(1, i32::MAX as usize));
        }
        s.push('Q');
        Ok(s)
    }
}

/// A tetrahedral mesh made by TetGen with its boundary.
#[derive(Clone, Debug)]
pub struct TetgenMesh {
    /// The tets; the PLC's points come first, in their input order.
    pub mesh: Mesh3,
    /// Boundary triangles, oriented with outward normals.
    pub boundary: Vec<[u32; 3]>,
    /// The marker of the input facet each boundary triangle lies on.
    pub boundary_markers: Vec<i32>,
}

/// Everything that can go wrong meshing with TetGen.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TetgenError {
    /// TetGen code 1.
    #[error("TetGen ran out of memory (code 1)")]
    OutOfMemory,
    /// TetGen code 2, also a failed internal assertion or a loop past its step bound.
    #[error("TetGen hit an internal error (code 2)")]
    Internal,
    /// TetGen code 3.
    #[error("the input surface intersects itself (TetGen code 3)")]
    SelfIntersection,
    /// TetGen code 4.
    #[error("an input feature is smaller than TetGen's tolerance (code 4)")]
    SmallFeature,
    /// TetGen code 5.
    #[error("two input facets are too close to each other (TetGen code 5)")]
    CloseFacets,
    /// TetGen code 10.
    #[error("TetGen rejected its input (code 10)")]
    InputRejected,
    /// The input points span no volume.
    #[error("the input points span no volume (flat bounding box)")]
    FlatInput,
    /// Any other failure code of the shim.
    #[error("TetGen failed with code {0}")]
    Unknown(i32),
    /// Input array lengths disagree.
    #[error("{what} has {found} entries, expected {expected}")]
    LengthMismatch { what: &'static str, expected: usize, found: usize },
    /// A point coordinate is NaN or infinite.
    #[error("point {point} has a non-finite coordinate")]
    NonFinitePoint { point: usize },
    /// A triangle references a missing point or the same point twice.
    #[error("triangle {triangle} has invalid corners {corners:?} ({num_points} points)")]
    InvalidTriangle { triangle: usize, corners: [u32; 3], num_points: usize },
    /// A target size is not positive and finite.
    #[error("{what} {index} has size {value}; sizes must be positive and finite")]
    InvalidSize { what: &'static str, index: usize, value: f64 },
    /// More entries than TetGen's `int` indices can address.
    #[error("{what}: {count} entries exceed TetGen's limit")]
    TooLarge { what: &'static str, count: usize },
    /// TetGen removed every tet as exterior: the surface encloses nothing (it is not closed).
    #[error("TetGen's mesh has no tets: the surface does not enclose a volume (is it closed?)")]
    NoTets,
    /// TetGen dropped or reordered input points (duplicates, or points no triangle uses).
    #[error("TetGen dropped input points (duplicates or unused): {input} in, {output} out, or reordered them")]
    DroppedPoints { input: usize, output: usize },
    /// A switch value out of range.
    #[error("invalid TetGen switch values: {0}")]
    InvalidSwitches(String),
    /// TetGen's output is not a valid positively oriented mesh.
    #[error("TetGen's output is not a valid mesh: {0}")]
    InvalidOutput(#[from] MeshError),
    /// A tet of TetGen's Delaunay tetrahedralisation is flat or inverted in exact arithmetic.
    #[error("TetGen's Delaunay tet {tet} is not positively oriented")]
    InvertedDelaunayTet { tet: usize },
}

/// TetGen's background mesh for `-m` (spec §2, 3D): a convex tet mesh with a target edge length
/// at every node, in which TetGen locates every point it creates to size it.
///
/// Not a [`Mesh3`]: its tets are a Delaunay tetrahedralisation (see [`delaunay`]), which may hold
/// flat tets that only exact arithmetic tells positive. They are harmless here: TetGen walks the
/// background mesh with its own exact predicates and interpolates within whichever tet holds a
/// point.
#[derive(Clone, Debug)]
pub struct BackgroundMesh {
    points: Vec<[f64; 3]>,
    tets: Vec<[u32; 4]>,
    sizes: Vec<f64>,
}

/// Tetrahedralises the closed surface `plc`.
///
/// `point_sizes` (one target edge length per PLC point) and the `background` mesh drive TetGen's
/// `-m`; new points take their size from the background mesh when there is one, else from the
/// surface sizes.
pub fn tetrahedralize(
    plc: &Plc,
    point_sizes: Option<&[f64]>,
    background: Option<&BackgroundMesh>,
    switches: &TetgenSwitches,
) -> Result<TetgenMesh, TetgenError> {
    let n = plc.points.len();
    check_points(&plc.points)?;
    check_len("face_markers", plc.triangles.len(), plc.face_markers.len())?;
    for (t, &corners) in plc.triangles.iter().enumerate() {
        let [a, b, c] = corners;
        if corners.iter().any(|&v| v as usize >= n) || a == b || b == c || a == c {
            return Err(TetgenError::InvalidTriangle { triangle: t, corners, num_points: n });
        }
    }
    if let Some(sizes) = point_sizes {
        check_len("point_sizes", n, sizes.len())?;
        check_sizes("point", sizes)?;
    }
    if let Some(background) = background {
        to_int(background.tets.len(), "background tets")?;
    }
    let command = switches.to_command(point_sizes.is_some() || background.is_some())?;
    let triangles: Vec<c_int> = plc.triangles.iter().flatten().map(|&v| v as c_int).collect();
    let bg_tets: Vec<c_int> = background.map_or(Vec::new(), |b| b.tets.iter().flatten().map(|&v| v as c_int).collect());
    let bg_points = background.map_or(&[][..], |b| &b.points);
    let out = run(
        &command,
        &plc.points,
        (&triangles, &plc.face_markers),
        point_sizes,
        (bg_points, &bg_tets, background.map(|b| &b.sizes[..])),
    )?;
    if out.tets.is_empty() {
        return Err(TetgenError::NoTets);
    }
    keeps_input_points(&plc.points, &out.points)?;
    let mesh = Mesh3::new(out.points, out.tets)?;
    let mut boundary = out.faces;
    orient_outward(&mesh, &mut boundary);
    let boundary_markers = out.face_markers.unwrap_or_else(|| vec![0; boundary.len()]);
    Ok(TetgenMesh { mesh, boundary, boundary_markers })
}

/// Delaunay tetrahedralisation of the convex hull of `points` (no `p` switch): tets over
/// `points` in their order (duplicate points are an error), each positively oriented in exact
/// arithmetic.
///
/// Not a [`Mesh3`]: points that are coplanar up to the rounding of their coordinates and nearly
/// cocircular (a rectangle of vertices on a planar face of a mesh boundary read from a file)
/// make flat Delaunay tets, of volume far below the rounding error of a floating-point
/// determinant, whose computed volume may come out zero or negative.
pub fn delaunay(points: &[[f64; 3]]) -> Result<Vec<[u32; 4]>, TetgenError> {
    check_points(points)?;
    let out = run("Q", points, (&[], &[]), None, (&[], &[], None))?;
    keeps_input_points(points, &out.points)?;
    let tets: Vec<[u32; 4]> = out.tets.chunks_exact(4).map(|t| [t[0], t[1], t[2], t[3]]).collect();
    let inverted = |t: &[u32; 4]| {
        let [a, b, c, d] = t.map(|v| points[v as usize]);
        orient3d(a, b, c, d) != Ordering::Greater
    };
    match tets.iter().position(inverted) {
        Some(tet) => Err(TetgenError::InvertedDelaunayTet { tet }),
        None => Ok(tets),
    }
}

/// The convex background mesh for `-m` (spec §2, 3D): the Delaunay tetrahedralisation of
/// `points` plus the 8 corners of their bounding box grown by `padding_fraction` times its diagonal on
/// every side, with `sizes` at the points and the size of the nearest point at each corner.
///
/// TetGen locates every point it creates in the background mesh; with the (non-convex) current
/// mesh itself, points just outside its curved boundary would get no size.
pub fn convex_background(
    points: &[[f64; 3]],
    sizes: &[f64],
    padding_fraction: f64,
) -> Result<BackgroundMesh, TetgenError> {
    check_len("sizes", points.len(), sizes.len())?;
    check_sizes("point", sizes)?;
    let Some((lo, hi)) = bounding_box(points) else { return Err(TetgenError::FlatInput) };
    let padding = padding_fraction * (Vector3::from(hi) - Vector3::from(lo)).norm();
    let tree = RTree::bulk_load(points.iter().enumerate().map(|(i, &p)| GeomWithData::new(p, i)).collect());
    let mut all = points.to_vec();
    let mut all_sizes = sizes.to_vec();
    for c in 0..8 {
        let corner = [0, 1, 2].map(|k| if c >> k & 1 == 0 { lo[k] - padding } else { hi[k] + padding });
        let nearest = tree.nearest_neighbor(corner).map_or(0, |n| n.data);
        all.push(corner);
        all_sizes.push(sizes[nearest]);
    }
    Ok(BackgroundMesh { tets: delaunay(&all)?, points: all, sizes: all_sizes })
}

struct RawOutput {
    points: Vec<[f64; 3]>,
    tets: Vec<u32>,
    faces: Vec<[u32; 3]>,
    face_markers: Option<Vec<i32>>,
}

/// One call into the shim; the borrowed inputs are copied by TetGen before it runs.
fn run(
    command: &str,
    points: &[[f64; 3]],
    (triangles, markers): (&[c_int], &[c_int]),
    point_sizes: Option<&[f64]>,
    (bg_points, bg_tets, bg_sizes): (&[[f64; 3]], &[c_int], Option<&[f64]>),
) -> Result<RawOutput, TetgenError> {
    let switches = CString::new(command).map_err(|_| TetgenError::InvalidSwitches(command.into()))?;
    let num_points = to_int(points.len(), "points")?;
    if num_points < 4 {
        return Err(TetgenError::FlatInput);
    }
    let num_triangles = to_int(markers.len(), "triangles")?;
    let num_bg_points = if bg_sizes.is_some() { to_int(bg_points.len(), "background points")? } else { 0 };
    let mut result = null_mut();
    // SAFETY: every pointer is valid for the length the shim reads (checked above), or null
    // where the contract allows it; the shim copies the inputs before returning.
    let code = unsafe {
        sys::amber_tetgen_tetrahedralize(
            switches.as_ptr(),
            points.as_ptr().cast(),
            num_points,
            triangles.as_ptr(),
            markers.as_ptr(),
            num_triangles,
            point_sizes.map_or(null(), <[f64]>::as_ptr),
            bg_points.as_ptr().cast(),
            num_bg_points,
            bg_tets.as_ptr(),
            (bg_tets.len() / 4) as c_int,
            bg_sizes.map_or(null(), <[f64]>::as_ptr),
            &mut result,
        )
    };
    if code != sys::AMBER_TETGEN_OK {
        return Err(error_from_code(code));
    }
    // SAFETY: on success `result` is a live handle whose arrays have the reported lengths; it
    // is read once and freed right after.
    unsafe {
        let np = sys::amber_tetgen_num_points(result) as usize;
        let nt = sys::amber_tetgen_num_tets(result) as usize;
        let nf = sys::amber_tetgen_num_faces(result) as usize;
        let out = RawOutput {
            points: slice(sys::amber_tetgen_points(result), 3 * np)
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]])
                .collect(),
            tets: slice(sys::amber_tetgen_tets(result), 4 * nt).iter().map(|&v| v as u32).collect(),
            faces: slice(sys::amber_tetgen_faces(result), 3 * nf)
                .chunks_exact(3)
                .map(|f| [f[0] as u32, f[1] as u32, f[2] as u32])
                .collect(),
            face_markers: (!sys::amber_tetgen_face_markers(result).is_null())
                .then(|| slice(sys::amber_tetgen_face_markers(result), nf).to_vec()),
        };
        sys::amber_tetgen_free(result);
        Ok(out)
    }
}

/// A slice over a shim array that may be null when empty.
///
/// # Safety
/// `ptr` must be valid for `len` reads whenever `len > 0`.
unsafe fn slice<'a, T>(ptr: *const T, len: usize) -> &'a [T] {
    if len == 0 || ptr.is_null() { &[] } else { unsafe { std::slice::from_raw_parts(ptr, len) } }
}

fn error_from_code(code: c_int) -> TetgenError {
    match code {
        sys::AMBER_TETGEN_OUT_OF_MEMORY => TetgenError::OutOfMemory,
        sys::AMBER_TETGEN_INTERNAL_ERROR => TetgenError::Internal,
        sys::AMBER_TETGEN_SELF_INTERSECTION => TetgenError::SelfIntersection,
        sys::AMBER_TETGEN_SMALL_FEATURE => TetgenError::SmallFeature,
        sys::AMBER_TETGEN_CLOSE_FACETS => TetgenError::CloseFacets,
        sys::AMBER_TETGEN_INPUT_ERROR => TetgenError::InputRejected,
        sys::AMBER_TETGEN_FLAT_INPUT => TetgenError::FlatInput,
        other => TetgenError::Unknown(other),
    }
}

fn to_int(count: usize, what: &'static str) -> Result<c_int, TetgenError> {
    // TetGen also multiplies counts by up to 4 in `int` arithmetic.
    c_int::try_from(count).ok().filter(|&c| c <= c_int::MAX / 4).ok_or(TetgenError::TooLarge { what, count })
}

/// TetGen drops duplicate and unused input points and renumbers the rest; the callers rely on
/// the input points coming first, unchanged and in order.
fn keeps_input_points(input: &[[f64; 3]], output: &[[f64; 3]]) -> Result<(), TetgenError> {
    if output.get(..input.len()) == Some(input) {
        Ok(())
    } else {
        Err(TetgenError::DroppedPoints { input: input.len(), output: output.len() })
    }
}

fn check_len(what: &'static str, expected: usize, found: usize) -> Result<(), TetgenError> {
    if expected == found { Ok(()) } else { Err(TetgenError::LengthMismatch { what, expected, found }) }
}

fn check_points(points: &[[f64; 3]]) -> Result<(), TetgenError> {
    match points.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
        Some(point) => Err(TetgenError::NonFinitePoint { point }),
        None => Ok(()),
    }
}

fn check_sizes(what: &'static str, sizes: &[f64]) -> Result<(), TetgenError> {
    match sizes.iter().position(|s| !(s.is_finite() && *s > 0.0)) {
        Some(index) => Err(TetgenError::InvalidSize { what, index, value: sizes[index] }),
        None => Ok(()),
    }
}

/// Turns every boundary triangle so that the tet behind it lies on its negative side; faces
/// with two tets behind them (internal facets) are left as TetGen gave them.
fn orient_outward(mesh: &Mesh3, faces: &mut [[u32; 3]]) {
    let key = |mut f: [u32; 3]| {
        f.sort_unstable();
        f
    };
    let mut behind: HashMap<[u32; 3], (u32, usize)> =
        faces.iter().enumerate().map(|(i, &f)| (key(f), (0, i))).collect();
    let mut opposite = vec![u32::MAX; faces.len()];
    for tet in mesh.elements() {
        for skip in 0..4 {
            let f = [0, 1, 2, 3].map(|k| tet[k]);
            let face = key([f[(skip + 1) % 4], f[(skip + 2) % 4], f[(skip + 3) % 4]]);
            if let Some((count, i)) = behind.get_mut(&face) {
                *count += 1;
                opposite[*i] = tet[skip];
            }
        }
    }
    for (count, i) in behind.into_values() {
        if count == 1 {
            let f = &mut faces[i];
            if signed_volume::<3>(mesh.vertices(), &[f[0], f[1], f[2], opposite[i]]) > 0.0 {
                f.swap(1, 2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit cube, each side split into n × n squares of two triangles, marker = side 1–6;
    /// the first 8 points are the corners. Orientation is mixed on purpose: TetGen must not care.
    fn cube(n: u32) -> Plc {
        let mut index = HashMap::new();
        let mut plc = Plc::default();
        let mut point = |c: [u32; 3], plc: &mut Plc| {
            *index.entry(c).or_insert_with(|| {
                plc.points.push(c.map(|x| x as f64 / n as f64));
                plc.points.len() as u32 - 1
            })
        };
        for c in 0..8 {
            point([c & 1, (c >> 1) & 1, (c >> 2) & 1].map(|b| b * n), &mut plc);
        }
        for side in 0..6 {
            let (axis, level) = (side / 2, (side % 2) as u32 * n);
            for i in 0..n {
                for j in 0..n {
                    let at = |di: u32, dj: u32| {
                        let mut c = [0; 3];
                        c[axis] = level;
                        c[(axis + 1) % 3] = i + di;
                        c[(axis + 2) % 3] = j + dj;
                        c
                    };
                    let q = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)].map(|c| point(c, &mut plc));
                    plc.triangles.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
                    plc.face_markers.extend([side as i32 + 1; 2]);
                }
            }
        }
        plc
    }

    fn edge_lengths_near(mesh: &Mesh3, x_range: std::ops::Range<f64>) -> Vec<f64> {
        let v = mesh.vertices();
        let mut lengths = Vec::new();
        for tet in mesh.elements() {
            for (a, b) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
                let (p, q) = (v[tet[a] as usize], v[tet[b] as usize]);
                if x_range.contains(&(0.5 * (p[0] + q[0]))) {
                    lengths.push(((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt());
                }
            }
        }
        lengths.sort_by(f64::total_cmp);
        lengths
    }

    #[test]
    fn default_switches_render_as_in_the_spec() {
        let s = TetgenSwitches::default();
        assert_eq!(s.to_command(true).unwrap(), "pYq1.4/20mO7/7o/150Q");
        assert_eq!(s.to_command(false).unwrap(), "pYq1.4/20O7/7o/150Q");
        assert_eq!(TetgenSwitches::plain_quality(1.4).to_command(false).unwrap(), "pq1.4/0Q");
        let capped = TetgenSwitches { max_steiner_points: Some(5000), ..s };
        assert_eq!(capped.to_command(true).unwrap(), "pYq1.4/20mO7/7o/150S5000Q");
        let bad =
            TetgenSwitches { optimization: Some(Optimization { level: 12, scheme: 7, max_dihedral_deg: 150.0 }), ..s };
        assert!(matches!(bad.to_command(true), Err(TetgenError::InvalidSwitches(_))));
    }

    #[test]
    fn cube_gives_positive_tets_of_total_volume_one() {
        // With -Y TetGen cannot split the boundary, so the surface already has the target size.
        let plc = cube(8);
        let sizes = vec![0.125; plc.points.len()];
        let out = tetrahedralize(&plc, Some(&sizes), None, &TetgenSwitches::default()).unwrap();
        let m = &out.mesh;
        assert!(m.num_elements() > 1000, "{} tets", m.num_elements());
        assert!(m.volumes().iter().all(|&v| v > 0.0));
        assert!((m.total_volume() - 1.0).abs() < 1e-12, "volume {}", m.total_volume());
        assert_eq!(&m.vertices()[..plc.points.len()], &plc.points[..]);
        // -Y keeps the input triangles as the boundary, now outward and with their markers.
        assert_eq!(out.boundary.len(), plc.triangles.len());
        for side in 1..=6 {
            assert_eq!(out.boundary_markers.iter().filter(|&&m| m == side).count(), 128);
        }
        // Outward faces: the cones from any apex (here the centre) add up to the volume.
        let mut vertices = m.vertices().to_vec();
        vertices.push([0.5; 3]);
        let apex = vertices.len() as u32 - 1;
        let enclosed: f64 = out.boundary.iter().map(|f| signed_volume::<3>(&vertices, &[apex, f[0], f[1], f[2]])).sum();
        assert!((enclosed - 1.0).abs() < 1e-12, "enclosed {enclosed}");
    }

    #[test]
    fn self_intersecting_plc_is_a_typed_error() {
        // A second cube shifted by half an edge overlaps the first: facets cross each other.
        let mut plc = cube(1);
        let shifted = cube(1);
        plc.points.extend(shifted.points.iter().map(|p| [p[0] + 0.5, p[1] + 0.3, p[2] + 0.2]));
        plc.triangles.extend(shifted.triangles.iter().map(|t| t.map(|v| v + 8)));
        plc.face_markers.extend(shifted.face_markers.iter().map(|m| m + 6));
        let err = tetrahedralize(&plc, None, None, &TetgenSwitches::default()).unwrap_err();
        assert!(matches!(err, TetgenError::SelfIntersection), "{err}");
        // The process survived and TetGen still works.
        assert!(tetrahedralize(&cube(1), None, None, &TetgenSwitches::default()).is_ok());
    }

    /// Reads `tests/data/segment-flip-cycle.txt`: `points N`, N lines `x y z`, `triangles M`,
    /// M lines of three point indices; `#` lines are comments.
    fn segment_flip_cycle() -> Plc {
        let text = include_str!("../../tests/data/segment-flip-cycle.txt");
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        let mut rows = |name: &str| -> Vec<[String; 3]> {
            let count = lines.next().unwrap().strip_prefix(name).unwrap().trim().parse().unwrap();
            let row = |l: &str| <[String; 3]>::try_from(l.split(' ').map(str::to_owned).collect::<Vec<_>>()).unwrap();
            lines.by_ref().take(count).map(row).collect()
        };
        let points = rows("points").iter().map(|p| p.each_ref().map(|x| x.parse().unwrap())).collect();
        let triangles: Vec<[u32; 3]> =
            rows("triangles").iter().map(|t| t.each_ref().map(|x| x.parse().unwrap())).collect();
        let face_markers = vec![1; triangles.len()];
        Plc { points, triangles, face_markers }
    }

    #[test]
    fn segment_recovery_that_flips_in_circles_is_an_internal_error() {
        // Unbounded, TetGen flips the same faces round and round while recovering one segment
        // of this PLC and never returns.
        let plc = segment_flip_cycle();
        assert_eq!((plc.points.len(), plc.triangles.len()), (2060, 5));
        for switches in
            [TetgenSwitches::default(), TetgenSwitches { quality: None, optimization: None, ..Default::default() }]
        {
            let err = tetrahedralize(&plc, None, None, &switches).unwrap_err();
            assert!(matches!(err, TetgenError::Internal), "{err}");
        }
        // The lock was released and TetGen still works.
        assert!(tetrahedralize(&cube(1), None, None, &TetgenSwitches::default()).is_ok());
    }

    #[test]
    fn bad_input_is_rejected_before_tetgen() {
        let mut plc = cube(1);
        plc.triangles[3] = [0, 0, 1];
        assert!(matches!(
            tetrahedralize(&plc, None, None, &TetgenSwitches::default()),
            Err(TetgenError::InvalidTriangle { triangle: 3, .. })
        ));
        let plc = cube(1);
        assert!(matches!(
            tetrahedralize(&plc, Some(&[1.0; 7]), None, &TetgenSwitches::default()),
            Err(TetgenError::LengthMismatch { .. })
        ));
        let mut sizes = vec![1.0; 8];
        sizes[5] = f64::NAN;
        assert!(matches!(
            tetrahedralize(&plc, Some(&sizes), None, &TetgenSwitches::default()),
            Err(TetgenError::InvalidSize { index: 5, .. })
        ));
        let flat: Vec<[f64; 3]> = (0..6).map(|i| [i as f64, (i * i) as f64, 0.0]).collect();
        assert!(matches!(delaunay(&flat), Err(TetgenError::FlatInput)));
        let mut open = cube(1);
        open.triangles.pop();
        open.face_markers.pop();
        assert!(matches!(tetrahedralize(&open, None, None, &TetgenSwitches::default()), Err(TetgenError::NoTets)));
        let mut twice = cube(1).points;
        twice.push(twice[3]);
        assert!(matches!(delaunay(&twice), Err(TetgenError::DroppedPoints { input: 9, output: 8 })));
    }

    #[test]
    fn smaller_point_sizes_give_finer_tets() {
        // Size 0.05 on the x = 0 side, 0.4 on the x = 1 side; edges of the 12-triangle surface
        // are split by -q/-m (no Y), and the interior follows the interpolated sizes.
        let plc = cube(1);
        let sizes: Vec<f64> = plc.points.iter().map(|p| if p[0] == 0.0 { 0.05 } else { 0.4 }).collect();
        let switches = TetgenSwitches { keep_boundary: false, ..TetgenSwitches::default() };
        let out = tetrahedralize(&plc, Some(&sizes), None, &switches).unwrap();
        let median = |v: Vec<f64>| v[v.len() / 2];
        let (fine, coarse) =
            (median(edge_lengths_near(&out.mesh, 0.0..0.2)), median(edge_lengths_near(&out.mesh, 0.8..1.0)));
        assert!(fine < 0.5 * coarse, "median edge near x=0: {fine}, near x=1: {coarse}");
        assert!((out.mesh.total_volume() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn background_mesh_drives_the_sizes() {
        // Background = a 5×5×5 grid, size 0.04 + 0.3·x, made convex with padded corners: a
        // graded interior inside the 12-triangle cube with no point sizes at all.
        let grid: Vec<[f64; 3]> =
            (0..125).map(|i| [(i % 5) as f64 / 4.0, ((i / 5) % 5) as f64 / 4.0, (i / 25) as f64 / 4.0]).collect();
        let grid_sizes: Vec<f64> = grid.iter().map(|p| 0.04 + 0.3 * p[0]).collect();
        let padding = 0.1 / 3f64.sqrt();
        let bg = convex_background(&grid, &grid_sizes, padding).unwrap();
        let volume: f64 = bg.tets.iter().map(|t| signed_volume::<3>(&bg.points, t)).sum();
        assert!((volume - 1.2f64.powi(3)).abs() < 1e-12, "{volume}");
        assert_eq!(&bg.sizes[..125], &grid_sizes[..]);
        let (lo, hi) = (grid_sizes[0], grid_sizes[4]);
        assert_eq!(&bg.sizes[125..], &[lo, hi, lo, hi, lo, hi, lo, hi]);
        let switches = TetgenSwitches { keep_boundary: false, ..TetgenSwitches::default() };
        let out = tetrahedralize(&cube(1), None, Some(&bg), &switches).unwrap();
        let median = |v: Vec<f64>| v[v.len() / 2];
        let (fine, coarse) =
            (median(edge_lengths_near(&out.mesh, 0.0..0.2)), median(edge_lengths_near(&out.mesh, 0.8..1.0)));
        assert!(fine < 0.5 * coarse, "median edge near x=0: {fine}, near x=1: {coarse}");
    }

    /// Four points of a planar face of the Console part val/001's expert mesh boundary (coplanar
    /// up to the rounding of their coordinates: y = 1.421e-14 beside 1.4209997e-14) and one
    /// point off it: their Delaunay tetrahedralisation has a flat tet whose floating-point volume
    /// is zero or negative. It is accepted (exactly positive), which a `Mesh3` could not be.
    #[test]
    fn near_coplanar_points_have_an_exactly_positive_delaunay_tetrahedralisation() {
        let points = [
            [-82.6985, 0.8121609, 94.6517185546875],
            [-80.4094, 1.421e-14, 114.17020201171874],
            [-80.4094, 1.4209997299286992e-14, 118.07390074218749],
            [-52.549339386367365, 68.0476114032497, 65.3049786985771],
            [-82.6985, 0.8121609, 86.844330390625],
        ];
        let tets = delaunay(&points).unwrap();
        let volumes: Vec<f64> = tets.iter().map(|t| signed_volume::<3>(&points, t)).collect();
        assert!(volumes.iter().any(|&v| v <= 0.0), "{volumes:?}");
        let cells: Vec<u32> = tets.iter().flatten().copied().collect();
        assert!(matches!(Mesh3::new(points.to_vec(), cells), Err(MeshError::NonPositiveElement { .. })));
    }
}
