//! The study's pictures, as SVG charts ([`crate::render::chart`]):
//! - per-bench capture, 2DLM beside 3DRB, one chart per face angle and bench width (the seed paper's Figure 6);
//! - first-bench capture against bench width, per face angle and for all angles together, with the Modified
//!   Ritchie width, the retention target and, when given, the historic records (the paper's Figure 7).
//!
//! Capture is shown in per cent with Wilson 95 % intervals as error bars.

use super::records::ObservedPoint;
use super::runner::{Model, StudyResult};
use super::stats::{wilson_interval, Z_95};
use crate::error::Result;
use crate::render::colormap::CATEGORICAL;
use crate::render::{bar_chart, write_svg, Chart, Series, SeriesStyle};
use std::path::Path;

/// A number as short text: `9`, `8.5`.
pub fn short(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Colour of a model in single-angle charts.
fn model_colour(model: Model) -> [u8; 3] {
    match model {
        Model::Lumped2d => CATEGORICAL[0],
        Model::Rigid3d => CATEGORICAL[1],
    }
}

/// Colour of the historic records.
const RECORDS_COLOUR: [u8; 3] = [40, 40, 40];

/// Per cent with a Wilson interval of `k` of `n`, or NaN when `n` is 0.
fn percent(k: usize, n: usize) -> (f64, (f64, f64)) {
    match wilson_interval(k, n, Z_95) {
        Some((lo, hi)) => (100.0 * k as f64 / n as f64, (100.0 * lo, 100.0 * hi)),
        None => (f64::NAN, (f64::NAN, f64::NAN)),
    }
}

/// Writes `per_bench/figure6_{angle}deg_{width}m.svg` for every configuration; returns the paths written,
/// relative to `out_dir`.
pub fn write_per_bench(result: &StudyResult, out_dir: &Path) -> Result<Vec<String>> {
    let dir = out_dir.join("per_bench");
    crate::io::create_folder(&dir)?;
    let n = result.config.n_benches;
    let mut categories: Vec<String> = (1..=n).map(|k| format!("bench {k}")).collect();
    categories.push(format!("past bench {n}"));
    let cats: Vec<&str> = categories.iter().map(String::as_str).collect();
    let mut written = Vec::new();
    for (c, conf) in result.configurations.iter().enumerate() {
        let mut names = Vec::new();
        let mut values = Vec::new();
        let mut errors = Vec::new();
        for model in result.models() {
            let (per_bench, total) = result.pooled(model, c);
            // Benches 1..=n, then "past" (index 0).
            let order: Vec<usize> = (1..=n).chain(std::iter::once(0)).collect();
            let (v, e): (Vec<f64>, Vec<(f64, f64)>) = order.iter().map(|&k| percent(per_bench[k], total)).unzip();
            names.push(format!("{} ({} rocks)", model.label(), total));
            values.push(v);
            errors.push((model, e));
        }
        let series: Vec<(&str, &[f64])> =
            names.iter().map(String::as_str).zip(values.iter().map(Vec::as_slice)).collect();
        let mut chart = bar_chart(
            &format!(
                "Rocks captured per bench: {}° faces, {} m benches, {} m high",
                short(conf.face_angle_deg),
                short(conf.bench_width_m),
                short(result.config.bench_height_m)
            ),
            &cats,
            &series,
        );
        for (se, (model, e)) in chart.series.iter_mut().zip(errors) {
            se.colour = model_colour(model);
            se.error_bars = Some(e);
        }
        chart.y_label = "rocks captured (%), Wilson 95 % interval".into();
        chart.x_label = "where rocks stop (bench 1 is the first below the release)".into();
        chart.y_range = Some((0.0, 104.0));
        let name = format!("per_bench/figure6_{}deg_{}m.svg", short(conf.face_angle_deg), short(conf.bench_width_m));
        write_svg(&out_dir.join(&name), &chart)?;
        written.push(name);
    }
    Ok(written)
}

/// Points (x, y) of a series and their error bars (low, high).
type PointsWithErrors = (Vec<(f64, f64)>, Vec<(f64, f64)>);

/// First-bench capture of `model` at face angle `angle`, as (width, per cent) points with Wilson intervals.
fn first_bench_series(result: &StudyResult, model: Model, angle: f64) -> PointsWithErrors {
    let mut points = Vec::new();
    let mut errors = Vec::new();
    for (c, conf) in result.configurations.iter().enumerate().filter(|(_, c)| c.face_angle_deg == angle) {
        let (per_bench, total) = result.pooled(model, c);
        let (v, e) = percent(per_bench[1], total);
        points.push((conf.bench_width_m, v));
        errors.push(e);
    }
    (points, errors)
}

fn records_series(name: String, observed: &[ObservedPoint]) -> Series {
    let mut s = Series::new(
        name,
        observed.iter().map(|p| (p.bench_width_m, 100.0 * p.captured_fraction)).collect(),
        SeriesStyle::LineMarkers,
        RECORDS_COLOUR,
    );
    s.error_bars = Some(observed.iter().map(|p| (100.0 * p.ci_low, 100.0 * p.ci_high)).collect());
    s
}

/// The reference lines of Figure 7: the Modified Ritchie width and the retention target.
fn reference_lines(result: &StudyResult, chart: &mut Chart) {
    let mr = result.config.modified_ritchie_width_m();
    chart.vlines.push((mr, format!("Modified Ritchie width {} m", short(mr))));
    let target = 100.0 * result.config.retention_target;
    chart.hlines.push((target, format!("{} % retention target", short(target))));
    let widths = result.configurations.iter().map(|c| c.bench_width_m);
    let (lo, hi) = widths.chain([mr]).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), w| (a.min(w), b.max(w)));
    let pad = ((hi - lo) * 0.04).max(0.25);
    chart.x_range = Some((lo - pad, hi + pad));
    // A little room below 0 and above 100 % so that curves at 0 or 100 % are not hidden by the frame.
    chart.y_range = Some((-3.0, 104.0));
    chart.x_label = "catch-bench width (m)".into();
    chart.y_label = "rocks captured on the first bench (%)".into();
}

