//! Residual diagnosis: per-run residuals against covariates of the run and of its simulated paths, by Spearman
//! rank correlation with permutation p-values.
//!
//! Residuals are `observed − median simulated run-out` (negative: the model runs too far) and the rest-point
//! offset (distance from the observed rest point to the median simulated one). Covariates come only from the
//! release and the simulations, never from the observed outcome, so that no covariate correlates with a residual
//! by construction.

use super::model::{Model, RunSims};
use super::stats::{median, spearman_permutation};
use crate::random::stream;
use serde::{Deserialize, Serialize};

/// One covariate's link with a residual.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Diagnostic {
    /// Covariate name.
    pub covariate: String,
    /// `runout` (observed − median simulated run-out) or `endpoint_offset`.
    pub residual: String,
    /// Spearman's rank correlation.
    pub spearman_rho: f64,
    /// Two-sided permutation p-value.
    pub p_value: f64,
    /// Runs.
    pub n: usize,
}

/// Per-run covariates, one column per name, rows in the order of the simulations.
#[derive(Debug, Clone, PartialEq)]
pub struct Covariates {
    /// Names.
    pub names: Vec<String>,
    /// `values[c][i]`: covariate c of run i.
    pub values: Vec<Vec<f64>>,
}

impl Covariates {
    /// The column named `name`.
    pub fn get(&self, name: &str) -> Option<&[f64]> {
        self.names.iter().position(|n| n == name).map(|k| self.values[k].as_slice())
    }
}

/// Residuals of `sims`: (observed − median simulated run-out, rest-point offset), m.
pub fn residuals(model: &dyn Model, sims: &[RunSims]) -> (Vec<f64>, Vec<f64>) {
    let runs = model.runs();
    let runout = sims.iter().map(|s| runs[s.run].runout_m - s.median_runout()).collect();
    let offset = sims
        .iter()
        .map(|s| {
            let [x, y] = s.median_rest_xy();
            (x - runs[s.run].rest_m[0]).hypot(y - runs[s.run].rest_m[1])
        })
        .collect();
    (runout, offset)
}

/// The covariates of the runs of `sims`: block (mass, size, elongation, flatness, area per mass), release (height
/// above ground, initial speed, position), and the medians over repeats of path quantities (drop height to the
/// simulated rest point, mean slope, share of gentle ground, slope at rest, impact speeds and angles, share of
/// each material).
pub fn covariates(model: &dyn Model, sims: &[RunSims]) -> Covariates {
    let runs = model.runs();
    let profile = model.kind() == super::config::ModelKind::Lumped2d;
    let mut names: Vec<String> = Vec::new();
    let mut values: Vec<Vec<f64>> = Vec::new();
    let mut add = |name: &str, f: &dyn Fn(&RunSims) -> f64| {
        names.push(name.to_string());
        values.push(sims.iter().map(f).collect());
    };
    add("mass_kg", &|s| runs[s.run].mass_kg);
    add("size_m", &|s| runs[s.run].size_nominal_m());
    add("elongation", &|s| runs[s.run].elongation());
    add("flatness", &|s| runs[s.run].flatness());
    add("area_per_mass_m2_kg", &|s| runs[s.run].area_per_mass_m2_kg());
    add("release_height_m", &|s| model.release_height_m(&runs[s.run]));
    add("drop_height_m", &|s| {
        runs[s.run].release_m[2] - median(&s.sims.iter().map(|x| x.rest_m[2]).collect::<Vec<_>>())
    });
    add("initial_speed_mps", &|s| {
        let v = runs[s.run].velocity_mps;
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    });
    add("path_slope_mean_deg", &|s| s.median_of(|x| x.summary.slope_mean_deg));
    add("gentle_fraction", &|s| s.median_of(|x| x.summary.gentle_fraction));
    add("end_slope_deg", &|s| s.median_of(|x| x.summary.end_slope_deg));
    add("impact_speed_mean_mps", &|s| s.median_of(|x| x.summary.impact_speed_mean_mps));
    add("impact_speed_max_mps", &|s| s.median_of(|x| x.summary.impact_speed_max_mps));
    add("impact_angle_mean_deg", &|s| s.median_of(|x| x.summary.impact_angle_mean_deg));
    add("release_x_m", &|s| runs[s.run].release_m[0]);
    if !profile {
        add("release_y_m", &|s| runs[s.run].release_m[1]);
    }
    let mats = model.materials();
    if mats.len() > 1 {
        for (k, m) in mats.iter().enumerate() {
            add(&format!("path_fraction_{m}"), &|s| {
                s.median_of(|x| x.summary.material_fraction.get(k).copied().unwrap_or(0.0))
            });
        }
    }
    Covariates { names, values }
}

/// Stream index base of the diagnosis permutations.
const DIAG_STREAM: u64 = u64::MAX - 2000;

/// Spearman correlations of both residuals with every covariate, with `permutations` permutations each (seeded).
/// Sorted by p-value, then by |ρ| descending.
pub fn diagnose(model: &dyn Model, sims: &[RunSims], permutations: usize, seed: u64) -> (Covariates, Vec<Diagnostic>) {
    let cov = covariates(model, sims);
    let (runout, offset) = residuals(model, sims);
    let mut out = Vec::new();
    for (k, (name, x)) in cov.names.iter().zip(&cov.values).enumerate() {
        for (j, (label, r)) in [("runout", &runout), ("endpoint_offset", &offset)].into_iter().enumerate() {
            let mut rng = stream(seed, DIAG_STREAM - (2 * k + j) as u64);
            let (rho, p) = spearman_permutation(x, r, permutations, &mut rng);
            out.push(Diagnostic {
                covariate: name.clone(),
                residual: label.to_string(),
                spearman_rho: rho,
                p_value: p,
                n: x.len(),
            });
        }
    }
    out.sort_by(|a, b| a.p_value.total_cmp(&b.p_value).then(b.spearman_rho.abs().total_cmp(&a.spearman_rho.abs())));
    (cov, out)
}
