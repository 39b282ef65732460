//! "Nice" axis ticks (1-2-5 steps) and compact number formatting, shared by maps and charts.

/// The smallest step of the form {1, 2, 5} × 10^k that cuts `span` into at most `max_intervals` intervals.
///
/// Returns 1 for a span that is zero, negative or not finite.
pub fn nice_step(span: f64, max_intervals: usize) -> f64 {
    let (mult, exp) = nice_step_parts(span, max_intervals);
    scaled(mult, exp)
}

/// [`nice_step`] as `(multiplier in {1, 2, 5}, power of ten)`.
fn nice_step_parts(span: f64, max_intervals: usize) -> (i64, i32) {
    if !(span.is_finite() && span > 0.0) {
        return (1, 0);
    }
    let raw = span / max_intervals.max(1) as f64;
    let exp = raw.log10().floor() as i32;
    let norm = raw / 10f64.powi(exp);
    if norm <= 1.0 + 1e-9 {
        (1, exp)
    } else if norm <= 2.0 + 1e-9 {
        (2, exp)
    } else if norm <= 5.0 + 1e-9 {
        (5, exp)
    } else {
        (1, exp + 1)
    }
}

/// `n × 10^exp`, rounded once (dividing by a power of ten for negative exponents keeps 0.6 as 0.6).
fn scaled(n: i64, exp: i32) -> f64 {
    if exp >= 0 {
        n as f64 * 10f64.powi(exp)
    } else {
        n as f64 / 10f64.powi(-exp)
    }
}

/// Multiples of a [`nice_step`] inside `[lo, hi]` (ends included within rounding), at most `max_intervals + 1`
/// of them. Values are computed as `k * step`, so they print cleanly; `-0` is returned as `0`.
pub fn nice_ticks(lo: f64, hi: f64, max_intervals: usize) -> Vec<f64> {
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
    if !(lo.is_finite() && hi.is_finite()) {
        return Vec::new();
    }
    if hi == lo {
        return vec![lo];
    }
    let (mult, exp) = nice_step_parts(hi - lo, max_intervals);
    let step = scaled(mult, exp);
    let eps = 1e-9 * (hi - lo).max(step);
    let first = ((lo - eps) / step).ceil() as i64;
    let last = ((hi + eps) / step).floor() as i64;
    (first..=last).map(|k| if k == 0 { 0.0 } else { scaled(k * mult, exp) }).collect()
}

/// Ticks for a logarithmic axis over `[lo, hi]` (both > 0): the powers of ten inside, plus 2× and 5× when fewer
/// than three decades are spanned. Empty if `lo <= 0`.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
    if !(lo > 0.0 && hi.is_finite()) {
        return Vec::new();
    }
    let k0 = lo.log10().floor() as i32;
    let k1 = hi.log10().ceil() as i32;
    let mults: &[i64] = if k1 - k0 <= 3 { &[1, 2, 5] } else { &[1] };
    let mut out = Vec::new();
    for k in k0..=k1 {
        for &m in mults {
            let v = scaled(m, k);
            if v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9) {
                out.push(v);
            }
        }
    }
    out
}

/// The largest length of the form {1, 2, 5} × 10^k that is at most `max` (for scale bars). 0 if `max <= 0`.
pub fn nice_length(max: f64) -> f64 {
    if !(max.is_finite() && max > 0.0) {
        return 0.0;
    }
    let mag = 10f64.powf(max.log10().floor());
    let norm = max / mag;
    let mult = if norm >= 5.0 - 1e-9 {
        5.0
    } else if norm >= 2.0 - 1e-9 {
        2.0
    } else {
        1.0
    };
    mult * mag
}

/// A tick value printed with just enough decimals for `step` (0.2 → one decimal, 0.05 → two, 10 → none).
pub fn format_tick(value: f64, step: f64) -> String {
    let decimals = if step >= 1.0 || !(step.is_finite() && step > 0.0) {
        0
    } else {
        ((-step.log10()) - 1e-9).ceil().clamp(0.0, 12.0) as usize
    };
    clean_zero(format!("{value:.decimals$}"))
}

/// A value with about three significant digits, for colour bar ends and labels: `0.0123`, `12.3`, `1234`,
/// `1.23e7`. Trailing zeros after the decimal point are dropped.
pub fn format_value(value: f64) -> String {
    if value == 0.0 {
        return "0".into();
    }
    if !value.is_finite() {
        return format!("{value}");
    }
    let a = value.abs();
    if !(1e-3..1e7).contains(&a) {
        return format!("{value:.2e}");
    }
    let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
    let mut s = format!("{value:.decimals$}");
    if s.contains('.') {
        s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    }
    clean_zero(s)
}

/// `-0`, `-0.0` and so on become `0`, `0.0`.
fn clean_zero(s: String) -> String {
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_125(step: f64) -> bool {
        let norm = step / 10f64.powf(step.log10().floor());
        [1.0, 2.0, 5.0].iter().any(|m| (norm - m).abs() < 1e-9)
    }

    #[test]
    fn nice_ticks_use_1_2_5_steps() {
        assert_eq!(nice_ticks(0.0, 1.0, 5), vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0]);
        assert_eq!(nice_ticks(0.0, 97.0, 5), vec![0.0, 20.0, 40.0, 60.0, 80.0]);
        assert_eq!(nice_ticks(-3.2, 7.9, 6), vec![-2.0, 0.0, 2.0, 4.0, 6.0]);
        for (lo, hi, n) in [(0.0, 1.0, 5), (3.7, 1234.5, 6), (-0.013, 0.021, 4), (1e5, 1.3e5, 5), (0.5, 0.51, 8)] {
            let t = nice_ticks(lo, hi, n);
            assert!(t.len() >= 2 && t.len() <= n + 1, "{lo}..{hi}: {t:?}");
            let step = t[1] - t[0];
            assert!(is_125(step), "{lo}..{hi}: step {step}");
            assert!(t.iter().all(|&v| v >= lo - 1e-9 && v <= hi + 1e-9));
        }
        assert_eq!(nice_ticks(2.0, 2.0, 5), vec![2.0]);
    }

    #[test]
    fn steps_lengths_and_formats() {
        assert_eq!(nice_step(10.0, 5), 2.0);
        assert_eq!(nice_step(0.7, 7), 0.1);
        assert_eq!(nice_length(340.0), 200.0);
        assert_eq!(nice_length(99.0), 50.0);
        assert_eq!(nice_length(1000.0), 1000.0);
        assert_eq!(log_ticks(1.0, 1000.0), vec![1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0]);
        assert_eq!(log_ticks(0.5, 1e5), vec![1.0, 10.0, 100.0, 1000.0, 10000.0, 100000.0]);
        assert_eq!(format_tick(0.6000000000000001, 0.2), "0.6");
        assert_eq!(format_tick(-0.0001, 0.05), "0.00");
        assert_eq!(format_tick(2600200.0, 200.0), "2600200");
        assert_eq!(format_value(0.012345), "0.0123");
        assert_eq!(format_value(12.345), "12.3");
        assert_eq!(format_value(1234.6), "1235");
        assert_eq!(format_value(3.0), "3");
        assert_eq!(format_value(-1.5), "-1.5");
        assert_eq!(format_value(1.234e8), "1.23e8");
    }
}
