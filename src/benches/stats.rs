//! Small statistics for capture fractions: Wilson score intervals, the spread of repeated runs, and linear
//! interpolation between bench widths.

/// z of a two-sided 95 % normal interval.
pub const Z_95: f64 = 1.959_963_984_540_054;

/// The Wilson score interval of a binomial proportion: `k` successes in `n` trials, at normal quantile `z`
/// (Wilson 1927). Unlike the normal ("Wald") interval it stays inside [0, 1] and is not empty at k = 0 or k = n,
/// which matters for capture fractions near 0 or 100 % (physics.md §7 asks for it). `None` when `n` is 0.
///
/// # Examples
/// ```
/// use talus::benches::{wilson_interval, Z_95};
/// let (lo, hi) = wilson_interval(5, 10, Z_95).unwrap();
/// assert!((lo - 0.2366).abs() < 1e-4 && (hi - 0.7634).abs() < 1e-4);
/// ```
pub fn wilson_interval(k: usize, n: usize, z: f64) -> Option<(f64, f64)> {
    if n == 0 {
        return None;
    }
    let n_f = n as f64;
    let p = k.min(n) as f64 / n_f;
    let z2 = z * z;
    let denom = 1.0 + z2 / n_f;
    let centre = (p + z2 / (2.0 * n_f)) / denom;
    let half = z / denom * (p * (1.0 - p) / n_f + z2 / (4.0 * n_f * n_f)).sqrt();
    // At k = 0 and k = n the bound is exactly 0 or 1; clamping removes rounding.
    let lo = if k == 0 { 0.0 } else { (centre - half).max(0.0) };
    let hi = if k >= n { 1.0 } else { (centre + half).min(1.0) };
    Some((lo, hi))
}

/// Mean, sample standard deviation (n − 1; 0 for one value), minimum and maximum.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub sd: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

impl Spread {
    /// The spread of `values`; `None` when empty.
    pub fn of(values: &[f64]) -> Option<Spread> {
        if values.is_empty() {
            return None;
        }
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let sd = if values.len() > 1 {
            (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
        } else {
            0.0
        };
        let min = values.iter().copied().fold(f64::INFINITY, f64::min);
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Some(Spread { mean, sd, min, max })
    }
}

/// The value at `x` of the piecewise-linear curve through `points` (sorted by x, finite), with the two x it was
/// interpolated between (equal when `x` is one of them). `None` outside the curve's x range.
pub fn interpolate(points: &[(f64, f64)], x: f64) -> Option<(f64, [f64; 2])> {
    if let Some(p) = points.iter().find(|p| p.0 == x) {
        return Some((p.1, [x, x]));
    }
    let w = points.windows(2).find(|w| w[0].0 < x && x < w[1].0)?;
    let f = (x - w[0].0) / (w[1].0 - w[0].0);
    Some((w[0].1 + f * (w[1].1 - w[0].1), [w[0].0, w[1].0]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_and_spread() {
        let pts = [(4.0, 0.2), (8.0, 0.6), (9.0, 0.8)];
        let (v, at) = interpolate(&pts, 8.5).unwrap();
        assert!((v - 0.7).abs() < 1e-12);
        assert_eq!(at, [8.0, 9.0]);
        assert_eq!(interpolate(&pts, 8.0), Some((0.6, [8.0, 8.0])));
        assert_eq!(interpolate(&pts, 9.5), None);
        let s = Spread::of(&[1.0, 2.0, 3.0]).unwrap();
        assert_eq!((s.mean, s.sd, s.min, s.max), (2.0, 1.0, 1.0, 3.0));
        assert_eq!(Spread::of(&[0.5]).unwrap().sd, 0.0);
    }
}
