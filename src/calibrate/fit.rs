//! The population fit: the free parameters that bring the simulated run-out distributions closest to the
//! observed ones over the calibration runs, by Nelder–Mead with common random numbers.
//!
//! **Several searches, chosen on fresh numbers** (ours): with a few repeats per run, the minimum a search finds is
//! partly a property of its random numbers. On Tschamut two searches that differ only in their streams landed at
//! Cr 0.31 and Cr 0.09, and the objective of the first's result rose from 8.8 m at the fit to 11.2 m when simulated
//! again with other numbers (the second's from 9.2 to 10.2): the better-looking search was the worse model
//! (`examples/fit_stability.rs`). With `search_starts = K > 1` the population fit runs K searches from the same start,
//! search k on the streams of `seed + k`, then simulates each result `repeats` times on streams none of the searches
//! used and keeps the lowest objective there. This is the usual remedy for the optimisation bias of a
//! sample-average objective (the "winner's curse" of comparing candidates on the numbers they were chosen with;
//! Kleywegt, Shapiro & Homem-de-Mello 2002, SIAM J. Optim. 12: 479–502, validate candidate solutions on an
//! independent sample).
//!
//! **Several start points** (ours): Nelder–Mead is a local search, and the Tschamut objective has more than one
//! valley. With the tied settings and seed 2, one 5-fold's fold 1 ends at an objective of 17.2 m (dynamic friction
//! 33°, static 40°) from a dynamic start of 28°, and at 10.3 m (18°, 26°) from 18°; held out, 32.9 m against 7.5 m
//! of run-out MAE. With `start_points = P > 1` the fit also starts from P − 1 points of a Latin hypercube over the
//! free parameters' bounds (McKay, Beckman & Conover 1979, Technometrics 21: 239–245: each parameter's range cut
//! into P − 1 equal strata with one point in each, the strata paired at random), the usual multi-start for a local
//! optimiser; the results are compared on fresh numbers as above, so the choice uses the calibration runs only.
//!
//! **Screened start points** (ours): a full search from each start costs the whole budget (120 evaluations on
//! Tschamut), so few starts can be afforded. With `screen_points = S > 0` the settings' start and S points of a
//! Latin hypercube are each evaluated once, on the first search's numbers, and the P with the lowest objective are
//! the start points: many starts looked at for the price of S evaluations, the searches spent on the most promising
//! (the screening stage of multi-level multi-start methods, Rinnooy Kan & Timmer 1987, Math. Program. 39: 27–56).

use super::config::CalibrationConfig;
use super::model::{evaluate_repeats, Model, RunSims};
use super::objective::score;
use super::params::{Candidate, FreeParam};
use super::search::{nelder_mead, SearchResult};
use super::stats::shuffle;
use crate::random::{stream, uniform};
use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};

/// What the fitting steps share: the model, the settings, a progress sink and a simulation counter.
pub struct Context<'a> {
    /// The model.
    pub model: &'a dyn Model,
    /// The settings.
    pub cfg: &'a CalibrationConfig,
    /// Progress messages.
    pub log: &'a (dyn Fn(&str) + Sync),
    /// Simulations run so far.
    pub simulations: AtomicUsize,
    /// When the context was made, for the pace of [`Context::time_for`].
    started: std::time::Instant,
}

impl<'a> Context<'a> {
    /// A context.
    pub fn new(model: &'a dyn Model, cfg: &'a CalibrationConfig, log: &'a (dyn Fn(&str) + Sync)) -> Self {
        Context { model, cfg, log, simulations: AtomicUsize::new(0), started: std::time::Instant::now() }
    }

    /// How long `n` more simulations take at the pace so far, for the progress log ("about 4 min at 150
    /// simulations/s"); empty before the pace is known.
    pub fn time_for(&self, n: usize) -> String {
        time_at_pace(n, self.simulations.load(Ordering::Relaxed), self.started.elapsed().as_secs_f64())
    }

    /// Simulates `which` runs `repeats` times under `candidate` (see [`super::model::evaluate`]) and counts the
    /// simulations.
    pub fn sims(&self, candidate: &Candidate, which: &[usize], repeats: usize) -> crate::Result<Vec<RunSims>> {
        self.sims_repeats(candidate, which, 0..repeats)
    }

    /// [`Context::sims`] of the repeats numbered `repeats` only (see [`evaluate_repeats`]).
    pub fn sims_repeats(&self, c: &Candidate, which: &[usize], repeats: Range<usize>) -> crate::Result<Vec<RunSims>> {
        self.sims_seeded(c, which, repeats, self.cfg.seed)
    }

    /// [`Context::sims_repeats`] on the streams of `seed` instead of the settings' seed.
    pub fn sims_seeded(
        &self,
        c: &Candidate,
        which: &[usize],
        repeats: Range<usize>,
        seed: u64,
    ) -> crate::Result<Vec<RunSims>> {
        self.simulations.fetch_add(which.len() * repeats.len(), Ordering::Relaxed);
        evaluate_repeats(self.model, c, which, repeats, seed, self.cfg.threads)
    }

