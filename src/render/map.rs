//! Maps: a raster layer coloured over a grey hillshade, with title, colour bar (or class legend), coordinate
//! ticks, scale bar and north arrow, written as PNG.
//!
//! # Geometry
//! The map covers the layer grid's extent, north up, with square map units: one output pixel is `1 /
//! pixels_per_m` metres in both directions. The scale is an integer number of pixels per layer cell when that
//! puts the long side between 700 and 1400 pixels (crisp cells), otherwise the long side is 1000 pixels. When a
//! pixel covers several cells (large grids), it shows the value of largest magnitude among them, so that narrow
//! rockfall paths and extreme residuals stay visible (ours: a conservative choice for hazard maps).
//!
//! # Colours
//! The hillshade (azimuth 315°, altitude 45°, Horn's 3×3 gradient) is computed on the terrain's own cells and
//! sampled at each output pixel by bilinear interpolation in map coordinates, so the terrain may have another cell
//! size and extent than the layer. Layer colours are blended over it at alpha 0.75 (opaque when there is no
//! terrain). Nodata cells, cells equal to 0 when [`MapLayer::transparent_zero`] is set, and cells ≤ 0 on a log
//! scale are left transparent, showing the hillshade.

use super::canvas::{opaque, with_alpha, Canvas, Rect, Rgba};
use super::colormap::{Class, Colormap};
use super::font::{draw_text, draw_text_halo, text_height, text_width};
use super::ticks::{format_tick, format_value, log_ticks, nice_length, nice_step, nice_ticks};
use crate::error::{Error, Result};
use crate::raster::Grid;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How values map to the colour ramp.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ValueScale {
    /// Linear between the range ends.
    #[default]
    Linear,
    /// Logarithmic between the range ends (both > 0); values ≤ 0 are transparent.
    Log,
}

/// The raster shown on a map and how to colour it.
#[derive(Debug, Clone)]
pub struct MapLayer<'a> {
    /// The values, north-up; `NaN` is nodata. Its extent is the map's extent.
    pub grid: &'a Grid,
    /// Title printed above the map.
    pub title: String,
    /// Unit printed above the colour bar, e.g. `"kJ"` or `"passages per cell"`.
    pub unit: String,
    /// Colour ramp for continuous values (ignored when `classes` is set).
    pub colormap: Colormap,
    /// Colour bar range `(min, max)`. `None`: the grid's valid min and max (log scale: the smallest positive value
    /// to the max; diverging ramp: symmetric about zero, ±max |value|). A constant layer of value v gets
    /// (v, v + max(|v|, 1)), or (v, 10 v) on a log scale; a layer without data (0, 1), or (1, 10).
    pub range: Option<(f32, f32)>,
    /// Linear or logarithmic colouring.
    pub scale: ValueScale,
    /// Classes instead of a ramp: a legend of coloured boxes replaces the colour bar.
    pub classes: Option<Vec<Class>>,
    /// Show cells whose value is exactly 0 as transparent (e.g. hazard rasters where no rock passed).
    pub transparent_zero: bool,
}

impl<'a> MapLayer<'a> {
    /// A layer with the default viridis ramp, automatic linear range, no classes, zeros coloured.
    pub fn new(grid: &'a Grid, title: impl Into<String>, unit: impl Into<String>) -> Self {
        MapLayer {
            grid,
            title: title.into(),
            unit: unit.into(),
            colormap: Colormap::Viridis,
            range: None,
            scale: ValueScale::Linear,
            classes: None,
            transparent_zero: false,
        }
    }
}

/// A line drawn over the map, in the layer grid's map coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct OverlayLine {
    /// Vertices (x, y) in metres.
    pub xy: Vec<(f64, f64)>,
    /// Line colour.
    pub colour: [u8; 3],
    /// Line width in output pixels.
    pub width_px: f64,
    /// Text printed at the line's last vertex and in the legend.
    pub label: Option<String>,
}

/// Points and lines drawn over the map, in the layer grid's map coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Overlays {
    /// Points (x, y) in metres, drawn as small dots with a light halo (e.g. rock end points).
    pub points: Vec<(f64, f64)>,
    /// Dot colour (default near-black).
    pub point_colour: [u8; 3],
    /// Dot radius in output pixels (default 2.5).
    pub point_radius_px: f64,
    /// Legend text for the points, e.g. `"end points"`; no legend entry when `None`.
    pub point_label: Option<String>,
    /// Polylines (e.g. profiles, barriers, source zones).
    pub lines: Vec<OverlayLine>,
}

impl Default for Overlays {
    fn default() -> Self {
        Overlays {
            points: Vec::new(),
            point_colour: [25, 25, 25],
            point_radius_px: 2.5,
            point_label: None,
            lines: Vec::new(),
        }
    }
}

/// What was drawn where, so callers and tests can check sizes and ranges.
#[derive(Debug, Clone, PartialEq)]
pub struct MapInfo {
    /// PNG width in pixels.
    pub width_px: u32,
    /// PNG height in pixels.
    pub height_px: u32,
    /// Value at the bottom of the colour bar (for a plain hillshade: the lowest elevation).
    pub colorbar_min: f32,
    /// Value at the top of the colour bar (for a plain hillshade: the highest elevation).
    pub colorbar_max: f32,
    /// Pixel (column, row) of the map's north-west corner.
    pub map_origin_px: (u32, u32),
    /// Map area size in pixels (width, height).
    pub map_size_px: (u32, u32),
    /// Output pixels per metre, the same in x and y.
    pub pixels_per_m: f64,
    /// Map extent in metres: (x_min, y_min, x_max, y_max).
    pub extent_m: (f64, f64, f64, f64),
}

impl MapInfo {
    /// The PNG pixel position (column, row, continuous) of map point (x, y).
    pub fn to_px(&self, x: f64, y: f64) -> (f64, f64) {
        (
            self.map_origin_px.0 as f64 + (x - self.extent_m.0) * self.pixels_per_m,
            self.map_origin_px.1 as f64 + (self.extent_m.3 - y) * self.pixels_per_m,
        )
    }
}

/// Hillshade sun azimuth, degrees clockwise from north.
pub const SUN_AZIMUTH_DEG: f64 = 315.0;
/// Hillshade sun altitude above the horizon, degrees.
pub const SUN_ALTITUDE_DEG: f64 = 45.0;
/// Opacity of layer colours over the hillshade.
pub const LAYER_ALPHA: f64 = 0.75;

