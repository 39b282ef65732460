//! Seeded random streams and the distributions parameters are drawn from.
//!
//! Every rock (or run, or repeat) gets its own stream from `(seed, index)`, so results do not depend on the order
//! in which threads pick rocks up. ChaCha8 is a named, portable algorithm: the same seed gives the same numbers on
//! every machine and every future version of `rand_chacha` 0.10.

use crate::error::{Error, Result};
use rand::{RngExt, SeedableRng};
pub use rand_chacha::ChaCha8Rng as Rng;

/// The random stream of item `index` (a rock, a run) under the global `seed`.
pub fn stream(seed: u64, index: u64) -> Rng {
    let mut rng = Rng::seed_from_u64(seed);
    rng.set_stream(index);
    rng
}

/// A uniform draw in [0, 1).
pub fn uniform(rng: &mut Rng) -> f64 {
    rng.random::<f64>()
}

/// A uniform draw in [lo, hi]; returns `lo` when `hi <= lo`.
pub fn uniform_in(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    if hi <= lo {
        lo
    } else {
        lo + (hi - lo) * uniform(rng)
    }
}

/// A standard normal draw (Box–Muller; one of the pair is discarded to keep streams simple).
pub fn standard_normal(rng: &mut Rng) -> f64 {
    let u1 = 1.0 - uniform(rng); // (0, 1]
    let u2 = uniform(rng);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A normal distribution truncated to [min, max], as rockfall codes give their parameters (RocFall truncates at
/// ±3σ by default, physics.md §3).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TruncNormal {
    /// Mean.
    pub mean: f64,
    /// Standard deviation (0 for a fixed value).
    #[serde(default)]
    pub sd: f64,
    /// Lower bound of the draws.
    pub min: f64,
    /// Upper bound of the draws.
    pub max: f64,
}

impl TruncNormal {
    /// A fixed value.
    pub fn fixed(value: f64) -> Self {
        TruncNormal { mean: value, sd: 0.0, min: value, max: value }
    }

    /// Mean ± sd, truncated at ±3 sd and to [lo, hi].
    pub fn three_sigma(mean: f64, sd: f64, lo: f64, hi: f64) -> Self {
        TruncNormal { mean, sd, min: (mean - 3.0 * sd).max(lo), max: (mean + 3.0 * sd).min(hi) }
    }

    /// Draws a value by rejection (falls back to clamping after 64 rejections, which only happens when the window
    /// lies far in a tail).
    pub fn sample(&self, rng: &mut Rng) -> f64 {
        if self.sd <= 0.0 || self.max <= self.min {
            return self.mean.clamp(self.min, self.max.max(self.min));
        }
        for _ in 0..64 {
            let v = self.mean + self.sd * standard_normal(rng);
            if v >= self.min && v <= self.max {
                return v;
            }
        }
        self.mean.clamp(self.min, self.max)
    }

    /// Checks that the distribution is finite, ordered, and inside [lo, hi]; `field` names it in errors.
    pub fn validate(&self, field: &str, lo: f64, hi: f64) -> Result<()> {
        let all = [self.mean, self.sd, self.min, self.max];
        if all.iter().any(|v| !v.is_finite()) {
            return Err(Error::invalid(field, "has a value that is not a finite number", "give plain numbers"));
        }
        if self.sd < 0.0 {
            return Err(Error::invalid(field, format!("standard deviation {} is negative", self.sd), "use sd >= 0"));
        }
        if self.mean < lo || self.mean > hi {
            return Err(Error::invalid(
                field,
                format!("mean {} is outside the allowed range [{lo}, {hi}]", self.mean),
                format!("give a mean between {lo} and {hi}"),
            ));
        }
        if self.min > self.mean || self.max < self.mean || self.min < lo || self.max > hi {
            return Err(Error::invalid(
                field,
                format!(
                    "bounds [{}, {}] must contain the mean {} and lie within [{lo}, {hi}]",
                    self.min, self.max, self.mean
                ),
                "fix min and max, or leave them out to truncate at 3 standard deviations",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<f64> = (0..4).map(|_| uniform(&mut stream(7, 3))).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(uniform(&mut stream(7, 3)), uniform(&mut stream(7, 4)));
    }

    #[test]
    fn truncated_normal_stays_in_bounds_with_right_moments() {
        let d = TruncNormal::three_sigma(0.155, 0.060, 0.0, 1.0);
        let mut rng = stream(1, 0);
        let xs: Vec<f64> = (0..20000).map(|_| d.sample(&mut rng)).collect();
        assert!(xs.iter().all(|&x| x >= d.min && x <= d.max));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((mean - 0.155).abs() < 0.003, "{mean}");
    }
}
