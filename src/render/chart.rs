//! SVG charts written as text: lines, markers, steps and grouped bars, with "nice" ticks, grid lines, a legend,
//! error bars and labelled reference lines. Output is SVG 1.1 with a `viewBox`, so it scales in browsers and
//! reports.

use super::colormap::CATEGORICAL;
use super::ticks::{format_tick, nice_ticks};
use crate::error::{Error, Result};
use crate::io::write_bytes_atomic;
use std::fmt::Write as _;
use std::path::Path;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesStyle {
    /// Straight segments through the points (broken at non-finite points).
    Line,
    /// A marker at each point.
    Markers,
    /// Both.
    LineMarkers,
    /// A staircase: the value of point i holds from its x to the next point's x (histograms).
    Step,
    /// Bars from zero, grouped side by side with the chart's other bar series (x is the category index).
    Bars,
}

/// One data series.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend name.
    pub name: String,
    /// Points (x, y).
    pub points: Vec<(f64, f64)>,
    /// Drawing style.
    pub style: SeriesStyle,
    /// Colour.
    pub colour: [u8; 3],
    /// Per point: (low, high) of a vertical error bar, same length as `points`.
    pub error_bars: Option<Vec<(f64, f64)>>,
}

impl Series {
    /// A series without error bars.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>, style: SeriesStyle, colour: [u8; 3]) -> Self {
        Series { name: name.into(), points, style, colour, error_bars: None }
    }
}

/// A chart: axes, series and reference lines.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chart {
    /// Title above the plot.
    pub title: String,
    /// x-axis label, with unit.
    pub x_label: String,
    /// y-axis label, with unit.
    pub y_label: String,
    /// x range; `None` fits the data and reference lines.
    pub x_range: Option<(f64, f64)>,
    /// y range; `None` fits the data, error bars and reference lines (from 0 for bars and steps).
    pub y_range: Option<(f64, f64)>,
    /// The data.
    pub series: Vec<Series>,
    /// Vertical reference lines at x, with labels (e.g. the Modified Ritchie width).
    pub vlines: Vec<(f64, String)>,
    /// Horizontal reference lines at y, with labels.
    pub hlines: Vec<(f64, String)>,
    /// Category names for bar charts: x = i is labelled `x_categories[i]` instead of a number.
    pub x_categories: Option<Vec<String>>,
}

/// Chart size in SVG user units (pixels at 100 %).
const W: f64 = 860.0;
const H: f64 = 540.0;
const LEFT: f64 = 84.0;
const RIGHT: f64 = 28.0;
const TOP: f64 = 52.0;
const BOTTOM: f64 = 70.0;
const FONT: &str = "Helvetica, Arial, sans-serif";

/// Escapes `&`, `<`, `>`, `"` and `'` for XML text and attributes.
pub fn escape_xml(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Writes `chart` as SVG to `path`, atomically, after [`validate`].
pub fn write_svg(path: &Path, chart: &Chart) -> Result<()> {
    validate(chart)?;
    write_bytes_atomic(path, to_svg(chart).as_bytes())
}

/// Axis range from data bounds: widened when degenerate, padded by `pad` (fraction) on the sides not pinned.
fn fit_range(lo: f64, hi: f64, pad: f64, pin_zero: bool) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let (mut lo, mut hi) = (lo, hi);
    if pin_zero {
        lo = lo.min(0.0);
        hi = hi.max(0.0);
    }
    if hi <= lo {
        let d = (lo.abs() * 0.1).max(1.0);
        return (lo - d, hi + d);
    }
    let span = hi - lo;
    let lo = if pin_zero && lo == 0.0 { 0.0 } else { lo - pad * span };
    let hi = if pin_zero && hi == 0.0 { 0.0 } else { hi + pad * span };
    (lo, hi)
}

fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)))
}

/// The chart as an SVG 1.1 document. The legend goes in the corner of the plot where it hides nothing (data,
/// error bars, reference labels); when every corner would hide something, it goes in a row above the plot.
pub fn to_svg(chart: &Chart) -> String {
    match render(chart, None) {
        (svg, 0) => svg,
        _ => {
            let rows = legend_rows(chart).len() as f64;
            render(chart, Some(rows)).0
        }
    }
}

