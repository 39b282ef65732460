//! The five error measures of a calibrated model on a set of runs, and the floor the field scatter sets.
//!
//! Each run is simulated R times from its own release state; with `median_i` the median of its simulated run-outs,
//! `obs_i` its observed run-out:
//! - `runout_mae_m` = mean_i |median_i − obs_i|;
//! - `runout_w1_m` = 1-Wasserstein distance between all observed run-outs and all simulated ones;
//! - `endpoint_mae_m` = mean_i of the horizontal distance from the observed rest point to the coordinate-wise
//!   median of the simulated rest points;
//! - `coverage_90` = share of runs whose observed run-out lies within the 5th–95th percentiles of its simulations;
//! - `runout_bias_m` = mean simulated run-out − mean observed run-out.
//!
//! On the runs with a tracked path (none: the two are absent), the rebound height ([`super::rebound`]):
//! `rebound_mae_m` = mean |median simulated − observed rebound height| and `rebound_crps_m` its mean CRPS.
//!
//! **Scatter floor**: the `runout_mae_m` a perfect model of each release group's median would reach:
//! mean_i |obs_i − median of the observed run-outs of i's release group|, the median taken over all observed runs
//! of the group in the campaign (ours: a held-out set holds too few runs per group for its own median; the floor
//! is only a yardstick and chooses nothing).
//!
//! **Were the model right** (`runout_w1_if_right_m`, `coverage_90_if_right`, `runout_bias_if_right_m`, ours): a
//! few dozen field runs are a small sample, so even the true model shows a W1 above zero against them, and a bias:
//! the mean of n runs that scatter by σ is off by about σ/√n; and a 5–95 % interval read from R simulations holds a
//! further draw less often than 90 % of the time (about 0.9 (R − 1)/(R + 1): 0.81 for R = 20).
//! The yardsticks are the values the same runs would show were their field run-outs draws of the model itself: in
//! draw d (d = 0..R) run i's observed run-out is replaced by its simulation (d + i) mod R and compared with the
//! other R − 1 simulations (of every run for W1 and bias, of its own for coverage); the mean over the R draws, for
//! the bias the root mean square (a parametric bootstrap that needs no further simulation). A `runout_w1_m` well above its yardstick is misfit, one near it is
//! what the number of runs allows; a coverage above its yardstick means simulated ranges wider than the field's.
//! They choose nothing.

use super::model::{count_ends, not_at_rest, RunSims, SimEnd};
use super::objective::rebound_crps;
use super::runs::FieldRun;
use super::stats::{mean, median, quantile_sorted, sorted, wasserstein1};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The five measures (plus context) on one set of runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Mean |median simulated − observed run-out|, m.
    pub runout_mae_m: f64,
    /// 1-Wasserstein distance between observed and simulated run-outs, m.
    pub runout_w1_m: f64,
    /// Mean horizontal distance from observed to median simulated rest point, m.
    pub endpoint_mae_m: f64,
    /// Share of runs inside their simulated 5–95 % run-out interval.
    pub coverage_90: f64,
    /// Mean simulated − mean observed run-out, m.
    pub runout_bias_m: f64,
    /// The scatter floor of `runout_mae_m`, m.
    pub scatter_floor_mae_m: f64,
    /// The mean `runout_w1_m` these runs would show were their field run-outs draws of the model itself, m.
    pub runout_w1_if_right_m: f64,
    /// The mean `coverage_90` these runs would show were their field run-outs draws of the model itself.
    pub coverage_90_if_right: f64,
    /// The root mean square of the `runout_bias_m` these runs would show were their field run-outs draws of the
    /// model itself, m.
    pub runout_bias_if_right_m: f64,
    /// Runs measured.
    pub runs: usize,
    /// Simulations per run.
    pub repeats: usize,
    /// Mean observed run-out, m.
    pub observed_mean_m: f64,
    /// Mean simulated run-out, m.
    pub simulated_mean_m: f64,
    /// Share of simulations that did not come to rest (left the terrain or hit a time limit).
    pub not_stopped_fraction: f64,
    /// Share of simulations that left the terrain (a 2DLM profile: either end); the rest of those not at rest ran to
    /// the time limit (0 in reports before 2026-12-01).
    #[serde(default)]
    pub left_terrain_fraction: f64,
    /// Mean |median simulated − observed rebound height| over the tracked runs, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rebound_mae_m: Option<f64>,
    /// Mean CRPS of the rebound heights over the tracked runs, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rebound_crps_m: Option<f64>,
}