    /// The objective of `candidate` on `which` runs with the search repeats (infinite if the candidate is
    /// invalid).
    pub fn objective(&self, candidate: &Candidate, which: &[usize]) -> f64 {
        self.objective_seeded(candidate, which, self.cfg.search_repeats, self.cfg.seed)
    }

    fn objective_seeded(&self, c: &Candidate, which: &[usize], repeats: usize, seed: u64) -> f64 {
        match self.sims_seeded(c, which, 0..repeats, seed) {
            Ok(s) => score(self.cfg, self.model.runs(), &s),
            Err(_) => f64::INFINITY,
        }
    }
}

/// How long `n` simulations take at the pace of `done` in `secs` (empty below 100 done: no pace yet; and below a
/// second, not worth saying).
fn time_at_pace(n: usize, done: usize, secs: f64) -> String {
    if done < 100 || secs <= 0.0 {
        return String::new();
    }
    let pace = done as f64 / secs;
    let t = n as f64 / pace;
    if t < 1.0 {
        return String::new();
    }
    let when = if t < 90.0 { format!("{t:.0} s") } else { format!("{:.0} min", t / 60.0) };
    format!(", about {when} at the pace so far ({pace:.0} simulations/s)")
}

/// `start` with the free parameters set from unit coordinates `u`.
pub fn with_unit(start: &Candidate, free: &[FreeParam], u: &[f64]) -> Candidate {
    let mut c = start.clone();
    for (p, &x) in free.iter().zip(u) {
        c.params.set(p.name.clone(), p.from_unit(x));
    }
    super::params::normalize(&mut c.params);
    c
}

/// The unit coordinates of `free` in `c` (a parameter `c` leaves unset at the middle of its bounds).
pub fn unit_of(c: &Candidate, free: &[FreeParam]) -> Vec<f64> {
    free.iter().map(|p| p.to_unit(c.params.get_or(&p.name, 0.5 * (p.min + p.max)))).collect()
}

/// Fits `free` (starting from their values in `start`) on runs `which` within `max_evaluations`, with the common
/// random numbers of `seed`. Returns the best candidate and the search record.
pub fn fit(
    ctx: &Context,
    start: &Candidate,
    free: &[FreeParam],
    which: &[usize],
    max_evaluations: usize,
    what: &str,
    seed: u64,
) -> (Candidate, SearchResult) {
    let x0 = unit_of(start, free);
    let mut count = 0usize;
    let result = nelder_mead(
        |u| {
            count += 1;
            let v = ctx.objective_seeded(&with_unit(start, free, u), which, ctx.cfg.search_repeats, seed);
            if count.is_multiple_of(10) {
                (ctx.log)(&format!("{what}: {count} evaluations, objective {v:.2} m"));
            }
            v
        },
        &x0,
        0.2,
        max_evaluations,
        0.01,
        0.05,
    );
    (with_unit(start, free, &result.x), result)
}

/// The streams on which [`fit_population`] chooses between its searches: an offset from the seed that no search
/// reaches (search k uses `seed + k`, k < 10).
const SELECTION_SEED_OFFSET: u64 = 0x5e1e_c7ed;
/// The streams of the Latin hypercube of [`start_points`]: an offset from the seed no simulation uses.
const START_POINTS_SEED_OFFSET: u64 = 0x57a2_7e75;

/// `n` start points in the unit cube: `x0`, then a Latin hypercube of `n − 1` points (see the module notes) drawn
/// from the streams of `seed` (one per coordinate).
pub fn start_points(x0: &[f64], n: usize, seed: u64) -> Vec<Vec<f64>> {
    let m = n.saturating_sub(1);
    let mut points = vec![x0.to_vec(); m];
    for d in 0..x0.len() {
        let mut rng = stream(seed.wrapping_add(START_POINTS_SEED_OFFSET), d as u64);
        let mut strata: Vec<usize> = (0..m).collect();
        shuffle(&mut strata, &mut rng);
        for (point, s) in points.iter_mut().zip(strata) {
            point[d] = (s as f64 + uniform(&mut rng)) / m as f64;
        }
    }
    points.insert(0, x0.to_vec());
    points
}

/// One search of the population fit.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SearchRecord {
    /// Seed of its common random numbers.
    pub seed: u64,
    /// Its best objective on its own numbers, m.
    pub objective_m: f64,
    /// The same candidate's objective on the selection's numbers (`repeats` per run), m.
    pub selection_objective_m: f64,
    /// Objective evaluations used.
    pub evaluations: usize,
    /// Its free parameters.
    pub parameters: std::collections::BTreeMap<String, f64>,
    /// The free parameters it started from.
    #[serde(default)]
    pub start: std::collections::BTreeMap<String, f64>,
    /// Its start's objective in the screening (on the first search's numbers), m; none without screening.
    #[serde(default)]
    pub start_screened_m: Option<f64>,
}

