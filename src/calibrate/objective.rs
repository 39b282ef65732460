//! What the population fit minimises. By default the mean over runs of the continuous ranked probability score of
//! each run's simulated run-outs against its observed run-out (Gneiting & Raftery 2007): a proper score, so it is
//! smallest for the right predictive distribution of every run, median and spread together, and it is the score
//! the effects loop cross-validates, so that a refit never undoes what the cross-validation credited (ours). The
//! 1-Wasserstein distance per release group (physics.md §5), the energy score of the rest points (the CRPS in the
//! plane) and the run-out MAE are the alternatives.

use super::config::Objective;
use super::model::RunSims;
use super::runs::FieldRun;
use super::stats::{mean, wasserstein1};
use std::collections::BTreeMap;

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
        Objective::Crps => {
            mean(&sims.iter().map(|s| super::metrics::crps(&s.runouts(), runs[s.run].runout_m)).collect::<Vec<_>>())
        }
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
