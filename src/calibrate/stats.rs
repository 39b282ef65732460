//! Small statistics used by calibration: quantiles, the 1-Wasserstein distance between samples, rank
//! correlation, and permutation tests. All deterministic given the random stream passed in.

use crate::random::{uniform, Rng};

/// Mean of `v` (NaN when empty).
pub fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.iter().sum::<f64>() / v.len() as f64
}

/// The mean of the paired differences `a − b` and its standard error (sample sd over √n; 0 for fewer than 2 pairs):
/// how much worse `a` is than `b` over the same units (runs), and how sure that is.
pub fn paired_excess(a: &[f64], b: &[f64]) -> (f64, f64) {
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let se = if d.len() > 1 { sample_sd(&d) / (d.len() as f64).sqrt() } else { 0.0 };
    (mean(&d), se)
}

/// The standard normal quantile Φ⁻¹(p) for 0 < p < 1 (NaN outside), by Acklam's rational approximation
/// (relative error below 1.2·10⁻⁹; P. J. Acklam, "An algorithm for computing the inverse normal cumulative
/// distribution function", 2003).
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -39.69683028665376,
        220.9460984245205,
        -275.9285104469687,
        138.357751867269,
        -30.66479806614716,
        2.506628277459239,
    ];
    const B: [f64; 5] =
        [-54.47609879822406, 161.5858368580409, -155.6989798598866, 66.80131188771972, -13.28068155288572];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -0.3223964580411365,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [7.784695709041462e-3, 0.3224671290700398, 2.445134137142996, 3.754408661907416];
    if !(p > 0.0 && p < 1.0) {
        return f64::NAN;
    }
    let poly = |k: &[f64], x: f64| k.iter().fold(0.0, |acc, c| acc * x + c);
    // The tails in q = √(−2 ln p), the lower one; the upper by symmetry.
    let tail = |p: f64| {
        let q = (-2.0 * p.ln()).sqrt();
        poly(&C, q) / (poly(&D, q) * q + 1.0)
    };
    match p {
        _ if p < 0.02425 => tail(p),
        _ if p > 1.0 - 0.02425 => -tail(1.0 - p),
        _ => {
            let q = p - 0.5;
            let r = q * q;
            poly(&A, r) * q / (poly(&B, r) * r + 1.0)
        }
    }
}

/// Sample standard deviation (n − 1 in the denominator; 0 for fewer than 2 values).
pub fn sample_sd(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// `v` sorted ascending (NaNs last).
pub fn sorted(v: &[f64]) -> Vec<f64> {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    s
}

/// Quantile `p` ∈ [0, 1] of an ascending sample by linear interpolation between order statistics (Hyndman & Fan
/// type 7, the default of R and numpy). NaN when empty.
pub fn quantile_sorted(s: &[f64], p: f64) -> f64 {
    if s.is_empty() {
        return f64::NAN;
    }
    let h = (s.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(s.len() - 1);
    s[lo] + (h - lo as f64) * (s[hi] - s[lo])
}

/// Median (type 7).
pub fn median(v: &[f64]) -> f64 {
    quantile_sorted(&sorted(v), 0.5)
}

/// The 1-Wasserstein distance between the empirical distributions of `a` and `b`: ∫ |F_a(x) − F_b(x)| dx, exact
/// for samples of any sizes. NaN if either is empty.
pub fn wasserstein1(a: &[f64], b: &[f64]) -> f64 {
    if a.is_empty() || b.is_empty() {
        return f64::NAN;
    }
    let (sa, sb) = (sorted(a), sorted(b));
    let (na, nb) = (sa.len() as f64, sb.len() as f64);
    let (mut i, mut j) = (0usize, 0usize);
    let mut x_prev = sa[0].min(sb[0]);
    let mut total = 0.0;
    while i < sa.len() || j < sb.len() {
        let x = match (sa.get(i), sb.get(j)) {
            (Some(&u), Some(&v)) => u.min(v),
            (Some(&u), None) => u,
            (None, Some(&v)) => v,
            (None, None) => break,
        };
        total += (i as f64 / na - j as f64 / nb).abs() * (x - x_prev);
        while i < sa.len() && sa[i] <= x {
            i += 1;
        }
        while j < sb.len() && sb[j] <= x {
            j += 1;
        }
        x_prev = x;
    }
    total
}

/// Ranks 1..n with ties given their average rank.
pub fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut k = 0;
    while k < idx.len() {
        let mut e = k;
        while e + 1 < idx.len() && v[idx[e + 1]] == v[idx[k]] {
            e += 1;
        }
        let avg = (k + e) as f64 / 2.0 + 1.0;
        for &i in &idx[k..=e] {
            r[i] = avg;
        }
        k = e + 1;
    }
    r
}

/// Pearson correlation (0 when either variable is constant).
pub fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let (mx, my) = (mean(x), mean(y));
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx).powi(2);
        syy += (b - my).powi(2);
    }
    if sxx <= 0.0 || syy <= 0.0 {
        0.0
    } else {
        sxy / (sxx * syy).sqrt()
    }
}

