//! Gauges along a profile: envelope stations every few metres and vertical collectors at chosen x. Each rock's
//! path is sampled where it crosses a gauge (height above the profile, speed); the ensemble statistics live in
//! fixed logarithmic bins, so memory does not grow with the number of rocks.
//!
//! # Units
//! Heights in m, speeds in m/s, energies in J.

use super::path::{FlightPiece, PathObserver, SlidePiece};
use super::profile::Profile;

/// Bins per doubling of the value: bin edges are `FLOOR · 2^(k/64)`, so a percentile read from the bins is within
/// ±0.55 % of a value of the ensemble.
const BINS_PER_OCTAVE: f64 = 64.0;
/// Values below this (m, m/s or J) fall in the underflow bin and are reported as 0.
const FLOOR: f64 = 1e-3;

/// A histogram over fixed logarithmic bins (see the module docs). Only the range of bins that received values is
/// stored.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LogHistogram {
    count: u64,
    underflow: u64,
    offset: i64,
    bins: Vec<u64>,
    max: f64,
}

impl LogHistogram {
    /// Adds a value (negative values count as 0).
    pub fn add(&mut self, value: f64) {
        let v = if value.is_finite() { value.max(0.0) } else { 0.0 };
        self.count += 1;
        if self.count == 1 || v > self.max {
            self.max = v;
        }
        if v < FLOOR {
            self.underflow += 1;
            return;
        }
        let k = ((v / FLOOR).log2() * BINS_PER_OCTAVE).floor() as i64;
        if self.bins.is_empty() {
            self.offset = k;
            self.bins.push(0);
        } else if k < self.offset {
            let grow = (self.offset - k) as usize;
            self.bins.splice(0..0, std::iter::repeat_n(0, grow));
            self.offset = k;
        } else if k >= self.offset + self.bins.len() as i64 {
            self.bins.resize((k - self.offset + 1) as usize, 0);
        }
        self.bins[(k - self.offset) as usize] += 1;
    }

    /// Number of values.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The largest value (exact), or `None` when empty.
    pub fn max(&self) -> Option<f64> {
        (self.count > 0).then_some(self.max)
    }

    /// The `p`-quantile (0 < p ≤ 1) by the nearest-rank rule, read at the geometric centre of its bin (never above
    /// the exact maximum); `None` when empty.
    pub fn quantile(&self, p: f64) -> Option<f64> {
        if self.count == 0 {
            return None;
        }
        let rank = ((p.clamp(0.0, 1.0) * self.count as f64).ceil() as u64).max(1);
        if rank <= self.underflow {
            return Some(0.0);
        }
        let mut seen = self.underflow;
        for (i, &c) in self.bins.iter().enumerate() {
            seen += c;
            if seen >= rank {
                let k = (self.offset + i as i64) as f64;
                return Some((FLOOR * ((k + 0.5) / BINS_PER_OCTAVE).exp2()).min(self.max));
            }
        }
        Some(self.max)
    }
}

/// Statistics of the rocks passing one gauge: each rock counts once, with the largest height and speed of its
/// crossings there.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GaugeStats {
    /// Passing height above the profile (measured vertically), m.
    pub height_m: LogHistogram,
    /// Speed, m/s.
    pub speed_mps: LogHistogram,
    /// Translational kinetic energy, J.
    pub kinetic_j: LogHistogram,
}

impl GaugeStats {
    /// Number of rocks that passed.
    pub fn rocks(&self) -> u64 {
        self.height_m.count()
    }
}

/// A rock crossing a gauge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Gauge index: stations first, then collectors.
    pub gauge: u32,
    /// Height above the profile, measured vertically, m.
    pub height_m: f64,
    /// Speed, m/s.
    pub speed_mps: f64,
}

/// Where the gauges are: stations at `x0 + k·spacing` (k < `n_stations`) and collectors at given x.
#[derive(Debug, Clone, PartialEq)]
pub struct GaugeLayout {
    /// x of the first station, m.
    pub station_x0_m: f64,
    /// Station spacing, m.
    pub station_spacing_m: f64,
    /// Number of stations.
    pub n_stations: usize,
    /// Collector positions, m, in the order given.
    pub collectors_x_m: Vec<f64>,
}

impl GaugeLayout {
    /// Stations every `spacing_m` over the whole profile, and the given collectors.
    pub fn new(profile: &Profile, spacing_m: f64, collectors_x_m: Vec<f64>) -> GaugeLayout {
        let (x0, x1) = profile.x_range_m();
        let n = ((x1 - x0) / spacing_m + 1e-9).floor() as usize + 1;
        GaugeLayout { station_x0_m: x0, station_spacing_m: spacing_m, n_stations: n, collectors_x_m }
    }

    /// x of gauge `i` (stations first, then collectors), m.
    pub fn x_of(&self, i: usize) -> f64 {
        if i < self.n_stations {
            self.station_x0_m + i as f64 * self.station_spacing_m
        } else {
            self.collectors_x_m[i - self.n_stations]
        }
    }

    /// Total number of gauges.
    pub fn len(&self) -> usize {
        self.n_stations + self.collectors_x_m.len()
    }

