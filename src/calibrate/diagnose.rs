//! Residual diagnosis: per-run residuals against covariates of the run and of its simulated paths, by Spearman
//! rank correlation with permutation p-values.
//!
//! Residuals are `observed − median simulated run-out` (negative: the model runs too far) and the rest-point
//! offset (distance from the observed rest point to the median simulated one), and on a tracked campaign the
//! rebound residual `observed − median simulated rebound height` ([`super::rebound`]) of the tracked runs.
//! Covariates come only from the release and the simulations, never from the observed outcome, so that no covariate
//! correlates with a residual by construction.

use super::model::{Model, RunSims};
use super::runs::FieldRun;
use super::stats::{median, spearman_permutation};
use crate::random::stream;
use serde::{Deserialize, Serialize};

/// One covariate's link with a residual.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Diagnostic {
    /// Covariate name.
    pub covariate: String,
    /// `runout` (observed − median simulated run-out), `endpoint_offset`, `rebound` (observed − median
    /// simulated rebound height, tracked runs only) or `bounce_restitution` (an observed bounce's rank among
    /// simulated ones, [`super::impacts::bounce_diagnostics`]).
    pub residual: String,
    /// Spearman's rank correlation.
    pub spearman_rho: f64,
    /// Two-sided permutation p-value.
    pub p_value: f64,
    /// Runs (bounces for `bounce_restitution`).
    pub n: usize,
}

impl Diagnostic {
    /// What `spearman_rho` holds for this diagnostic, for labels: a rank correlation for covariates, the share of
    /// runs outside their simulated range for the spread check, the largest excess for the zone check.
    pub fn statistic_label(&self) -> &'static str {
        match self.covariate.as_str() {
            OUTSIDE_RANGE => "share",
            DEPOSITION_EXCESS => "excess",
            _ => "rho",
        }
    }
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
/// Stream index base of the rebound residual's permutations.
const REBOUND_STREAM: u64 = u64::MAX - 2500;
/// Fewest tracked runs for the rebound residual to be diagnosed.
const MIN_TRACKED: usize = 6;

/// Spearman correlations of the residuals with every covariate, with `permutations` permutations each (seeded):
/// run-out and rest-point offset on every run, rebound on the tracked runs (if at least six). Sorted by p-value,
/// then by |ρ| descending.
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
    let runs = model.runs();
    let tracked: Vec<usize> = (0..sims.len()).filter(|&i| runs[sims[i].run].rebound_height_m.is_some()).collect();
    if tracked.len() >= MIN_TRACKED {
        let residual: Vec<f64> = tracked
            .iter()
            .map(|&i| {
                let s = &sims[i];
                runs[s.run].rebound_height_m.unwrap_or(0.0) - s.median_of(|x| x.summary.rebound_height_m)
            })
            .collect();
        for (k, (name, x)) in cov.names.iter().zip(&cov.values).enumerate() {
            let x: Vec<f64> = tracked.iter().map(|&i| x[i]).collect();
            let mut rng = stream(seed, REBOUND_STREAM - k as u64);
            let (rho, p) = spearman_permutation(&x, &residual, permutations, &mut rng);
            out.push(Diagnostic {
                covariate: name.clone(),
                residual: "rebound".to_string(),
                spearman_rho: rho,
                p_value: p,
                n: x.len(),
            });
        }
    }
    out.sort_by(by_strength);
    (cov, out)
}

/// Diagnostics in order of strength: smallest p-value first, then largest |rho|.
pub fn by_strength(a: &Diagnostic, b: &Diagnostic) -> std::cmp::Ordering {
    a.p_value.total_cmp(&b.p_value).then(b.spearman_rho.abs().total_cmp(&a.spearman_rho.abs()))
}

/// `diagnostics` with `more` among them, in order of strength.
pub fn merged(mut diagnostics: Vec<Diagnostic>, more: Vec<Diagnostic>) -> Vec<Diagnostic> {
    diagnostics.extend(more);
    diagnostics.sort_by(by_strength);
    diagnostics
}

