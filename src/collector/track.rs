//! Finding where one rock's path crosses the collector lines (and when it reaches a protected zone), as the rock
//! runs.

use super::Collector;
use crate::sim::barrier::segment_intersection;
use crate::sim::{BarrierHit, Observer, Sample};
use crate::terrain::point_in_polygon;

/// The area a barrier should protect, in the local frame: a rock reaches it when its path crosses the line, or
/// when a path sample lies inside the polygon.
#[derive(Debug, Clone, PartialEq)]
pub enum ProtectedZone {
    /// An asset line (a road, a railway, a pit ramp).
    Line(Vec<[f64; 2]>),
    /// An asset polygon (a building plot, a pit floor).
    Polygon(Vec<[f64; 2]>),
}

/// All collectors of a run, with a uniform-grid index of their segments, and the protected zone, if any.
#[derive(Debug, Clone)]
pub struct CollectorSet {
    /// The collectors.
    pub collectors: Vec<Collector>,
    /// The protected zone tracked for every rock.
    pub zone: Option<ProtectedZone>,
    x0: f64,
    y0: f64,
    bin_m: f64,
    nx: usize,
    ny: usize,
    offsets: Vec<u32>,
    /// (collector, segment) per bin.
    items: Vec<(u32, u32)>,
}

impl CollectorSet {
    /// Indexes `collectors` (local frame).
    pub fn new(collectors: Vec<Collector>, zone: Option<ProtectedZone>) -> Self {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for c in &collectors {
            for p in &c.line_m {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        if collectors.is_empty() || !lo[0].is_finite() {
            return CollectorSet {
                collectors,
                zone,
                x0: 0.0,
                y0: 0.0,
                bin_m: 1.0,
                nx: 0,
                ny: 0,
                offsets: vec![0],
                items: Vec::new(),
            };
        }
        // Bins of at least 4 m and at most about 512 a side (ours: a few segments per bin for lines with vertices
        // every few metres).
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let bin_m = (span / 512.0).max(4.0);
        let nx = ((hi[0] - lo[0]) / bin_m).floor() as usize + 1;
        let ny = ((hi[1] - lo[1]) / bin_m).floor() as usize + 1;
        let mut pairs: Vec<(usize, (u32, u32))> = Vec::new();
        for (ci, c) in collectors.iter().enumerate() {
            for (si, w) in c.line_m.windows(2).enumerate() {
                let (i0, i1) = bin_range(w[0][0].min(w[1][0]), w[0][0].max(w[1][0]), lo[0], bin_m, nx);
                let (j0, j1) = bin_range(w[0][1].min(w[1][1]), w[0][1].max(w[1][1]), lo[1], bin_m, ny);
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        pairs.push((j * nx + i, (ci as u32, si as u32)));
                    }
                }
            }
        }
        pairs.sort_unstable();
        let mut offsets = vec![0u32; nx * ny + 1];
        for (b, _) in &pairs {
            offsets[b + 1] += 1;
        }
        for k in 1..offsets.len() {
            offsets[k] += offsets[k - 1];
        }
        let items = pairs.into_iter().map(|(_, it)| it).collect();
        CollectorSet { collectors, zone, x0: lo[0], y0: lo[1], bin_m, nx, ny, offsets, items }
    }

    /// True if there is nothing to track.
    pub fn is_empty(&self) -> bool {
        self.collectors.is_empty() && self.zone.is_none()
    }

    /// Every collector crossing of the horizontal move a → b: (collector, segment, s along a → b, t along the
    /// collector segment), sorted by s.
    fn crossings(&self, a: [f64; 2], b: [f64; 2], out: &mut Vec<(u32, u32, f64, f64)>) {
        out.clear();
        if self.nx == 0 {
            return;
        }
        let (x1, y1) = (self.x0 + self.nx as f64 * self.bin_m, self.y0 + self.ny as f64 * self.bin_m);
        if a[0].max(b[0]) < self.x0 || a[1].max(b[1]) < self.y0 || a[0].min(b[0]) > x1 || a[1].min(b[1]) > y1 {
            return;
        }
        let (i0, i1) = bin_range(a[0].min(b[0]), a[0].max(b[0]), self.x0, self.bin_m, self.nx);
        let (j0, j1) = bin_range(a[1].min(b[1]), a[1].max(b[1]), self.y0, self.bin_m, self.ny);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let k = j * self.nx + i;
                for &(ci, si) in &self.items[self.offsets[k] as usize..self.offsets[k + 1] as usize] {
                    if out.iter().any(|&(c, s, _, _)| c == ci && s == si) {
                        continue;
                    }
                    let line = &self.collectors[ci as usize].line_m;
                    let (u, v) = (line[si as usize], line[si as usize + 1]);
                    if let Some(s) = segment_intersection(a, b, u, v) {
                        // Where along the collector segment: solve with the roles swapped.
                        let t = segment_intersection(u, v, a, b).unwrap_or(0.0);
                        out.push((ci, si, s, t));
                    }
                }
            }
        }
        out.sort_by(|x, y| x.2.total_cmp(&y.2).then(x.0.cmp(&y.0)).then(x.1.cmp(&y.1)));
    }
}

