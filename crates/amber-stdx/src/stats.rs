//! Order statistics of a sample: the linearly interpolated quantile and the median.
//!
//! One definition serves the results tables (`ndcd_quantiles`), the mesh quality reports, the
//! size clip of the training loop and the benchmarks' medians.

/// The `q` quantile (0 ≤ q ≤ 1) of `sorted` (ascending), linearly interpolated between the two
/// nearest order statistics (the "type 7" of R and NumPy's default): with x = q·(n − 1),
/// s⌊x⌋ + frac(x)·(s⌊x⌋₊₁ − s⌊x⌋). NaN for no values.
///
/// ```
/// assert_eq!(amber_stdx::quantile(&[1.0, 2.0, 4.0], 0.75), 3.0);
/// assert!(amber_stdx::quantile(&[], 0.5).is_nan());
/// ```
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        n => {
            let x = q * (n - 1) as f64;
            let (i, frac) = (x.floor() as usize, x.fract());
            sorted[i] + frac * (sorted[(i + 1).min(n - 1)] - sorted[i])
        }
    }
}

/// The median of `values` (in any order): the middle value, or the mean of the two middle
/// ones for an even count; NaN for no values.
///
/// ```
/// assert_eq!(amber_stdx::median(&[3.0, 1.0, 2.0]), 2.0);
/// assert_eq!(amber_stdx::median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
/// ```
pub fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    quantile(&sorted, 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_interpolate_between_order_statistics() {
        let s = [0.1, 0.2, 0.3, 0.4, 0.5];
        assert_eq!(quantile(&s, 0.0), 0.1);
        assert_eq!(quantile(&s, 1.0), 0.5);
        assert_eq!(quantile(&s, 0.5), 0.3);
        assert!((quantile(&s, 0.25) - 0.2).abs() < 1e-15);
        assert!((quantile(&s, 0.1) - 0.14).abs() < 1e-15);
        assert_eq!(quantile(&[7.0], 0.3), 7.0);
        // Equal neighbours give exactly their value, whatever the fraction.
        assert_eq!(quantile(&[0.1, 0.1, 0.1], 0.37), 0.1);
    }

    #[test]
    fn medians_of_odd_even_and_empty_samples() {
        assert_eq!(median(&[5.0]), 5.0);
        assert_eq!(median(&[2.0, 1.0]), 1.5);
        assert!(median(&[]).is_nan());
    }
}