const WHITE: Rgba = [255, 255, 255, 255];
const INK: Rgba = [33, 33, 33, 255];
const SUBTLE: Rgba = [105, 105, 105, 255];
const FRAME: Rgba = [70, 70, 70, 255];
/// Map background where there is no terrain.
const NO_TERRAIN: [u8; 3] = [238, 238, 236];
/// Label scale (font pixels → 2×2 output pixels) and title scale.
const S: u32 = 2;
const TITLE_S: u32 = 3;
const PAD: i32 = 20;
const BAR_W: u32 = 24;

/// Renders `layer` over the hillshade of `terrain` (if any) with `overlays` to the PNG `path`.
///
/// Fails if the layer grid is empty or has non-positive cell sizes, or if `range` is reversed or (log scale) not
/// positive.
pub fn render_map(path: &Path, layer: &MapLayer, terrain: Option<&Grid>, overlays: &Overlays) -> Result<MapInfo> {
    let painter = Painter::new(layer)?;
    let canvas_and_info = compose(layer.grid, Some((layer, &painter)), terrain, overlays, &layer.title)?;
    canvas_and_info.0.save_png(path)?;
    Ok(canvas_and_info.1)
}

/// Renders the plain hillshade of `terrain` with `overlays` to the PNG `path` (no colour bar; the elevation range
/// is printed under the map and returned as the colour bar range).
pub fn render_hillshade(path: &Path, terrain: &Grid, overlays: &Overlays) -> Result<MapInfo> {
    let (canvas, info) = compose(terrain, None, Some(terrain), overlays, "Terrain (hillshade)")?;
    canvas.save_png(path)?;
    Ok(info)
}

/// The grey of a hillshade value in [0, 1]: shadowed slopes stay mid-grey so colours over them remain readable.
fn shade_grey(hs: f64) -> u8 {
    (70.0 + 185.0 * hs.clamp(0.0, 1.0)).round() as u8
}

/// The hillshade of flat ground, used behind the colour bar so it matches flat parts of the map.
fn flat_shade() -> f64 {
    SUN_ALTITUDE_DEG.to_radians().sin()
}

/// Hillshade in [0, 1] of every cell of `terrain` (NaN where the elevation is nodata), for the sun at
/// `azimuth_deg` (clockwise from north) and `altitude_deg`. Horn's (1981) 3×3 gradient; missing neighbours (edges,
/// nodata) take the centre value.
pub fn hillshade(terrain: &Grid, azimuth_deg: f64, altitude_deg: f64) -> Grid {
    let (nc, nr) = (terrain.ncols, terrain.nrows);
    let zenith = (90.0 - altitude_deg).to_radians();
    // Azimuth as a math angle (counter-clockwise from east), as in the usual hillshade formula.
    let az = (360.0 - azimuth_deg + 90.0).rem_euclid(360.0).to_radians();
    let mut out = terrain.clone();
    for r in 0..nr {
        for c in 0..nc {
            let Some(z0) = terrain.get(c, r) else {
                out.values[r * nc + c] = f32::NAN;
                continue;
            };
            let z = |dc: isize, dr: isize| -> f64 {
                let (cc, rr) = (c as isize + dc, r as isize + dr);
                if cc < 0 || rr < 0 {
                    return z0 as f64;
                }
                terrain.get(cc as usize, rr as usize).unwrap_or(z0) as f64
            };
            let (a, b, cc, d, f, g, h, i) =
                (z(-1, -1), z(0, -1), z(1, -1), z(-1, 0), z(1, 0), z(-1, 1), z(0, 1), z(1, 1));
            // dz/dx positive eastwards; dz/dy positive southwards (rows go south).
            let dzdx = ((cc + 2.0 * f + i) - (a + 2.0 * d + g)) / (8.0 * terrain.cell_x_m);
            let dzdy = ((g + 2.0 * h + i) - (a + 2.0 * b + cc)) / (8.0 * terrain.cell_y_m);
            let slope = (dzdx * dzdx + dzdy * dzdy).sqrt().atan();
            let aspect = dzdy.atan2(-dzdx);
            let hs = zenith.cos() * slope.cos() + zenith.sin() * slope.sin() * (az - aspect).cos();
            out.values[r * nc + c] = hs.clamp(0.0, 1.0) as f32;
        }
    }
    out
}

/// Bilinear interpolation of `g` at map point (x, y) between cell centres, ignoring nodata neighbours (weights
/// renormalised). `None` outside the grid's extent or where all four neighbours are nodata.
fn sample_bilinear(g: &Grid, x: f64, y: f64) -> Option<f64> {
    let fc = (x - g.x_min_m) / g.cell_x_m - 0.5;
    let fr = (g.y_max_m - y) / g.cell_y_m - 0.5;
    if fc < -0.5 || fr < -0.5 || fc > g.ncols as f64 - 0.5 || fr > g.nrows as f64 - 0.5 {
        return None;
    }
    let fc = fc.clamp(0.0, (g.ncols - 1) as f64);
    let fr = fr.clamp(0.0, (g.nrows - 1) as f64);
    let (c0, r0) = (fc.floor() as usize, fr.floor() as usize);
    let (c1, r1) = ((c0 + 1).min(g.ncols - 1), (r0 + 1).min(g.nrows - 1));
    let (tx, ty) = (fc - c0 as f64, fr - r0 as f64);
    let mut sum = 0.0;
    let mut wsum = 0.0;
    for (c, r, w) in
        [(c0, r0, (1.0 - tx) * (1.0 - ty)), (c1, r0, tx * (1.0 - ty)), (c0, r1, (1.0 - tx) * ty), (c1, r1, tx * ty)]
    {
        if let Some(v) = g.get(c, r) {
            sum += v as f64 * w;
            wsum += w;
        }
    }
    (wsum > 1e-9).then(|| sum / wsum)
}

/// The hillshade `s` around map point (x, y): bilinear at the point for `n` = 1, else the mean of n × n bilinear
/// samples spread over the pixel (`1 / ppm` metres wide).
fn shade_at(s: &Grid, x: f64, y: f64, n: usize, ppm: f64) -> Option<f64> {
    if n <= 1 {
        return sample_bilinear(s, x, y);
    }
    let mut sum = 0.0;
    let mut k = 0;
    for i in 0..n {
        for j in 0..n {
            let dx = ((i as f64 + 0.5) / n as f64 - 0.5) / ppm;
            let dy = ((j as f64 + 0.5) / n as f64 - 0.5) / ppm;
            if let Some(v) = sample_bilinear(s, x + dx, y + dy) {
                sum += v;
                k += 1;
            }
        }
    }
    (k > 0).then(|| sum / k as f64)
}

