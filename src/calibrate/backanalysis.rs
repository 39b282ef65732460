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
//!
//! **How sharply the runs pin a parameter** (ours): the same simulations give, at each grid value, the campaign's mean
//! score (each run's run-out CRPS plus what its track adds, as the effects loop scores it). The grid values whose mean
//! score exceeds the lowest one's by no more than d standard errors of the difference (paired over the runs, on common
//! random numbers) are ones the calibration runs cannot tell from the best: the band, reported as the range of those
//! values (`as_good`) and the values inside it that are out ("0.000 to 0.300 but not 0.200"). d is the
//! Bonferroni form of Hsu's multiple comparisons with the best (J. C. Hsu, "Constrained simultaneous confidence
//! intervals for multiple comparisons with the best", Annals of Statistics 12, 1984): a value is compared with the best
//! of the k − 1 others, so d = Φ⁻¹(1 − 0.05/(k − 1)), 2.39 on a 7-value grid, and the band holds the best grid value
//! with 95 % confidence. (Two standard errors until stop 75: over 100 seeds of each synthetic 2DLM control the truth's
//! grid value fell outside it in up to 9 % of them; docs/calibration.md, "Bands that hold the truth".) A band holding
//! every grid value says the data leave that parameter open, whatever value the population fit reports. With
//! `[back_analysis] refit_evaluations` above 0 (the 2DLM default, 100) the other free parameters are fitted again at
//! each grid value (from the population fit, on the population fit's random numbers), so the band follows their
//! trade-offs, as a profile likelihood does; at 0 (the 3DRB default: a 3DRB evaluation costs seconds, and the refits
//! would cost a population fit per grid value) they are held at the population fit, and where parameters trade off the
//! runs leave more open jointly than the bands say. The per-run values are always found with the others held. On 3DRB a
//! change of Cr of 10⁻⁴ already decorrelates part of the simulated paths (a rigid body's bounces are chaotic), so the
//! population fit's last steps there follow noise: docs/calibration.md, "How sharply the runs pin the parameters".
//!
//! A spread between rocks (`cr_sd`, `dynamic_friction_sd_deg`, `rn_sd`, …) has no per-run value (one run-out does
//! not measure a spread), but it gets the same profile (ours): the runs' scores are CRPS, which a spread too wide or
//! too narrow raises, so its band says how far the runs pin the spread as well.
//!
//! **Scored on fresh numbers** (ours, since stop 74): the grid's simulations use streams that neither the population
//! fit nor a refit chose anything on (common to every grid value, so the differences stay paired). On the fit's own
//! numbers a value near the fit, or one whose others were refitted on them, looks better than it is by the luck the
//! fit found there (the winner's curse that the population fit's choice between searches avoids the same way,
//! `fit.rs`). The population fit is scored on the same numbers, and each profile gives its excess over the lowest
//! grid value with the paired standard error: within d for one more candidate (Φ⁻¹(1 − 0.05/k), the fit against
//! the best of the k grid values), the fit is in its own band by the rule that makes the band; outside, the search
//! stopped short of the valley, its own numbers flattered it, or these numbers are unlucky for it (docs/calibration.md,
//! "Bands on fresh numbers").

use super::fit::Context;
use super::model::RunSims;
use super::objective::run_score;
use super::params::{Candidate, FreeParam};
use super::stats::{mean, normal_quantile, paired_excess, sample_sd};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::atomic::Ordering;

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
    /// The campaign's score along the grid (see the module notes); none where no grid value could be simulated.
    #[serde(default)]
    pub profile: Option<Profile>,
}

/// The profile of a spread between rocks, which has no per-run value (see the module notes).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpreadProfile {
    /// Material (or zone).
    pub material: String,
    /// Parameter.
    pub parameter: String,
    /// Population fit value.
    pub population: f64,
    /// The campaign's score along the grid; none where no grid value could be simulated.
    pub profile: Option<Profile>,
}

/// The per-run rows of the location parameters and the profiles of the spreads.
#[derive(Debug, Clone, Default)]
pub struct BackAnalysis {
    /// One row per location parameter.
    pub rows: Vec<BackAnalysisRow>,
    /// One profile per spread between rocks.
    pub spreads: Vec<SpreadProfile>,
}

