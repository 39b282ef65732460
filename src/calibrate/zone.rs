//! Is there a place where the terrain behaves differently from its declared material, and where?
//!
//! **The check** (ours, a posterior predictive check): the statistic is the largest |deposition excess| (observed
//! minus simulated rest-point density, [`super::maps::deposition_excess`]). Its null distribution comes from the
//! model itself: replace each observed rest point by one of the run's own simulated rest points (drawn from half of
//! the repeats, while the other half gives the simulated density, so the replacement is independent of it) and
//! recompute. If the model were right, the observed statistic would look like these; p = (1 + k)/(1 + B).
//!
//! **The overrun check** (ours, the same construction): the share of simulations that run farther than every
//! observed run of their release group. Field rocks that all stop before a line while simulated ones cross it
//! leave little deposition excess where the simulated ones go (they spread out beyond it, or leave the terrain),
//! so the deposition statistic can miss the place; this share does not. Its null comes from the same
//! pseudo-observations. The check's p-value is the smaller of the two, doubled (Bonferroni).
//!
//! **The candidate zones** (up to [`MAX_ZONES`]): the cells around the extreme excess where the excess keeps at
//! least half its peak value and the same sign (4-connected), dilated by one cell; then the same around the
//! largest excess outside the zones before it. On a terrain a zone's convex hull becomes the polygon, on a profile
//! its x extent the interval. A positive peak is a slow zone (real rocks stop there, simulated ones run on); a
//! negative one a fast zone. One more candidate, a slow zone, comes from the overrun points: where each overrunning
//! simulation's path first passes its group's farthest observed run-out, as a kernel density, the cells around its
//! peak taken the same way (a band where the field stops rocks that the model lets through).

use super::maps::{deposit, deposition_excess, empty_grid};
use super::model::{MapFrame, Model, RunSims, WithRuns};
use super::params::Region;
use super::runs::FieldRun;
use crate::random::{stream, uniform};
use crate::raster::Grid;

/// The outcome of the zone check.
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneCheck {
    /// Largest |deposition excess| (kernel-weighted rest points).
    pub statistic: f64,
    /// Monte Carlo p-value of the deposition statistic.
    pub deposition_p_value: f64,
    /// Share of simulations that pass their release group's farthest observed run-out.
    pub overrun_share: f64,
    /// Monte Carlo p-value of the overrun share (one-sided: more overruns than the model itself produces).
    pub overrun_p_value: f64,
    /// The check's p-value: the smaller of the two, doubled, at most 1.
    pub p_value: f64,
    /// Candidate zones: around the extreme, then around the largest |excess| outside the zones before it (at
    /// most [`MAX_ZONES`]), then the overrun band (if any simulation overruns).
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
    let overrun = overrun_share(model.runs(), sims, density_range.clone());
    // Null: pseudo-observations from the other half (or all repeats when there are too few).
    let pool = if half > 0 { half..repeats } else { 0..repeats };
    let mut rng = stream(seed, ZONE_STREAM);
    let mut pseudo = model.runs().to_vec();
    let (mut hits, mut overrun_hits) = (0usize, 0usize);
    for _ in 0..bootstrap {
        for s in sims {
            let k = pool.start + ((uniform(&mut rng) * pool.len() as f64) as usize).min(pool.len().saturating_sub(1));
            let sim = &s.sims[k];
            pseudo[s.run].rest_m = sim.rest_m;
            pseudo[s.run].runout_m = sim.runout_m;
        }
        let null = WithRuns::new(model, &pseudo[..], model.groups().clone());
        let f = deposition_excess(&null, sims, &g, frame.profile, density_range.clone());
        if extreme(&f).1 >= statistic - 1e-12 {
            hits += 1;
        }
        if overrun_share(&pseudo, sims, density_range.clone()) >= overrun - 1e-12 {
            overrun_hits += 1;
        }
    }
    let p = |k: usize| (1 + k) as f64 / (1 + bootstrap) as f64;
    let (deposition_p_value, overrun_p_value) = (p(hits), p(overrun_hits));
    let full = deposition_excess(model, sims, &g, frame.profile, 0..repeats);
    let mut regions = candidate_regions(&g, &field, frame.profile);
    let band = overrun_field(model.runs(), sims, &g, frame.profile);
    let (arg, peak) = extreme(&band);
    if peak > 0.0 {
        regions.extend(region_around(&g, &band, arg, 1.0, frame.profile).map(|(r, _)| r));
    }
    for (v, f) in g.values.iter_mut().zip(&full) {
        *v = *f as f32;
    }
    ZoneCheck {
        statistic,
        deposition_p_value,
        overrun_share: overrun,
        overrun_p_value,
        p_value: (2.0 * deposition_p_value.min(overrun_p_value)).min(1.0),
        regions,
        excess: g,
    }
}

/// Each release group's farthest observed run-out among the runs of `sims`, by group index.
fn group_max_runout(runs: &[FieldRun], sims: &[RunSims]) -> std::collections::HashMap<usize, f64> {
    let mut out = std::collections::HashMap::new();
    for s in sims {
        let r = &runs[s.run];
        let m = out.entry(r.group).or_insert(f64::NEG_INFINITY);
        *m = r.runout_m.max(*m);
    }
    out
}