    /// Whether there are no gauges.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Calls `f(gauge, x)` for every gauge with x in [lo, hi].
    fn each_in(&self, lo: f64, hi: f64, mut f: impl FnMut(u32, f64)) {
        let d = self.station_spacing_m;
        let k0 = ((lo - self.station_x0_m) / d).ceil().max(0.0);
        let k1 = ((hi - self.station_x0_m) / d).floor().min(self.n_stations as f64 - 1.0);
        if k0 <= k1 {
            for k in k0 as usize..=k1 as usize {
                f(k as u32, self.station_x0_m + k as f64 * d);
            }
        }
        for (j, &x) in self.collectors_x_m.iter().enumerate() {
            if x >= lo && x <= hi {
                f((self.n_stations + j) as u32, x);
            }
        }
    }
}

/// A [`PathObserver`] that records one rock's gauge crossings.
#[derive(Debug)]
pub struct GaugeRecorder<'a> {
    layout: &'a GaugeLayout,
    profile: &'a Profile,
    /// The crossings, in path order (a gauge may appear more than once).
    pub crossings: Vec<Crossing>,
}

impl<'a> GaugeRecorder<'a> {
    /// A recorder for one rock.
    pub fn new(layout: &'a GaugeLayout, profile: &'a Profile) -> Self {
        GaugeRecorder { layout, profile, crossings: Vec::new() }
    }
}

impl PathObserver for GaugeRecorder<'_> {
    fn flight(&mut self, f: &FlightPiece) {
        if f.vx_mps == 0.0 {
            return; // a vertical fall crosses no vertical line
        }
        let (lo, hi) = f.x_range_m();
        let (profile, out) = (self.profile, &mut self.crossings);
        self.layout.each_in(lo, hi, |gauge, x| {
            let dt = ((x - f.x0_m) / f.vx_mps).clamp(0.0, f.duration_s);
            let p = f.position_at(dt);
            let v = f.velocity_at(dt);
            let ground = profile.z_at(x).unwrap_or(p[1]);
            out.push(Crossing { gauge, height_m: (p[1] - ground).max(0.0), speed_mps: v[0].hypot(v[1]) });
        });
    }

    fn slide(&mut self, s: &SlidePiece) {
        if s.direction[0] == 0.0 {
            return;
        }
        let (lo, hi) = s.x_range_m();
        let out = &mut self.crossings;
        self.layout.each_in(lo, hi, |gauge, x| {
            let d = ((x - s.x0_m) / s.direction[0]).max(0.0);
            out.push(Crossing { gauge, height_m: 0.0, speed_mps: s.speed_at_distance(d) });
        });
    }
}

/// Ensemble statistics at every gauge of a layout.
#[derive(Debug, Clone, PartialEq)]
pub struct GaugeEnsemble {
    /// The gauges.
    pub layout: GaugeLayout,
    /// Statistics per gauge, indexed like the layout.
    pub stats: Vec<GaugeStats>,
}

impl GaugeEnsemble {
    /// Empty statistics for `layout`.
    pub fn new(layout: GaugeLayout) -> Self {
        let stats = vec![GaugeStats::default(); layout.len()];
        GaugeEnsemble { layout, stats }
    }

    /// Adds one rock of `mass_kg` from its crossings: each gauge counts the rock once, with its largest height and
    /// speed there. The crossings are sorted in place.
    pub fn add_rock(&mut self, crossings: &mut [Crossing], mass_kg: f64) {
        crossings.sort_by_key(|c| c.gauge);
        let mut i = 0;
        while i < crossings.len() {
            let g = crossings[i].gauge;
            let (mut h, mut v) = (0.0f64, 0.0f64);
            while i < crossings.len() && crossings[i].gauge == g {
                h = h.max(crossings[i].height_m);
                v = v.max(crossings[i].speed_mps);
                i += 1;
            }
            let st = &mut self.stats[g as usize];
            st.height_m.add(h);
            st.speed_mps.add(v);
            st.kinetic_j.add(0.5 * mass_kg * v * v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_are_within_bin_precision() {
        let mut h = LogHistogram::default();
        for i in 1..=1000 {
            h.add(i as f64 * 0.01);
        }
        h.add(0.0);
        assert_eq!(h.count(), 1001);
        for (p, exact) in [(0.5, 5.0), (0.9, 9.0), (0.95, 9.5)] {
            let q = h.quantile(p).unwrap();
            assert!((q / exact - 1.0).abs() < 0.006, "{p}: {q}");
        }
        assert_eq!(h.max(), Some(10.0));
        assert_eq!(h.quantile(1.0), Some(10.0));
        assert_eq!(h.quantile(0.0001), Some(0.0));
        assert_eq!(LogHistogram::default().quantile(0.5), None);
    }

    #[test]
    fn a_rock_counts_once_per_gauge() {
        let p = Profile::new(&[[0.0, 0.0], [10.0, 0.0]], vec![0], vec!["m".into()], "t").unwrap();
        let layout = GaugeLayout::new(&p, 1.0, vec![2.5]);
        assert_eq!(layout.n_stations, 11);
        let mut e = GaugeEnsemble::new(layout);
        let mut c = vec![
            Crossing { gauge: 3, height_m: 1.0, speed_mps: 2.0 },
            Crossing { gauge: 11, height_m: 0.5, speed_mps: 4.0 },
            Crossing { gauge: 3, height_m: 2.0, speed_mps: 1.0 },
        ];
        e.add_rock(&mut c, 2.0);
        assert_eq!(e.stats[3].rocks(), 1);
        assert_eq!(e.stats[3].height_m.max(), Some(2.0));
        assert_eq!(e.stats[3].speed_mps.max(), Some(2.0));
        assert_eq!(e.stats[11].kinetic_j.max(), Some(16.0));
        assert_eq!(e.stats[0].rocks(), 0);
    }
}
