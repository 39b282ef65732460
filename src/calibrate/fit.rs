//! The population fit: the free parameters that bring the simulated run-out distributions closest to the
//! observed ones over the calibration runs, by Nelder–Mead with common random numbers.

use super::config::CalibrationConfig;
use super::model::{evaluate, Model, RunSims};
use super::objective::objective;
use super::params::{Candidate, FreeParam};
use super::search::{nelder_mead, SearchResult};
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
}

impl<'a> Context<'a> {
    /// A context.
    pub fn new(model: &'a dyn Model, cfg: &'a CalibrationConfig, log: &'a (dyn Fn(&str) + Sync)) -> Self {
        Context { model, cfg, log, simulations: AtomicUsize::new(0) }
    }

    /// Simulates `which` runs `repeats` times under `candidate` (see [`evaluate`]) and counts the simulations.
    pub fn sims(&self, candidate: &Candidate, which: &[usize], repeats: usize) -> crate::Result<Vec<RunSims>> {
        self.simulations.fetch_add(which.len() * repeats, Ordering::Relaxed);
        evaluate(self.model, candidate, which, repeats, self.cfg.seed, self.cfg.threads)
    }

    /// The objective of `candidate` on `which` runs with the search repeats (infinite if the candidate is
    /// invalid).
    pub fn objective(&self, candidate: &Candidate, which: &[usize]) -> f64 {
        match self.sims(candidate, which, self.cfg.search_repeats) {
            Ok(s) => objective(self.cfg.objective, self.model.runs(), &s),
            Err(_) => f64::INFINITY,
        }
    }
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

/// Fits `free` (starting from their values in `start`) on runs `which` within `max_evaluations`. Returns the best
/// candidate and the search record.
pub fn fit(
    ctx: &Context,
    start: &Candidate,
    free: &[FreeParam],
    which: &[usize],
    max_evaluations: usize,
    what: &str,
) -> (Candidate, SearchResult) {
    let x0: Vec<f64> = free.iter().map(|p| p.to_unit(start.params.get_or(&p.name, 0.5 * (p.min + p.max)))).collect();
    let mut count = 0usize;
    let result = nelder_mead(
        |u| {
            count += 1;
            let v = ctx.objective(&with_unit(start, free, u), which);
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