/// How layer values become colours.
enum Painter {
    Ramp { colormap: Colormap, lo: f64, hi: f64, log: bool, transparent_zero: bool },
    Classes { classes: Vec<Class>, lo: f64, hi: f64, transparent_zero: bool },
}

impl Painter {
    fn new(layer: &MapLayer) -> Result<Self> {
        let g = layer.grid;
        let log = layer.scale == ValueScale::Log;
        if let Some((lo, hi)) = layer.range {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(Error::invalid(
                    "map range",
                    format!("colour bar range ({lo}, {hi}) is not an increasing pair of finite numbers"),
                    "give the range as (min, max) with min < max, or leave it unset to use the data's range",
                ));
            }
            if log && lo <= 0.0 {
                return Err(Error::invalid(
                    "map range",
                    format!("a log colour scale needs a positive minimum, got {lo}"),
                    "set the range minimum above zero (e.g. the smallest meaningful value) or use a linear scale",
                ));
            }
        }
        let data = if log {
            g.values.iter().filter(|v| **v > 0.0).fold(None, |acc: Option<(f32, f32)>, &v| match acc {
                None => Some((v, v)),
                Some((a, b)) => Some((a.min(v), b.max(v))),
            })
        } else {
            g.min_max()
        };
        let (lo, hi) = match (layer.range, data) {
            (Some((a, b)), _) => (a as f64, b as f64),
            (None, Some((a, b))) if layer.colormap.is_diverging() && layer.classes.is_none() && !log => {
                let m = (a.abs().max(b.abs()) as f64).max(f64::MIN_POSITIVE);
                (-m, m)
            }
            (None, Some((a, b))) => (a as f64, b as f64),
            (None, None) if log => (1.0, 10.0),
            (None, None) => (0.0, 1.0),
        };
        // A constant layer still gets a bar to read its value from.
        let (lo, hi) = match (hi > lo, log) {
            (true, _) => (lo, hi),
            (false, true) => (lo, lo * 10.0),
            (false, false) => (lo, lo + lo.abs().max(1.0)),
        };
        let transparent_zero = layer.transparent_zero;
        Ok(match &layer.classes {
            Some(classes) => Painter::Classes { classes: classes.clone(), lo, hi, transparent_zero },
            None => Painter::Ramp { colormap: layer.colormap, lo, hi, log, transparent_zero },
        })
    }

    fn range(&self) -> (f64, f64) {
        match self {
            Painter::Ramp { lo, hi, .. } | Painter::Classes { lo, hi, .. } => (*lo, *hi),
        }
    }

    /// Position of `v` along the colour bar in [0, 1] (unclamped), for ramps.
    fn t(&self, v: f64) -> f64 {
        match *self {
            Painter::Ramp { lo, hi, log: true, .. } => {
                if hi > lo {
                    (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
                } else {
                    0.5
                }
            }
            Painter::Ramp { lo, hi, .. } | Painter::Classes { lo, hi, .. } => {
                if hi > lo {
                    (v - lo) / (hi - lo)
                } else {
                    0.5
                }
            }
        }
    }

    /// The colour of value `v`, `None` for transparent.
    fn colour(&self, v: f32) -> Option<[u8; 3]> {
        if v.is_nan() {
            return None;
        }
        match self {
            Painter::Ramp { colormap, log, transparent_zero, .. } => {
                if (*transparent_zero && v == 0.0) || (*log && v <= 0.0) {
                    return None;
                }
                Some(colormap.sample(self.t(v as f64)))
            }
            Painter::Classes { classes, transparent_zero, .. } => {
                if *transparent_zero && v == 0.0 {
                    return None;
                }
                Class::index_of(classes, v).map(|i| classes[i].colour)
            }
        }
    }
}

/// Output pixels per metre: an integer number of pixels per cell if that gives a long side of 700–1400 pixels,
/// otherwise 1000 pixels on the long side.
fn choose_pixels_per_m(width_m: f64, height_m: f64, cell_m: f64) -> f64 {
    let long_m = width_m.max(height_m);
    let cells = long_m / cell_m;
    let k = (1000.0 / cells).round().max(1.0);
    if (700.0..=1400.0).contains(&(k * cells)) {
        k / cell_m
    } else {
        1000.0 / long_m
    }
}

fn check_grid(g: &Grid, what: &str) -> Result<()> {
    let ok_cells = g.cell_x_m.is_finite() && g.cell_x_m > 0.0 && g.cell_y_m.is_finite() && g.cell_y_m > 0.0;
    if g.ncols == 0 || g.nrows == 0 || !ok_cells || g.values.len() != g.ncols * g.nrows {
        return Err(Error::invalid(
            what,
            format!(
                "cannot draw a {}×{} grid with cells {}×{} m and {} values",
                g.ncols,
                g.nrows,
                g.cell_x_m,
                g.cell_y_m,
                g.values.len()
            ),
            "pass a grid with at least one cell, positive cell sizes and ncols × nrows values",
        ));
    }
    Ok(())
}

/// Per output pixel along one axis: the half-open range of cells it shows.
fn cell_ranges(n_px: u32, n_cells: usize, px_per_cell: f64) -> Vec<(usize, usize)> {
    (0..n_px)
        .map(|p| {
            if px_per_cell >= 1.0 {
                let c = (((p as f64 + 0.5) / px_per_cell) as usize).min(n_cells - 1);
                (c, c + 1)
            } else {
                let c0 = ((p as f64 / px_per_cell) as usize).min(n_cells - 1);
                let c1 = (((p as f64 + 1.0) / px_per_cell).ceil() as usize).clamp(c0 + 1, n_cells);
                (c0, c1)
            }
        })
        .collect()
}