/// Legend entries laid out in rows that fit the plot width: per row, (series index, x offset).
fn legend_rows(chart: &Chart) -> Vec<Vec<(usize, f64)>> {
    let avail = W - RIGHT - LEFT;
    let mut rows: Vec<Vec<(usize, f64)>> = Vec::new();
    let mut x = 0.0;
    for (i, se) in chart.series.iter().enumerate().filter(|(_, se)| !se.name.is_empty()) {
        let w = legend_entry_width(&se.name);
        if rows.is_empty() || x + w > avail {
            rows.push(Vec::new());
            x = 0.0;
        }
        rows.last_mut().unwrap().push((i, x));
        x += w + 12.0;
    }
    rows
}

/// Approximate width of a legend entry: swatch, gap, text at 13 px (about 7.2 units per character).
fn legend_entry_width(name: &str) -> f64 {
    44.0 + name.chars().count() as f64 * 7.2
}

/// Draws a legend swatch for `se` between x0 and x1 on the line cy, and its name after it.
fn legend_entry(s: &mut String, se: &Series, x0: f64, cy: f64) {
    let x1 = x0 + 26.0;
    let col = hex(se.colour);
    match se.style {
        SeriesStyle::Bars => {
            let _ =
                writeln!(s, r#"<rect x="{:.2}" y="{:.2}" width="18" height="12" fill="{col}"/>"#, x0 + 4.0, cy - 6.0);
        }
        SeriesStyle::Markers => {
            let _ = writeln!(s, r#"<circle cx="{:.2}" cy="{cy:.2}" r="4" fill="{col}"/>"#, (x0 + x1) / 2.0);
        }
        _ => {
            let _ = writeln!(
                s,
                r#"<line x1="{x0:.2}" y1="{cy:.2}" x2="{x1:.2}" y2="{cy:.2}" stroke="{col}" stroke-width="2.5"/>"#
            );
            if se.style == SeriesStyle::LineMarkers {
                let _ = writeln!(s, r#"<circle cx="{:.2}" cy="{cy:.2}" r="4" fill="{col}"/>"#, (x0 + x1) / 2.0);
            }
        }
    }
    let _ = writeln!(
        s,
        r##"<text x="{:.2}" y="{:.2}" fill="#222222">{}</text>"##,
        x1 + 8.0,
        cy + 4.5,
        escape_xml(&se.name)
    );
}

/// Renders the chart with the legend inside the plot (`legend_rows_on_top` = `None`) or in that many rows above
/// it. Returns the SVG and, for an inside legend, how many drawn things it hides.
fn render(chart: &Chart, legend_rows_on_top: Option<f64>) -> (String, usize) {
    let top = TOP + legend_rows_on_top.map(|r| r * 20.0 + 8.0).unwrap_or(0.0);
    let (px0, px1, py0, py1) = (LEFT, W - RIGHT, top, H - BOTTOM);
    // Things drawn in the plot, as boxes (x0, y0, x1, y1), that the legend should not hide.
    let mut ink: Vec<(f64, f64, f64, f64)> = Vec::new();
    let n_bar_series = chart.series.iter().filter(|s| s.style == SeriesStyle::Bars).count();
    let bar_group_w = 0.8;

    // Ranges.
    let (xr0, xr1) = match (chart.x_range, &chart.x_categories) {
        (Some(r), _) => r,
        (None, Some(cats)) => (-0.5, cats.len().max(1) as f64 - 0.5),
        (None, None) => {
            let (lo, hi) = bounds(
                chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.0)).chain(chart.vlines.iter().map(|v| v.0)),
            );
            let markers = chart
                .series
                .iter()
                .any(|s| matches!(s.style, SeriesStyle::Markers | SeriesStyle::LineMarkers) || s.error_bars.is_some());
            fit_range(lo, hi, if markers { 0.04 } else { 0.0 }, false)
        }
    };
    let (yr0, yr1) = match chart.y_range {
        Some(r) => r,
        None => {
            let err = chart.series.iter().flat_map(|s| s.error_bars.iter().flatten().flat_map(|e| [e.0, e.1]));
            let (lo, hi) = bounds(
                chart
                    .series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|p| p.1))
                    .chain(err)
                    .chain(chart.hlines.iter().map(|h| h.0)),
            );
            let pin = chart.series.iter().any(|s| matches!(s.style, SeriesStyle::Bars | SeriesStyle::Step));
            fit_range(lo, hi, 0.06, pin)
        }
    };
    let sx = |x: f64| px0 + (x - xr0) / (xr1 - xr0) * (px1 - px0);
    let sy = |y: f64| py1 - (y - yr0) / (yr1 - yr0) * (py1 - py0);
    let bar_x = |series_index: usize, x: f64| -> (f64, f64) {
        let k = chart.series[..series_index].iter().filter(|s| s.style == SeriesStyle::Bars).count();
        let w = bar_group_w / n_bar_series.max(1) as f64;
        let left = x - bar_group_w / 2.0 + k as f64 * w;
        (sx(left), sx(left + w))
    };
    // x of a point as drawn (bar centres are offset within their group).
    let draw_x = |i: usize, x: f64| -> f64 {
        if chart.series[i].style == SeriesStyle::Bars {
            let (a, b) = bar_x(i, x);
            (a + b) / 2.0
        } else {
            sx(x)
        }
    };

    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="{FONT}" font-size="13">"#
    );
    let _ = writeln!(s, "<title>{}</title>", escape_xml(&chart.title));
    let _ = writeln!(s, r#"<rect x="0" y="0" width="{W}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<defs><clipPath id="plot-area"><rect x="{px0}" y="{py0}" width="{:.2}" height="{:.2}"/></clipPath></defs>"#,
        px1 - px0,
        py1 - py0
    );

    // Grid and ticks.
    let _ = writeln!(s, r##"<g stroke="#e3e3e3" stroke-width="1">"##);
    let x_ticks: Vec<(f64, String)> = match &chart.x_categories {
        Some(cats) => cats.iter().enumerate().map(|(i, c)| (i as f64, c.clone())).collect(),
        None => {
            let t = nice_ticks(xr0, xr1, 10);
            let step = if t.len() > 1 { t[1] - t[0] } else { 1.0 };
            t.into_iter().map(|v| (v, format_tick(v, step))).collect()
        }
    };
    let y_ticks: Vec<(f64, String)> = {
        let t = nice_ticks(yr0, yr1, 8);
        let step = if t.len() > 1 { t[1] - t[0] } else { 1.0 };
        t.into_iter().map(|v| (v, format_tick(v, step))).collect()
    };
    if chart.x_categories.is_none() {
        for (v, _) in &x_ticks {
            let _ = writeln!(s, r#"<line x1="{0:.2}" y1="{py0}" x2="{0:.2}" y2="{py1}"/>"#, sx(*v));
        }
    }
    for (v, _) in &y_ticks {
        let _ = writeln!(s, r#"<line x1="{px0}" y1="{0:.2}" x2="{px1}" y2="{0:.2}"/>"#, sy(*v));
    }
    let _ = writeln!(s, "</g>");
    let _ = writeln!(
        s,
        r##"<rect x="{px0}" y="{py0}" width="{:.2}" height="{:.2}" fill="none" stroke="#444444" stroke-width="1"/>"##,
        px1 - px0,
        py1 - py0
    );
    let _ = writeln!(s, r##"<g fill="#333333" font-size="12">"##);
    for (v, label) in &x_ticks {
        let x = sx(*v);
        let _ = writeln!(s, r##"<line x1="{x:.2}" y1="{py1}" x2="{x:.2}" y2="{:.2}" stroke="#444444"/>"##, py1 + 5.0);
        let _ =
            writeln!(s, r#"<text x="{x:.2}" y="{:.2}" text-anchor="middle">{}</text>"#, py1 + 20.0, escape_xml(label));
    }
    for (v, label) in &y_ticks {
        let y = sy(*v);
        let _ = writeln!(s, r##"<line x1="{:.2}" y1="{y:.2}" x2="{px0}" y2="{y:.2}" stroke="#444444"/>"##, px0 - 5.0);
        let _ = writeln!(
            s,
            r#"<text x="{:.2}" y="{:.2}" text-anchor="end">{}</text>"#,
            px0 - 9.0,
            y + 4.0,
            escape_xml(label)
        );
    }
    let _ = writeln!(s, "</g>");

    // Title and axis labels.
    let _ = writeln!(
        s,
        r##"<text x="{:.2}" y="30" text-anchor="middle" font-size="18" font-weight="bold" fill="#222222">{}</text>"##,
        (px0 + px1) / 2.0,
        escape_xml(&chart.title)
    );
    let _ = writeln!(
        s,
        r##"<text x="{:.2}" y="{:.2}" text-anchor="middle" font-size="14" fill="#222222">{}</text>"##,
        (px0 + px1) / 2.0,
        H - 22.0,
        escape_xml(&chart.x_label)
    );
    let _ = writeln!(
        s,
        r##"<text transform="translate(22 {:.2}) rotate(-90)" text-anchor="middle" font-size="14" fill="#222222">{}</text>"##,
        (py0 + py1) / 2.0,
        escape_xml(&chart.y_label)
    );

    // Series, clipped to the plot area.
    let _ = writeln!(s, r#"<g clip-path="url(#plot-area)">"#);
    for (i, se) in chart.series.iter().enumerate() {
        let col = hex(se.colour);
        let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
        match se.style {
            SeriesStyle::Bars => {
                for p in se.points.iter().filter(finite) {
                    let (a, b) = bar_x(i, p.0);
                    let (ya, yb) = (sy(p.1.max(0.0)), sy(p.1.min(0.0)));
                    ink.push((a, ya, b, yb));
                    let _ = writeln!(
                        s,
                        r#"<rect x="{a:.2}" y="{ya:.2}" width="{:.2}" height="{:.2}" fill="{col}" fill-opacity="0.9"/>"#,
                        (b - a - 1.0).max(0.5),
                        (yb - ya).max(0.0)
                    );
                }
            }
            SeriesStyle::Step => {
                let pts: Vec<&(f64, f64)> = se.points.iter().filter(finite).collect();
                if let Some(first) = pts.first() {
                    let mut d = format!("M{:.2} {:.2}", sx(first.0), sy(first.1));
                    for w in pts.windows(2) {
                        let _ = write!(d, " H{:.2} V{:.2}", sx(w[1].0), sy(w[1].1));
                        ink.push((sx(w[0].0), sy(w[0].1) - 1.0, sx(w[1].0), sy(w[0].1) + 1.0));
                        let (ya, yb) = (sy(w[0].1).min(sy(w[1].1)), sy(w[0].1).max(sy(w[1].1)));
                        ink.push((sx(w[1].0) - 1.0, ya, sx(w[1].0) + 1.0, yb));
                    }
                    let _ = writeln!(
                        s,
                        r#"<path d="{d}" fill="none" stroke="{col}" stroke-width="2" stroke-linejoin="miter"/>"#
                    );
                }
            }
            SeriesStyle::Line | SeriesStyle::LineMarkers | SeriesStyle::Markers => {}
        }
        if matches!(se.style, SeriesStyle::Line | SeriesStyle::LineMarkers) {
            for run in se.points.split(|p| !(p.0.is_finite() && p.1.is_finite())) {
                if run.len() < 2 {
                    continue;
                }
                let pts: Vec<String> = run.iter().map(|p| format!("{:.2},{:.2}", sx(p.0), sy(p.1))).collect();
                for w in run.windows(2) {
                    for k in 0..=16 {
                        let f = k as f64 / 16.0;
                        let (x, y) = (sx(w[0].0 + f * (w[1].0 - w[0].0)), sy(w[0].1 + f * (w[1].1 - w[0].1)));
                        ink.push((x - 1.0, y - 1.0, x + 1.0, y + 1.0));
                    }
                }
                let _ = writeln!(
                    s,
                    r#"<polyline points="{}" fill="none" stroke="{col}" stroke-width="2" stroke-linejoin="round"/>"#,
                    pts.join(" ")
                );
            }
        }
        if let Some(errs) = &se.error_bars {
            for (p, e) in se.points.iter().zip(errs) {
                if !(p.0.is_finite() && e.0.is_finite() && e.1.is_finite()) {
                    continue;
                }
                let x = draw_x(i, p.0);
                let (ylo, yhi) = (sy(e.0), sy(e.1));
                ink.push((x - 4.0, ylo.min(yhi), x + 4.0, ylo.max(yhi)));
                let _ = writeln!(
                    s,
                    r##"<path d="M{x:.2} {ylo:.2} V{yhi:.2} M{:.2} {ylo:.2} H{:.2} M{:.2} {yhi:.2} H{:.2}" fill="none" stroke="{}" stroke-width="1.5"/>"##,
                    x - 4.0,
                    x + 4.0,
                    x - 4.0,
                    x + 4.0,
                    if se.style == SeriesStyle::Bars { "#222222".to_string() } else { col.clone() }
                );
            }
        }
        if matches!(se.style, SeriesStyle::Markers | SeriesStyle::LineMarkers) {
            for p in se.points.iter().filter(finite) {
                ink.push((sx(p.0) - 4.0, sy(p.1) - 4.0, sx(p.0) + 4.0, sy(p.1) + 4.0));
                let _ = writeln!(
                    s,
                    r#"<circle cx="{:.2}" cy="{:.2}" r="4" fill="{col}" stroke="white" stroke-width="1"/>"#,
                    sx(p.0),
                    sy(p.1)
                );
            }
        }
    }
    let _ = writeln!(s, "</g>");

    // Reference lines with labels (text drawn twice: a white halo, then ink).
    let mut label = |s: &mut String, x: f64, y: f64, anchor: &str, text: &str| {
        let w = text.chars().count() as f64 * 7.2;
        let x0 = if anchor == "end" { x - w } else { x };
        ink.push((x0, y - 12.0, x0 + w, y + 3.0));
        let t = escape_xml(text);
        let _ = writeln!(
            s,
            r#"<text x="{x:.2}" y="{y:.2}" text-anchor="{anchor}" stroke="white" stroke-width="4" stroke-linejoin="round" fill="white">{t}</text>"#
        );
        let _ = writeln!(s, r##"<text x="{x:.2}" y="{y:.2}" text-anchor="{anchor}" fill="#222222">{t}</text>"##);
    };
    for (k, (v, text)) in chart.vlines.iter().enumerate() {
        if !(v.is_finite() && *v >= xr0 && *v <= xr1) {
            continue;
        }
        let x = sx(*v);
        let _ = writeln!(
            s,
            r##"<line x1="{x:.2}" y1="{py0}" x2="{x:.2}" y2="{py1}" stroke="#555555" stroke-width="1.5" stroke-dasharray="6 4"/>"##
        );
        let y = py0 + 16.0 + 16.0 * k as f64;
        let right_side = x + 8.0 + text.chars().count() as f64 * 7.2 <= px1;
        if right_side {
            label(&mut s, x + 5.0, y, "start", text);
        } else {
            label(&mut s, x - 5.0, y, "end", text);
        }
    }
    for (v, text) in &chart.hlines {
        if !(v.is_finite() && *v >= yr0 && *v <= yr1) {
            continue;
        }
        let y = sy(*v);
        let _ = writeln!(
            s,
            r##"<line x1="{px0}" y1="{y:.2}" x2="{px1}" y2="{y:.2}" stroke="#555555" stroke-width="1.5" stroke-dasharray="6 4"/>"##
        );
        let ty = if y - 6.0 > py0 + 12.0 { y - 6.0 } else { y + 16.0 };
        label(&mut s, px0 + 6.0, ty, "start", text);
    }

    // Legend: in the corner that hides the fewest things, or in rows above the plot.
    let named: Vec<&Series> = chart.series.iter().filter(|se| !se.name.is_empty()).collect();
    let mut hidden_count = 0;
    if legend_rows_on_top.is_some() {
        for (r, row) in legend_rows(chart).iter().enumerate() {
            let cy = TOP + 4.0 + 20.0 * r as f64;
            for &(i, dx) in row {
                legend_entry(&mut s, &chart.series[i], px0 + dx, cy);
            }
        }
    } else if !named.is_empty() {
        let row_h = 20.0;
        let lw = named.iter().map(|se| legend_entry_width(&se.name)).fold(0.0, f64::max) + 20.0;
        let lh = named.len() as f64 * row_h + 10.0;
        let corners = [
            (px1 - lw - 10.0, py0 + 10.0),
            (px0 + 10.0, py0 + 10.0),
            (px1 - lw - 10.0, py1 - lh - 10.0),
            (px0 + 10.0, py1 - lh - 10.0),
        ];
        let hidden = |(lx, ly): (f64, f64)| -> usize {
            ink.iter().filter(|b| b.0 <= lx + lw && b.2 >= lx && b.1 <= ly + lh && b.3 >= ly).count()
        };
        let (lx, ly) = corners.iter().copied().min_by_key(|c| hidden(*c)).unwrap_or(corners[0]);
        hidden_count = hidden((lx, ly));
        let _ = writeln!(
            s,
            r##"<g><rect x="{lx:.2}" y="{ly:.2}" width="{lw:.2}" height="{lh:.2}" fill="white" fill-opacity="0.9" stroke="#999999"/>"##
        );
        for (k, se) in named.iter().enumerate() {
            legend_entry(&mut s, se, lx + 10.0, ly + 5.0 + row_h * (k as f64 + 0.5));
        }
        let _ = writeln!(s, "</g>");
    }
    let _ = writeln!(s, "</svg>");
    (s, hidden_count)
}

/// Overlaid step histograms of several samples (e.g. observed vs simulated run-out) on common bins spanning all
/// finite samples. Heights are fractions of each series' own sample count, so samples of different sizes compare;
/// legend names carry the count `n`.
pub fn histogram_chart(title: &str, x_label: &str, samples_by_series: &[(&str, &[f64])], bins: usize) -> Chart {
    let bins = bins.max(1);
    let (mut lo, mut hi) = bounds(samples_by_series.iter().flat_map(|(_, v)| v.iter().copied()));
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (0.0, 1.0);
    } else if hi <= lo {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let width = (hi - lo) / bins as f64;
    let edge = |i: usize| if i == bins { hi } else { lo + i as f64 * width };
    let series = samples_by_series
        .iter()
        .enumerate()
        .map(|(k, (name, values))| {
            let mut counts = vec![0usize; bins];
            let mut n = 0usize;
            for &v in values.iter().filter(|v| v.is_finite()) {
                counts[(((v - lo) / width) as usize).min(bins - 1)] += 1;
                n += 1;
            }
            let frac = |c: usize| if n > 0 { c as f64 / n as f64 } else { 0.0 };
            let mut points = vec![(lo, 0.0)];
            points.extend(counts.iter().enumerate().map(|(i, &c)| (edge(i), frac(c))));
            points.push((hi, 0.0));
            Series::new(format!("{name} (n={n})"), points, SeriesStyle::Step, CATEGORICAL[k % CATEGORICAL.len()])
        })
        .collect();
    Chart {
        title: title.into(),
        x_label: x_label.into(),
        y_label: "fraction of samples per bin".into(),
        x_range: Some((lo, hi)),
        series,
        ..Default::default()
    }
}

/// A grouped bar chart: one group per category, one bar per series (e.g. captured fraction per bench for several
/// models). `series` pairs a name with one value per category (`NaN` leaves a gap). Set `y_label` on the result.
pub fn bar_chart(title: &str, categories: &[&str], series: &[(&str, &[f64])]) -> Chart {
    Chart {
        title: title.into(),
        x_categories: Some(categories.iter().map(|c| c.to_string()).collect()),
        series: series
            .iter()
            .enumerate()
            .map(|(k, (name, values))| {
                let points = values.iter().take(categories.len()).enumerate().map(|(i, &v)| (i as f64, v)).collect();
                Series::new(*name, points, SeriesStyle::Bars, CATEGORICAL[k % CATEGORICAL.len()])
            })
            .collect(),
        ..Default::default()
    }
}

/// Checks that a chart is drawable: error bars must pair up with points.
pub fn validate(chart: &Chart) -> Result<()> {
    for se in &chart.series {
        if let Some(e) = &se.error_bars {
            if e.len() != se.points.len() {
                return Err(Error::invalid(
                    format!("chart series {:?}: error_bars", se.name),
                    format!("{} error bars for {} points", e.len(), se.points.len()),
                    "give one (low, high) pair per point",
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal XML well-formedness check: tags balance, attributes are quoted, entities are known.
    fn check_xml(s: &str) -> std::result::Result<(), String> {
        let mut stack: Vec<String> = Vec::new();
        let mut rest = s;
        let mut root_seen = false;
        while let Some(i) = rest.find('<') {
            check_text(&rest[..i])?;
            rest = &rest[i..];
            let end = rest.find('>').ok_or("unterminated tag")?;
            let tag = &rest[1..end];
            rest = &rest[end + 1..];
            if tag.starts_with('?') || tag.starts_with("!--") {
                continue;
            }
            if let Some(name) = tag.strip_prefix('/') {
                let open = stack.pop().ok_or(format!("closing </{name}> without opening"))?;
                if open != name.trim() {
                    return Err(format!("<{open}> closed by </{name}>"));
                }
                continue;
            }
            let self_closing = tag.ends_with('/');
            let body = tag.trim_end_matches('/');
            let name = body.split_whitespace().next().ok_or("empty tag")?.to_string();
            if !body.matches('"').count().is_multiple_of(2) {
                return Err(format!("unbalanced quotes in <{name}>"));
            }
            check_text(body)?;
            if stack.is_empty() {
                if root_seen {
                    return Err("two root elements".into());
                }
                root_seen = true;
            }
            if !self_closing {
                stack.push(name);
            }
        }
        check_text(rest)?;
        if stack.is_empty() && root_seen {
            Ok(())
        } else {
            Err(format!("unclosed: {stack:?}"))
        }
    }

    fn check_text(t: &str) -> std::result::Result<(), String> {
        for (i, _) in t.match_indices('&') {
            let ent = &t[i..t[i..].find(';').map(|j| i + j + 1).ok_or("bare &")?];
            if !["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"].contains(&ent) {
                return Err(format!("unknown entity {ent}"));
            }
        }
        if t.contains('<') {
            Err("stray <".into())
        } else {
            Ok(())
        }
    }

    #[test]
    fn xml_checker_catches_errors() {
        assert!(check_xml("<a><b/></a>").is_ok());
        assert!(check_xml("<a><b></a>").is_err());
        assert!(check_xml("<a x=\"1></a>").is_err());
        assert!(check_xml("<a>&</a>").is_err());
        assert!(check_xml("<a/><b/>").is_err());
    }

    #[test]
    fn chart_svg_is_well_formed_and_labelled() {
        let mut obs = Series::new(
            "observed <bench 1>",
            vec![(1.0, 2.0), (2.0, 3.5), (3.0, 2.5)],
            SeriesStyle::LineMarkers,
            CATEGORICAL[0],
        );
        obs.error_bars = Some(vec![(1.5, 2.5), (3.0, 4.0), (2.0, 3.0)]);
        let sim = Series::new(
            "simulated & co",
            vec![(0.5, 1.0), (f64::NAN, 0.0), (3.5, 3.0)],
            SeriesStyle::Line,
            CATEGORICAL[1],
        );
        let chart = Chart {
            title: "Lateral spread".into(),
            x_label: "distance (m)".into(),
            y_label: "rocks".into(),
            series: vec![obs, sim],
            vlines: vec![(2.2, "Modified Ritchie width".into())],
            hlines: vec![(3.0, "limit".into())],
            ..Default::default()
        };
        validate(&chart).unwrap();
        let svg = to_svg(&chart);
        check_xml(&svg).unwrap();
        assert!(svg.contains("viewBox=\"0 0 860 540\""));
        assert!(svg.contains("observed &lt;bench 1&gt;"));
        assert!(svg.contains("simulated &amp; co"));
        assert!(svg.contains("Modified Ritchie width"));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.svg");
        write_svg(&path, &chart).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), svg);
    }

    #[test]
    fn histograms_and_bars() {
        let observed = [1.0, 2.0, 2.5, 3.0, 3.2, 8.0];
        let simulated: Vec<f64> = (0..100).map(|i| i as f64 * 0.09).collect();
        let h = histogram_chart("Run-out", "run-out (m)", &[("observed", &observed), ("simulated", &simulated)], 9);
        assert_eq!(h.series.len(), 2);
        assert_eq!(h.series[0].name, "observed (n=6)");
        // Fractions of each series sum to one.
        for se in &h.series {
            let sum: f64 = se.points[1..se.points.len() - 1].iter().map(|p| p.1).sum();
            assert!((sum - 1.0).abs() < 1e-12, "{}: {sum}", se.name);
        }
        check_xml(&to_svg(&h)).unwrap();

        let mut b =
            bar_chart("Captured", &["bench A", "bench B"], &[("3DRB", &[0.9, 0.7]), ("2DLM", &[0.8, f64::NAN])]);
        b.y_label = "captured fraction".into();
        let svg = to_svg(&b);
        check_xml(&svg).unwrap();
        assert!(svg.contains("bench B") && svg.contains("2DLM"));
        assert_eq!(svg.matches("<rect").count(), 2 + 3 + 1 + 2 + 1); // background, clip, frame, bars, legend
    }
}