/// The bin range [lo, hi] (clamped) covering [a, b].
fn bin_range(a: f64, b: f64, origin: f64, bin: f64, n: usize) -> (usize, usize) {
    let f = |v: f64| (((v - origin) / bin).floor().max(0.0) as usize).min(n - 1);
    (f(a), f(b))
}

/// A rock's crossing of a collector, with its quantities there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Time, s.
    pub t_s: f64,
    /// Distance along the collector, m.
    pub along_m: f64,
    /// Translational kinetic energy, J.
    pub translational_j: f64,
    /// Total kinetic energy, J.
    pub kinetic_j: f64,
    /// Passing height of the rock's lowest point above the ground, m.
    pub height_m: f64,
    /// Speed, m/s.
    pub speed_mps: f64,
    /// Angle in plan between the horizontal velocity and the line, 0–90°.
    pub angle_deg: f64,
}

/// What one rock left on the collectors.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RockCrossings {
    /// The rock's size (diameter of the sphere of its volume), m.
    pub size_m: f64,
    /// First crossing of each line crossed: (collector, crossing), in the order the lines were first crossed.
    pub line_first: Vec<(u32, Crossing)>,
    /// First crossing of each stretch crossed: (collector, stretch, crossing).
    pub stretch_first: Vec<(u32, u32, Crossing)>,
    /// When the rock first reached the protected zone, s.
    pub zone_t_s: Option<f64>,
    /// Barriers met: (barrier index, caught).
    pub barrier_hits: Vec<(u32, bool)>,
}

/// Observer that records a rock's crossings of the collectors of a [`CollectorSet`].
#[derive(Debug, Clone)]
pub struct CollectorTrack<'a> {
    set: &'a CollectorSet,
    last: Option<Sample>,
    scratch: Vec<(u32, u32, f64, f64)>,
    /// What was recorded so far.
    pub crossings: RockCrossings,
}

impl<'a> CollectorTrack<'a> {
    /// A track on `set` for a rock of size `size_m`.
    pub fn new(set: &'a CollectorSet, size_m: f64) -> Self {
        CollectorTrack {
            set,
            last: None,
            scratch: Vec::new(),
            crossings: RockCrossings { size_m, ..Default::default() },
        }
    }

    /// The rock's crossings.
    pub fn into_crossings(self) -> RockCrossings {
        self.crossings
    }

    fn zone(&mut self, a: &Sample, b: &Sample) {
        if self.crossings.zone_t_s.is_some() {
            return;
        }
        let (pa, pb) = ([a.position_m.x, a.position_m.y], [b.position_m.x, b.position_m.y]);
        match &self.set.zone {
            None => {}
            Some(ProtectedZone::Line(line)) => {
                let mut best: Option<f64> = None;
                for w in line.windows(2) {
                    if let Some(s) = segment_intersection(pa, pb, w[0], w[1]) {
                        best = Some(best.map_or(s, |t: f64| t.min(s)));
                    }
                }
                if let Some(s) = best {
                    self.crossings.zone_t_s = Some(a.t_s + s * (b.t_s - a.t_s));
                }
            }
            Some(ProtectedZone::Polygon(poly)) if point_in_polygon(pb[0], pb[1], poly) => {
                self.crossings.zone_t_s = Some(b.t_s);
            }
            Some(ProtectedZone::Polygon(_)) => {}
        }
    }
}

fn lerp(a: f64, b: f64, s: f64) -> f64 {
    a + s * (b - a)
}

