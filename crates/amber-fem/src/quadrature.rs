//! Quadrature rules on simplices, in barycentric coordinates.

use crate::FemError;

/// A quadrature rule on the reference simplex: barycentric points and weights summing to 1, so
/// that ∫_K g ≈ |K| Σ_q w_q g(x_q).
#[derive(Clone, Debug, PartialEq)]
pub struct Quadrature {
    /// Barycentric coordinates of each point (the first `D + 1` entries are used).
    points: Vec<[f64; 4]>,
    weights: Vec<f64>,
    degree: usize,
}

impl Quadrature {
    /// The cheapest rule on a `D`-simplex that integrates polynomials of degree `order` exactly.
    ///
    /// Triangles: degree 1 (centroid), 2 (3 interior points, scikit-fem's default for P1, which
    /// the reference used), 4 (Dunavant, 6 points), 5 (7 points). Tetrahedra: degree 1, 2.
    pub fn simplex<const D: usize>(order: usize) -> Result<Self, FemError> {
        let rule = match (D, order) {
            (_, 0 | 1) => Self::symmetric::<D>(&[(1.0, &[])], 1),
            (2, 2) => Self::symmetric::<D>(&[(1.0 / 3.0, &[1.0 / 6.0])], 2),
            (2, 3 | 4) => Self::symmetric::<D>(
                &[(0.223_381_589_678_011, &[0.445_948_490_915_965]), (0.109_951_743_655_322, &[0.091_576_213_509_771])],
                4,
            ),
            (2, 5) => {
                let s = 15f64.sqrt();
                Self::symmetric::<D>(
                    &[
                        (0.225, &[]),
                        ((155.0 + s) / 1200.0, &[(6.0 + s) / 21.0]),
                        ((155.0 - s) / 1200.0, &[(6.0 - s) / 21.0]),
                    ],
                    5,
                )
            }
            (3, 2) => Self::symmetric::<D>(&[(0.25, &[(5.0 - 5f64.sqrt()) / 20.0])], 2),
            _ => return Err(FemError::UnsupportedQuadrature { dimension: D, order }),
        };
        Ok(rule)
    }

    /// Builds a rule from orbits `(weight per point, [a])`: the points with `D` barycentric
    /// coordinates equal to `a` and the last one `1 − D·a`, in every position (no `a`: centroid).
    fn symmetric<const D: usize>(orbits: &[(f64, &[f64])], degree: usize) -> Self {
        let mut points = Vec::new();
        let mut weights = Vec::new();
        for &(w, a) in orbits {
            match a {
                [] => {
                    let mut p = [0.0; 4];
                    p[..=D].fill(1.0 / (D + 1) as f64);
                    points.push(p);
                    weights.push(w);
                }
                &[a, ..] => {
                    for odd in 0..=D {
                        let mut p = [0.0; 4];
                        p[..=D].fill(a);
                        p[odd] = 1.0 - D as f64 * a;
                        points.push(p);
                        weights.push(w);
                    }
                }
            }
        }
        Self { points, weights, degree }
    }

    /// Polynomial degree integrated exactly.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// `(barycentric point, weight)` pairs; weights sum to 1.
    pub fn iter(&self) -> impl Iterator<Item = (&[f64; 4], f64)> + '_ {
        self.points.iter().zip(self.weights.iter().copied())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ over the reference triangle of λ0^a λ1^b λ2^c = a! b! c! 2! / (a+b+c+2)! × |K|.
    fn exact_tri(a: i32, b: i32, c: i32) -> f64 {
        let f = |n: i32| (1..=n).map(f64::from).product::<f64>();
        f(a) * f(b) * f(c) * 2.0 / f(a + b + c + 2)
    }

    #[test]
    fn triangle_rules_are_exact_to_their_degree() {
        for order in [1, 2, 4, 5] {
            let q = Quadrature::simplex::<2>(order).unwrap();
            assert_eq!(q.degree(), order);
            for a in 0..=order as i32 {
                for b in 0..=order as i32 - a {
                    let c = order as i32 - a - b;
                    let num: f64 = q.iter().map(|(p, w)| w * p[0].powi(a) * p[1].powi(b) * p[2].powi(c)).sum();
                    assert!((num - exact_tri(a, b, c)).abs() < 1e-14, "order {order}: {a} {b} {c}");
                }
            }
        }
    }

    #[test]
    fn tetrahedron_rule_of_degree_two_is_exact() {
        let q = Quadrature::simplex::<3>(2).unwrap();
        // ∫ λ0² = 2!·3!/5! = 1/10 and ∫ λ0λ1 = 3!/5! = 1/20 (relative to |K|).
        let sq: f64 = q.iter().map(|(p, w)| w * p[0] * p[0]).sum();
        let mixed: f64 = q.iter().map(|(p, w)| w * p[0] * p[1]).sum();
        assert!((sq - 0.1).abs() < 1e-15 && (mixed - 0.05).abs() < 1e-15);
        assert!(Quadrature::simplex::<3>(4).is_err());
    }
}