/// Spearman's rank correlation ρ (Pearson correlation of the average ranks).
pub fn spearman(x: &[f64], y: &[f64]) -> f64 {
    pearson(&ranks(x), &ranks(y))
}

/// In-place Fisher–Yates shuffle.
pub fn shuffle<T>(v: &mut [T], rng: &mut Rng) {
    for i in (1..v.len()).rev() {
        let j = ((uniform(rng) * (i + 1) as f64) as usize).min(i);
        v.swap(i, j);
    }
}

/// Spearman's ρ of `x` and `y` with a two-sided permutation p-value: the share of `permutations` random
/// re-pairings whose |ρ| reaches the observed one, counting the observed pairing itself (p = (1 + k)/(1 + B),
/// never 0). Returns (ρ, p); (0, 1) when either variable is constant.
pub fn spearman_permutation(x: &[f64], y: &[f64], permutations: usize, rng: &mut Rng) -> (f64, f64) {
    let (rx, mut ry) = (ranks(x), ranks(y));
    let rho = pearson(&rx, &ry);
    if rho == 0.0 || x.len() < 3 {
        return (rho, 1.0);
    }
    let mut hits = 0usize;
    for _ in 0..permutations {
        shuffle(&mut ry, rng);
        if pearson(&rx, &ry).abs() >= rho.abs() - 1e-12 {
            hits += 1;
        }
    }
    (rho, (1 + hits) as f64 / (1 + permutations) as f64)
}

/// One-sided paired sign-flip permutation test of H1: mean(d) > 0, where `d` are paired differences (e.g. baseline
/// error − new error per run). p = (1 + k)/(1 + B) with k the random sign flips whose mean reaches the observed.
pub fn paired_sign_flip_p(d: &[f64], permutations: usize, rng: &mut Rng) -> f64 {
    if d.is_empty() {
        return 1.0;
    }
    let observed = mean(d);
    let mut hits = 0usize;
    for _ in 0..permutations {
        let s: f64 = d.iter().map(|x| if uniform(rng) < 0.5 { -x } else { *x }).sum::<f64>() / d.len() as f64;
        if s >= observed - 1e-12 {
            hits += 1;
        }
    }
    (1 + hits) as f64 / (1 + permutations) as f64
}

/// Most units [`exact_sign_flip_p`] takes (2^20 patterns).
pub const MAX_EXACT_SIGN_FLIP_UNITS: usize = 20;