/// The calibration runs' mean score along a parameter's grid, the others at the population fit or fitted again
/// at each value (`others_refit_evaluations`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Profile {
    /// The grid values.
    pub values: Vec<f64>,
    /// Each value's mean over the runs of their score, m.
    pub score_m: Vec<f64>,
    /// Each value's mean score less the lowest one's, m.
    pub excess_m: Vec<f64>,
    /// The standard error of that difference, paired over the runs, m.
    pub excess_se_m: Vec<f64>,
    /// The lowest and highest grid values whose excess is within `band_critical_se` standard errors: values the
    /// runs cannot tell from the best (a value between them can be out: [`Profile::gaps`]).
    pub as_good: [f64; 2],
    /// The standard errors an excess may reach within the band: [`best_critical`] of the other grid values (2 in
    /// reports before stop 75).
    #[serde(default = "two")]
    pub band_critical_se: f64,
    /// The evaluations that fitted the other free parameters again at each grid value (0: held at the population
    /// fit).
    #[serde(default)]
    pub others_refit_evaluations: usize,
    /// The population fit's own mean score on the grid's random numbers less the lowest grid value's, m (none if it
    /// could not be simulated): within `population_critical_se` standard errors, the fit is in its own band.
    #[serde(default)]
    pub population_excess_m: Option<f64>,
    /// The standard error of that difference, paired over the runs, m.
    #[serde(default)]
    pub population_excess_se_m: Option<f64>,
    /// The standard errors the fit's excess may reach within the band: [`best_critical`] of the grid values (2 in
    /// reports before stop 75).
    #[serde(default = "two")]
    pub population_critical_se: f64,
}

/// What reports before stop 75 used for both critical values.
fn two() -> f64 {
    2.0
}

/// The one-sided level of the comparisons with the best.
pub const BAND_ALPHA: f64 = 0.05;

/// The standard errors by which a candidate may exceed the best of `comparisons` others and still be as good: the
/// Bonferroni bound of Hsu's multiple comparisons with the best, Φ⁻¹(1 − α/comparisons) with α = [`BAND_ALPHA`]
/// (1.64 for one comparison, 2.39 for six, 2.45 for seven; see the module notes).
pub fn best_critical(comparisons: usize) -> f64 {
    normal_quantile(1.0 - BAND_ALPHA / comparisons.max(1) as f64)
}

/// Is an excess of `excess_m` with standard error `se_m` within `critical_se` standard errors of the best?
fn within(excess_m: f64, se_m: f64, critical_se: f64) -> bool {
    excess_m <= critical_se * se_m
}

impl Profile {
    /// Whether each grid value is in the band (as good as the best).
    fn in_band(&self) -> impl Iterator<Item = bool> + '_ {
        self.excess_m.iter().zip(&self.excess_se_m).map(|(&e, &se)| within(e, se, self.band_critical_se))
    }

    /// Is every grid value in the band (the runs leave the parameter open)?
    pub fn is_open(&self) -> bool {
        self.in_band().all(|b| b)
    }

    /// The grid values between the band's lowest and highest that are not in it. The band is a set of grid values:
    /// a neighbour of the best, its paths close to the best's, can be told apart by a smaller excess than a far value
    /// whose paths differ, and noise can put any value out.
    pub fn gaps(&self) -> Vec<f64> {
        let [lo, hi] = self.as_good;
        (self.values.iter().zip(self.in_band())).filter(|&(&v, b)| !b && v > lo && v < hi).map(|(&v, _)| v).collect()
    }

    /// Is the population fit within its band (its excess within `population_critical_se` standard errors)? None if
    /// it could not be simulated.
    pub fn population_within(&self) -> Option<bool> {
        Some(within(self.population_excess_m?, self.population_excess_se_m?, self.population_critical_se))
    }

    /// The values as good as the best, in words: "0.300 to 0.550 of 7 values across 0.050-0.800", "0.000 to 0.300
    /// but not 0.200 of …", "only 0.300 of …", "all 7 values across …: the runs leave it open", followed by the
    /// population fit against them ("; the population fit +0.31 ± 0.45 m against the lowest (within its band)";
    /// nothing if it could not be simulated).
    pub fn describe(&self) -> String {
        let (lo, hi, n) = (self.values[0], self.values[self.values.len() - 1], self.values.len());
        let across = format!("{n} values across {lo:.3}-{hi:.3}");
        let gaps: Vec<String> = self.gaps().iter().map(|v| format!("{v:.3}")).collect();
        let but_not = if gaps.is_empty() { String::new() } else { format!(" but not {}", gaps.join(", ")) };
        let band = match self.as_good {
            _ if self.is_open() => format!("all {across}: the runs leave it open"),
            [a, b] if a == b => format!("only {a:.3} of {across}"),
            [a, b] => format!("{a:.3} to {b:.3}{but_not} of {across}"),
        };
        band + &self.describe_population()
    }

    /// The population fit against the lowest grid value, in words ("; the population fit +0.31 ± 0.45 m against
    /// the lowest (within its band)"); empty if it could not be simulated.
    fn describe_population(&self) -> String {
        let (Some(e), Some(se)) = (self.population_excess_m, self.population_excess_se_m) else { return String::new() };
        let within = if self.population_within() == Some(true) { "within its band" } else { "outside its band" };
        let e = if e.abs() < 0.005 { 0.0 } else { e }; // "+0.00", not "-0.00"
        format!("; the population fit {e:+.2} ± {se:.2} m against the lowest ({within})")
    }
}