impl Metrics {
    /// `runout_mae_m` over the scatter floor (1 is the best any model can do on average).
    pub fn mae_over_floor(&self) -> f64 {
        if self.scatter_floor_mae_m > 0.0 {
            self.runout_mae_m / self.scatter_floor_mae_m
        } else {
            f64::NAN
        }
    }
}

/// Metrics overall and per block.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MetricsSet {
    /// All runs of the set.
    pub overall: Metrics,
    /// Per block id.
    pub by_block: BTreeMap<String, Metrics>,
}

/// The metrics of `sims` (one entry per run, indices into `runs`).
pub fn metrics(runs: &[FieldRun], sims: &[RunSims]) -> Metrics {
    let n = sims.len();
    let obs: Vec<f64> = sims.iter().map(|s| runs[s.run].runout_m).collect();
    let all: Vec<f64> = sims.iter().flat_map(|s| s.runouts()).collect();
    let mut abs_err = Vec::with_capacity(n);
    let mut end_err = Vec::with_capacity(n);
    let mut covered = 0usize;
    for s in sims {
        let r = &runs[s.run];
        abs_err.push((s.median_runout() - r.runout_m).abs());
        let [mx, my] = s.median_rest_xy();
        end_err.push((mx - r.rest_m[0]).hypot(my - r.rest_m[1]));
        if in_90_range(&sorted(&s.runouts()), r.runout_m) {
            covered += 1;
        }
    }
    let (not_stopped, _) = not_at_rest(sims);
    let (left_terrain, _) = count_ends(sims, |e| e == SimEnd::LeftTerrain);
    let which: Vec<usize> = sims.iter().map(|s| s.run).collect();
    let if_right = were_the_model_right(sims);
    let tracked: Vec<&RunSims> = sims.iter().filter(|s| runs[s.run].rebound_height_m.is_some()).collect();
    let over_tracked = |f: &dyn Fn(&RunSims) -> f64| {
        (!tracked.is_empty()).then(|| mean(&tracked.iter().map(|s| f(s)).collect::<Vec<_>>()))
    };
    Metrics {
        rebound_mae_m: over_tracked(&|s| {
            (s.median_of(|x| x.summary.rebound_height_m) - runs[s.run].rebound_height_m.unwrap_or(0.0)).abs()
        }),
        rebound_crps_m: over_tracked(&|s| rebound_crps(&runs[s.run], s).unwrap_or(0.0)),
        runout_mae_m: mean(&abs_err),
        runout_w1_m: wasserstein1(&obs, &all),
        endpoint_mae_m: mean(&end_err),
        coverage_90: if n > 0 { covered as f64 / n as f64 } else { f64::NAN },
        runout_bias_m: mean(&all) - mean(&obs),
        scatter_floor_mae_m: scatter_floor(runs, &which),
        runout_w1_if_right_m: if_right[0],
        coverage_90_if_right: if_right[1],
        runout_bias_if_right_m: if_right[2],
        runs: n,
        repeats: sims.first().map(|s| s.sims.len()).unwrap_or(0),
        observed_mean_m: mean(&obs),
        simulated_mean_m: mean(&all),
        not_stopped_fraction: share(not_stopped, all.len()),
        left_terrain_fraction: share(left_terrain, all.len()),
    }
}

/// Metrics overall and for each block.
pub fn metrics_set(runs: &[FieldRun], sims: &[RunSims]) -> MetricsSet {
    let mut blocks: BTreeMap<String, Vec<RunSims>> = BTreeMap::new();
    for s in sims {
        blocks.entry(runs[s.run].block_id.clone()).or_default().push(s.clone());
    }
    MetricsSet {
        overall: metrics(runs, sims),
        by_block: blocks.iter().map(|(b, v)| (b.clone(), metrics(runs, v))).collect(),
    }
}

/// The scatter floor of `runout_mae_m` over runs `which`: mean |obs − median obs of the run's release group (all
/// runs of the campaign)|.
pub fn scatter_floor(runs: &[FieldRun], which: &[usize]) -> f64 {
    let mut groups: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    for r in runs {
        groups.entry(r.group).or_default().push(r.runout_m);
    }
    let med: BTreeMap<usize, f64> = groups.iter().map(|(g, v)| (*g, median(v))).collect();
    mean(&which.iter().map(|&i| (runs[i].runout_m - med[&runs[i].group]).abs()).collect::<Vec<_>>())
}