impl Observer for CollectorTrack<'_> {
    fn sample(&mut self, b: &Sample) {
        let Some(a) = self.last else {
            if let Some(ProtectedZone::Polygon(poly)) = &self.set.zone {
                if point_in_polygon(b.position_m.x, b.position_m.y, poly) {
                    self.crossings.zone_t_s = Some(b.t_s);
                }
            }
            self.last = Some(*b);
            return;
        };
        self.last = Some(*b);
        self.zone(&a, b);
        let (pa, pb) = ([a.position_m.x, a.position_m.y], [b.position_m.x, b.position_m.y]);
        if pa == pb {
            return;
        }
        let mut hits = std::mem::take(&mut self.scratch);
        self.set.crossings(pa, pb, &mut hits);
        for &(ci, si, s, t) in &hits {
            let c = &self.set.collectors[ci as usize];
            let (u, v) = (c.line_m[si as usize], c.line_m[si as usize + 1]);
            let along = c.distance_at_vertex(si as usize) + t * ((v[0] - u[0]).powi(2) + (v[1] - u[1]).powi(2)).sqrt();
            let vel = a.velocity_mps + (b.velocity_mps - a.velocity_mps) * s;
            let (vh, dh) =
                ((vel.x * vel.x + vel.y * vel.y).sqrt(), ((v[0] - u[0]).powi(2) + (v[1] - u[1]).powi(2)).sqrt());
            let angle = if vh > 0.0 && dh > 0.0 {
                ((vel.x * (v[1] - u[1]) - vel.y * (v[0] - u[0])).abs() / (vh * dh)).clamp(0.0, 1.0).asin().to_degrees()
            } else {
                90.0
            };
            let x = Crossing {
                t_s: lerp(a.t_s, b.t_s, s),
                along_m: along,
                translational_j: lerp(a.translational_j, b.translational_j, s),
                kinetic_j: lerp(a.kinetic_j, b.kinetic_j, s),
                height_m: lerp(a.clearance_m, b.clearance_m, s),
                speed_mps: vel.norm(),
                angle_deg: angle,
            };
            let r = &mut self.crossings;
            if !r.line_first.iter().any(|(k, _)| *k == ci) {
                r.line_first.push((ci, x));
            }
            let stretch = c.stretch_of(along) as u32;
            if !r.stretch_first.iter().any(|(k, st, _)| *k == ci && *st == stretch) {
                r.stretch_first.push((ci, stretch, x));
            }
        }
        self.scratch = hits;
    }

    fn barrier(&mut self, hit: &BarrierHit) {
        self.crossings.barrier_hits.push((hit.barrier as u32, hit.caught));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn sample(t: f64, x: f64, y: f64, e: f64) -> Sample {
        Sample {
            t_s: t,
            position_m: Vector3::new(x, y, 0.0),
            velocity_mps: Vector3::new(1.0, 1.0, 0.0),
            spin_radps: 0.0,
            translational_j: e,
            kinetic_j: e,
            clearance_m: e / 10.0,
            in_contact: false,
        }
    }

    #[test]
    fn first_crossings_per_line_and_stretch_and_zone() {
        let c = Collector::new("c", vec![[0.0, 5.0], [20.0, 5.0]], 5.0);
        let set = CollectorSet::new(
            vec![c],
            Some(ProtectedZone::Polygon(vec![[0.0, 8.0], [20.0, 8.0], [20.0, 20.0], [0.0, 20.0]])),
        );
        let mut tr = CollectorTrack::new(&set, 1.0);
        for (k, (x, y)) in [(6.0, 4.0), (7.0, 6.0), (8.0, 4.0), (12.0, 6.0), (12.0, 9.0)].iter().enumerate() {
            tr.sample(&sample(k as f64, *x, *y, 100.0 * (k + 1) as f64));
        }
        let r = tr.into_crossings();
        assert_eq!(r.line_first.len(), 1);
        let first = r.line_first[0].1;
        assert!((first.t_s - 0.5).abs() < 1e-12 && (first.along_m - 6.5).abs() < 1e-12);
        assert!((first.kinetic_j - 150.0).abs() < 1e-9 && (first.height_m - 15.0).abs() < 1e-9);
        assert!((first.angle_deg - 45.0).abs() < 1e-9);
        // Stretch 1 (5–10 m) crossed three times, stretch 2 (10–15 m) once: two stretch records.
        let stretches: Vec<u32> = r.stretch_first.iter().map(|s| s.1).collect();
        assert_eq!(stretches, vec![1, 2]);
        assert_eq!(r.zone_t_s, Some(4.0));
    }
}