/// The profile of `scores[k][j]`, the score of run j at grid value `values[k]` (ascending; values that could not be
/// simulated hold NaN scores and are left out), the others fitted again with `refit_evaluations` at each value (0:
/// held), with the population fit's scores `fitted[j]` on the same numbers compared to the lowest; none if no value
/// has scores or there are no runs.
pub fn profile(values: &[f64], scores: &[Vec<f64>], refit_evaluations: usize, fitted: &[f64]) -> Option<Profile> {
    let ok: Vec<usize> = (0..values.len()).filter(|&k| scores[k].iter().all(|v| v.is_finite())).collect();
    let score_m: Vec<f64> = ok.iter().map(|&k| mean(&scores[k])).collect();
    let best = (0..ok.len()).min_by(|&a, &b| score_m[a].total_cmp(&score_m[b]))?;
    let (excess_m, excess_se_m): (Vec<f64>, Vec<f64>) =
        ok.iter().map(|&k| paired_excess(&scores[k], &scores[ok[best]])).unzip();
    // The best value qualifies (excess 0) whenever there are runs; the values ascend.
    let band_critical_se = best_critical(ok.len() - 1);
    let as_good: Vec<f64> = (0..ok.len())
        .filter(|&i| within(excess_m[i], excess_se_m[i], band_critical_se))
        .map(|i| values[ok[i]])
        .collect();
    let lowest = &scores[ok[best]];
    let population =
        (fitted.len() == lowest.len() && fitted.iter().all(|v| v.is_finite())).then(|| paired_excess(fitted, lowest));
    Some(Profile {
        values: ok.iter().map(|&k| values[k]).collect(),
        score_m,
        excess_m,
        excess_se_m,
        as_good: [*as_good.first()?, *as_good.last()?],
        band_critical_se,
        others_refit_evaluations: refit_evaluations,
        population_excess_m: population.map(|p| p.0),
        population_excess_se_m: population.map(|p| p.1),
        population_critical_se: best_critical(ok.len()),
    })
}

/// `c` with the `others` fitted again on runs `which` within `evaluations` (from their values in `c`, on the
/// calibration's common random numbers), quietly: the simulations are counted in `ctx`, the progress is not logged.
fn refit_others(ctx: &Context, c: &Candidate, others: &[FreeParam], which: &[usize], evaluations: usize) -> Candidate {
    let quiet = Context::new(ctx.model, ctx.cfg, &|_| {});
    let (fitted, _) = super::fit::fit(&quiet, c, others, which, evaluations, "", ctx.cfg.seed);
    ctx.simulations.fetch_add(quiet.simulations.load(Ordering::Relaxed), Ordering::Relaxed);
    fitted
}

/// `f` of each run's simulations, or NaN for each of the `n` runs where they could not be made.
fn per_run(sims: &crate::Result<Vec<RunSims>>, n: usize, f: impl Fn(&RunSims) -> f64) -> Vec<f64> {
    match sims {
        Ok(s) => s.iter().map(f).collect(),
        Err(_) => vec![f64::NAN; n],
    }
}

/// The streams of the back-analysis's simulations: an offset from the seed that neither the population fit's searches
/// (`seed + k`, k < 10) nor its choice between them use, so no grid value is scored on numbers it was fitted on.
pub const BAND_SEED_OFFSET: u64 = 0xba2d_5eed;

/// Is this a parameter the per-run back-analysis fits (locations, not spreads between rocks such as `cr_sd` or
/// `dynamic_friction_sd_deg`; the slope roughness `roughness_sd_deg` moves a run's median, so it counts)?
pub fn is_location(name: &str) -> bool {
    !(name.ends_with("_sd") || name.ends_with("friction_sd_deg"))
}

