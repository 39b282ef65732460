//! Is there a place where the terrain behaves differently from its declared material, and where?
//!
//! **The check** (ours, a posterior predictive check): the statistic is the largest |deposition excess| (observed
//! minus simulated rest-point density, [`super::maps::deposition_excess`]). Its null distribution comes from the
//! model itself: replace each observed rest point by one of the run's own simulated rest points (drawn from half of
//! the repeats, while the other half gives the simulated density, so the replacement is independent of it) and
//! recompute. If the model were right, the observed statistic would look like these; p = (1 + k)/(1 + B).
//!
//! **The candidate zones** (up to [`MAX_ZONES`]): the cells around the extreme excess where the excess keeps at
//! least half its peak value and the same sign (4-connected), dilated by one cell; then the same around the
//! largest excess outside the zones before it. On a terrain a zone's convex hull becomes the polygon, on a profile
//! its x extent the interval. A positive peak is a slow zone (real rocks stop there, simulated ones run on); a
//! negative one a fast zone.

use super::maps::{deposition_excess, empty_grid};
use super::model::{MapFrame, Model, RunSims};
use super::params::Region;
use crate::random::{stream, uniform};
use crate::raster::Grid;

/// The outcome of the zone check.
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneCheck {
    /// Largest |deposition excess| (kernel-weighted rest points).
    pub statistic: f64,
    /// Monte Carlo p-value.
    pub p_value: f64,
    /// Candidate zones: around the extreme, then around the largest |excess| outside the zones before it (at
    /// most [`MAX_ZONES`]).
    pub regions: Vec<Region>,
    /// The deposition excess map (all repeats as the simulated density).
    pub excess: Grid,
}

/// Candidate zones proposed per check (ours: a hidden zone need not hold the largest excess; a calibration that
/// compromises between the zone and the rest of the terrain also leaves an excess elsewhere, and the
/// cross-validation tells which one is real).
pub const MAX_ZONES: usize = 3;

/// Stream index base of the check's draws.
const ZONE_STREAM: u64 = u64::MAX - 3000;

/// Runs the check on `sims` (all repeats of each run) with `bootstrap` null draws.
pub fn zone_check(model: &dyn Model, sims: &[RunSims], frame: &MapFrame, bootstrap: usize, seed: u64) -> ZoneCheck {
    let mut g = empty_grid(frame);
    let repeats = sims.iter().map(|s| s.sims.len()).min().unwrap_or(0);
    let half = if repeats >= 4 { repeats / 2 } else { 0 };
    let density_range = 0..if half > 0 { half } else { repeats };
    let field = deposition_excess(model, sims, &g, frame.profile, density_range.clone());
    let statistic = extreme(&field).1;
    // Null: pseudo-observations from the other half (or all repeats when there are too few).
    let pool = if half > 0 { half..repeats } else { 0..repeats };
    let mut rng = stream(seed, ZONE_STREAM);
    let mut pseudo = model.runs().to_vec();
    let mut hits = 0usize;
    for _ in 0..bootstrap {
        for s in sims {
            let k = pool.start + ((uniform(&mut rng) * pool.len() as f64) as usize).min(pool.len().saturating_sub(1));
            let sim = &s.sims[k];
            pseudo[s.run].rest_m = sim.rest_m;
        }
        let null = NullModel { inner: model, runs: &pseudo };
        let f = deposition_excess(&null, sims, &g, frame.profile, density_range.clone());
        if extreme(&f).1 >= statistic - 1e-12 {
            hits += 1;
        }
    }
    let p_value = (1 + hits) as f64 / (1 + bootstrap) as f64;
    let full = deposition_excess(model, sims, &g, frame.profile, 0..repeats);
    let regions = candidate_regions(&g, &field, frame.profile);
    for (v, f) in g.values.iter_mut().zip(&full) {
        *v = *f as f32;
    }
    ZoneCheck { statistic, p_value, regions, excess: g }
}

/// Up to [`MAX_ZONES`] zones: each around the largest |field| outside the zones found before it.
fn candidate_regions(g: &Grid, field: &[f64], profile: bool) -> Vec<Region> {
    let mut masked = field.to_vec();
    let mut out = Vec::new();
    while out.len() < MAX_ZONES {
        let (arg, value) = extreme(&masked);
        if value <= 0.0 {
            break;
        }
        let sign = masked[arg].signum();
        let Some((region, cells)) = region_around(g, &masked, arg, sign, profile) else { break };
        out.push(region);
        for k in cells {
            masked[k] = 0.0;
        }
    }
    out
}