fn compose(
    g: &Grid,
    layer: Option<(&MapLayer, &Painter)>,
    terrain: Option<&Grid>,
    overlays: &Overlays,
    title: &str,
) -> Result<(Canvas, MapInfo)> {
    check_grid(g, "map layer grid")?;
    if let Some(t) = terrain {
        check_grid(t, "map terrain grid")?;
    }
    let width_m = g.ncols as f64 * g.cell_x_m;
    let height_m = g.nrows as f64 * g.cell_y_m;
    let extent = (g.x_min_m, g.y_max_m - height_m, g.x_min_m + width_m, g.y_max_m);
    let ppm = choose_pixels_per_m(width_m, height_m, g.cell_x_m.min(g.cell_y_m));
    let map_w = ((width_m * ppm).round() as u32).max(1);
    let map_h = ((height_m * ppm).round() as u32).max(1);

    // Coordinate ticks decide the left margin.
    let e_ticks = nice_ticks(extent.0, extent.2, (map_w / 170).max(2) as usize);
    let n_ticks = nice_ticks(extent.1, extent.3, (map_h / 120).max(2) as usize);
    let e_step = if e_ticks.len() > 1 { e_ticks[1] - e_ticks[0] } else { nice_step(width_m, 4) };
    let n_step = if n_ticks.len() > 1 { n_ticks[1] - n_ticks[0] } else { nice_step(height_m, 4) };
    let n_labels: Vec<String> = n_ticks.iter().map(|&v| format_tick(v, n_step)).collect();
    let n_label_w = n_labels.iter().map(|l| text_width(l, S)).max().unwrap_or(0);

    let map_x0 = PAD + n_label_w as i32 + 14;
    let map_y0 = PAD + text_height(TITLE_S) as i32 + 18;
    let map_x1 = map_x0 + map_w as i32;
    let map_y1 = map_y0 + map_h as i32;

    // Right panel content, measured first.
    let panel_x = map_x1 + 34;
    let bar_h = (map_h as f64 * 0.55).clamp(200.0, 440.0) as u32;
    let mut panel = Panel::default();
    if let Some((layer, painter)) = layer {
        panel.plan_layer(layer, painter, bar_h);
    }
    panel.plan_overlays(overlays);
    let north_h = 70;
    let panel_content_h = panel.height + north_h + 20;
    let panel_w = panel.width.max(60);

    let title_right = map_x0 + text_width(title, TITLE_S) as i32 + 1;
    let width = (panel_x + panel_w as i32).max(title_right) as u32 + PAD as u32;

    // Under the map: the scale bar on the left, notes (extent, cells, CRS) right-aligned beside it, or below it
    // when there is no room.
    let contour_interval = match (layer, terrain) {
        (None, Some(t)) => contour_interval(t),
        _ => None,
    };
    let mut parts = Vec::new();
    if layer.is_none() {
        if let Some((lo, hi)) = g.min_max() {
            parts.push(format!("elevation {}–{} m", format_value(lo as f64), format_value(hi as f64)));
        }
    }
    if let Some(ci) = contour_interval {
        parts.push(format!("contours {} m (bold {} m)", format_value(ci), format_value(5.0 * ci)));
    }
    if g.cell_y_m != g.cell_x_m {
        parts.push(format!(
            "{} × {} cells of {} × {} m",
            g.ncols,
            g.nrows,
            format_value(g.cell_x_m),
            format_value(g.cell_y_m)
        ));
    } else {
        parts.push(format!("{} × {} cells of {} m", g.ncols, g.nrows, format_value(g.cell_x_m)));
    }
    if let Some(code) = g.crs.epsg {
        parts.push(format!("EPSG:{code}"));
    }
    let sb_y = map_y1 + 44;
    let sb_len_m = nice_length((map_w as f64 * 0.3).max(160.0) / ppm);
    let sb_right = map_x0 + scale_bar_width(sb_len_m, ppm);
    let mut notes = None;
    for right in [map_x1, width as i32 - PAD] {
        let lines = wrap_parts(&parts, (right - sb_right - 40).max(0) as u32);
        if lines.iter().all(|l| text_width(l, S) as i32 <= right - sb_right - 40) {
            notes = Some((lines, right, sb_y));
            break;
        }
    }
    let (note_lines, note_right, note_y) = match notes {
        Some(n) => n,
        None => (wrap_parts(&parts, (width as i32 - PAD - map_x0) as u32), width as i32 - PAD, sb_y + 44),
    };
    let bottom = (sb_y + 34).max(note_y + 24 * note_lines.len() as i32) + PAD - 4;
    let height = (bottom.max(map_y0 + panel_content_h as i32 + 20)) as u32;
    let mut cv = Canvas::new(width, height, WHITE);

    // Map pixels: hillshade grey, then the layer.
    let shade = terrain.map(|t| hillshade(t, SUN_AZIMUTH_DEG, SUN_ALTITUDE_DEG));
    let alpha = if shade.is_some() { LAYER_ALPHA } else { 1.0 };
    // Terrain finer than the pixels is averaged over n × n samples per pixel rather than aliased.
    let shade_sub = terrain.map_or(1, |t| (1.0 / (ppm * t.cell_x_m.min(t.cell_y_m))).ceil().clamp(1.0, 4.0) as usize);
    let cols = cell_ranges(map_w, g.ncols, ppm * g.cell_x_m);
    let rows = cell_ranges(map_h, g.nrows, ppm * g.cell_y_m);
    for py in 0..map_h {
        let y = extent.3 - (py as f64 + 0.5) / ppm;
        for px in 0..map_w {
            let x = extent.0 + (px as f64 + 0.5) / ppm;
            let base = match &shade {
                Some(s) => shade_at(s, x, y, shade_sub, ppm).map(|h| [shade_grey(h); 3]).unwrap_or(NO_TERRAIN),
                None => NO_TERRAIN,
            };
            let (ox, oy) = (map_x0 + px as i32, map_y0 + py as i32);
            cv.set(ox, oy, opaque(base));
            if let Some((_, painter)) = layer {
                let (c0, c1) = cols[px as usize];
                let (r0, r1) = rows[py as usize];
                let mut best = f32::NAN;
                for r in r0..r1 {
                    for c in c0..c1 {
                        let v = g.values[r * g.ncols + c];
                        if !v.is_nan() && (best.is_nan() || v.abs() > best.abs()) {
                            best = v;
                        }
                    }
                }
                if let Some(col) = painter.colour(best) {
                    cv.blend(ox, oy, with_alpha(col, alpha), 1.0);
                }
            }
        }
    }

    // A plain terrain picture gets contours.
    if let (Some(t), Some(ci)) = (terrain, contour_interval) {
        draw_contours(&mut cv, t, ci, (map_x0, map_y0, map_w, map_h), extent, ppm);
    }

    // Overlays, clipped to the map.
    let info_geom = MapInfo {
        width_px: width,
        height_px: height,
        colorbar_min: 0.0,
        colorbar_max: 0.0,
        map_origin_px: (map_x0 as u32, map_y0 as u32),
        map_size_px: (map_w, map_h),
        pixels_per_m: ppm,
        extent_m: extent,
    };
    let map_rect = Rect::new(map_x0, map_y0, map_w, map_h);
    cv.set_clip(Some(map_rect));
    draw_overlays(&mut cv, &info_geom, overlays);
    cv.set_clip(None);
    cv.stroke_rect(map_x0 - 1, map_y0 - 1, map_w + 2, map_h + 2, 1, FRAME);

    // Coordinate ticks: eastings below, northings left.
    let mut last_right = i32::MIN;
    for &e in &e_ticks {
        let px = map_x0 + ((e - extent.0) * ppm).round() as i32;
        let label = format_tick(e, e_step);
        let lw = text_width(&label, S) as i32;
        let lx = (px - lw / 2).clamp(0, width as i32 - lw);
        cv.fill_rect(px.min(map_x1 - 1), map_y1 + 1, 1, 6, FRAME);
        if lx > last_right + 16 {
            draw_text(&mut cv, lx, map_y1 + 10, &label, S, SUBTLE);
            last_right = lx + lw;
        }
    }
    for (&n, label) in n_ticks.iter().zip(&n_labels) {
        let py = map_y0 + ((extent.3 - n) * ppm).round() as i32;
        let lw = text_width(label, S) as i32;
        cv.fill_rect(map_x0 - 7, py.min(map_y1 - 1), 6, 1, FRAME);
        let ty = (py - 7).clamp(map_y0 - 7, map_y1 - 7);
        draw_text(&mut cv, map_x0 - 10 - lw, ty, label, S, SUBTLE);
    }

    // Title.
    draw_text(&mut cv, map_x0, PAD, title, TITLE_S, INK);
    draw_text(&mut cv, map_x0 + 1, PAD, title, TITLE_S, INK);

    // Right panel.
    let mut y = map_y0;
    if let Some((layer, painter)) = layer {
        y = panel.draw_layer(&mut cv, panel_x, y, layer, painter, bar_h, shade.is_some());
    }
    y = panel.draw_overlay_legend(&mut cv, panel_x, y, overlays);
    let arrow_top = (map_y1 - north_h as i32).max(y + 20);
    draw_north_arrow(&mut cv, panel_x + 14, arrow_top);

    // Scale bar and notes under the map.
    draw_scale_bar(&mut cv, map_x0, sb_y, sb_len_m, ppm);
    for (k, l) in note_lines.iter().enumerate() {
        draw_text(&mut cv, note_right - text_width(l, S) as i32, note_y + 24 * k as i32, l, S, SUBTLE);
    }

    let (cmin, cmax) = match layer {
        Some((_, p)) => p.range(),
        None => g.min_max().map(|(a, b)| (a as f64, b as f64)).unwrap_or((0.0, 0.0)),
    };
    Ok((cv, MapInfo { colorbar_min: cmin as f32, colorbar_max: cmax as f32, ..info_geom }))
}

