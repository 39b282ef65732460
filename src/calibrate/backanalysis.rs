//! Per-run back-analysis, as in the field papers (physics.md §5, "getting Cr = 0.155 ± 0.060"): each calibration
//! run gets its own value of each parameter, and the values are reported as mean ± sample sd per material (the form
//! of the seed paper's Tables 1 and 2).
//!
//! For one parameter at a time (ours), with every other parameter at the population fit, the parameter is stepped
//! over a grid across its bounds; each run's median simulated run-out (common random numbers, so the curve is
//! smooth in the parameter) is interpolated linearly to where it meets the run's observed run-out. Where the curve
//! crosses more than once the crossing nearest the population value is taken; a run whose curve never meets its
//! observation (the parameter cannot explain it within the bounds) is counted as censored and left out of mean ±
//! sd. A single run-out cannot pin down several parameters at once, hence one at a time.

use super::fit::Context;
use super::params::{Candidate, FreeParam};
use super::stats::{mean, sample_sd};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Mean ± sd of a back-analysed parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Mean over runs.
    pub mean: f64,
    /// Sample standard deviation.
    pub sd: f64,
    /// Runs with a value.
    pub n: usize,
}

/// One row of the back-analysis table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BackAnalysisRow {
    /// Material (or zone).
    pub material: String,
    /// Parameter.
    pub parameter: String,
    /// Population fit value.
    pub population: f64,
    /// Over all calibration runs.
    pub all: Spread,
    /// Runs whose observation the parameter could not reach within its bounds.
    pub censored: usize,
    /// Per block.
    pub by_block: BTreeMap<String, Spread>,
}

/// Is this a parameter the per-run back-analysis fits (locations, not spreads between rocks such as `cr_sd` or
/// `dynamic_friction_sd_deg`; the slope roughness `roughness_sd_deg` moves a run's median, so it counts)?
pub fn is_location(name: &str) -> bool {
    !(name.ends_with("_sd") || name.ends_with("friction_sd_deg"))
}

/// Back-analyses every free location parameter of `base` on runs `which`.
pub fn back_analyse(ctx: &Context, base: &Candidate, free: &[FreeParam], which: &[usize]) -> Vec<BackAnalysisRow> {
    let runs = ctx.model.runs();
    let g = ctx.cfg.back_analysis.grid_points;
    let mut rows = Vec::new();
    for p in free.iter().filter(|p| is_location(&p.name) && p.name.contains('.')) {
        let (material, parameter) = p.name.split_once('.').unwrap_or(("", &p.name));
        (ctx.log)(&format!("back-analysis of {}", p.name));
        let grid: Vec<f64> = (0..g).map(|k| p.min + (p.max - p.min) * k as f64 / (g - 1) as f64).collect();
        // medians[k][j]: median run-out of run which[j] at grid value k.
        let mut medians = Vec::with_capacity(g);
        for &v in &grid {
            let mut c = base.clone();
            c.params.set(p.name.clone(), v);
            super::params::normalize(&mut c.params);
            match ctx.sims(&c, which, ctx.cfg.search_repeats) {
                Ok(s) => medians.push(s.iter().map(|r| r.median_runout()).collect::<Vec<_>>()),
                Err(_) => medians.push(vec![f64::NAN; which.len()]),
            }
        }
        let population = base.params.get_or(&p.name, f64::NAN);
        let mut values = Vec::new();
        let mut by_block: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        let mut censored = 0;
        for (j, &i) in which.iter().enumerate() {
            let obs = runs[i].runout_m;
            let d: Vec<f64> = medians.iter().map(|m| m[j] - obs).collect();
            let mut best: Option<f64> = None;
            for k in 0..g - 1 {
                let (a, b) = (d[k], d[k + 1]);
                if !(a.is_finite() && b.is_finite()) || a * b > 0.0 || (a == 0.0 && b == 0.0) {
                    continue;
                }
                let v = if a == b { grid[k] } else { grid[k] + (grid[k + 1] - grid[k]) * a / (a - b) };
                if best.is_none_or(|x| (v - population).abs() < (x - population).abs()) {
                    best = Some(v);
                }
            }
            match best {
                Some(v) => {
                    values.push(v);
                    by_block.entry(runs[i].block_id.clone()).or_default().push(v);
                }
                None => censored += 1,
            }
        }
        let spread = |v: &[f64]| Spread { mean: mean(v), sd: sample_sd(v), n: v.len() };
        rows.push(BackAnalysisRow {
            material: material.to_string(),
            parameter: parameter.to_string(),
            population,
            all: spread(&values),
            censored,
            by_block: by_block.iter().map(|(b, v)| (b.clone(), spread(v))).collect(),
        });
    }
    rows
}

#[cfg(test)]
mod tests {
    #[test]
    fn spreads_between_rocks_are_not_back_analysed_per_run() {
        for (name, location) in [
            ("default.cr_mean", true),
            ("default.dynamic_friction_deg", true),
            ("default.roughness_sd_deg", true),
            ("default.cr_sd", false),
            ("default.rn_sd", false),
            ("default.dynamic_friction_sd_deg", false),
        ] {
            assert_eq!(super::is_location(name), location, "{name}");
        }
    }
}