/// True if `y` lies within the 5-95 % range of the ascending sample `s` (what `coverage_90` counts).
fn in_90_range(s: &[f64], y: f64) -> bool {
    y >= quantile_sorted(s, 0.05) && y <= quantile_sorted(s, 0.95)
}

/// [W1, coverage_90, RMS bias] were the model right: one simulation per run stands in for the field run (in draw d
/// run i's simulation (d + i) mod R) against the other simulations, over R draws (R the fewest simulations of a
/// run; NaN below 2). See the module's "Were the model right".
pub fn were_the_model_right(sims: &[RunSims]) -> [f64; 3] {
    let r = sims.iter().map(|s| s.sims.len()).min().unwrap_or(0);
    if r < 2 {
        return [f64::NAN; 3];
    }
    let (mut w1, mut covered, mut bias2) = (0.0, 0usize, 0.0);
    for d in 0..r {
        let (mut stand_ins, mut others) = (Vec::with_capacity(sims.len()), Vec::new());
        for (i, s) in sims.iter().enumerate() {
            let pick = (d + i) % s.sims.len();
            let stand_in = s.sims[pick].runout_m;
            let mut own: Vec<f64> =
                s.sims.iter().enumerate().filter(|&(j, _)| j != pick).map(|(_, x)| x.runout_m).collect();
            own.sort_by(f64::total_cmp);
            covered += usize::from(in_90_range(&own, stand_in));
            stand_ins.push(stand_in);
            others.extend(own);
        }
        w1 += wasserstein1(&stand_ins, &others);
        bias2 += (mean(&others) - mean(&stand_ins)).powi(2);
    }
    [w1 / r as f64, covered as f64 / (r * sims.len()) as f64, (bias2 / r as f64).sqrt()]
}

/// The continuous ranked probability score of a simulated run-out sample against the observed run-out, m (the
/// unbiased "fair" estimator: mean |x − y| − Σ_{i≠j} |x_i − x_j| / (2 n (n − 1)); Gneiting & Raftery 2007). A proper
/// score: it is smallest when the simulated distribution is the true one, so it rewards the right spread as well
/// as the right median. Lower is better.
pub fn crps(values: &[f64], y: f64) -> f64 {
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    let a = values.iter().map(|x| (x - y).abs()).sum::<f64>() / n as f64;
    if n < 2 {
        return a;
    }
    let s = super::stats::sorted(values);
    // Σ_{i<j} (x_j − x_i) over a sorted sample = Σ_k x_k (2k − n + 1).
    let pair_sum: f64 = s.iter().enumerate().map(|(k, x)| x * (2.0 * k as f64 - n as f64 + 1.0)).sum();
    a - pair_sum / (n as f64 * (n as f64 - 1.0))
}

