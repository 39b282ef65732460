//! PNG maps of a run's rasters over a hillshade of its terrain, with end points, barriers and collectors on top.

use crate::error::Result;
use crate::raster::Grid;
use crate::render::{render_map, Class, Colormap, MapInfo, MapLayer, OverlayLine, Overlays, ValueScale};
use crate::terrain::frame::map_xy;
use crate::terrain::Terrain;
use std::path::Path;

/// How a raster is coloured.
#[derive(Debug, Clone)]
pub struct Style {
    /// Map title.
    pub title: String,
    /// Unit over the colour bar.
    pub unit: String,
    /// Ramp.
    pub colormap: Colormap,
    /// Linear or log.
    pub scale: ValueScale,
    /// Classes instead of a ramp.
    pub classes: Option<Vec<Class>>,
    /// Colour bar range (default: the data's).
    pub range: Option<(f32, f32)>,
}

impl Style {
    fn ramp(title: &str, unit: &str, colormap: Colormap, scale: ValueScale) -> Style {
        Style { title: title.into(), unit: unit.into(), colormap, scale, classes: None, range: None }
    }
}

/// The style of the run raster `stem` (see [`crate::run::RASTERS`]).
pub fn raster_style(stem: &str) -> Style {
    match stem {
        "endpoint_density" => {
            Style::ramp("End-point density", "probability per cell", Colormap::Viridis, ValueScale::Log)
        }
        "reach_probability" => {
            Style::ramp("Reach probability", "fraction of rocks", Colormap::Viridis, ValueScale::Log)
        }
        "kinetic_energy_p95_kj" => {
            Style::ramp("Kinetic energy, 95th percentile", "kJ", Colormap::Inferno, ValueScale::Log)
        }
        "kinetic_energy_max_kj" => Style::ramp("Kinetic energy, maximum", "kJ", Colormap::Inferno, ValueScale::Log),
        "bounce_height_p95_m" => Style::ramp("Passing height, 95th percentile", "m", Colormap::Magma, ValueScale::Log),
        "bounce_height_max_m" => Style::ramp("Passing height, maximum", "m", Colormap::Magma, ValueScale::Log),
        other => Style::ramp(other, "", Colormap::Viridis, ValueScale::Linear),
    }
}

/// Elevations of `terrain` (map coordinates) over the extent of `grid`, at half its cell size or coarser (at most
/// 1200 cells on the long side), for the hillshade.
pub fn dem_for(terrain: &Terrain, grid: &Grid) -> Grid {
    let (w, h) = (grid.ncols as f64 * grid.cell_x_m, grid.nrows as f64 * grid.cell_y_m);
    let cell = (0.5 * grid.cell_x_m.min(grid.cell_y_m)).max(w.max(h) / 1200.0);
    let (nc, nr) = ((w / cell).round().max(1.0) as usize, (h / cell).round().max(1.0) as usize);
    let (cx, cy) = (w / nc as f64, h / nr as f64);
    let mut dem = Grid::filled(nc, nr, grid.x_min_m, grid.y_max_m, cx, f32::NAN);
    dem.cell_y_m = cy;
    dem.crs = grid.crs.clone();
    let (ox, oy, oz) = (terrain.origin.x, terrain.origin.y, terrain.origin.z);
    for r in 0..nr {
        for c in 0..nc {
            let x = grid.x_min_m + (c as f64 + 0.5) * cx - ox;
            let y = grid.y_max_m - (r as f64 + 0.5) * cy - oy;
            if let Some(z) = terrain.surface.height(x, y) {
                dem.values[r * nc + c] = (z + oz) as f32;
            }
        }
    }
    dem
}

/// Colour of barriers on maps.
pub const BARRIER_COLOUR: [u8; 3] = [225, 0, 210];
/// Colour of collector lines on maps.
pub const COLLECTOR_COLOUR: [u8; 3] = [20, 20, 20];

/// Most end points drawn on a run's maps.
pub const MAX_MAP_POINTS: usize = 3000;

/// Every `step`-th of the points added, `step` doubling whenever more than [`MAX_MAP_POINTS`] would be kept: a
/// uniform thinning of the stopped rocks' end points for the maps, in memory that does not grow with the run.
#[derive(Debug, Clone)]
pub struct ThinnedPoints {
    /// Points kept (every `step`-th added).
    pub points: Vec<[f64; 2]>,
    /// One point kept in `step`.
    pub step: usize,
    /// Points added.
    pub total: usize,
}

impl Default for ThinnedPoints {
    fn default() -> Self {
        ThinnedPoints { points: Vec::new(), step: 1, total: 0 }
    }
}