/// The `points` start points of the population fit in the unit cube, each with its objective in the screening: the
/// first `points` of [`start_points`], or, with `screen_points = S > 0`, the `points` lowest of the start and S
/// hypercube points, each evaluated once on the numbers of `seed` (ties keep the earlier point).
fn screened_starts(
    ctx: &Context,
    start: &Candidate,
    free: &[FreeParam],
    which: &[usize],
    points: usize,
    what: &str,
) -> Vec<(Vec<f64>, Option<f64>)> {
    let (cfg, x0) = (ctx.cfg, unit_of(start, free));
    if cfg.screen_points == 0 {
        return start_points(&x0, points, cfg.seed).into_iter().map(|x| (x, None)).collect();
    }
    let mut screened: Vec<(Vec<f64>, f64)> = start_points(&x0, cfg.screen_points + 1, cfg.seed)
        .into_iter()
        .map(|x| {
            let v = ctx.objective_seeded(&with_unit(start, free, &x), which, cfg.search_repeats, cfg.seed);
            (x, v)
        })
        .collect();
    screened.sort_by(|a, b| a.1.total_cmp(&b.1));
    screened.truncate(points);
    let kept: Vec<String> = screened.iter().map(|(_, v)| format!("{v:.2}")).collect();
    (ctx.log)(&format!(
        "{what}: {} start points screened; the starts are the best {points} ({} m)",
        cfg.screen_points + 1,
        kept.join(", ")
    ));
    screened.into_iter().map(|(x, v)| (x, Some(v))).collect()
}

/// The population fit: [`fit`] with the settings' budget, or, with `search_starts = K` and `start_points = P` not
/// both 1 or with `screen_points` set, K searches on the streams of `seed`, `seed + 1`, … from each of P start
/// points ([`start_points`], screened where set), of which the one with the lowest objective on fresh streams
/// (`repeats` per run) is kept (see the module notes).
/// Returns the kept candidate, its search record and every search's summary (empty for one search).
pub fn fit_population(
    ctx: &Context,
    start: &Candidate,
    free: &[FreeParam],
    which: &[usize],
    what: &str,
) -> (Candidate, SearchResult, Vec<SearchRecord>) {
    let budget = ctx.cfg.max_evaluations(ctx.model.kind());
    let (streams, points) = (ctx.cfg.search_starts.max(1), ctx.cfg.start_points.max(1));
    if streams * points == 1 && ctx.cfg.screen_points == 0 {
        let (c, s) = fit(ctx, start, free, which, budget, what, ctx.cfg.seed);
        return (c, s, Vec::new());
    }
    let values = |c: &Candidate| free.iter().map(|p| (p.name.clone(), c.params.get_or(&p.name, f64::NAN))).collect();
    let selection_seed = ctx.cfg.seed.wrapping_add(SELECTION_SEED_OFFSET);
    let mut results = Vec::new();
    let mut records = Vec::new();
    for (x, screened) in screened_starts(ctx, start, free, which, points, what) {
        let from = with_unit(start, free, &x);
        for k in 0..streams {
            let seed = ctx.cfg.seed.wrapping_add(k as u64);
            let what = format!("{what}, search {}/{}", results.len() + 1, streams * points);
            let (c, s) = fit(ctx, &from, free, which, budget, &what, seed);
            let selection = ctx.objective_seeded(&c, which, ctx.cfg.repeats, selection_seed);
            (ctx.log)(&format!("{what}: objective {:.2} m on its numbers, {selection:.2} m on fresh ones", s.f));
            records.push(SearchRecord {
                seed,
                objective_m: s.f,
                selection_objective_m: selection,
                evaluations: s.evaluations,
                parameters: values(&c),
                start: values(&from),
                start_screened_m: screened,
            });
            results.push((c, s));
        }
    }
    let best = (0..results.len())
        .min_by(|&a, &b| records[a].selection_objective_m.total_cmp(&records[b].selection_objective_m))
        .unwrap_or(0);
    let (c, s) = results.swap_remove(best);
    (c, s, records)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn start_points_are_the_start_then_one_point_per_stratum_of_each_parameter() {
        let x0 = [0.3, 0.9, 0.5];
        assert_eq!(start_points(&x0, 1, 7), vec![x0.to_vec()]);
        let p = start_points(&x0, 5, 7);
        assert_eq!(p.len(), 5);
        assert_eq!(p[0], x0.to_vec());
        for d in 0..x0.len() {
            let mut strata: Vec<usize> = p[1..].iter().map(|x| (x[d] * 4.0) as usize).collect();
            strata.sort();
            assert_eq!(strata, [0, 1, 2, 3], "coordinate {d}: {p:?}");
        }
        // Seeded: the same seed gives the same points, another seed others.
        assert_eq!(start_points(&x0, 5, 7), p);
        assert_ne!(start_points(&x0, 5, 8), p);
    }

    #[test]
    fn the_time_left_is_read_off_the_pace_so_far() {
        assert_eq!(time_at_pace(5000, 99, 1.0), "");
        assert_eq!(time_at_pace(5000, 1000, 0.0), "");
        assert_eq!(time_at_pace(100, 1000, 0.5), "", "under a second");
        assert_eq!(time_at_pace(6000, 1500, 10.0), ", about 40 s at the pace so far (150 simulations/s)");
        assert_eq!(time_at_pace(61_440, 15_000, 100.0), ", about 7 min at the pace so far (150 simulations/s)");
    }
}
