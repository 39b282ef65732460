//! Hazard zones: intensity × probability, in the manner of Swiss and Austrian rockfall hazard mapping.
//!
//! The Swiss recommendations (BWW, BRP, BUWAL 1997, "Berücksichtigung der Massenbewegungsgefahren bei
//! raumwirksamen Tätigkeiten") class rockfall intensity by kinetic energy: weak below 30 kJ, medium 30 to 300 kJ,
//! strong above 300 kJ; they cross it with three probability classes in a 3 × 3 diagram whose cells give the
//! hazard level: high (red) for strong intensity at any probability and for medium intensity at high
//! probability; medium (blue) for medium intensity at medium or low probability and for weak intensity at high
//! probability; low (yellow) for weak intensity at medium or low probability. Austrian hazard zone plans follow a
//! similar intensity × probability scheme (**unverified**: whether with the same thresholds), hence settings.
//!
//! A simulation gives per cell the probability that a released rock reaches it, not an annual frequency, so the
//! probability axis here is the reach probability (ours; the Cadanav method, Abbruzzese & Labiouse 2014, NHESS,
//! "New Cadanav methodology for rock fall hazard zoning based on 3D trajectory modelling", multiplies it by an
//! onset frequency, which a user may do with the thresholds): low up to 1 %, medium up to
//! 10 %, high above (ours; settings). The intensity of a cell is the 95th percentile over rocks of their largest
//! kinetic energy there (the `kinetic_energy_p95_kj` raster, like Rockyfor3D's E_95CI), or its maximum.
//!
//! Outputs: `hazard_zones.tif` (0 = not reached, 1 = low, 2 = medium, 3 = high) and `hazard_matrix.tif` (the
//! diagram cell, 10 × intensity class + probability class, 1 = weak/low … 3 = strong/high; nodata off the
//! terrain and 0 where no rock came).

use crate::error::{Error, Result};
use crate::raster::Grid;
use serde::{Deserialize, Serialize};

/// Which per-cell energy sets the intensity.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum IntensityEnergy {
    /// 95th percentile over rocks (default).
    #[default]
    P95,
    /// Largest.
    Max,
}

/// `[hazard_zones]`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ZoneSettings {
    /// Kinetic energy thresholds between weak, medium and strong intensity, kJ (default [30, 300]).
    pub energy_kj: [f64; 2],
    /// Reach probability thresholds between low, medium and high probability (default [0.01, 0.1]).
    pub reach: [f64; 2],
    /// Which per-cell energy: `p95` (default) or `max`.
    pub energy: IntensityEnergy,
}

impl Default for ZoneSettings {
    fn default() -> Self {
        ZoneSettings { energy_kj: [30.0, 300.0], reach: [0.01, 0.1], energy: IntensityEnergy::P95 }
    }
}

/// Hazard levels: code, name, colour (Swiss hazard map colours).
pub const LEVELS: [(u8, &str, [u8; 3]); 3] =
    [(1, "low (yellow)", [250, 215, 0]), (2, "medium (blue)", [40, 110, 225]), (3, "high (red)", [225, 30, 30])];

/// The area of each hazard level (low, medium, high) of a level grid, m².
pub fn areas_m2(levels: &Grid) -> [f64; 3] {
    let cell_m2 = levels.cell_x_m * levels.cell_y_m;
    [1.0, 2.0, 3.0].map(|l| levels.values.iter().filter(|&&v| v == l).count() as f64 * cell_m2)
}

/// The hazard level (1 low, 2 medium, 3 high) of intensity class `i` and probability class `p` (1..=3 each).
pub fn level(i: u8, p: u8) -> u8 {
    match (i, p) {
        (3, _) | (2, 3) => 3,
        (2, _) | (1, 3) => 2,
        _ => 1,
    }
}

