//! What a run's summary says about its collector lines and barriers.

use super::stats::{CollectorStats, Quantity};
use super::Collector;
use crate::sim::Barrier;
use serde::Serialize;

/// One collector line in the run summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CollectorFacts {
    /// Name.
    pub name: String,
    /// Length, m.
    pub length_m: f64,
    /// Stretches.
    pub stretches: usize,
    /// Rocks that crossed.
    pub rocks_crossing: u64,
    /// Fraction of the released rocks that crossed.
    pub fraction_crossing: f64,
    /// 95th percentile of the total kinetic energy at the crossings, kJ (`null` if none crossed).
    pub kinetic_kj_p95: Option<f64>,
    /// Largest total kinetic energy at a crossing, kJ.
    pub kinetic_kj_max: Option<f64>,
    /// 95th percentile of the passing height, m.
    pub passing_height_m_p95: Option<f64>,
    /// Largest passing height, m.
    pub passing_height_m_max: Option<f64>,
}

/// One barrier in the run summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BarrierFacts {
    /// Name.
    pub name: String,
    /// Height, m.
    pub height_m: f64,
    /// Energy capacity, kJ.
    pub capacity_kj: f64,
    /// Rocks caught.
    pub caught: u64,
    /// Rocks that broke through it (slowed).
    pub broke_through: u64,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// Facts of `collectors` (the first lines of `stats`).
pub fn collector_facts(collectors: &[Collector], stats: &CollectorStats) -> Vec<CollectorFacts> {
    collectors
        .iter()
        .zip(&stats.lines)
        .map(|(c, l)| CollectorFacts {
            name: c.name.clone(),
            length_m: c.length_m(),
            stretches: c.stretch_count(),
            rocks_crossing: l.crossing,
            fraction_crossing: l.crossing as f64 / stats.rocks.max(1) as f64,
            kinetic_kj_p95: finite(l.dists.quantile(Quantity::Kinetic, 0.95)),
            kinetic_kj_max: finite(l.dists.max(Quantity::Kinetic)),
            passing_height_m_p95: finite(l.dists.quantile(Quantity::Height, 0.95)),
            passing_height_m_max: finite(l.dists.max(Quantity::Height)),
        })
        .collect()
}

/// Facts of the terrain's barriers.
pub fn barrier_facts(barriers: &[Barrier], stats: &CollectorStats) -> Vec<BarrierFacts> {
    barriers
        .iter()
        .enumerate()
        .map(|(k, b)| BarrierFacts {
            name: b.name.clone(),
            height_m: b.height_m,
            capacity_kj: b.capacity_j / 1000.0,
            caught: stats.barrier_caught.get(k).copied().unwrap_or(0),
            broke_through: stats.barrier_through.get(k).copied().unwrap_or(0),
        })
        .collect()
}
