//! Maps of where the model goes wrong, on a grid over the runs (campaign frame):
//!
//! - the **residual map**: in each cell, the mean run-out residual (observed − median simulated) of the runs whose
//!   paths cross the cell before they reach their observed run-out distance, each run weighted by the share of its
//!   simulations that cross it. An effect tied to a place shows as a patch of one colour where the affected runs
//!   pass; NaN where fewer than one run's worth of paths pass.
//! - the **deposition excess**: a kernel density of the observed rest points minus the mean density of the
//!   simulated rest points (Gaussian kernel, bandwidth 1.5 cells). Positive where real rocks stop and simulated ones
//!   do not; negative where the model piles rocks up that reality does not.

use super::model::{MapFrame, Model, RunSims, Sim};
use crate::raster::Grid;

/// An empty (NaN) grid over the frame, in the campaign's frame and the DEM's CRS.
pub fn empty_grid(frame: &MapFrame) -> Grid {
    let [x0, y0, x1, y1] = frame.extent_m;
    let c = frame.cell_m;
    let ncols = ((x1 - x0) / c).ceil().max(1.0) as usize;
    let (nrows, y_max, cell_y) = if frame.profile {
        (1, 0.5, 1.0)
    } else {
        (((y1 - y0) / c).ceil().max(1.0) as usize, y0 + ((y1 - y0) / c).ceil().max(1.0) * c, c)
    };
    let mut g = Grid::filled(ncols, nrows, x0, y_max, c, f32::NAN);
    g.cell_y_m = cell_y;
    if let Some(dem) = &frame.dem {
        g.crs = dem.crs.clone();
    }
    g
}

/// The cell of (x, y) (on a profile only x counts).
fn cell(g: &Grid, x: f64, y: f64, profile: bool) -> Option<(usize, usize)> {
    g.cell_of(x, if profile { 0.0 } else { y })
}

/// The residual map of `sims`.
pub fn residual_map(model: &dyn Model, sims: &[RunSims], frame: &MapFrame) -> Grid {
    let runs = model.runs();
    let mut g = empty_grid(frame);
    let n = g.values.len();
    let (mut sum, mut weight) = (vec![0.0f64; n], vec![0.0f64; n]);
    let mut seen = vec![0u32; n];
    let mut stamp = 0u32;
    for s in sims {
        let r = &runs[s.run];
        let resid = r.runout_m - s.median_runout();
        let w = 1.0 / s.sims.len().max(1) as f64;
        for sim in &s.sims {
            stamp += 1;
            for p in truncated_path(sim, r.release_m, r.runout_m + frame.cell_m) {
                if let Some((c, row)) = cell(&g, p[0], p[1], frame.profile) {
                    let k = row * g.ncols + c;
                    if seen[k] != stamp {
                        seen[k] = stamp;
                        sum[k] += w * resid;
                        weight[k] += w;
                    }
                }
            }
        }
    }
    for k in 0..n {
        if weight[k] >= 1.0 - 1e-9 {
            g.values[k] = (sum[k] / weight[k]) as f32;
        }
    }
    g
}

/// The points of a simulated path up to `max_runout_m` from the release (horizontal straight-line distance).
fn truncated_path(sim: &Sim, release: [f64; 3], max_runout_m: f64) -> impl Iterator<Item = [f64; 2]> + '_ {
    sim.path
        .iter()
        .map(|p| [p[0] as f64, p[1] as f64])
        .take_while(move |p| (p[0] - release[0]).hypot(p[1] - release[1]) <= max_runout_m)
}

/// Adds a Gaussian kernel of total weight `w` (bandwidth `h` m, cut at 3h) at (x, y) to `field`.
pub fn deposit(g: &Grid, field: &mut [f64], x: f64, y: f64, w: f64, h: f64, profile: bool) {
    let reach = 3.0 * h;
    let y = if profile { 0.0 } else { y };
    let c0 = ((x - reach - g.x_min_m) / g.cell_x_m).floor().max(0.0) as usize;
    let c1 = (((x + reach - g.x_min_m) / g.cell_x_m).ceil().max(0.0) as usize).min(g.ncols);
    let (r0, r1) = if profile {
        (0, 1)
    } else {
        (
            ((g.y_max_m - y - reach) / g.cell_y_m).floor().max(0.0) as usize,
            (((g.y_max_m - y + reach) / g.cell_y_m).ceil().max(0.0) as usize).min(g.nrows),
        )
    };
    for row in r0..r1 {
        for col in c0..c1 {
            let (cx, cy) = g.cell_centre(col, row);
            let d2 = (cx - x).powi(2) + if profile { 0.0 } else { (cy - y).powi(2) };
            if d2 <= reach * reach {
                field[row * g.ncols + col] += w * (-0.5 * d2 / (h * h)).exp();
            }
        }
    }
}

/// Kernel density of observed rest points minus the mean density of the simulated ones (`sim_range` of each
/// run's simulations), as a raw field over `g`'s cells.
pub fn deposition_excess(
    model: &dyn Model,
    sims: &[RunSims],
    g: &Grid,
    profile: bool,
    sim_range: std::ops::Range<usize>,
) -> Vec<f64> {
    let runs = model.runs();
    let h = 1.5 * g.cell_x_m;
    let mut field = vec![0.0; g.values.len()];
    for s in sims {
        let r = &runs[s.run];
        deposit(g, &mut field, r.rest_m[0], r.rest_m[1], 1.0, h, profile);
        let chosen = s.repeats_in(sim_range.clone());
        let w = 1.0 / chosen.len().max(1) as f64;
        for sim in chosen {
            deposit(g, &mut field, sim.rest_m[0], sim.rest_m[1], -w, h, profile);
        }
    }
    field
}
