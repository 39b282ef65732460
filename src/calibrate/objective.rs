//! What the population fit minimises. By default the mean over runs of the continuous ranked probability score of
//! each run's simulated run-outs against its observed run-out (Gneiting & Raftery 2007): a proper score, so it is
//! smallest for the right predictive distribution of every run, median and spread together, and it is the score
//! the effects loop cross-validates, so that a refit never undoes what the cross-validation credited (ours). The
//! 1-Wasserstein distance per release group (physics.md §5), the energy score of the rest points (the CRPS in the
//! plane) and the run-out MAE are the alternatives.
//!
//! **Tracked runs** (ours): where a campaign has tracked paths, what is minimised is the [`score`]: the objective
//! plus, for each tracked run, its rebound height's CRPS ([`super::rebound`]) times the rebound weight (metres of
//! run-out per metre of rebound). By default the weight is the ratio of the observed spreads on the calibration runs
//! (mean absolute deviation from the median of the run-outs over that of the rebound heights,
//! [`default_rebound_weight`]), so each measurement counts in proportion to its own scatter. Run-outs alone cannot
//! tell an effect that kills the bounce of fast impacts from a lower restitution everywhere; the rebound heights
//! can (docs/calibration.md).

use super::config::{CalibrationConfig, Objective};
use super::metrics::crps;
use super::model::RunSims;
use super::runs::FieldRun;
use super::stats::{mean, median, wasserstein1};
use std::collections::BTreeMap;

/// What the fit and the effects loop minimise on `sims` (indices into `runs`): the objective plus the tracked runs'
/// weighted rebound CRPS, summed and divided by all runs scored. Lower is better.
pub fn score(cfg: &CalibrationConfig, runs: &[FieldRun], sims: &[RunSims]) -> f64 {
    score_of(cfg, runs, &sims.iter().collect::<Vec<_>>())
}

/// [`score`] of a selection of runs' simulations.
pub fn score_of(cfg: &CalibrationConfig, runs: &[FieldRun], sims: &[&RunSims]) -> f64 {
    let w = cfg.rebound_weight.unwrap_or(0.0);
    let base = objective_of(cfg.objective, runs, sims);
    if w == 0.0 || sims.is_empty() {
        return base;
    }
    base + w * sims.iter().filter_map(|s| rebound_crps(&runs[s.run], s)).sum::<f64>() / sims.len() as f64
}

/// One run's error in the effects loop: the CRPS of its run-out plus, if it was tracked, `rebound_weight` times the
/// CRPS of its rebound height, m.
pub fn run_score(rebound_weight: f64, run: &FieldRun, s: &RunSims) -> f64 {
    crps(&s.runouts(), run.runout_m) + rebound_crps(run, s).map_or(0.0, |c| rebound_weight * c)
}

/// The CRPS of a tracked run's simulated rebound heights against its observed one, m (`None` if not tracked).
pub fn rebound_crps(run: &FieldRun, s: &RunSims) -> Option<f64> {
    run.rebound_height_m.map(|obs| crps(&s.rebound_heights(), obs))
}

/// The default rebound weight on calibration runs `which`: the mean absolute deviation from the median of their
/// observed run-outs over that of their observed rebound heights, both on the tracked runs; `None` with fewer than
/// three tracked runs or no spread of rebound heights.
pub fn default_rebound_weight(runs: &[FieldRun], which: &[usize]) -> Option<f64> {
    let tracked: Vec<&FieldRun> = which.iter().map(|&i| &runs[i]).filter(|r| r.rebound_height_m.is_some()).collect();
    let mad = |v: Vec<f64>| {
        let m = median(&v);
        mean(&v.iter().map(|x| (x - m).abs()).collect::<Vec<_>>())
    };
    let rebound = mad(tracked.iter().filter_map(|r| r.rebound_height_m).collect());
    (tracked.len() >= 3 && rebound > 0.0).then(|| mad(tracked.iter().map(|r| r.runout_m).collect()) / rebound)
}

/// The objective value of `sims` (indices into `runs`); lower is better.
pub fn objective(kind: Objective, runs: &[FieldRun], sims: &[RunSims]) -> f64 {
    objective_of(kind, runs, &sims.iter().collect::<Vec<_>>())
}

/// [`objective`] of a selection of runs' simulations.
pub fn objective_of(kind: Objective, runs: &[FieldRun], sims: &[&RunSims]) -> f64 {
    match kind {
        Objective::W1 => {
            let obs: Vec<f64> = sims.iter().map(|s| runs[s.run].runout_m).collect();
            let all: Vec<f64> = sims.iter().flat_map(|s| s.runouts()).collect();
            wasserstein1(&obs, &all)
        }
        Objective::Mae => {
            mean(&sims.iter().map(|s| (s.median_runout() - runs[s.run].runout_m).abs()).collect::<Vec<_>>())
        }
        Objective::Crps => mean(&sims.iter().map(|s| crps(&s.runouts(), runs[s.run].runout_m)).collect::<Vec<_>>()),
        Objective::CrpsW1Groups => {
            0.5 * (objective_of(Objective::Crps, runs, sims) + objective_of(Objective::W1Groups, runs, sims))
        }
        Objective::EnergyRest => mean(
            &sims
                .iter()
                .map(|s| {
                    let rests: Vec<[f64; 2]> = s.sims.iter().map(|x| [x.rest_m[0], x.rest_m[1]]).collect();
                    let r = &runs[s.run].rest_m;
                    super::metrics::energy_score(&rests, [r[0], r[1]])
                })
                .collect::<Vec<_>>(),
        ),
        Objective::EnergyW1Groups => {
            0.5 * (objective_of(Objective::EnergyRest, runs, sims) + objective_of(Objective::W1Groups, runs, sims))
        }
        Objective::W1Groups => {
            let mut groups: BTreeMap<usize, (Vec<f64>, Vec<f64>)> = BTreeMap::new();
            for s in sims {
                let e = groups.entry(runs[s.run].group).or_default();
                e.0.push(runs[s.run].runout_m);
                e.1.extend(s.runouts());
            }
            let n: usize = groups.values().map(|g| g.0.len()).sum();
            groups.values().map(|(o, s)| o.len() as f64 * wasserstein1(o, s)).sum::<f64>() / n.max(1) as f64
        }
    }
}
