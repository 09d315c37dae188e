//! Exact orientation predicates for `f64` points: a floating-point filter with Shewchuk's error
//! bounds, and when it cannot decide, the determinant evaluated exactly in expansion arithmetic
//! (sums of non-overlapping doubles). Exact as long as no product under- or overflows, which
//! holds for any coordinates between about 1e-70 and 1e70 in magnitude.

use std::cmp::Ordering;

/// ε = 2⁻⁵³, the unit roundoff of `f64`.
const EPS: f64 = f64::EPSILON / 2.0;
/// Shewchuk's `ccwerrboundA` and `o3derrboundA`: forward error bounds of the plain evaluation.
const ORIENT2D_BOUND: f64 = (3.0 + 16.0 * EPS) * EPS;
const ORIENT3D_BOUND: f64 = (7.0 + 56.0 * EPS) * EPS;

/// Sign of det[b − a, c − a, d − a], i.e. of the signed volume of tet (a, b, c, d): `Greater`
/// when d lies on the side the normal (b − a) × (c − a) points to.
pub(crate) fn orient3d(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> Ordering {
    // Shewchuk's form det[a − d, b − d, c − d] = −det[b − a, c − a, d − a].
    let [adx, ady, adz] = [a[0] - d[0], a[1] - d[1], a[2] - d[2]];
    let [bdx, bdy, bdz] = [b[0] - d[0], b[1] - d[1], b[2] - d[2]];
    let [cdx, cdy, cdz] = [c[0] - d[0], c[1] - d[1], c[2] - d[2]];
    let (bc, cb) = (bdy * cdz, bdz * cdy);
    let (ca, ac) = (cdy * adz, cdz * ady);
    let (ab, ba) = (ady * bdz, adz * bdy);
    let det = adx * (bc - cb) + bdx * (ca - ac) + cdx * (ab - ba);
    let permanent =
        (bc.abs() + cb.abs()) * adx.abs() + (ca.abs() + ac.abs()) * bdx.abs() + (ab.abs() + ba.abs()) * cdx.abs();
    let shewchuk = if det.abs() > ORIENT3D_BOUND * permanent {
        det.partial_cmp(&0.0).unwrap_or(Ordering::Equal)
    } else {
        let m = |i: usize, k: usize| {
            let p = [a, b, c][i];
            two_diff(p[k], d[k])
        };
        let minor =
            |i: usize, j: usize, k0: usize, k1: usize| sub(&mul(&m(i, k0), &m(j, k1)), &mul(&m(i, k1), &m(j, k0)));
        let terms =
            [mul(&m(0, 0), &minor(1, 2, 1, 2)), mul(&m(1, 0), &minor(2, 0, 1, 2)), mul(&m(2, 0), &minor(0, 1, 1, 2))];
        sign(&add(&add(&terms[0], &terms[1]), &terms[2]))
    };
    shewchuk.reverse()
}

/// Sign of det[b − a, c − a]: `Greater` when a, b, c turn counter-clockwise.
pub(crate) fn orient2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> Ordering {
    let left = (a[0] - c[0]) * (b[1] - c[1]);
    let right = (a[1] - c[1]) * (b[0] - c[0]);
    let det = left - right;
    if det.abs() > ORIENT2D_BOUND * (left.abs() + right.abs()) {
        return det.partial_cmp(&0.0).unwrap_or(Ordering::Equal);
    }
    let d = |p: [f64; 2], k: usize| two_diff(p[k], c[k]);
    sign(&sub(&mul(&d(a, 0), &d(b, 1)), &mul(&d(a, 1), &d(b, 0))))
}

/// An exact value as a sum of non-overlapping doubles of increasing magnitude, on the stack.
/// 192 terms is the most `orient3d` needs: a 3×3 determinant of 2-term differences.
#[derive(Clone, Copy)]
struct Expansion {
    len: usize,
    terms: [f64; 192],
}

impl Expansion {
    const ZERO: Self = Self { len: 0, terms: [0.0; 192] };

    fn terms(&self) -> &[f64] {
        &self.terms[..self.len]
    }

    /// Adds one double in place (Shewchuk's Grow-Expansion), dropping zero components.
    fn grow(&mut self, b: f64) {
        let mut q = b;
        let mut k = 0;
        for i in 0..self.len {
            let (s, h) = two_sum(q, self.terms[i]);
            if h != 0.0 {
                self.terms[k] = h;
                k += 1;
            }
            q = s;
        }
        if q != 0.0 {
            self.terms[k] = q;
            k += 1;
        }
        self.len = k;
    }
}

fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    let bv = x - a;
    let av = x - bv;
    (x, (a - av) + (b - bv))
}

/// a − b exactly.
fn two_diff(a: f64, b: f64) -> Expansion {
    let mut e = Expansion::ZERO;
    e.grow(a);
    e.grow(-b);
    e
}

fn add(e: &Expansion, f: &Expansion) -> Expansion {
    let mut out = *e;
    f.terms().iter().for_each(|&x| out.grow(x));
    out
}

fn sub(e: &Expansion, f: &Expansion) -> Expansion {
    let mut out = *e;
    f.terms().iter().for_each(|&x| out.grow(-x));
    out
}

fn mul(e: &Expansion, f: &Expansion) -> Expansion {
    let mut out = Expansion::ZERO;
    for &x in e.terms() {
        for &y in f.terms() {
            let p = x * y;
            // The fused multiply-add rounds once, so it returns the exact rounding error of p.
            out.grow(x.mul_add(y, -p));
            out.grow(p);
        }
    }
    out
}

/// The largest component decides the sign of a non-overlapping expansion.
fn sign(e: &Expansion) -> Ordering {
    e.terms().last().map_or(Ordering::Equal, |x| x.partial_cmp(&0.0).unwrap_or(Ordering::Equal))
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

    proptest::proptest! {
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