impl ZoneSettings {
    /// Checks the thresholds (`field` locates them in errors).
    pub fn check(&self, field: &str) -> Result<()> {
        let [e1, e2] = self.energy_kj;
        if !(e1.is_finite() && e2.is_finite() && 0.0 < e1 && e1 < e2) {
            return Err(Error::invalid(
                format!("{field}.energy_kj"),
                format!("[{e1}, {e2}] is not an increasing pair of positive energies"),
                "use e.g. [30, 300]",
            ));
        }
        let [p1, p2] = self.reach;
        if !(p1.is_finite() && p2.is_finite() && 0.0 < p1 && p1 < p2 && p2 <= 1.0) {
            return Err(Error::invalid(
                format!("{field}.reach"),
                format!("[{p1}, {p2}] is not an increasing pair of probabilities in (0, 1]"),
                "use e.g. [0.01, 0.1]",
            ));
        }
        Ok(())
    }

    /// Intensity class (1..=3) of an energy in kJ.
    pub fn intensity(&self, kj: f64) -> u8 {
        1 + (kj > self.energy_kj[0]) as u8 + (kj > self.energy_kj[1]) as u8
    }

    /// Probability class (1..=3) of a reach probability. Compared at the rasters' precision (f32), so that a cell
    /// reached by exactly 10 % of the rocks, stored as the f32 nearest 0.1 (slightly above it), is not high.
    pub fn probability(&self, p: f64) -> u8 {
        let above = |threshold: f64| (p as f32 > threshold as f32) as u8;
        1 + above(self.reach[0]) + above(self.reach[1])
    }

    /// The zone grids (levels, matrix cells) of a run from its rasters, in the order of [`crate::run::RASTERS`]
    /// (reach probability second, then the energies' P95 and max).
    pub fn run_grids(&self, rasters: &[Grid]) -> (Grid, Grid) {
        let energy = match self.energy {
            IntensityEnergy::P95 => &rasters[2],
            IntensityEnergy::Max => &rasters[3],
        };
        self.grids(&rasters[1], energy)
    }

    /// The zone grids (levels, matrix cells) from the reach probability and the energy rasters (kJ) of a run.
    pub fn grids(&self, reach: &Grid, energy_kj: &Grid) -> (Grid, Grid) {
        let mut levels = reach.clone();
        let mut matrix = reach.clone();
        for k in 0..reach.values.len() {
            let (p, e) = (reach.values[k], energy_kj.values[k]);
            let (l, m) = if p.is_nan() {
                (f32::NAN, f32::NAN)
            } else if p <= 0.0 || e.is_nan() {
                (0.0, 0.0)
            } else {
                let (i, q) = (self.intensity(e as f64), self.probability(p as f64));
                (level(i, q) as f32, (10 * i + q) as f32)
            };
            levels.values[k] = l;
            matrix.values[k] = m;
        }
        (levels, matrix)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn swiss_diagram_and_classes() {
        let s = ZoneSettings::default();
        assert_eq!((s.intensity(29.0), s.intensity(30.0), s.intensity(31.0), s.intensity(301.0)), (1, 1, 2, 3));
        assert_eq!((s.probability(0.001), s.probability(0.05), s.probability(0.5)), (1, 2, 3));
        // A cell reached by exactly 10 % (1 %) of the rocks, as the rasters store it, is medium (low): the f32
        // nearest 0.1 lies above 0.1.
        let stored = |rocks: f64, of: f64| (rocks / of) as f32 as f64;
        assert!(stored(5.0, 50.0) > 0.1);
        assert_eq!((s.probability(stored(5.0, 50.0)), s.probability(stored(6.0, 50.0))), (2, 3));
        assert_eq!((s.probability(stored(1.0, 100.0)), s.probability(stored(2.0, 100.0))), (1, 2));
        assert_eq!([level(3, 1), level(2, 3), level(2, 2), level(1, 3), level(1, 2), level(1, 1)], [3, 3, 2, 2, 1, 1]);
        let mut reach = Grid::filled(4, 1, 0.0, 1.0, 1.0, 0.0);
        reach.values = vec![f32::NAN, 0.0, 0.05, 0.5];
        let mut e = reach.clone();
        e.values = vec![f32::NAN, f32::NAN, 10.0, 500.0];
        let (l, m) = s.grids(&reach, &e);
        assert!(l.values[0].is_nan());
        assert_eq!(&l.values[1..], &[0.0, 1.0, 3.0]);
        assert_eq!(&m.values[1..], &[0.0, 12.0, 33.0]);
        assert!(ZoneSettings { reach: [0.2, 0.1], ..s.clone() }.check("z").is_err());
    }
}