/// The energy score of simulated rest points (x, y) against the observed one, m: the CRPS's generalisation to
/// points in the plane, with the same fair estimator, mean ‖x − y‖ − Σ_{i≠j} ‖x_i − x_j‖ / (2 n (n − 1)) (Gneiting &
/// Raftery 2007, eq. 22 with β = 1). Proper, like the CRPS; unlike a run-out score it tells a rock that stops
/// beside the observed rest point from one that stops as far from the release somewhere else. Lower is better.
pub fn energy_score(points: &[[f64; 2]], y: [f64; 2]) -> f64 {
    let n = points.len();
    if n == 0 {
        return f64::NAN;
    }
    let dist = |p: &[f64; 2], q: &[f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let a = points.iter().map(|p| dist(p, &y)).sum::<f64>() / n as f64;
    if n < 2 {
        return a;
    }
    let pair_sum: f64 =
        points.iter().enumerate().map(|(i, p)| points[i + 1..].iter().map(|q| dist(p, q)).sum::<f64>()).sum();
    a - pair_sum / (n as f64 * (n as f64 - 1.0))
}

/// Per-run CRPS of the simulated run-outs, in the order of `sims`.
pub fn run_crps(runs: &[FieldRun], sims: &[RunSims]) -> Vec<f64> {
    sims.iter().map(|s| crps(&s.runouts(), runs[s.run].runout_m)).collect()
}

/// Per-run absolute run-out error |median simulated − observed|, in the order of `sims`.
pub fn run_errors(runs: &[FieldRun], sims: &[RunSims]) -> Vec<f64> {
    sims.iter().map(|s| (s.median_runout() - runs[s.run].runout_m).abs()).collect()
}

/// `n` of `of` as a share (0 of none).
fn share(n: usize, of: usize) -> f64 {
    if of == 0 {
        0.0
    } else {
        n as f64 / of as f64
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::calibrate::model::{PathSummary, Sim};

    #[test]
    fn the_energy_score_is_the_crps_on_a_line_and_sees_a_sideways_miss() {
        let xs = [3.0, 7.5, 10.0, 12.0, 20.0];
        let on_line: Vec<[f64; 2]> = xs.iter().map(|&x| [x, 0.0]).collect();
        assert!((energy_score(&on_line, [9.0, 0.0]) - crps(&xs, 9.0)).abs() < 1e-12);
        assert_eq!(energy_score(&[[3.0, 4.0]], [0.0, 0.0]), 5.0);
        assert_eq!(energy_score(&[[1.0, 1.0], [1.0, 1.0]], [1.0, 1.0]), 0.0);
        // Rocks stopping as far from a release at the origin as the observed rock (10 m) but 90° round from it
        // score like a miss by 14.1 m; the run-out CRPS cannot see it.
        let sideways = [[0.0, 10.0], [0.0, 10.0]];
        assert!((energy_score(&sideways, [10.0, 0.0]) - 200f64.sqrt()).abs() < 1e-12);
        assert_eq!(crps(&[10.0, 10.0], 10.0), 0.0);
    }

    /// A run of block `b{group}` released at the origin that came to rest `obs` m along x (shared by tests).
    pub(crate) fn run(i: usize, group: usize, obs: f64) -> FieldRun {
        FieldRun {
            id: format!("r{i}"),
            index: i,
            block_id: format!("b{group}"),
            mass_kg: 10.0,
            size_m: [0.3, 0.2, 0.1],
            release_m: [0.0; 3],
            velocity_mps: [0.0; 3],
            spin_radps: [0.0; 3],
            rest_m: [obs, 0.0, 0.0],
            runout_m: obs,
            group,
            ..Default::default()
        }
    }

    /// Simulations of `run` ending at `values` along x (shared by tests).
    pub(crate) fn sims(run: usize, values: &[f64]) -> RunSims {
        RunSims {
            run,
            sims: values
                .iter()
                .map(|&v| Sim {
                    runout_m: v,
                    rest_m: [v, 0.0, 0.0],
                    end: super::super::model::SimEnd::Rest,
                    summary: PathSummary::default(),
                    path: vec![],
                })
                .collect(),
        }
    }

    #[test]
    fn metrics_match_hand_computation() {
        let runs = vec![run(0, 0, 10.0), run(1, 0, 14.0), run(2, 1, 20.0)];
        let s = vec![sims(0, &[9.0, 11.0, 12.0]), sims(1, &[9.0, 11.0, 12.0]), sims(2, &[30.0, 31.0, 32.0])];
        let m = metrics(&runs, &s);
        assert!((m.runout_mae_m - (1.0 + 3.0 + 11.0) / 3.0).abs() < 1e-12);
        assert!((m.endpoint_mae_m - m.runout_mae_m).abs() < 1e-12);
        // 5-95 % of [9, 11, 12] (linear interpolation) is [9.2, 11.9]: 10 lies inside, 14 and 20 outside.
        assert!((m.coverage_90 - 1.0 / 3.0).abs() < 1e-12);
        let sim_mean = (9.0 + 11.0 + 12.0) * 2.0 / 9.0 + 31.0 / 3.0;
        assert!((m.runout_bias_m - (sim_mean - 44.0 / 3.0)).abs() < 1e-12);
        // Group 0 median 12: |10−12| + |14−12| = 4; group 1 alone adds 0.
        assert!((m.scatter_floor_mae_m - 4.0 / 3.0).abs() < 1e-12);
        // A subset still uses the whole group's median.
        assert!((scatter_floor(&runs, &[0]) - 2.0).abs() < 1e-12);
        // CRPS: a point forecast reduces to the absolute error; a sample's own spread is credited.
        assert!((crps(&[3.0, 3.0], 5.0) - 2.0).abs() < 1e-12);
        assert!((crps(&[0.0, 2.0], 1.0) - 0.0).abs() < 1e-12);
        // W1 were the model right: the stand-ins (9, 11, 32), (11, 12, 30), (12, 9, 31) against each run's other
        // two simulations give W1 7/6, 4/3 and 5/6 (by hand, from the two step functions); the field runs play no part.
        assert!((m.runout_w1_if_right_m - 10.0 / 9.0).abs() < 1e-12, "{m:?}");
        // Coverage: each stand-in against the 5-95 % of its run's other two; 11 in [9.15, 11.85] (run 0, and run 1
        // in its first draw) and 31 in [30.1, 31.9] are inside, the other six outside.
        assert!((m.coverage_90_if_right - 1.0 / 3.0).abs() < 1e-12, "{m:?}");
        // Bias: the others' mean less the stand-ins', 105/6 − 52/3 = 1/6, 104/6 − 53/3 = −1/3 and 1/6: RMS √(1/18).
        assert!((m.runout_bias_if_right_m - (1.0f64 / 18.0).sqrt()).abs() < 1e-12, "{m:?}");
        let set = metrics_set(&runs, &s);
        assert_eq!(set.by_block.len(), 2);
        assert!((set.by_block["b1"].runout_mae_m - 11.0).abs() < 1e-12);
    }

    #[test]
    fn field_runs_drawn_from_the_model_show_the_w1_the_model_expects_and_shifted_ones_do_not() {
        use crate::random::{standard_normal, stream};
        // 30 runs, each simulated 20 times as N(100 + 2 i, 15²) m, and field runs drawn once from the same
        // distributions; then the field runs moved 20 m. Over seeds 1..=20 (over 200 seeds: W1 / W1-if-right
        // 0.99 on average, at most 1.99; moved, at least 2.45; coverage 0.817 on average, if right 0.815, from
        // 0.805 to 0.828, where 0.9 (R - 1)/(R + 1) = 0.814).
        let (n, r) = (30, 20);
        let (mut ratios, mut coverage, mut coverage_if_right) = (Vec::new(), Vec::new(), Vec::new());
        let (mut biases, mut bias_yardsticks) = (Vec::new(), Vec::new());
        for seed in 1..=20 {
            let mut rng = stream(seed, 0);
            let mut draw = |i: usize| 100.0 + 2.0 * i as f64 + 15.0 * standard_normal(&mut rng);
            let s: Vec<RunSims> = (0..n).map(|i| sims(i, &(0..r).map(|_| draw(i)).collect::<Vec<_>>())).collect();
            let same: Vec<FieldRun> = (0..n).map(|i| run(i, i, draw(i))).collect();
            let m = metrics(&same, &s);
            // 30 draws of sd ≈ 15-23 m are a small sample: even the true model shows a W1 of a few metres.
            assert!((3.0..6.0).contains(&m.runout_w1_if_right_m), "{m:?}");
            // and a bias of about 15 m / √30 = 2.7 m.
            assert!((1.5..4.5).contains(&m.runout_bias_if_right_m), "{m:?}");
            biases.push(m.runout_bias_m);
            bias_yardsticks.push(m.runout_bias_if_right_m);
            ratios.push(m.runout_w1_m / m.runout_w1_if_right_m);
            coverage.push(m.coverage_90);
            coverage_if_right.push(m.coverage_90_if_right);
            let moved: Vec<FieldRun> = same.iter().map(|f| run(f.index, f.group, f.runout_m + 20.0)).collect();
            let shifted = metrics(&moved, &s);
            assert_eq!(shifted.runout_w1_if_right_m, m.runout_w1_if_right_m);
            assert!(shifted.runout_w1_m > 2.3 * m.runout_w1_if_right_m, "{shifted:?}");
        }
        let mean_ratio = mean(&ratios);
        assert!((0.85..1.15).contains(&mean_ratio), "{ratios:?}");
        assert!(ratios.iter().all(|&x| x < 2.2), "{ratios:?}");
        // The field runs' biases scatter as the yardstick says.
        let rms_bias = (biases.iter().map(|b| b * b).sum::<f64>() / biases.len() as f64).sqrt();
        let mean_if_right = mean(&bias_yardsticks);
        // Over seeds 1..=20: RMS bias 2.92 m against the yardsticks' mean 2.76 m (2.09 to 3.51).
        assert!((0.8..1.25).contains(&(rms_bias / mean_if_right)), "{rms_bias} {mean_if_right}");
        // A 5-95 % interval of 20 simulations holds about 81 % of further draws, not 90 %.
        assert!(coverage_if_right.iter().all(|c| (0.79..0.84).contains(c)), "{coverage_if_right:?}");
        assert!((mean(&coverage) - mean(&coverage_if_right)).abs() < 0.04, "{coverage:?}");
    }
}