/// Writes `figure7_first_bench_{angle}deg.svg` per face angle and `figure7_first_bench.svg` for all angles;
/// `observed(angle)` gives the records curve for one angle (`Some(angle)`) or all (`None`). Returns the paths
/// written, relative to `out_dir`.
pub fn write_first_bench(
    result: &StudyResult,
    observed: &dyn Fn(Option<f64>) -> Vec<ObservedPoint>,
    out_dir: &Path,
) -> Result<Vec<String>> {
    let mut written = Vec::new();
    let mut angles: Vec<f64> = result.configurations.iter().map(|c| c.face_angle_deg).collect();
    angles.dedup();
    let h = short(result.config.bench_height_m);
    for &angle in &angles {
        let mut chart = Chart {
            title: format!("First-bench capture: {}° faces, {h} m benches", short(angle)),
            ..Default::default()
        };
        for model in result.models() {
            let (points, errors) = first_bench_series(result, model, angle);
            let runs = result.runs(model) * result.config.repeats;
            let mut s = Series::new(
                format!("{} ({runs} rocks per width)", model.label()),
                points,
                SeriesStyle::LineMarkers,
                model_colour(model),
            );
            s.error_bars = Some(errors);
            chart.series.push(s);
        }
        let obs = observed(Some(angle));
        if let Some(p) = obs.first() {
            chart.series.push(records_series(format!("historic records (n={})", p.records), &obs));
        }
        reference_lines(result, &mut chart);
        let name = format!("figure7_first_bench_{}deg.svg", short(angle));
        write_svg(&out_dir.join(&name), &chart)?;
        written.push(name);
    }
    // All angles on one chart: one colour per face angle; 2DLM as plain lines, 3DRB as lines with markers.
    let mut chart = Chart {
        title: format!("First-bench capture, {h} m benches: 2DLM (lines) and 3DRB (dots)"),
        ..Default::default()
    };
    let palette = [0, 2, 1, 5, 3, 4];
    for model in result.models() {
        for (k, &angle) in angles.iter().enumerate() {
            let (points, _) = first_bench_series(result, model, angle);
            let style = if model == Model::Lumped2d { SeriesStyle::Line } else { SeriesStyle::LineMarkers };
            chart.series.push(Series::new(
                format!("{} {}°", model.label(), short(angle)),
                points,
                style,
                CATEGORICAL[palette[k % palette.len()]],
            ));
        }
    }
    let obs = observed(None);
    if let Some(p) = obs.first() {
        chart.series.push(records_series(format!("historic records, all angles (n={})", p.records), &obs));
    }
    reference_lines(result, &mut chart);
    let name = "figure7_first_bench.svg".to_string();
    write_svg(&out_dir.join(&name), &chart)?;
    written.push(name);
    Ok(written)
}
