//! Raw FFI to the vendored TetGen 1.5 (`tetgen/`, AGPL-3.0, see `tetgen/NOTICE.md`) through the
//! `extern "C"` shim in `shim/shim.cpp`. Nothing else: the safe wrapper lives in
//! `amber-meshgen` (`mesh3d::tetgen`). This crate depends on nothing but `cc` at build time.
//!
//! Contract of [`amber_tetgen_tetrahedralize`]:
//! - `switches` is a NUL-terminated TetGen switch string *without* the leading dash
//!   (e.g. `"pYq1.4/20mO7/7o/150Q"`), at most 512 bytes.
//! - `points`: `3 * num_points` coordinates; `triangles`: `3 * num_triangles` zero-based point
//!   indices, each triangle one facet with the marker `triangle_markers[t]`; `point_sizes`:
//!   null or `num_points` target edge lengths (TetGen's `pointmtrlist`, used with `m`).
//! - Background mesh (only with `m`): `bg_num_points = 0` for none, else `3 * bg_num_points`
//!   coordinates, `4 * bg_num_tets` indices and `bg_num_points` nodal sizes.
//! - Returns [`AMBER_TETGEN_OK`] and stores a handle in `*result`, or an error code and leaves
//!   `*result` null. No C++ exception and no `exit()`/`abort()` escapes (a failed TetGen assert
//!   throws code 2). Calls are serialised by a lock: TetGen's predicates use global state.
//! - Every getter takes a live handle; the returned arrays live until [`amber_tetgen_free`].
//!   Tetrahedra have 4 corners; `face_markers` may be null (no boundary markers requested).

use std::ffi::{c_char, c_double, c_int};

/// Success.
pub const AMBER_TETGEN_OK: c_int = 0;
/// TetGen ran out of memory (its code 1, or `std::bad_alloc`).
pub const AMBER_TETGEN_OUT_OF_MEMORY: c_int = 1;
/// TetGen hit an internal error, a failed internal assertion, or one of the step bounds amber
/// added to loops that can go round forever (its code 2; see `tetgen/NOTICE.md`).
pub const AMBER_TETGEN_INTERNAL_ERROR: c_int = 2;
/// The input facets intersect each other (TetGen code 3).
pub const AMBER_TETGEN_SELF_INTERSECTION: c_int = 3;
/// An input feature is below TetGen's tolerance `-T` (code 4).
pub const AMBER_TETGEN_SMALL_FEATURE: c_int = 4;
/// Two input facets are too close to each other (code 5).
pub const AMBER_TETGEN_CLOSE_FACETS: c_int = 5;
/// TetGen rejected its input or switches (code 10).
pub const AMBER_TETGEN_INPUT_ERROR: c_int = 10;
/// The shim rejected its arguments (null pointer, index out of range, switches too long,
/// fewer than 4 points).
pub const AMBER_TETGEN_INVALID_ARGUMENT: c_int = 100;
/// The input points span no volume (their bounding box is flat).
pub const AMBER_TETGEN_FLAT_INPUT: c_int = 101;
/// An exception of unknown type or an undocumented TetGen code.
pub const AMBER_TETGEN_UNKNOWN_EXCEPTION: c_int = 102;
/// The output is not a linear tetrahedral mesh (e.g. `o2` was requested).
pub const AMBER_TETGEN_UNSUPPORTED_OUTPUT: c_int = 103;

/// Opaque handle to a TetGen result.
#[repr(C)]
pub struct AmberTetgenResult {
    _private: [u8; 0],
}

unsafe extern "C" {
    /// Runs `tetrahedralize`; see the crate docs for the contract.
    pub fn amber_tetgen_tetrahedralize(
        switches: *const c_char,
        points: *const c_double,
        num_points: c_int,
        triangles: *const c_int,
        triangle_markers: *const c_int,
        num_triangles: c_int,
        point_sizes: *const c_double,
        bg_points: *const c_double,
        bg_num_points: c_int,
        bg_tets: *const c_int,
        bg_num_tets: c_int,
        bg_sizes: *const c_double,
        result: *mut *mut AmberTetgenResult,
    ) -> c_int;
    /// Number of output points.
    pub fn amber_tetgen_num_points(result: *const AmberTetgenResult) -> c_int;
    /// `3 * num_points` output coordinates (input points first, in input order).
    pub fn amber_tetgen_points(result: *const AmberTetgenResult) -> *const c_double;
    /// Number of output tetrahedra.
    pub fn amber_tetgen_num_tets(result: *const AmberTetgenResult) -> c_int;
    /// `4 * num_tets` zero-based point indices.
    pub fn amber_tetgen_tets(result: *const AmberTetgenResult) -> *const c_int;
    /// Number of output boundary triangles.
    pub fn amber_tetgen_num_faces(result: *const AmberTetgenResult) -> c_int;
    /// `3 * num_faces` zero-based point indices.
    pub fn amber_tetgen_faces(result: *const AmberTetgenResult) -> *const c_int;
    /// `num_faces` facet markers (the marker of the input facet each face lies on), or null.
    pub fn amber_tetgen_face_markers(result: *const AmberTetgenResult) -> *const c_int;
    /// Frees a result; null is allowed.
    pub fn amber_tetgen_free(result: *mut AmberTetgenResult);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ptr::{null, null_mut};

    const CUBE: [f64; 24] =
        [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0., 0., 0., 1., 1., 0., 1., 1., 1., 1., 0., 1., 1.];

    fn run(switches: &std::ffi::CStr, triangles: &[c_int]) -> (c_int, *mut AmberTetgenResult) {
        let markers = vec![7; triangles.len() / 3];
        let mut result = null_mut();
        let code = unsafe {
            amber_tetgen_tetrahedralize(
                switches.as_ptr(),
                CUBE.as_ptr(),
                8,
                triangles.as_ptr(),
                markers.as_ptr(),
                (triangles.len() / 3) as c_int,
                null(),
                null(),
                0,
                null(),
                0,
                null(),
                &mut result,
            )
        };
        (code, result)
    }

    #[test]
    fn delaunay_of_cube_corners_fills_the_cube() {
        let (code, result) = run(c"Q", &[]);
        assert_eq!(code, AMBER_TETGEN_OK);
        unsafe {
            assert_eq!(amber_tetgen_num_points(result), 8);
            let n = amber_tetgen_num_tets(result) as usize;
            assert!((5..=6).contains(&n), "{n} tets");
            let tets = std::slice::from_raw_parts(amber_tetgen_tets(result), 4 * n);
            assert!(tets.iter().all(|&v| (0..8).contains(&v)));
            amber_tetgen_free(result);
        }
    }

    #[test]
    fn bad_arguments_are_codes_not_crashes() {
        let (code, result) = run(c"pQ", &[0, 1, 99]);
        assert_eq!(code, AMBER_TETGEN_INVALID_ARGUMENT);
        assert!(result.is_null());
        let long = std::ffi::CString::new("Q".repeat(600)).unwrap();
        assert_eq!(run(&long, &[]).0, AMBER_TETGEN_INVALID_ARGUMENT);
        unsafe { amber_tetgen_free(null_mut()) };
    }
}
