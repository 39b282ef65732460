//! Per-line and per-stretch statistics of collector crossings over all rocks, in fixed bins.

use super::dist::{Bins, Dist};
use super::track::{CollectorSet, Crossing, RockCrossings};
use crate::hazard::LogBins;

/// A quantity recorded at crossings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Translational kinetic energy (written in kJ).
    Translational,
    /// Total kinetic energy (written in kJ).
    Kinetic,
    /// Passing height of the lowest point, m.
    Height,
    /// Speed, m/s.
    Speed,
    /// Crossing angle in plan, degrees.
    Angle,
    /// Rock size (equivalent-sphere diameter), m.
    Size,
}

impl Quantity {
    /// All quantities, in output order.
    pub const ALL: [Quantity; 6] = [
        Quantity::Translational,
        Quantity::Kinetic,
        Quantity::Height,
        Quantity::Speed,
        Quantity::Angle,
        Quantity::Size,
    ];

    /// Column prefix in outputs (name and unit).
    pub fn column(self) -> &'static str {
        match self {
            Quantity::Translational => "translational_kj",
            Quantity::Kinetic => "kinetic_kj",
            Quantity::Height => "passing_height_m",
            Quantity::Speed => "speed_mps",
            Quantity::Angle => "crossing_angle_deg",
            Quantity::Size => "rock_size_m",
        }
    }

    /// Factor from the recorded SI value to the written unit.
    pub fn scale(self) -> f64 {
        match self {
            Quantity::Translational | Quantity::Kinetic => 1e-3,
            _ => 1.0,
        }
    }

    fn bins(self) -> Bins {
        match self {
            Quantity::Translational | Quantity::Kinetic => Bins::Log(LogBins::new(1.0, 1e10, 50)),
            Quantity::Height => Bins::Log(LogBins::new(1e-3, 1e3, 50)),
            Quantity::Speed => Bins::Log(LogBins::new(1e-3, 1e3, 50)),
            Quantity::Angle => Bins::Linear { width: 0.5, n: 180 },
            Quantity::Size => Bins::Log(LogBins::new(1e-3, 1e3, 50)),
        }
    }
}

/// Percentiles written for every quantity (P50, P90, P95, P99; the maximum is added).
pub const PERCENTILES: [f64; 4] = [0.5, 0.9, 0.95, 0.99];

/// The distributions of all quantities over a set of crossings.
#[derive(Debug, Clone, PartialEq)]
pub struct QuantityDists {
    dists: Vec<Dist>,
}

impl Default for QuantityDists {
    fn default() -> Self {
        QuantityDists { dists: Quantity::ALL.iter().map(|q| Dist::new(q.bins())).collect() }
    }
}

impl QuantityDists {
    /// Adds a crossing of a rock of size `size_m`.
    pub fn add(&mut self, x: &Crossing, size_m: f64) {
        let v = [x.translational_j, x.kinetic_j, x.height_m, x.speed_mps, x.angle_deg, size_m];
        for (d, v) in self.dists.iter_mut().zip(v) {
            d.add(v);
        }
    }

    /// Adds all of `other`.
    pub fn merge(&mut self, other: &QuantityDists) {
        for (a, b) in self.dists.iter_mut().zip(&other.dists) {
            a.merge(b);
        }
    }

    /// Crossings added.
    pub fn count(&self) -> u32 {
        self.dists[0].total
    }

    /// The `q`-quantile of `quantity` in its written unit (`NaN` when empty).
    pub fn quantile(&self, quantity: Quantity, q: f64) -> f64 {
        self.dists[quantity as usize].quantile(q) * quantity.scale()
    }

    /// The maximum of `quantity` in its written unit (`NaN` when empty).
    pub fn max(&self, quantity: Quantity) -> f64 {
        self.dists[quantity as usize].max * quantity.scale()
    }
}

/// One stretch of a line.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StretchStats {
    /// Rocks that crossed the stretch.
    pub crossing: u32,
    dists: Option<Box<QuantityDists>>,
}

impl StretchStats {
    /// The distributions over the rocks that crossed (their first crossing of the stretch), if any did.
    pub fn dists(&self) -> Option<&QuantityDists> {
        self.dists.as_deref()
    }
}

/// One line.
#[derive(Debug, Clone, PartialEq)]
pub struct LineStats {
    /// Rocks that crossed the line.
    pub crossing: u64,
    /// The distributions over the rocks' first crossings of the line.
    pub dists: QuantityDists,
    /// Per stretch, in order along the line.
    pub stretches: Vec<StretchStats>,
}

/// Collector statistics over all rocks of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct CollectorStats {
    /// Rocks added.
    pub rocks: u64,
    /// Rocks that reached the protected zone.
    pub zone_reached: u64,
    /// Per collector, in the set's order.
    pub lines: Vec<LineStats>,
    /// Per barrier of the terrain: rocks caught.
    pub barrier_caught: Vec<u64>,
    /// Per barrier of the terrain: rocks that broke through.
    pub barrier_through: Vec<u64>,
}

impl CollectorStats {
    /// Empty statistics for the collectors of `set` and `n_barriers` barriers.
    pub fn new(set: &CollectorSet, n_barriers: usize) -> Self {
        CollectorStats {
            rocks: 0,
            zone_reached: 0,
            lines: set
                .collectors
                .iter()
                .map(|c| LineStats {
                    crossing: 0,
                    dists: QuantityDists::default(),
                    stretches: vec![StretchStats::default(); c.stretch_count()],
                })
                .collect(),
            barrier_caught: vec![0; n_barriers],
            barrier_through: vec![0; n_barriers],
        }
    }

    /// Adds one rock.
    pub fn add(&mut self, r: &RockCrossings) {
        self.rocks += 1;
        if r.zone_t_s.is_some() {
            self.zone_reached += 1;
        }
        for (c, x) in &r.line_first {
            let l = &mut self.lines[*c as usize];
            l.crossing += 1;
            l.dists.add(x, r.size_m);
        }
        for (c, s, x) in &r.stretch_first {
            let st = &mut self.lines[*c as usize].stretches[*s as usize];
            st.crossing += 1;
            st.dists.get_or_insert_with(Default::default).add(x, r.size_m);
        }
        for &(b, caught) in &r.barrier_hits {
            let v = if caught { &mut self.barrier_caught } else { &mut self.barrier_through };
            if let Some(n) = v.get_mut(b as usize) {
                *n += 1;
            }
        }
    }

    /// The merged distributions of stretches `from..to` of line `c` (each rock counted once per stretch).
    pub fn stretch_range_dists(&self, c: usize, stretches: impl Iterator<Item = usize>) -> QuantityDists {
        let mut out = QuantityDists::default();
        for k in stretches {
            if let Some(d) = self.lines[c].stretches[k].dists() {
                out.merge(d);
            }
        }
        out
    }
}