fn draw_overlays(cv: &mut Canvas, info: &MapInfo, overlays: &Overlays) {
    for line in &overlays.lines {
        let pts: Vec<(f64, f64)> = line.xy.iter().map(|&(x, y)| info.to_px(x, y)).collect();
        // A light casing keeps dark lines readable over dark shading.
        cv.polyline(&pts, line.width_px + 2.0, [255, 255, 255, 150], true);
        cv.polyline(&pts, line.width_px, opaque(line.colour), true);
    }
    let r = overlays.point_radius_px;
    for &(x, y) in &overlays.points {
        let (px, py) = info.to_px(x, y);
        cv.fill_circle(px, py, r + 1.0, [255, 255, 255, 190]);
        cv.fill_circle(px, py, r, opaque(overlays.point_colour));
    }
    for line in &overlays.lines {
        let (Some(label), Some(&(x, y))) = (&line.label, line.xy.last()) else { continue };
        let (px, py) = info.to_px(x, y);
        let w = text_width(label, S) as f64;
        let right = (info.map_origin_px.0 + info.map_size_px.0) as f64;
        let lx = if px + 8.0 + w <= right - 2.0 { px + 8.0 } else { px - 8.0 - w };
        let top = info.map_origin_px.1 as f64 + 2.0;
        let bottom = (info.map_origin_px.1 + info.map_size_px.1) as f64 - 16.0;
        let ly = (py - 7.0).clamp(top, bottom.max(top));
        draw_text_halo(cv, lx.round() as i32, ly.round() as i32, label, S, INK, [255, 255, 255, 220]);
    }
}

/// The right-hand panel: colour bar or class legend, overlay legend.
#[derive(Default)]
struct Panel {
    width: u32,
    height: u32,
}

impl Panel {
    /// The colour bar's tick values and labels (ends first, then inner ticks that do not collide with them).
    fn bar_ticks(painter: &Painter, bar_h: u32) -> Vec<(f64, String)> {
        let (lo, hi) = painter.range();
        let mut out = vec![(lo, format_value(lo)), (hi, format_value(hi))];
        if hi <= lo {
            out.truncate(1);
            return out;
        }
        let inner = match painter {
            Painter::Ramp { log: true, .. } => log_ticks(lo, hi).into_iter().map(|v| (v, format_value(v))).collect(),
            _ => {
                let t = nice_ticks(lo, hi, (bar_h / 70).max(2) as usize);
                let step = if t.len() > 1 { t[1] - t[0] } else { 1.0 };
                t.into_iter().map(|v| (v, format_tick(v, step))).collect::<Vec<_>>()
            }
        };
        let min_gap = text_height(S) as f64 * 1.6;
        for (v, l) in inner {
            let pos = painter.t(v) * bar_h as f64;
            let clear = out.iter().all(|(w, _)| (painter.t(*w) * bar_h as f64 - pos).abs() >= min_gap);
            if clear {
                out.push((v, l));
            }
        }
        out
    }

    fn unit_heading(layer: &MapLayer, painter: &Painter) -> String {
        match painter {
            Painter::Ramp { log: true, .. } => format!("{} (log scale)", layer.unit),
            _ => layer.unit.clone(),
        }
    }