/// Back-analyses every free location parameter of `base` on runs `which` and profiles every free spread.
pub fn back_analyse(ctx: &Context, base: &Candidate, free: &[FreeParam], which: &[usize]) -> BackAnalysis {
    let runs = ctx.model.runs();
    let g = ctx.cfg.back_analysis.grid_points;
    let repeats = ctx.cfg.back_analysis.repeats.unwrap_or(ctx.cfg.search_repeats);
    let refit = ctx.cfg.profile_refit_evaluations(ctx.model.kind());
    let band_seed = ctx.cfg.seed.wrapping_add(BAND_SEED_OFFSET);
    let mut out = BackAnalysis::default();
    let score = |r: &RunSims| run_score(ctx.cfg, &runs[r.run], r);
    let profiled: Vec<&FreeParam> = free.iter().filter(|p| p.name.contains('.')).collect();
    // The population fit on the grid's numbers, which every profile compares with its lowest value.
    let fitted: Vec<f64> = if profiled.is_empty() {
        Vec::new()
    } else {
        per_run(&ctx.sims_seeded(base, which, 0..repeats, band_seed), which.len(), score)
    };
    for p in profiled {
        let (material, parameter) = p.name.split_once('.').unwrap_or(("", &p.name));
        let location = is_location(&p.name);
        let others: Vec<FreeParam> = free.iter().filter(|q| q.name != p.name).cloned().collect();
        let refitted = if others.is_empty() { 0 } else { refit };
        let what = if location { "back-analysis" } else { "profile" };
        let how = if refitted == 0 {
            String::new()
        } else {
            // At most: the held simulations, the refit's evaluations and its best candidate's, at each value.
            let sims = g * which.len() * (repeats * 2 + refitted * ctx.cfg.search_repeats);
            format!(", the others fitted again at each value{}", ctx.time_for(sims))
        };
        (ctx.log)(&format!("{what} of {}{how}", p.name));
        let grid: Vec<f64> = (0..g).map(|k| p.min + (p.max - p.min) * k as f64 / (g - 1) as f64).collect();
        // medians[k][j], scores[k][j]: median run-out and score of run which[j] at grid value k.
        let (mut medians, mut scores) = (Vec::with_capacity(g), Vec::with_capacity(g));
        for &v in &grid {
            let mut c = base.clone();
            c.params.set(p.name.clone(), v);
            super::params::normalize(&mut c.params);
            // The others held: for the per-run values, and for the band unless they are fitted again.
            let held = (location || refitted == 0).then(|| ctx.sims_seeded(&c, which, 0..repeats, band_seed));
            if let (true, Some(sims)) = (location, &held) {
                medians.push(per_run(sims, which.len(), RunSims::median_runout));
            }
            let sims = match held {
                Some(sims) if refitted == 0 => sims,
                _ => ctx.sims_seeded(&refit_others(ctx, &c, &others, which, refitted), which, 0..repeats, band_seed),
            };
            scores.push(per_run(&sims, which.len(), score));
        }
        let population = base.params.get_or(&p.name, f64::NAN);
        let profile = profile(&grid, &scores, refitted, &fitted);
        if let Some(pr) = &profile {
            (ctx.log)(&format!(
                "{}: the calibration runs' mean score is as good as the best at {}",
                p.name,
                pr.describe()
            ));
        }
        if !location {
            out.spreads.push(SpreadProfile {
                material: material.to_string(),
                parameter: parameter.to_string(),
                population,
                profile,
            });
            continue;
        }
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
        out.rows.push(BackAnalysisRow {
            material: material.to_string(),
            parameter: parameter.to_string(),
            population,
            all: spread(&values),
            censored,
            by_block: by_block.iter().map(|(b, v)| (b.clone(), spread(v))).collect(),
            profile,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::profile;

    #[test]
    fn the_profile_keeps_the_values_the_runs_cannot_tell_from_the_best() {
        let values = [0.0, 0.5, 1.0, 1.5];
        // Three runs. Value 0.5 is best; 0.0 is worse on every run by 1 (no spread: clearly worse); 1.0 is worse on
        // average by 0.1 but within its spread (differences 0.9, −0.5, −0.1: mean 0.1, se 0.41); 1.5 could not be
        // simulated.
        let scores = vec![vec![3.0, 4.0, 5.0], vec![2.0, 3.0, 4.0], vec![2.9, 2.5, 3.9], vec![f64::NAN; 3]];
        let p = profile(&values, &scores, 0, &[]).unwrap();
        assert_eq!(p.values, [0.0, 0.5, 1.0]);
        assert_eq!(p.excess_m[1], 0.0);
        assert!((p.excess_m[0] - 1.0).abs() < 1e-12 && p.excess_se_m[0] < 1e-12);
        assert!((p.excess_m[2] - (2.9 + 2.5 + 3.9 - 9.0) / 3.0).abs() < 1e-12);
        assert!((p.excess_se_m[2] - 0.4163).abs() < 1e-3, "{:?}", p.excess_se_m);
        assert_eq!(p.as_good, [0.5, 1.0]);
        assert_eq!(p.describe(), "0.500 to 1.000 of 3 values across 0.000-1.000");
        assert_eq!((p.population_excess_m, p.describe_population()), (None, String::new()), "no fit scores");
        // The population fit on the same numbers against the lowest value: 0.1 ± 0.058 above it is within its band;
        // 1 above it on every run is not.
        let fit = profile(&values, &scores, 0, &[2.2, 3.1, 4.0]).unwrap();
        assert!((fit.population_excess_m.unwrap() - 0.1).abs() < 1e-12);
        assert!((fit.population_excess_se_m.unwrap() - 0.1 / 3f64.sqrt()).abs() < 1e-12);
        assert_eq!(
            fit.describe_population(),
            "; the population fit +0.10 ± 0.06 m against the lowest (within its band)"
        );
        assert_eq!(
            fit.describe(),
            "0.500 to 1.000 of 3 values across 0.000-1.000; the population fit +0.10 ± 0.06 m against the lowest \
             (within its band)"
        );
        let off = profile(&values, &scores, 0, &[3.0, 4.0, 5.0]).unwrap();
        assert_eq!(
            off.describe_population(),
            "; the population fit +1.00 ± 0.00 m against the lowest (outside its band)"
        );
        assert_eq!(profile(&values, &scores, 0, &[2.0, f64::NAN, 4.0]).unwrap().population_excess_m, None);
        // Hsu's critical values (Bonferroni): the band compares a value with the best of the 2 other values, the
        // fit with the best of all 3. A fit 2.1 paired SE above the lowest is within (it was outside at two SE
        // until stop 75); 2.2 SE is not.
        assert!((p.band_critical_se - 1.959_964).abs() < 1e-5, "{}", p.band_critical_se);
        assert!((p.population_critical_se - 2.128_045).abs() < 1e-5, "{}", p.population_critical_se);
        assert!(
            (super::best_critical(6) - 2.393_980).abs() < 1e-5 && (super::best_critical(7) - 2.449_998).abs() < 1e-5
        );
        let at_ratio = |z: f64| {
            let x = 0.1 * 3f64.sqrt() / z; // the sd of the differences 0.1 + x, 0.1, 0.1 − x
            profile(&values, &scores, 0, &[2.1 + x, 3.1, 4.1 - x]).unwrap().describe_population()
        };
        assert!(at_ratio(2.1).ends_with("(within its band)"), "{}", at_ratio(2.1));
        assert!(at_ratio(2.2).ends_with("(outside its band)"), "{}", at_ratio(2.2));
        let level = profile(&values, &scores, 0, &[2.0, 3.0, 3.999]).unwrap();
        assert!(level.describe_population().starts_with("; the population fit +0.00 ± "), "not -0.00");
        // Every value in: open. A value out between two that are in: a gap, named, and not open (until stop 76 a
        // band whose ends were in was called open).
        let open = super::Profile { as_good: [0.0, 1.0], excess_m: vec![0.0, 0.0, 0.1], ..p.clone() };
        assert!(open.is_open() && open.gaps().is_empty());
        assert_eq!(open.describe(), "all 3 values across 0.000-1.000: the runs leave it open");
        let gap = super::Profile { as_good: [0.0, 1.0], excess_m: vec![0.0, 1.0, 0.1], ..p.clone() };
        assert!(!gap.is_open());
        assert_eq!(gap.gaps(), [0.5]);
        assert_eq!(gap.describe(), "0.000 to 1.000 but not 0.500 of 3 values across 0.000-1.000");
        assert!(!p.is_open() && p.gaps().is_empty(), "an end out is no gap");
        let one = super::Profile { as_good: [0.5, 0.5], ..p };
        assert_eq!(one.describe(), "only 0.500 of 3 values across 0.000-1.000");
        assert!(profile(&values, &vec![vec![f64::NAN]; 4], 0, &[]).is_none());
        assert!(profile(&values, &vec![Vec::new(); 4], 0, &[]).is_none(), "no runs");
    }

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
