//! Exact orientation and in-circle predicates for `f64` points, as `Ordering`s in our sign
//! conventions, on the `robust` crate (Shewchuk's adaptive predicates, which spade uses too: a
//! floating-point filter with his error bounds, and where it cannot decide, the determinant in
//! exact expansion arithmetic). The orientations are exact as long as no product under- or
//! overflows, which holds for any coordinates between about 1e-70 and 1e70 in magnitude; the
//! in-circle test, of degree four, within spade's `MIN_ALLOWED_VALUE`..`MAX_ALLOWED_VALUE`, which
//! `PolygonDomain` enforces.

use std::cmp::Ordering;

use robust::{Coord, Coord3D};

/// Sign of det[b − a, c − a, d − a], i.e. of the signed volume of tet (a, b, c, d): `Greater`
/// when d lies on the side the normal (b − a) × (c − a) points to.
pub(crate) fn orient3d(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> Ordering {
    let p = |p: [f64; 3]| Coord3D { x: p[0], y: p[1], z: p[2] };
    // robust's orient3d is Shewchuk's det[a − d, b − d, c − d] = −det[b − a, c − a, d − a].
    sign(robust::orient3d(p(a), p(b), p(c), p(d))).reverse()
}

/// Sign of det[b − a, c − a]: `Greater` when a, b, c turn counter-clockwise.
pub(crate) fn orient2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> Ordering {
    let p = |p: [f64; 2]| Coord { x: p[0], y: p[1] };
    // robust's orient2d is det[a − c, b − c] = det[b − a, c − a].
    sign(robust::orient2d(p(a), p(b), p(c)))
}

/// Sign of the lifted determinant of a, b, c, d: `Greater` when d lies strictly inside the circle
/// through the counter-clockwise a, b, c.
pub(crate) fn incircle(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Ordering {
    let p = |p: [f64; 2]| Coord { x: p[0], y: p[1] };
    sign(robust::incircle(p(a), p(b), p(c), p(d)))
}

/// The sign of an exact determinant (NaN input: `Equal`).
fn sign(det: f64) -> Ordering {
    det.partial_cmp(&0.0).unwrap_or(Ordering::Equal)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orientation_of_a_unit_tet_and_triangle() {
        let o = [0.0; 3];
        assert_eq!(orient3d(o, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]), Ordering::Greater);
        assert_eq!(orient3d(o, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]), Ordering::Less);
        assert_eq!(orient3d(o, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, 0.3, 0.0]), Ordering::Equal);
        assert_eq!(orient2d([0.0, 0.0], [1.0, 0.0], [0.0, 1.0]), Ordering::Greater);
        assert_eq!(orient2d([0.0, 0.0], [1.0, 1.0], [3.0, 3.0]), Ordering::Equal);
        let [a, b, c] = [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]];
        assert_eq!(incircle(a, b, c, [0.0, -0.5]), Ordering::Greater);
        assert_eq!(incircle(a, b, c, [0.0, -1.0]), Ordering::Equal);
        assert_eq!(incircle(a, b, c, [0.0, -1.5]), Ordering::Less);
    }

    /// Exact reference for integer coordinates: differences below 2^40 keep the determinant in i128.
    fn det3_i128(a: [i64; 3], b: [i64; 3], c: [i64; 3], d: [i64; 3]) -> Ordering {
        let r = |p: [i64; 3]| [0, 1, 2].map(|k| (p[k] - a[k]) as i128);
        let (u, v, w) = (r(b), r(c), r(d));
        let det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0]);
        det.cmp(&0)
    }

    fn f(p: [i64; 3]) -> [f64; 3] {
        p.map(|x| x as f64)
    }

    /// The plain floating-point determinants, for inputs where rounding cannot flip their sign.
    fn naive3d(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
        let v = |p: [f64; 3]| nalgebra::Vector3::from(p) - nalgebra::Vector3::from(a);
        v(b).cross(&v(c)).dot(&v(d))
    }

    fn naive2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
        let v = |p: [f64; 2]| nalgebra::Vector2::from(p) - nalgebra::Vector2::from(a);
        v(b).perp(&v(c))
    }

    /// Eighths of integers below 2¹⁰: differences, products and sums of them are exact in
    /// `f64`, so the plain determinant of such points is exact.
    fn eighths(n: [i32; 2]) -> [f64; 2] {
        n.map(|k| f64::from(k) / 8.0)
    }

    proptest::proptest! {
        // Unit-sized points whose determinant is far above its rounding error (about 1e-15).
        #[test]
        fn orient3d_agrees_with_the_plain_determinant_on_well_conditioned_points(
            a in proptest::array::uniform3(-1.0..1.0f64),
            b in proptest::array::uniform3(-1.0..1.0f64),
            c in proptest::array::uniform3(-1.0..1.0f64),
            d in proptest::array::uniform3(-1.0..1.0f64),
        ) {
            let det = naive3d(a, b, c, d);
            proptest::prop_assume!(det.abs() > 1e-9);
            proptest::prop_assert_eq!(orient3d(a, b, c, d), sign(det));
        }

        #[test]
        fn orient2d_agrees_with_the_plain_determinant_on_well_conditioned_points(
            a in proptest::array::uniform2(-1.0..1.0f64),
            b in proptest::array::uniform2(-1.0..1.0f64),
            c in proptest::array::uniform2(-1.0..1.0f64),
        ) {
            let det = naive2d(a, b, c);
            proptest::prop_assume!(det.abs() > 1e-9);
            proptest::prop_assert_eq!(orient2d(a, b, c), sign(det));
        }

        // Points on the tilted plane z = x/2 − y/4 + 3 (and c on the line through a and b), with
        // coordinates for which the plain determinant is exactly 0 too.
        #[test]
        fn exactly_coplanar_and_collinear_points_are_equal(
            xy in proptest::array::uniform4(proptest::array::uniform2(-1000i32..1000)),
            t in -8i32..8,
        ) {
            let [a, b, c, d] = xy.map(|n| {
                let [x, y] = eighths(n);
                [x, y, x / 2.0 - y / 4.0 + 3.0]
            });
            proptest::prop_assert_eq!(naive3d(a, b, c, d), 0.0);
            proptest::prop_assert_eq!(orient3d(a, b, c, d), Ordering::Equal);
            let [p, q] = [eighths(xy[0]), eighths(xy[1])];
            let r = [0, 1].map(|k| p[k] + f64::from(t) * (q[k] - p[k]));
            proptest::prop_assert_eq!(naive2d(p, q, r), 0.0);
            proptest::prop_assert_eq!(orient2d(p, q, r), Ordering::Equal);
        }

        // d = b + c − a (+ a unit nudge) is exactly coplanar with a, b, c (or one unit off the
        // plane), with coordinates so large that the plain determinant is pure rounding noise.
        #[test]
        fn orient3d_matches_exact_integer_arithmetic(
            a in proptest::array::uniform3(-(1i64 << 37)..(1i64 << 37)),
            b in proptest::array::uniform3(-(1i64 << 37)..(1i64 << 37)),
            c in proptest::array::uniform3(-(1i64 << 37)..(1i64 << 37)),
            nudge in proptest::array::uniform3(-1i64..=1),
        ) {
            let d = [0, 1, 2].map(|k| b[k] + c[k] - a[k] + nudge[k]);
            proptest::prop_assert_eq!(orient3d(f(a), f(b), f(c), f(d)), det3_i128(a, b, c, d));
        }

        #[test]
        fn orient2d_matches_exact_integer_arithmetic(
            a in proptest::array::uniform2(-(1i64 << 52)..(1i64 << 52)),
            t in -1000i64..1000,
            dir in proptest::array::uniform2(-(1i64 << 40)..(1i64 << 40)),
            nudge in proptest::array::uniform2(-1i64..=1),
        ) {
            // c on the line through a and b = a + dir, nudged by at most one unit.
            let b = [a[0] + dir[0], a[1] + dir[1]];
            let c = [a[0] + t * dir[0] + nudge[0], a[1] + t * dir[1] + nudge[1]];
            let d = |p: [i64; 2], k: usize| (p[k] - a[k]) as i128;
            let exact = (d(b, 0) * d(c, 1) - d(b, 1) * d(c, 0)).cmp(&0);
            let g = |p: [i64; 2]| p.map(|x| x as f64);
            proptest::prop_assert_eq!(orient2d(g(a), g(b), g(c)), exact);
        }
    }
}