/// The covariate name of [`spread_check`].
pub const OUTSIDE_RANGE: &str = "outside_simulated_range";

/// The covariate name of the zone check's evidence (the largest deposition excess, [`super::maps::deposition_excess`]).
pub const DEPOSITION_EXCESS: &str = "deposition_excess";

/// The spread check (ours): are the observed run-outs outside the range of their own simulations more often than
/// chance allows? If a run's simulations and its field run were exchangeable draws, the observed value's rank among
/// the n simulated ones would be uniform on 0..=n, so it would fall below all of them or above all of them with
/// probability 2/(n+1) (0.095 for 20 repeats). More runs outside than that means the simulated run-outs are too
/// narrow (or off-centre): the signature of scatter the model lacks. Returned as a [`Diagnostic`] with covariate
/// [`OUTSIDE_RANGE`], residual `runout`, the observed share outside in `spearman_rho` (not a correlation here) and
/// the exact one-sided p-value of that many or more (the runs' chances summed as a Poisson binomial).
pub fn spread_check(runs: &[FieldRun], sims: &[RunSims]) -> Diagnostic {
    let mut chances = Vec::new();
    let mut outside = 0;
    for s in sims.iter().filter(|s| !s.sims.is_empty()) {
        let r = s.runouts();
        let (lo, hi) = r.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
        let obs = runs[s.run].runout_m;
        outside += usize::from(obs < lo || obs > hi);
        chances.push(2.0 / (r.len() as f64 + 1.0));
    }
    // dist[k]: probability of exactly k runs outside under exchangeability.
    let mut dist = vec![1.0];
    for &q in &chances {
        let mut next = vec![0.0; dist.len() + 1];
        for (k, &p) in dist.iter().enumerate() {
            next[k] += p * (1.0 - q);
            next[k + 1] += p * q;
        }
        dist = next;
    }
    let n = chances.len();
    Diagnostic {
        covariate: OUTSIDE_RANGE.into(),
        residual: "runout".into(),
        spearman_rho: if n > 0 { outside as f64 / n as f64 } else { 0.0 },
        p_value: dist[outside..].iter().sum::<f64>().min(1.0),
        n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::metrics::tests::{run, sims};

    #[test]
    fn the_spread_check_counts_runs_outside_their_simulated_range_against_the_exchangeable_rate() {
        // 20 runs, each simulated 19 times over 90..=108 m: the chance of falling outside is 2/20 = 0.1.
        let observed = |outside: usize| -> Vec<FieldRun> {
            (0..20).map(|i| run(i, 0, if i < outside { 120.0 } else { 100.5 })).collect()
        };
        let range: Vec<f64> = (0..19).map(|k| 90.0 + k as f64).collect();
        let s: Vec<RunSims> = (0..20).map(|i| sims(i, &range)).collect();
        // Two of 20 outside is what chance gives: no signal.
        let d = spread_check(&observed(2), &s);
        assert_eq!((d.covariate.as_str(), d.n), (OUTSIDE_RANGE, 20));
        assert!((d.spearman_rho - 0.1).abs() < 1e-12);
        // P(X >= 2) for Binomial(20, 0.1) = 1 - 0.9^20 - 20·0.1·0.9^19.
        let exact = 1.0 - 0.9f64.powi(20) - 20.0 * 0.1 * 0.9f64.powi(19);
        assert!((d.p_value - exact).abs() < 1e-12, "{}", d.p_value);
        // Eight of 20 outside: too narrow, p below 0.001.
        let d = spread_check(&observed(8), &s);
        assert!(d.p_value < 1e-3 && (d.spearman_rho - 0.4).abs() < 1e-12, "{d:?}");
        // None outside: p = 1.
        assert_eq!(spread_check(&observed(0), &s).p_value, 1.0);
    }
}
