//! Fixed logarithmic bins, so that per-cell percentiles cost bounded memory whatever the number of rocks.

/// Log-spaced bins over [min, max] with `per_decade` bins per factor of ten, plus an underflow bin (values at or
/// below `min`, including zero) and an overflow bin. A percentile read back is exact to within one bin: its
/// relative error is below 10^(1/per_decade) − 1 (12 % for 20 bins a decade), and it is interpolated
/// geometrically inside the bin and clamped to the exact maximum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogBins {
    /// Lower edge of the first regular bin.
    pub min: f64,
    /// Bins per decade.
    pub per_decade: usize,
    /// Regular bins.
    pub n: usize,
}

impl LogBins {
    /// Bins over [min, max] with `per_decade` bins per decade.
    pub fn new(min: f64, max: f64, per_decade: usize) -> Self {
        let n = ((max / min).log10() * per_decade as f64).ceil() as usize;
        LogBins { min, per_decade, n }
    }

    /// Number of counters (regular bins plus underflow and overflow).
    pub fn len(&self) -> usize {
        self.n + 2
    }

    /// Always false: there are at least the two open bins.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The counter a value falls in.
    pub fn bin(&self, v: f64) -> usize {
        if v.is_nan() || v <= self.min {
            return 0;
        }
        let k = ((v / self.min).log10() * self.per_decade as f64).floor() as usize;
        (k + 1).min(self.n + 1)
    }

    /// Lower and upper edges of counter `k`.
    fn edges(&self, k: usize) -> (f64, f64) {
        let e = |i: usize| self.min * 10f64.powf(i as f64 / self.per_decade as f64);
        match k {
            0 => (0.0, self.min),
            k if k > self.n => (e(self.n), f64::INFINITY),
            k => (e(k - 1), e(k)),
        }
    }

    /// The `q`-quantile (0..1) of the values counted in `counts` (total `total`), clamped to `max_value`.
    pub fn quantile(&self, counts: &[u32], total: u32, q: f64, max_value: f64) -> f64 {
        if total == 0 {
            return f64::NAN;
        }
        let rank = q * total as f64;
        let mut below = 0.0;
        for (k, &c) in counts.iter().enumerate() {
            let c = c as f64;
            if c > 0.0 && below + c >= rank {
                let (lo, hi) = self.edges(k);
                let frac = ((rank - below) / c).clamp(0.0, 1.0);
                let v = if k == 0 {
                    lo + frac * (hi - lo)
                } else if hi.is_infinite() {
                    max_value
                } else {
                    lo * (hi / lo).powf(frac)
                };
                return v.min(max_value);
            }
            below += c;
        }
        max_value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_are_within_one_bin() {
        let b = LogBins::new(1e-3, 1e5, 20);
        let values: Vec<f64> = (1..=1000).map(|i| i as f64 * 0.37).collect();
        let mut counts = vec![0u32; b.len()];
        for &v in &values {
            counts[b.bin(v)] += 1;
        }
        let max = 370.0;
        for q in [0.5, 0.9, 0.95, 0.99] {
            let exact = values[(q * 1000.0) as usize - 1];
            let got = b.quantile(&counts, 1000, q, max);
            assert!((got / exact - 1.0).abs() < 0.13, "q={q}: {got} vs {exact}");
        }
        assert_eq!(b.quantile(&counts, 1000, 1.0, max), max);
        assert_eq!(b.bin(0.0), 0);
        assert_eq!(b.bin(1e9), b.n + 1);
    }
}
