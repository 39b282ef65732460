//! Energy classes and costs of barriers.

use super::settings::DesignSpec;

/// The index of the smallest class of `classes_kj` that takes `energy_kj`, `None` above the largest.
pub fn class_for(energy_kj: f64, classes_kj: &[f64]) -> Option<usize> {
    if !energy_kj.is_finite() {
        return None;
    }
    classes_kj.iter().position(|&c| energy_kj <= c)
}

/// The class as written in tables: `1,000 kJ`, or `above 4,500 kJ`.
pub fn class_label(class: Option<usize>, spec: &DesignSpec) -> String {
    match class {
        Some(k) => format!("{} kJ", thousands(spec.classes_kj[k])),
        None => format!("above {} kJ", thousands(spec.classes_kj.last().copied().unwrap_or(0.0))),
    }
}

/// `4500` as `4,500`.
pub fn thousands(v: f64) -> String {
    let n = v.round() as i64;
    let digits = n.unsigned_abs().to_string();
    let mut out = String::from(if n < 0 { "-" } else { "" });
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// Cost of `length_m` of barrier of class `class` (`None` above the largest class).
pub fn cost(length_m: f64, class: Option<usize>, spec: &DesignSpec) -> Option<f64> {
    class.map(|k| length_m * spec.class_cost_per_m[k])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_labels_and_costs() {
        let s = DesignSpec::default();
        assert_eq!(class_for(99.0, &s.classes_kj), Some(0));
        assert_eq!(class_for(100.0, &s.classes_kj), Some(0));
        assert_eq!(class_for(101.0, &s.classes_kj), Some(1));
        assert_eq!(class_for(4600.0, &s.classes_kj), None);
        assert_eq!(class_label(Some(3), &s), "1,000 kJ");
        assert_eq!(class_label(None, &s), "above 4,500 kJ");
        assert_eq!(thousands(1234567.0), "1,234,567");
        assert_eq!(thousands(-4500.0), "-4,500");
        assert_eq!(cost(10.0, Some(1), &s), Some(16.0));
    }
}
