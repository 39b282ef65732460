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
//!
//! **Tracked bounces** (ours; 2DLM by default, 3DRB on request): a tracked run whose track shows bounces with a
//! tangential restitution adds `bounce_weight` times the mean over them of the CRPS of the tangential restitutions
//! of the run's simulated bounces, read as the track was, against each ([`bounce_crps`]); the default weight is
//! again the ratio of the observed spreads ([`default_bounce_weight`]). In the lumped-mass model that ratio is Rt:
//! run-outs alone trade Rt against the friction angle, the bounces do not (docs/calibration.md, "Bounces in the
//! score").

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
    let base = objective_of(cfg.objective, runs, sims);
    if !tracks_scored(cfg) || sims.is_empty() {
        return base;
    }
    base + sims.iter().map(|s| track_score(cfg, &runs[s.run], s)).sum::<f64>() / sims.len() as f64
}

/// True if the settings score anything of the tracks.
fn tracks_scored(cfg: &CalibrationConfig) -> bool {
    cfg.rebound_weight.unwrap_or(0.0) > 0.0 || cfg.bounce_weight.unwrap_or(0.0) > 0.0
}

/// What a tracked run's track adds to its score: `rebound_weight` times its rebound CRPS plus `bounce_weight`
/// times its bounce CRPS, m (0 for a run without a track).
fn track_score(cfg: &CalibrationConfig, run: &FieldRun, s: &RunSims) -> f64 {
    let weighted = |w: Option<f64>, c: Option<f64>| match (w.unwrap_or(0.0), c) {
        (w, Some(c)) if w > 0.0 => w * c,
        _ => 0.0,
    };
    weighted(cfg.rebound_weight, rebound_crps(run, s)) + weighted(cfg.bounce_weight, bounce_crps(run, s))
}

/// One run's error in the effects loop: the CRPS of its run-out plus what its track adds ([`score`]), m.
pub fn run_score(cfg: &CalibrationConfig, run: &FieldRun, s: &RunSims) -> f64 {
    crps(&s.runouts(), run.runout_m) + track_score(cfg, run, s)
}

/// The bounce score of a tracked run (ours): the mean over the bounces its track shows with a tangential
/// restitution of the CRPS of the tangential restitutions of its simulated paths' bounces, read as the track was
/// ([`super::impacts::read_as_tracked`]), against the observed one; a run whose simulated paths show no such
/// bounce scores as if they all read 0 (the speed along the ground lost). Averaged, as a run's rebound height is one
/// figure: a run's bounces count once beside its run-out. `None` for a run without such a bounce.
pub fn bounce_crps(run: &FieldRun, s: &RunSims) -> Option<f64> {
    let observed: Vec<f64> = run.impacts.iter().filter_map(|i| i.tangential_restitution).collect();
    if observed.is_empty() {
        return None;
    }
    let mut simulated: Vec<f64> =
        s.sims.iter().flat_map(|x| x.summary.tangential_restitutions.iter().copied()).collect();
    if simulated.is_empty() {
        simulated.push(0.0);
    }
    Some(mean(&observed.iter().map(|&o| crps(&simulated, o)).collect::<Vec<_>>()))
}

/// The default bounce weight on calibration runs `which`: the mean absolute deviation from the median of their
/// observed run-outs over that of the tangential restitutions of their tracks' bounces (as for rebound heights);
/// `None` with fewer than [`super::measured::MIN_BOUNCES_MEASURED`] such bounces or no spread.
pub fn default_bounce_weight(runs: &[FieldRun], which: &[usize]) -> Option<f64> {
    let et: Vec<f64> = which.iter().flat_map(|&i| &runs[i].impacts).filter_map(|i| i.tangential_restitution).collect();
    let all: Vec<f64> = which.iter().map(|&i| runs[i].runout_m).collect();
    let spread = mean_absolute_deviation(&et);
    (et.len() >= super::measured::MIN_BOUNCES_MEASURED && spread > 0.0).then(|| mean_absolute_deviation(&all) / spread)
}

/// Mean absolute deviation from the median.
fn mean_absolute_deviation(v: &[f64]) -> f64 {
    let m = median(v);
    mean(&v.iter().map(|x| (x - m).abs()).collect::<Vec<_>>())
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
    let mad = |v: Vec<f64>| mean_absolute_deviation(&v);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::impacts::Impact;
    use crate::calibrate::metrics::tests::{run, sims};

    fn bounce(tangential_restitution: Option<f64>) -> Impact {
        Impact {
            time_s: 1.0,
            point: 10,
            position_m: [0.0; 3],
            normal_speed_in_mps: 5.0,
            tangential_speed_in_mps: 3.0,
            incidence_deg: 40.0,
            normal_restitution: 0.5,
            tangential_restitution,
        }
    }

    #[test]
    fn a_runs_bounces_count_once_beside_its_run_out() {
        let mut r = run(0, 0, 10.0);
        let mut s = sims(0, &[10.0, 10.0]);
        assert_eq!(bounce_crps(&r, &s), None, "no track, no score");
        r.impacts = vec![bounce(Some(0.8)), bounce(None), bounce(Some(0.6))];
        // No simulated bounce: read as restitution 0, each observed bounce scores its own value.
        assert!((bounce_crps(&r, &s).unwrap() - 0.7).abs() < 1e-12);
        // Sharp simulated bounces at 0.7: the mean of |0.8 − 0.7| and |0.6 − 0.7|.
        for x in &mut s.sims {
            x.summary.tangential_restitutions = vec![0.7];
        }
        assert!((bounce_crps(&r, &s).unwrap() - 0.1).abs() < 1e-12);
        // Weighted into the run's score beside its run-out CRPS (0 here), off at weight 0.
        let cfg = CalibrationConfig { bounce_weight: Some(10.0), rebound_weight: Some(0.0), ..Default::default() };
        assert!((run_score(&cfg, &r, &s) - 1.0).abs() < 1e-9);
        assert!((score(&cfg, std::slice::from_ref(&r), std::slice::from_ref(&s)) - 1.0).abs() < 1e-9);
        let off = CalibrationConfig { bounce_weight: Some(0.0), ..cfg };
        assert_eq!(run_score(&off, &r, &s), 0.0);
    }
}
