//! The distribution of one quantity over rocks, in fixed bins: memory is the same for ten rocks or ten million.

use crate::hazard::LogBins;

/// Bins of a [`Dist`]: logarithmic (energies, heights, speeds, sizes) or linear (angles).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bins {
    /// Logarithmic bins (see [`LogBins`]).
    Log(LogBins),
    /// `n` linear bins of `width` from 0, plus an overflow bin.
    Linear {
        /// Bin width.
        width: f64,
        /// Regular bins.
        n: usize,
    },
}

impl Bins {
    fn len(&self) -> usize {
        match self {
            Bins::Log(b) => b.len(),
            Bins::Linear { n, .. } => n + 1,
        }
    }

    fn bin(&self, v: f64) -> usize {
        match self {
            Bins::Log(b) => b.bin(v),
            Bins::Linear { width, n } => {
                if v.is_nan() || v <= 0.0 {
                    0
                } else {
                    ((v / width).floor() as usize).min(*n)
                }
            }
        }
    }
}

/// Counts of one quantity in fixed bins, with the exact maximum.
#[derive(Debug, Clone, PartialEq)]
pub struct Dist {
    bins: Bins,
    counts: Vec<u32>,
    /// Values added.
    pub total: u32,
    /// Largest value added (`NaN` when empty).
    pub max: f64,
}

impl Dist {
    /// An empty distribution over `bins`.
    pub fn new(bins: Bins) -> Self {
        Dist { bins, counts: vec![0; bins.len()], total: 0, max: f64::NAN }
    }

    /// Adds a value (NaN is ignored).
    pub fn add(&mut self, v: f64) {
        if v.is_nan() {
            return;
        }
        self.counts[self.bins.bin(v)] += 1;
        self.total += 1;
        if self.max.is_nan() || v > self.max {
            self.max = v;
        }
    }

    /// Adds all of `other` (same bins).
    pub fn merge(&mut self, other: &Dist) {
        debug_assert_eq!(self.bins, other.bins);
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
        self.total += other.total;
        if !other.max.is_nan() && (self.max.is_nan() || other.max > self.max) {
            self.max = other.max;
        }
    }

    /// The `q`-quantile (0..1), exact to within one bin and never above the maximum; `NaN` when empty.
    pub fn quantile(&self, q: f64) -> f64 {
        if self.total == 0 {
            return f64::NAN;
        }
        match self.bins {
            Bins::Log(b) => b.quantile(&self.counts, self.total, q, self.max),
            Bins::Linear { width, n } => {
                let rank = q * self.total as f64;
                let mut below = 0.0;
                for (k, &c) in self.counts.iter().enumerate() {
                    let c = c as f64;
                    if c > 0.0 && below + c >= rank {
                        if k == n {
                            return self.max;
                        }
                        let frac = ((rank - below) / c).clamp(0.0, 1.0);
                        return ((k as f64 + frac) * width).min(self.max);
                    }
                    below += c;
                }
                self.max
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_and_log_quantiles_and_merge() {
        let mut a = Dist::new(Bins::Linear { width: 0.5, n: 180 });
        let mut b = a.clone();
        for i in 0..50 {
            a.add(i as f64);
        }
        for i in 50..100 {
            b.add(i as f64 * 0.9);
        }
        a.merge(&b);
        assert_eq!(a.total, 100);
        assert!((a.max - 89.1).abs() < 1e-12);
        // 47 of 0..50 and 3 of 45, 45.9, … lie below 47.
        assert!((a.quantile(0.5) - 47.0).abs() <= 0.5, "{}", a.quantile(0.5));
        assert_eq!(a.quantile(1.0), a.max);
        let mut l = Dist::new(Bins::Log(LogBins::new(1.0, 1e9, 50)));
        for i in 1..=1000 {
            l.add(i as f64 * 100.0);
        }
        let p95 = l.quantile(0.95);
        assert!((p95 / 95_000.0 - 1.0).abs() < 0.05, "{p95}");
        assert!(Dist::new(Bins::Linear { width: 1.0, n: 2 }).quantile(0.5).is_nan());
    }
}
