//! Hazard rasters accumulated while rocks run: each rock reports the cells its path crossed (with its largest
//! kinetic energy and passing height in each), and the accumulator adds them to per-cell counts, maxima and
//! fixed-bin histograms. Memory grows with the cells reached, never with the number of rocks, and every operation
//! is a count, a maximum or a histogram increment, so the result does not depend on the order rocks are added.

use super::grid::RasterFrame;
use super::histogram::LogBins;
use crate::sim::{Observer, Sample};
use std::collections::HashMap;

/// What one rock left in one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellVisit {
    /// Cell index in the frame.
    pub cell: u32,
    /// Largest total kinetic energy in the cell, J.
    pub kinetic_j: f32,
    /// Largest passing height (clearance of the lowest point) in the cell, m.
    pub height_m: f32,
}

/// Observer that records the cells a rock's path crosses, walking between samples at a third of a cell.
#[derive(Debug, Clone)]
pub struct CellTrack<'a> {
    frame: &'a RasterFrame,
    visits: Vec<CellVisit>,
    index: HashMap<u32, usize>,
    last: Option<Sample>,
}

impl<'a> CellTrack<'a> {
    /// An empty track on `frame`.
    pub fn new(frame: &'a RasterFrame) -> Self {
        CellTrack { frame, visits: Vec::new(), index: HashMap::new(), last: None }
    }

    /// The visits, in the order the cells were first reached.
    pub fn into_visits(self) -> Vec<CellVisit> {
        self.visits
    }

    fn visit(&mut self, x: f64, y: f64, kinetic_j: f64, height_m: f64) {
        let Some(cell) = self.frame.cell_of_local(x, y) else { return };
        let (k, h) = (kinetic_j as f32, height_m as f32);
        match self.index.get(&cell) {
            Some(&i) => {
                let v = &mut self.visits[i];
                v.kinetic_j = v.kinetic_j.max(k);
                v.height_m = v.height_m.max(h);
            }
            None => {
                self.index.insert(cell, self.visits.len());
                self.visits.push(CellVisit { cell, kinetic_j: k, height_m: h });
            }
        }
    }
}

impl Observer for CellTrack<'_> {
    fn sample(&mut self, s: &Sample) {
        match self.last {
            None => self.visit(s.position_m.x, s.position_m.y, s.kinetic_j, s.clearance_m),
            Some(a) => {
                let (dx, dy) = (s.position_m.x - a.position_m.x, s.position_m.y - a.position_m.y);
                let steps = (((dx * dx + dy * dy).sqrt() / (self.frame.cell_m / 3.0)).ceil() as usize).max(1);
                for i in 1..=steps {
                    let f = i as f64 / steps as f64;
                    let lerp = |p: f64, q: f64| p + f * (q - p);
                    self.visit(
                        lerp(a.position_m.x, s.position_m.x),
                        lerp(a.position_m.y, s.position_m.y),
                        lerp(a.kinetic_j, s.kinetic_j),
                        lerp(a.clearance_m, s.clearance_m),
                    );
                }
            }
        }
        self.last = Some(*s);
    }
}

/// Per-cell statistics over all rocks.
#[derive(Debug, Clone)]
pub struct HazardAccumulator {
    /// The raster frame.
    pub frame: RasterFrame,
    /// Rocks added.
    pub rocks: u64,
    reach: Vec<u32>,
    kinetic_max: Vec<f32>,
    height_max: Vec<f32>,
    slot: Vec<u32>,
    kinetic_hist: Vec<u32>,
    height_hist: Vec<u32>,
    kinetic_bins: LogBins,
    height_bins: LogBins,
}

const NO_SLOT: u32 = u32::MAX;

/// Kinetic energy bins: 1 J to 1 GJ, 20 a decade.
pub fn kinetic_bins() -> LogBins {
    LogBins::new(1.0, 1e9, 20)
}

/// Passing height bins: 1 cm to 1 km, 20 a decade.
pub fn height_bins() -> LogBins {
    LogBins::new(0.01, 1000.0, 20)
}

impl HazardAccumulator {
    /// An empty accumulator on `frame`.
    pub fn new(frame: RasterFrame) -> Self {
        let n = frame.len();
        HazardAccumulator {
            frame,
            rocks: 0,
            reach: vec![0; n],
            kinetic_max: vec![0.0; n],
            height_max: vec![0.0; n],
            slot: vec![NO_SLOT; n],
            kinetic_hist: Vec::new(),
            height_hist: Vec::new(),
            kinetic_bins: kinetic_bins(),
            height_bins: height_bins(),
        }
    }

    /// Adds one rock's visits.
    pub fn add(&mut self, visits: &[CellVisit]) {
        self.rocks += 1;
        let (nk, nh) = (self.kinetic_bins.len(), self.height_bins.len());
        for v in visits {
            let c = v.cell as usize;
            self.reach[c] += 1;
            self.kinetic_max[c] = self.kinetic_max[c].max(v.kinetic_j);
            self.height_max[c] = self.height_max[c].max(v.height_m);
            if self.slot[c] == NO_SLOT {
                self.slot[c] = (self.kinetic_hist.len() / nk) as u32;
                self.kinetic_hist.resize(self.kinetic_hist.len() + nk, 0);
                self.height_hist.resize(self.height_hist.len() + nh, 0);
            }
            let s = self.slot[c] as usize;
            self.kinetic_hist[s * nk + self.kinetic_bins.bin(v.kinetic_j as f64)] += 1;
            self.height_hist[s * nh + self.height_bins.bin(v.height_m as f64)] += 1;
        }
    }

    /// Rocks that reached cell `k`.
    pub fn reach_count(&self, k: usize) -> u32 {
        self.reach[k]
    }

    /// The `q`-quantile over rocks of the largest kinetic energy in cell `k`, J (`NaN` where no rock passed).
    pub fn kinetic_quantile_j(&self, k: usize, q: f64) -> f64 {
        self.quantile(k, q, true)
    }

    /// The `q`-quantile over rocks of the largest passing height in cell `k`, m (`NaN` where no rock passed).
    pub fn height_quantile_m(&self, k: usize, q: f64) -> f64 {
        self.quantile(k, q, false)
    }

    fn quantile(&self, k: usize, q: f64, kinetic: bool) -> f64 {
        if self.slot[k] == NO_SLOT {
            return f64::NAN;
        }
        let s = self.slot[k] as usize;
        let (bins, hist, max) = if kinetic {
            (&self.kinetic_bins, &self.kinetic_hist, self.kinetic_max[k])
        } else {
            (&self.height_bins, &self.height_hist, self.height_max[k])
        };
        bins.quantile(&hist[s * bins.len()..(s + 1) * bins.len()], self.reach[k], q, max as f64)
    }

    /// Largest kinetic energy in cell `k`, J (`NaN` where no rock passed).
    pub fn kinetic_max_j(&self, k: usize) -> f64 {
        if self.reach[k] == 0 {
            f64::NAN
        } else {
            self.kinetic_max[k] as f64
        }
    }

    /// Largest passing height in cell `k`, m (`NaN` where no rock passed).
    pub fn height_max_m(&self, k: usize) -> f64 {
        if self.reach[k] == 0 {
            f64::NAN
        } else {
            self.height_max[k] as f64
        }
    }

    /// Bytes held by the per-cell histograms (for the memory report).
    pub fn histogram_bytes(&self) -> usize {
        4 * (self.kinetic_hist.len() + self.height_hist.len())
    }
}