    fn plan_layer(&mut self, layer: &MapLayer, painter: &Painter, bar_h: u32) {
        let head_w = text_width(&Self::unit_heading(layer, painter), S);
        match painter {
            Painter::Ramp { .. } => {
                let lw = Self::bar_ticks(painter, bar_h).iter().map(|(_, l)| text_width(l, S)).max().unwrap_or(0);
                self.width = self.width.max(head_w).max(BAR_W + 12 + lw);
                self.height += 30 + bar_h + 20;
            }
            Painter::Classes { classes, .. } => {
                let lw = classes.iter().map(|c| text_width(&c.label, S)).max().unwrap_or(0);
                self.width = self.width.max(head_w).max(36 + lw);
                self.height += 30 + classes.len() as u32 * 28 + 20;
            }
        }
    }

    fn plan_overlays(&mut self, overlays: &Overlays) {
        let mut labels: Vec<&str> = overlays.lines.iter().filter_map(|l| l.label.as_deref()).collect();
        if !overlays.points.is_empty() {
            labels.extend(overlays.point_label.as_deref());
        }
        for l in &labels {
            self.width = self.width.max(36 + text_width(l, S));
        }
        self.height += labels.len() as u32 * 26;
    }

    #[allow(clippy::too_many_arguments)]
    fn draw_layer(
        &self,
        cv: &mut Canvas,
        x: i32,
        y: i32,
        layer: &MapLayer,
        painter: &Painter,
        bar_h: u32,
        over_terrain: bool,
    ) -> i32 {
        draw_text(cv, x, y, &Self::unit_heading(layer, painter), S, INK);
        let top = y + 30;
        // Colours as they appear over flat terrain.
        let behind = if over_terrain { Some(shade_grey(flat_shade())) } else { None };
        let mix = |c: [u8; 3]| -> Rgba {
            match behind {
                Some(g) => {
                    let m = |k: usize| (c[k] as f64 * LAYER_ALPHA + g as f64 * (1.0 - LAYER_ALPHA)).round() as u8;
                    [m(0), m(1), m(2), 255]
                }
                None => opaque(c),
            }
        };
        match painter {
            Painter::Ramp { colormap, .. } => {
                for row in 0..bar_h {
                    let t = 1.0 - (row as f64 + 0.5) / bar_h as f64;
                    cv.fill_rect(x, top + row as i32, BAR_W, 1, mix(colormap.sample(t)));
                }
                cv.stroke_rect(x - 1, top - 1, BAR_W + 2, bar_h + 2, 1, FRAME);
                for (v, label) in Self::bar_ticks(painter, bar_h) {
                    let t = painter.t(v).clamp(0.0, 1.0);
                    let py = top + ((1.0 - t) * (bar_h as f64 - 1.0)).round() as i32;
                    cv.fill_rect(x + BAR_W as i32 + 1, py, 6, 1, FRAME);
                    let ty = (py - 7).clamp(top - 7, top + bar_h as i32 - 7);
                    draw_text(cv, x + BAR_W as i32 + 12, ty, &label, S, INK);
                }
                top + bar_h as i32 + 20
            }
            Painter::Classes { classes, .. } => {
                // Highest class on top, like a colour bar.
                for (i, c) in classes.iter().rev().enumerate() {
                    let by = top + i as i32 * 28;
                    cv.fill_rect(x, by, 26, 18, mix(c.colour));
                    cv.stroke_rect(x, by, 26, 18, 1, FRAME);
                    draw_text(cv, x + 36, by + 2, &c.label, S, INK);
                }
                top + classes.len() as i32 * 28 + 20
            }
        }
    }

    fn draw_overlay_legend(&self, cv: &mut Canvas, x: i32, mut y: i32, overlays: &Overlays) -> i32 {
        for line in &overlays.lines {
            let Some(label) = &line.label else { continue };
            cv.line(
                (x as f64, y as f64 + 7.5),
                (x as f64 + 26.0, y as f64 + 7.5),
                line.width_px,
                opaque(line.colour),
                true,
            );
            draw_text(cv, x + 36, y, label, S, INK);
            y += 26;
        }
        if let (Some(label), false) = (&overlays.point_label, overlays.points.is_empty()) {
            let r = overlays.point_radius_px;
            cv.fill_circle(x as f64 + 13.0, y as f64 + 7.5, r + 1.0, [255, 255, 255, 190]);
            cv.fill_circle(x as f64 + 13.0, y as f64 + 7.5, r, opaque(overlays.point_colour));
            draw_text(cv, x + 36, y, label, S, INK);
            y += 26;
        }
        y
    }
}

/// A 1-2-5 contour interval giving at most 25 lines over the elevation range of `terrain`; `None` when flat.
fn contour_interval(terrain: &Grid) -> Option<f64> {
    let (lo, hi) = terrain.min_max()?;
    (hi > lo).then(|| nice_step((hi - lo) as f64, 25))
}

/// Joins `parts` with ", " into lines at most `max_w` pixels wide (a part wider than that gets its own line).
fn wrap_parts(parts: &[String], max_w: u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for p in parts {
        match lines.last_mut() {
            Some(l) if text_width(&format!("{l}, {p}"), S) <= max_w => *l = format!("{l}, {p}"),
            _ => lines.push(p.clone()),
        }
    }
    lines
}

/// Draws anti-aliased contours of `terrain` every `interval` metres over the map area `(x0, y0, w, h)`, every
/// fifth one bold.
fn draw_contours(
    cv: &mut Canvas,
    terrain: &Grid,
    interval: f64,
    area: (i32, i32, u32, u32),
    extent: (f64, f64, f64, f64),
    ppm: f64,
) {
    let (x0, y0, w, h) = area;
    let (w, h) = (w as usize, h as usize);
    let z: Vec<f64> = (0..h)
        .flat_map(|py| {
            let y = extent.3 - (py as f64 + 0.5) / ppm;
            (0..w).map(move |px| sample_bilinear(terrain, extent.0 + (px as f64 + 0.5) / ppm, y).unwrap_or(f64::NAN))
        })
        .collect();
    let ink = [80u8, 55, 30];
    for py in 0..h {
        for px in 0..w {
            let v = z[py * w + px];
            if v.is_nan() {
                continue;
            }
            // Elevation change per pixel, from central differences where the neighbours exist.
            let at = |c: usize, r: usize| z[r * w + c];
            let (l, r) = (at(px.saturating_sub(1), py), at((px + 1).min(w - 1), py));
            let (u, d) = (at(px, py.saturating_sub(1)), at(px, (py + 1).min(h - 1)));
            let gx = (r - l) / ((px + 1).min(w - 1) - px.saturating_sub(1)).max(1) as f64;
            let gy = (d - u) / ((py + 1).min(h - 1) - py.saturating_sub(1)).max(1) as f64;
            let g = (gx * gx + gy * gy).sqrt();
            if !(g.is_finite() && g > 1e-9) {
                continue;
            }
            let level = (v / interval).round();
            let index = (level as i64).rem_euclid(5) == 0;
            let dist_px = (v - level * interval).abs() / g;
            let half = if index { 0.9 } else { 0.5 };
            let k = (half + 0.5 - dist_px).clamp(0.0, 1.0);
            if k > 0.0 {
                cv.blend(x0 + px as i32, y0 + py as i32, with_alpha(ink, if index { 0.7 } else { 0.4 }), k);
            }
        }
    }
}