impl ThinnedPoints {
    /// Adds a point.
    pub fn add(&mut self, p: [f64; 2]) {
        if self.total.is_multiple_of(self.step) {
            self.points.push(p);
            if self.points.len() > MAX_MAP_POINTS {
                self.step *= 2;
                self.points = self.points.iter().step_by(2).copied().collect();
            }
        }
        self.total += 1;
    }
}

/// Overlays of a run: stopped rocks' end points (`stopped`, at most [`MAX_MAP_POINTS`]), the terrain's barriers
/// and the given collector lines (labelled when there are at most six lines in all).
pub fn run_overlays(
    terrain: &Terrain,
    stopped: &ThinnedPoints,
    collectors: &[crate::collector::Collector],
) -> Overlays {
    let points: Vec<(f64, f64)> = stopped.points.iter().map(|p| map_xy(terrain, *p)).map(|p| (p[0], p[1])).collect();
    let step = stopped.step;
    let label = if step == 1 { "end points".to_string() } else { format!("end points (1 in {step})") };
    let label_lines = terrain.barriers.len() + collectors.len() <= 6;
    let mut lines = Vec::new();
    for b in &terrain.barriers {
        lines.push(OverlayLine {
            xy: b.line_m.iter().map(|p| map_xy(terrain, *p)).map(|p| (p[0], p[1])).collect(),
            colour: BARRIER_COLOUR,
            width_px: 4.0,
            label: label_lines
                .then(|| format!("{} ({} m, {} kJ)", b.name, fmt_num(b.height_m), fmt_num(b.capacity_j / 1000.0))),
        });
    }
    for c in collectors {
        lines.push(OverlayLine {
            xy: c.line_m.iter().map(|p| map_xy(terrain, *p)).map(|p| (p[0], p[1])).collect(),
            colour: COLLECTOR_COLOUR,
            width_px: 2.5,
            label: label_lines.then(|| c.name.clone()),
        });
    }
    Overlays {
        points,
        point_label: (stopped.total > 0).then_some(label),
        point_radius_px: if stopped.total > 1000 { 1.5 } else { 2.0 },
        lines,
        ..Default::default()
    }
}

/// A number with at most one decimal and no trailing zeros.
pub fn fmt_num(v: f64) -> String {
    let s = format!("{v:.1}");
    s.strip_suffix(".0").map(str::to_string).unwrap_or(s)
}

/// Decades shown on a log colour bar at most (ours: smaller values take the bottom colour, so that a few
/// near-zero cells do not wash out the range that matters).
pub const LOG_DECADES: f32 = 3.0;

/// The log colour bar range of `grid`: its positive maximum down to at most [`LOG_DECADES`] below it.
pub fn log_range(grid: &Grid) -> Option<(f32, f32)> {
    let (lo, hi) = grid.values.iter().filter(|v| **v > 0.0).fold(None, |acc: Option<(f32, f32)>, &v| match acc {
        None => Some((v, v)),
        Some((a, b)) => Some((a.min(v), b.max(v))),
    })?;
    (hi > lo).then(|| (lo.max(hi / 10f32.powf(LOG_DECADES)), hi))
}

/// Renders `grid` with `style` over `dem` to `path`.
pub fn render(path: &Path, grid: &Grid, style: &Style, dem: Option<&Grid>, overlays: &Overlays) -> Result<MapInfo> {
    let mut layer = MapLayer::new(grid, style.title.clone(), style.unit.clone());
    layer.colormap = style.colormap;
    layer.scale = style.scale;
    layer.classes = style.classes.clone();
    layer.range = style
        .range
        .or_else(|| (style.scale == ValueScale::Log && style.classes.is_none()).then(|| log_range(grid)).flatten());
    layer.transparent_zero = true;
    render_map(path, &layer, dem, overlays)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinned_points_keep_every_step_th_and_at_most_the_map_limit() {
        for n in [0, 1, MAX_MAP_POINTS, MAX_MAP_POINTS + 1, 4 * MAX_MAP_POINTS + 5] {
            let mut t = ThinnedPoints::default();
            (0..n).for_each(|i| t.add([i as f64, 0.0]));
            assert_eq!(t.total, n);
            assert!(t.points.len() <= MAX_MAP_POINTS, "{n}: {} kept", t.points.len());
            assert!(t.step.is_power_of_two() && t.step >= n.div_ceil(MAX_MAP_POINTS).max(1), "{n}: step {}", t.step);
            let expected: Vec<f64> = (0..n).step_by(t.step).map(|i| i as f64).collect();
            assert_eq!(t.points.iter().map(|p| p[0]).collect::<Vec<_>>(), expected, "{n}");
        }
    }
}
