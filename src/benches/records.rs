//! Historic rock-fall records and the observed first-bench capture curve.
//!
//! # File format
//! ```text
//! bench_height_m,bench_width_m,face_angle_deg,runout_m
//! 20,7.5,62,3.2
//! 20,8,70,11.0
//! ```
//! One event per row: the height and face angle of the bench face the rock fell from, the width of the catch bench
//! below it, and the event's maximum horizontal run-out in m, **measured from the toe of that face** (so that it
//! compares with a catch-bench width). Columns may come in any order, extra columns are ignored, lines starting
//! with `#` are comments.
//!
//! # The observed curve (our definition)
//! A record counts as captured by a first bench of width W when its run-out is at most W (`runout_m <= W`): the
//! observed capture at W is the fraction of the selected records with `runout_m <= W`, i.e. the empirical
//! distribution of the run-out beyond the toe, with a Wilson 95 % interval. Records are selected by bench height
//! (within `bench_height_tolerance_m` of the study's) and, for a per-angle curve, by face angle (within
//! `face_angle_tolerance_deg`). This uses every record at every width, whatever bench it actually fell on; a
//! record's own `bench_width_m` only says whether its own bench caught it, which is reported separately.

use super::stats::{wilson_interval, Z_95};
use crate::error::{Error, Result};
use crate::io::csv_text::Table;
use serde::Serialize;
use std::path::Path;

/// One historic event.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HistoricRecord {
    /// Height of the face the rock fell from, m.
    pub bench_height_m: f64,
    /// Width of the catch bench below it, m.
    pub bench_width_m: f64,
    /// Face angle, degrees.
    pub face_angle_deg: f64,
    /// Maximum horizontal run-out from the toe of the face, m.
    pub runout_m: f64,
}

impl HistoricRecord {
    /// Whether its own catch bench caught it (`runout_m <= bench_width_m`).
    pub fn caught_by_own_bench(&self) -> bool {
        self.runout_m <= self.bench_width_m
    }
}

/// The observed capture at one bench width.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ObservedPoint {
    /// Bench width W, m.
    pub bench_width_m: f64,
    /// Records selected.
    pub records: usize,
    /// Of them, records with run-out at most W.
    pub captured: usize,
    /// `captured / records`.
    pub captured_fraction: f64,
    /// Wilson 95 % interval, low end.
    pub ci_low: f64,
    /// Wilson 95 % interval, high end.
    pub ci_high: f64,
}

const COLUMNS: [&str; 4] = ["bench_height_m", "bench_width_m", "face_angle_deg", "runout_m"];

/// Reads a records CSV (see the module docs).
///
/// # Errors
/// I/O errors; a missing column (naming it); a value that is not a finite number, a negative width or run-out,
/// a height that is not positive or an angle outside (0, 90] (naming the file, line and column); no records.
pub fn read_records(path: &Path) -> Result<Vec<HistoricRecord>> {
    let t = Table::read(path, true)?;
    let hint = format!("start the file with the header {}", COLUMNS.join(","));
    let mut idx = [0; 4];
    for (k, name) in COLUMNS.iter().enumerate() {
        idx[k] = t.need(name, &hint)?;
    }
    let mut out = Vec::new();
    for row in &t.rows {
        let mut v = [0.0; 4];
        for (k, name) in COLUMNS.iter().enumerate() {
            v[k] = t.number(row, idx[k], name)?;
        }
        let [h, w, a, r] = v;
        let bad = |name: &str, what: &str| t.error(row, format!("{name} must be {what}"), "fix the value");
        if h <= 0.0 {
            return Err(bad("bench_height_m", "positive"));
        }
        if w < 0.0 {
            return Err(bad("bench_width_m", "0 or more"));
        }
        if !(a > 0.0 && a <= 90.0) {
            return Err(bad("face_angle_deg", "in (0, 90] degrees"));
        }
        if r < 0.0 {
            return Err(bad("runout_m", "0 or more (measured from the toe of the face)"));
        }
        out.push(HistoricRecord { bench_height_m: h, bench_width_m: w, face_angle_deg: a, runout_m: r });
    }
    if out.is_empty() {
        return Err(Error::format(t.source, "holds no records", "add one row per historic event"));
    }
    Ok(out)
}

/// The records whose bench height is within `height_tolerance_m` of `bench_height_m` and, when `face_angle` is
/// `Some((angle, tolerance))`, whose face angle is within the tolerance of the angle.
pub fn select(
    records: &[HistoricRecord],
    bench_height_m: f64,
    height_tolerance_m: f64,
    face_angle: Option<(f64, f64)>,
) -> Vec<HistoricRecord> {
    records
        .iter()
        .filter(|r| (r.bench_height_m - bench_height_m).abs() <= height_tolerance_m)
        .filter(|r| face_angle.is_none_or(|(a, tol)| (r.face_angle_deg - a).abs() <= tol))
        .copied()
        .collect()
}

/// The observed first-bench capture at each of `widths_m` (see the module docs); empty when no record is given.
pub fn observed_capture(records: &[HistoricRecord], widths_m: &[f64]) -> Vec<ObservedPoint> {
    if records.is_empty() {
        return Vec::new();
    }
    widths_m
        .iter()
        .map(|&w| {
            let n = records.len();
            let k = records.iter().filter(|r| r.runout_m <= w).count();
            let (lo, hi) = wilson_interval(k, n, Z_95).unwrap_or((0.0, 1.0));
            ObservedPoint {
                bench_width_m: w,
                records: n,
                captured: k,
                captured_fraction: k as f64 / n as f64,
                ci_low: lo,
                ci_high: hi,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_selects_and_counts() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.csv");
        std::fs::write(
            &path,
            "# synthetic\nface_angle_deg,bench_height_m,runout_m,bench_width_m,note\n60,20,3,7,a\n62,20,9,8,b\n75,30,2,7,c\n",
        )
        .unwrap();
        let r = read_records(&path).unwrap();
        assert_eq!(r.len(), 3);
        assert!(r[0].caught_by_own_bench() && !r[1].caught_by_own_bench());
        let sel = select(&r, 20.0, 5.0, Some((60.0, 7.5)));
        assert_eq!(sel.len(), 2);
        let obs = observed_capture(&sel, &[4.0, 10.0]);
        assert_eq!((obs[0].captured, obs[1].captured), (1, 2));
        std::fs::write(&path, "bench_height_m,bench_width_m,face_angle_deg\n20,7,60\n").unwrap();
        assert!(read_records(&path).unwrap_err().to_string().contains("no column `runout_m`"));
        std::fs::write(&path, "bench_height_m,bench_width_m,face_angle_deg,runout_m\n20,7,60,-1\n").unwrap();
        let e = read_records(&path).unwrap_err().to_string();
        assert!(e.contains("r.csv:2") && e.contains("runout_m"), "{e}");
    }
}