/// A north arrow (split dark/light arrowhead) with "N" above, its top-left near (x, y); 70 pixels tall.
fn draw_north_arrow(cv: &mut Canvas, x: i32, y: i32) {
    let cx = x as f64 + 12.0;
    let nw = text_width("N", S) as i32;
    draw_text(cv, cx.round() as i32 - nw / 2, y, "N", S, INK);
    let top = y as f64 + 22.0;
    let tip = (cx, top);
    let base = top + 44.0;
    let notch = (cx, base - 12.0);
    cv.fill_polygon(&[tip, notch, (cx - 11.0, base)], INK);
    cv.fill_polygon(&[tip, (cx + 11.0, base), notch], WHITE);
    cv.polygon(&[tip, (cx + 11.0, base), notch, (cx - 11.0, base)], 1.2, INK, true);
}

/// Width in pixels of the scale bar of `len_m` metres, end label included.
fn scale_bar_width(len_m: f64, ppm: f64) -> i32 {
    let (end, num) = scale_bar_end_label(len_m);
    (len_m * ppm).round() as i32 - text_width(&num, S) as i32 / 2 + text_width(&end, S) as i32
}

/// The scale bar's end label (`"200 m"`, `"1 km"`) and its number alone.
fn scale_bar_end_label(len_m: f64) -> (String, String) {
    let (unit, div) = if len_m >= 1000.0 { ("km", 1000.0) } else { ("m", 1.0) };
    let num = format_value(len_m / div);
    (format!("{num} {unit}"), num)
}