/// (index, value) of the largest |field|.
fn extreme(field: &[f64]) -> (usize, f64) {
    field.iter().enumerate().fold((0, 0.0), |(bi, bv), (i, v)| if v.abs() > bv { (i, v.abs()) } else { (bi, bv) })
}

/// The zone around cell `arg`: same-sign cells at ≥ half the peak, 4-connected, dilated by one cell; with the
/// cells it covers.
fn region_around(g: &Grid, field: &[f64], arg: usize, sign: f64, profile: bool) -> Option<(Region, Vec<usize>)> {
    let peak = sign * field.get(arg)?;
    if peak <= 0.0 {
        return None;
    }
    let (nc, nr) = (g.ncols, g.nrows);
    let mut inside = vec![false; field.len()];
    let mut stack = vec![arg];
    inside[arg] = true;
    while let Some(k) = stack.pop() {
        let (c, r) = (k % nc, k / nc);
        let mut nb = Vec::with_capacity(4);
        if c > 0 {
            nb.push(k - 1);
        }
        if c + 1 < nc {
            nb.push(k + 1);
        }
        if r > 0 {
            nb.push(k - nc);
        }
        if r + 1 < nr {
            nb.push(k + nc);
        }
        for j in nb {
            if !inside[j] && sign * field[j] >= 0.5 * peak {
                inside[j] = true;
                stack.push(j);
            }
        }
    }
    // Dilate by one cell.
    let core = inside.clone();
    for (k, _) in core.iter().enumerate().filter(|(_, &on)| on) {
        let (c, r) = ((k % nc) as i64, (k / nc) as i64);
        for (dc, dr) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
            let (cc, rr) = (c + dc, r + dr);
            if cc >= 0 && rr >= 0 && (cc as usize) < nc && (rr as usize) < nr {
                inside[rr as usize * nc + cc as usize] = true;
            }
        }
    }
    let cells: Vec<usize> = (0..inside.len()).filter(|&k| inside[k]).collect();
    let half = 0.5 * g.cell_x_m;
    if profile {
        let xs: Vec<f64> = (0..field.len()).filter(|&k| inside[k]).map(|k| g.cell_centre(k % nc, 0).0).collect();
        let lo = xs.iter().copied().fold(f64::INFINITY, f64::min) - half;
        let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max) + half;
        return Some((Region::Interval([lo, hi]), cells));
    }
    let mut corners = Vec::new();
    let hy = 0.5 * g.cell_y_m;
    for (k, _) in inside.iter().enumerate().filter(|(_, &on)| on) {
        let (x, y) = g.cell_centre(k % nc, k / nc);
        corners.extend([[x - half, y - hy], [x + half, y - hy], [x + half, y + hy], [x - half, y + hy]]);
    }
    let hull = convex_hull(corners);
    (hull.len() >= 3).then_some((Region::Polygon(hull), cells))
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without repeated end point.
pub fn convex_hull(mut pts: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let mut lower: Vec<[f64; 2]> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<[f64; 2]> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// A model whose observed rest points are replaced (for the null draws); everything else is delegated.
struct NullModel<'a> {
    inner: &'a dyn Model,
    runs: &'a [super::runs::FieldRun],
}

impl Model for NullModel<'_> {
    fn kind(&self) -> super::config::ModelKind {
        self.inner.kind()
    }
    fn runs(&self) -> &[super::runs::FieldRun] {
        self.runs
    }
    fn group_names(&self) -> &[String] {
        self.inner.group_names()
    }
    fn materials(&self) -> &[String] {
        self.inner.materials()
    }
    fn release_height_m(&self, run: &super::runs::FieldRun) -> f64 {
        self.inner.release_height_m(run)
    }
    fn dominant_material(&self, region: &Region) -> String {
        self.inner.dominant_material(region)
    }
    fn map_frame(&self) -> MapFrame {
        self.inner.map_frame()
    }
    fn prepare<'a>(
        &'a self,
        candidate: &super::params::Candidate,
    ) -> crate::Result<Box<dyn super::model::Prepared + 'a>> {
        self.inner.prepare(candidate)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_with_inner_points() {
        let h = convex_hull(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5], [0.2, 0.7]]);
        assert_eq!(h.len(), 4);
        assert!(crate::terrain::point_in_polygon(0.5, 0.5, &h));
        assert!(!crate::terrain::point_in_polygon(1.5, 0.5, &h));
    }
}