/// Share of the simulations (`range` of each run's) that run farther than their group's farthest observed run.
pub fn overrun_share(runs: &[FieldRun], sims: &[RunSims], range: std::ops::Range<usize>) -> f64 {
    let limit = group_max_runout(runs, sims);
    let (mut over, mut n) = (0usize, 0usize);
    for s in sims {
        let lim = limit[&runs[s.run].group];
        for sim in s.repeats_in(range.clone()) {
            n += 1;
            over += usize::from(sim.runout_m > lim);
        }
    }
    over as f64 / n.max(1) as f64
}

/// Kernel density (as [`deposition_excess`]) of the overrun points: where each simulation that runs farther than
/// its group's farthest observed run first passes that distance from its release.
fn overrun_field(runs: &[FieldRun], sims: &[RunSims], g: &Grid, profile: bool) -> Vec<f64> {
    let limit = group_max_runout(runs, sims);
    let h = 1.5 * g.cell_x_m;
    let mut field = vec![0.0; g.values.len()];
    for s in sims {
        let r = &runs[s.run];
        let lim = limit[&r.group];
        let w = 1.0 / s.sims.len().max(1) as f64;
        for sim in s.sims.iter().filter(|x| x.runout_m > lim) {
            let far = |p: &&[f32; 2]| (p[0] as f64 - r.release_m[0]).hypot(p[1] as f64 - r.release_m[1]) > lim;
            if let Some(p) = sim.path.iter().find(far) {
                deposit(g, &mut field, p[0] as f64, p[1] as f64, w, h, profile);
            }
        }
    }
    field
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

    /// Runs released at (0, y) running along +x; each simulation runs straight to its run-out.
    fn straight(observed: &[f64], simulated: &[Vec<f64>]) -> (Vec<FieldRun>, Vec<RunSims>) {
        let runs: Vec<FieldRun> = observed
            .iter()
            .enumerate()
            .map(|(i, &r)| FieldRun {
                id: format!("r{i}"),
                index: i,
                block_id: "1".into(),
                mass_kg: 50.0,
                size_m: [0.4, 0.3, 0.3],
                release_m: [0.0, 10.0 * (i % 2) as f64, 0.0],
                velocity_mps: [0.0; 3],
                spin_radps: [0.0; 3],
                rest_m: [r, 10.0 * (i % 2) as f64, 0.0],
                runout_m: r,
                group: i % 2,
                ..Default::default()
            })
            .collect();
        let sims = simulated
            .iter()
            .enumerate()
            .map(|(i, v)| RunSims {
                run: i,
                sims: v
                    .iter()
                    .map(|&d| super::super::model::Sim {
                        runout_m: d,
                        rest_m: [d, runs[i].release_m[1], 0.0],
                        end: super::super::model::SimEnd::Rest,
                        summary: Default::default(),
                        path: (0..=d as usize).map(|x| [x as f32, runs[i].release_m[1] as f32]).collect(),
                    })
                    .collect(),
            })
            .collect();
        (runs, sims)
    }

    #[test]
    fn the_overrun_share_counts_simulations_past_their_groups_farthest_observed_run() {
        // Groups 0 (runs 0, 2: farthest 50 m) and 1 (runs 1, 3: farthest 45 m).
        let observed = [50.0, 45.0, 40.0, 30.0];
        let simulated = vec![vec![45.0, 55.0], vec![44.0, 80.0], vec![49.0, 51.0], vec![20.0, 46.0]];
        let (runs, sims) = straight(&observed, &simulated);
        // Past the limit: 55, 51 (group 0, > 50); 80, 46 (group 1, > 45): 4 of 8, all in the second repeat.
        assert!((overrun_share(&runs, &sims, 0..2) - 0.5).abs() < 1e-12);
        assert_eq!(overrun_share(&runs, &sims, 0..1), 0.0);
        assert_eq!(overrun_share(&runs, &sims, 1..2), 1.0);
    }

    #[test]
    fn the_overrun_band_lies_where_simulations_pass_the_farthest_observed_run() {
        // Field rocks all stop by 50 m; a third of the simulated ones run on to 90 m.
        let observed: Vec<f64> = (0..10).map(|i| 40.0 + i as f64).collect();
        let simulated: Vec<Vec<f64>> = (0..10).map(|i| vec![38.0 + i as f64, 42.0 + i as f64, 90.0]).collect();
        let (runs, sims) = straight(&observed, &simulated);
        let g = Grid::filled(30, 6, -10.0, 20.0, 5.0, f32::NAN);
        let band = overrun_field(&runs, &sims, &g, false);
        let (arg, peak) = extreme(&band);
        assert!(peak > 0.0);
        let (x, _) = g.cell_centre(arg % g.ncols, arg / g.ncols);
        // The groups' farthest observed runs are 48 and 49 m: the band peaks there, not at the simulated rests (90 m).
        assert!((45.0..=55.0).contains(&x), "peak at x = {x}");
        let (region, _) = region_around(&g, &band, arg, 1.0, false).unwrap();
        assert!(region.contains(50.0, 5.0) && !region.contains(90.0, 5.0) && !region.contains(30.0, 5.0));
    }
}