/// A scale bar `len_m` metres long (a round length) with alternating segments, labelled above; its top-left at
/// (x, y).
fn draw_scale_bar(cv: &mut Canvas, x: i32, y: i32, len_m: f64, ppm: f64) {
    if len_m <= 0.0 {
        return;
    }
    let len_px = (len_m * ppm).round() as u32;
    let bar_y = y + 22;
    let segs = if len_px >= 120 { 4 } else { 2 };
    for i in 0..segs {
        let sx = x + (len_px * i / segs) as i32;
        let sw = len_px * (i + 1) / segs - len_px * i / segs;
        let fill = if i % 2 == 0 { INK } else { WHITE };
        cv.fill_rect(sx, bar_y, sw, 8, fill);
    }
    cv.stroke_rect(x, bar_y, len_px + 1, 8, 1, INK);
    draw_text(cv, x - text_width("0", S) as i32 / 2, y, "0", S, INK);
    let (end, num) = scale_bar_end_label(len_m);
    let div = if len_m >= 1000.0 { 1000.0 } else { 1.0 };
    let half = format_value(len_m / 2.0 / div);
    let hw = text_width(&half, S) as i32;
    if len_px as i32 > 2 * hw + 40 {
        draw_text(cv, x + len_px as i32 / 2 - hw / 2, y, &half, S, INK);
    }
    draw_text(cv, x + len_px as i32 - text_width(&num, S) as i32 / 2, y, &end, S, INK);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
        let bytes = std::fs::read(path).unwrap();
        let mut r = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size().unwrap()];
        let info = r.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        let px = buf[..info.buffer_size()].chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
        (info.width, info.height, px)
    }

    /// A 100×80 layer of 2 m cells with a nodata hole, over a tilted, bumpy terrain of 5 m cells covering it.
    fn scene() -> (Grid, Grid) {
        let mut layer = Grid::filled(100, 80, 1000.0, 5000.0, 2.0, 0.0);
        for r in 0..80 {
            for c in 0..100 {
                layer.values[r * 100 + c] = 3.0 + (c as f32) * 0.5 + (r as f32) * 0.1;
            }
        }
        for r in 10..30 {
            for c in 10..40 {
                layer.values[r * 100 + c] = f32::NAN;
            }
        }
        let mut dem = Grid::filled(50, 40, 995.0, 5005.0, 5.0, 0.0);
        for r in 0..40 {
            for c in 0..50 {
                dem.values[r * 50 + c] = 800.0 + r as f32 * 3.0 + (c as f32 * 0.4).sin() * 6.0;
            }
        }
        (layer, dem)
    }

    #[test]
    fn map_png_matches_map_info_and_data_range() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("map.png");
        let (layer, dem) = scene();
        let ml = MapLayer::new(&layer, "Test layer", "kJ");
        let info = render_map(&path, &ml, Some(&dem), &Overlays::default()).unwrap();
        let (w, h, px) = decode(&path);
        assert_eq!((w, h), (info.width_px, info.height_px));
        let (lo, hi) = layer.min_max().unwrap();
        assert_eq!((info.colorbar_min, info.colorbar_max), (lo, hi));
        // 100 cells of 2 m at 10 px per cell.
        assert_eq!(info.map_size_px, (1000, 800));
        assert!((info.pixels_per_m - 5.0).abs() < 1e-12);
        assert!(info.map_origin_px.0 + info.map_size_px.0 < w && info.map_origin_px.1 + info.map_size_px.1 < h);

        // Nodata cells show the hillshade grey, data cells the blended ramp (not grey).
        let at = |x: f64, y: f64| {
            let (c, r) = info.to_px(x, y);
            px[r as usize * w as usize + c as usize]
        };
        let hole = layer.cell_centre(25, 20);
        let p = at(hole.0, hole.1);
        assert!(p[0] == p[1] && p[1] == p[2], "nodata pixel {p:?} is not grey");
        // Exactly the hillshade grey of that pixel's centre.
        let (c, r) = info.to_px(hole.0, hole.1);
        let x = info.extent_m.0 + (c.floor() - info.map_origin_px.0 as f64 + 0.5) / info.pixels_per_m;
        let y = info.extent_m.3 - (r.floor() - info.map_origin_px.1 as f64 + 0.5) / info.pixels_per_m;
        let hs = hillshade(&dem, SUN_AZIMUTH_DEG, SUN_ALTITUDE_DEG);
        assert_eq!(p[0], shade_grey(sample_bilinear(&hs, x, y).unwrap()));
        let data = layer.cell_centre(80, 60);
        let q = at(data.0, data.1);
        assert!(q[0] != q[1] || q[1] != q[2], "data pixel {q:?} is grey");
    }

    #[test]
    fn transparent_zero_log_scale_classes_and_hillshade() {
        let dir = tempfile::tempdir().unwrap();
        let (mut layer, dem) = scene();
        layer.values[0] = 0.0;
        let mut ml = MapLayer::new(&layer, "Zero and log", "passages");
        ml.transparent_zero = true;
        ml.scale = ValueScale::Log;
        let info = render_map(&dir.path().join("log.png"), &ml, Some(&dem), &Overlays::default()).unwrap();
        assert_eq!(info.colorbar_min, 3.1); // the smallest positive value, now that cell (0, 0) is 0
        let (w, _, px) = decode(&dir.path().join("log.png"));
        let c = layer.cell_centre(0, 0);
        let (x, y) = info.to_px(c.0, c.1);
        let p = px[y as usize * w as usize + x as usize];
        assert!(p[0] == p[1] && p[1] == p[2], "zero pixel {p:?} is not grey");

        ml.scale = ValueScale::Linear;
        ml.classes = Some(super::super::colormap::hazard_classes(&["low", "high"], &[10.0, 100.0]));
        render_map(&dir.path().join("classes.png"), &ml, None, &Overlays::default()).unwrap();

        ml.range = Some((5.0, 1.0));
        assert!(render_map(&dir.path().join("bad.png"), &ml, None, &Overlays::default()).is_err());

        let info = render_hillshade(&dir.path().join("hs.png"), &dem, &Overlays::default()).unwrap();
        let (w, h, _) = decode(&dir.path().join("hs.png"));
        assert_eq!((w, h), (info.width_px, info.height_px));
        assert_eq!((info.colorbar_min, info.colorbar_max), dem.min_max().unwrap());
    }

    #[test]
    fn odd_shapes_render_at_the_size_they_report() {
        let dir = tempfile::tempdir().unwrap();
        let mut tall = Grid::filled(12, 300, 0.0, 3000.0, 10.0, 1.0);
        tall.values[5] = 7.0;
        let tiny = Grid::filled(3, 2, 0.0, 2.0, 1.0, 2.5);
        let empty = Grid::filled(40, 30, 0.0, 30.0, 1.0, f32::NAN);
        let mut rect_cells = Grid::filled(60, 40, 0.0, 80.0, 1.0, 0.0);
        rect_cells.cell_y_m = 2.0;
        rect_cells.values[10] = -3.0;
        let huge = Grid::filled(3000, 20, 0.0, 20.0, 1.0, 1.0);
        let dem = Grid::filled(8, 8, -5.0, 3005.0, 500.0, 100.0);
        let pts =
            Overlays { points: vec![(5.0, 5.0), (1e9, 1e9)], point_label: Some("ends".into()), ..Default::default() };
        for (k, g) in [&tall, &tiny, &empty, &rect_cells, &huge].into_iter().enumerate() {
            let path = dir.path().join(format!("{k}.png"));
            let mut ml = MapLayer::new(g, "Odd", "m");
            ml.colormap = Colormap::Diverging;
            let info = render_map(&path, &ml, Some(&dem), &pts).unwrap();
            let (w, h, _) = decode(&path);
            assert_eq!((w, h), (info.width_px, info.height_px), "grid {k}");
            let long = info.map_size_px.0.max(info.map_size_px.1);
            assert!((700..=1400).contains(&long), "grid {k}: long side {long}");
            // Square map units.
            let (gw, gh) = (g.ncols as f64 * g.cell_x_m, g.nrows as f64 * g.cell_y_m);
            assert!((info.map_size_px.0 as f64 / info.map_size_px.1 as f64 - gw / gh).abs() < 0.05 * gw / gh);
        }
        // Diverging layers centre on zero; constant and empty layers still get a readable range.
        let info = render_map(&dir.path().join("t.png"), &MapLayer::new(&tiny, "", ""), None, &pts).unwrap();
        assert_eq!((info.colorbar_min, info.colorbar_max), (2.5, 5.0));
        let mut ml = MapLayer::new(&rect_cells, "", "");
        ml.colormap = Colormap::Diverging;
        let info = render_map(&dir.path().join("d.png"), &ml, None, &pts).unwrap();
        assert_eq!((info.colorbar_min, info.colorbar_max), (-3.0, 3.0));
        let info = render_map(&dir.path().join("e.png"), &MapLayer::new(&empty, "", ""), None, &pts).unwrap();
        assert_eq!((info.colorbar_min, info.colorbar_max), (0.0, 1.0));
        assert!(render_map(
            &dir.path().join("z.png"),
            &MapLayer::new(&Grid::filled(0, 0, 0.0, 0.0, 1.0, 0.0), "", ""),
            None,
            &pts
        )
        .is_err());
    }

    #[test]
    fn hillshade_lights_north_west_slopes() {
        // Elevation rising to the east: the slope faces west, towards the sun at 315°: brighter than flat.
        let mut g = Grid::filled(5, 5, 0.0, 5.0, 1.0, 0.0);
        for r in 0..5 {
            for c in 0..5 {
                g.values[r * 5 + c] = c as f32 * 0.5;
            }
        }
        let hs = hillshade(&g, 315.0, 45.0);
        assert!(hs.values[12] as f64 > flat_shade() + 0.05);
        for v in &mut g.values {
            *v = -*v;
        }
        let hs = hillshade(&g, 315.0, 45.0);
        assert!((hs.values[12] as f64) < flat_shade() - 0.05);
    }

    #[test]
    fn pixel_scale_is_integer_per_cell_when_possible() {
        assert_eq!(choose_pixels_per_m(100.0, 80.0, 1.0), 10.0);
        assert_eq!(choose_pixels_per_m(600.0, 80.0, 1.0), 2.0);
        let f = choose_pixels_per_m(5000.0, 3000.0, 1.0);
        assert!((f * 5000.0 - 1000.0).abs() < 1e-9);
        assert_eq!(cell_ranges(4, 2, 2.0), vec![(0, 1), (0, 1), (1, 2), (1, 2)]);
        assert_eq!(cell_ranges(2, 5, 0.4), vec![(0, 3), (2, 5)]);
    }
}