/// Exact one-sided sign-flip test of H1: sum(d) > 0 over a few independent units (e.g. the inner folds of a
/// cross-validation, whose runs share the fold's refitted parameters and so are not independent of each other):
/// the share of all 2^k sign patterns whose sum reaches the observed one, counting the observed itself (so never
/// below 2^-k). 1 when `d` is empty; `d` holds at most [`MAX_EXACT_SIGN_FLIP_UNITS`] units.
pub fn exact_sign_flip_p(d: &[f64]) -> f64 {
    assert!(
        d.len() <= MAX_EXACT_SIGN_FLIP_UNITS,
        "an exact sign-flip test enumerates 2^k patterns; k = {} is too many",
        d.len()
    );
    let observed: f64 = d.iter().sum();
    let patterns = 1usize << d.len();
    let hits = (0..patterns)
        .filter(|bits| {
            let s: f64 = d.iter().enumerate().map(|(i, x)| if bits >> i & 1 == 1 { -x } else { *x }).sum();
            s >= observed - 1e-12
        })
        .count();
    hits as f64 / patterns as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::stream;

    #[test]
    fn the_normal_quantile_matches_the_tables() {
        // Φ⁻¹ at the table's probabilities (Abramowitz & Stegun, Table 26.5), in the middle and in both tails.
        for (p, z) in
            [(0.5, 0.0), (0.8, 0.841_621_234), (0.95, 1.644_853_627), (0.975, 1.959_963_985), (0.99, 2.326_347_874)]
        {
            assert!((normal_quantile(p) - z).abs() < 1e-8, "{p}: {}", normal_quantile(p));
            assert!((normal_quantile(1.0 - p) + z).abs() < 1e-8, "{p}");
        }
        assert!((normal_quantile(1e-6) + 4.753_424_309).abs() < 1e-7);
        assert!(normal_quantile(0.0).is_nan() && normal_quantile(1.0).is_nan() && normal_quantile(f64::NAN).is_nan());
    }

    #[test]
    fn quantiles_and_wasserstein_match_hand_values() {
        let s = sorted(&[3.0, 1.0, 2.0, 4.0]);
        assert_eq!(quantile_sorted(&s, 0.5), 2.5);
        assert_eq!(quantile_sorted(&s, 0.0), 1.0);
        assert!((quantile_sorted(&s, 0.05) - 1.15).abs() < 1e-12);
        // Shifted samples: W1 is the shift.
        assert!((wasserstein1(&[0.0, 1.0, 2.0], &[5.0, 6.0, 7.0]) - 5.0).abs() < 1e-12);
        // Different sizes: {0} vs {0, 2}: half the mass moves 2 m.
        assert!((wasserstein1(&[0.0], &[0.0, 2.0]) - 1.0).abs() < 1e-12);
        assert_eq!(wasserstein1(&[1.0, 2.0], &[2.0, 1.0]), 0.0);
    }

    #[test]
    fn ranks_average_ties_and_spearman_detects_monotone_links() {
        assert_eq!(ranks(&[10.0, 20.0, 10.0, 30.0]), vec![1.5, 3.0, 1.5, 4.0]);
        let x: Vec<f64> = (0..30).map(|i| i as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| v * v * v).collect();
        assert!((spearman(&x, &y) - 1.0).abs() < 1e-12);
        let mut rng = stream(3, 0);
        let (rho, p) = spearman_permutation(&x, &y, 199, &mut rng);
        assert!(rho > 0.99 && p <= 0.01, "{rho} {p}");
        let noise: Vec<f64> = (0..30).map(|_| uniform(&mut rng)).collect();
        let (_, p) = spearman_permutation(&x, &noise, 199, &mut rng);
        assert!(p > 0.01, "{p}");
    }

    #[test]
    fn sign_flip_test_separates_a_shift_from_noise() {
        let mut rng = stream(5, 0);
        let shifted: Vec<f64> = (0..30).map(|_| 1.0 + 0.5 * (uniform(&mut rng) - 0.5)).collect();
        assert!(paired_sign_flip_p(&shifted, 499, &mut rng) < 0.01);
        let centred: Vec<f64> = (0..30).map(|_| uniform(&mut rng) - 0.5).collect();
        let centred: Vec<f64> = centred.iter().map(|v| v - mean(&centred)).collect();
        assert!(paired_sign_flip_p(&centred, 499, &mut rng) > 0.2);
    }

    #[test]
    fn the_exact_sign_flip_test_counts_the_patterns_that_reach_the_observed_sum() {
        // Five units all better: only the observed pattern reaches its sum.
        assert_eq!(exact_sign_flip_p(&[1.0, 2.0, 0.5, 1.0, 3.0]), 1.0 / 32.0);
        // One worse unit: the patterns reaching 1 + 1 + 1 − 0.5 = 2.5 are it and the one that flips the −0.5 only.
        assert_eq!(exact_sign_flip_p(&[1.0, 1.0, 1.0, -0.5]), 2.0 / 16.0);
        // All worse: every pattern reaches the lowest sum.
        assert_eq!(exact_sign_flip_p(&[-1.0, -1.0]), 1.0);
        assert_eq!(exact_sign_flip_p(&[]), 1.0);
    }
}
