//! What still reaches the protected zone with the proposed barrier in place, rock by rock of the re-run (the same
//! rocks, seeds and releases as the run without it).
//!
//! With an asset zone, a rock of the re-run reaches it as before (crossing the asset line, entering the polygon).
//! Without one, the protected zone is beyond the candidate line: a rock reaches it when it crosses the candidate
//! line and the barrier did not catch it. Each rock that still reaches the zone is put in one class:
//! - **through**: it hit the barrier with more energy than its capacity and broke through, slowed;
//! - **over**: it crossed the candidate line within the barrier's span without touching it (passing height at or
//!   above the fence);
//! - **around**: it crossed the candidate line beyond the barrier's ends;
//! - **elsewhere** (asset zone only): it reached the zone without crossing the candidate line.

use crate::collector::RockCrossings;
use serde::Serialize;

/// Rocks reaching the protected zone without and with the barrier.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Residual {
    /// Rocks released (in each run).
    pub rocks: u64,
    /// Rocks reaching the protected zone without the barrier.
    pub reaching_without: u64,
    /// Rocks reaching it with the barrier.
    pub reaching_with: u64,
    /// Rocks the barrier caught.
    pub caught: u64,
    /// Of `reaching_with`: broke through.
    pub through: u64,
    /// Of `reaching_with`: passed over.
    pub over: u64,
    /// Of `reaching_with`: passed round the ends.
    pub around: u64,
    /// Of `reaching_with`: reached the asset zone without crossing the candidate line.
    pub elsewhere: u64,
    #[serde(skip)]
    asset_zone: bool,
    #[serde(skip)]
    span_m: (f64, f64),
}

impl Residual {
    /// Counting starts; `reaching_without` comes from the run without the barrier; the barrier covers
    /// `from_m..to_m` along the candidate line.
    pub fn new(reaching_without: u64, asset_zone: bool, from_m: f64, to_m: f64) -> Self {
        Residual { reaching_without, asset_zone, span_m: (from_m, to_m), ..Default::default() }
    }

    /// Adds a rock of the re-run: `line` is the candidate line's collector index, `barrier` the proposed barrier's
    /// index among the terrain's barriers.
    pub fn add(&mut self, r: &RockCrossings, line: u32, barrier: u32) {
        self.rocks += 1;
        let hit = r.barrier_hits.iter().find(|h| h.0 == barrier).map(|h| h.1);
        let crossing = r.line_first.iter().find(|c| c.0 == line).map(|c| c.1);
        let caught = hit == Some(true);
        if caught {
            self.caught += 1;
        }
        let reached = if self.asset_zone { r.zone_t_s.is_some() } else { crossing.is_some() && !caught };
        if !reached {
            return;
        }
        self.reaching_with += 1;
        match (hit, crossing) {
            (Some(false), _) => self.through += 1,
            (Some(true), _) => self.elsewhere += 1,
            (None, Some(x)) if x.along_m >= self.span_m.0 - 1e-6 && x.along_m <= self.span_m.1 + 1e-6 => self.over += 1,
            (None, Some(_)) => self.around += 1,
            (None, None) => self.elsewhere += 1,
        }
    }

    /// Fraction of released rocks reaching the zone without the barrier.
    pub fn probability_without(&self) -> f64 {
        self.reaching_without as f64 / self.rocks.max(1) as f64
    }

    /// Fraction of released rocks reaching the zone with the barrier.
    pub fn probability_with(&self) -> f64 {
        self.reaching_with as f64 / self.rocks.max(1) as f64
    }
}
