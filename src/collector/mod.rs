//! Data collectors: lines on the terrain that record the rocks crossing them, as RocFall3 and RAMMS barriers or
//! "data collectors" do.
//!
//! A collector is a polyline in the terrain's horizontal frame, cut into stretches of `segment_m` metres (the last
//! one shorter) from its first vertex. While rocks run, every move between two path samples (at most
//! `sample_spacing_m` apart, 0.5 m by default) is tested against the collector segments; a crossing is where the
//! horizontal path meets the line, and the rock's quantities there are interpolated linearly between the two
//! samples:
//!
//! - translational and total (translational + rotational) kinetic energy;
//! - passing height: the height of the rock's lowest point above the ground, measured vertically (the
//!   engine's clearance), so a fence of height h is touched exactly by rocks passing below h;
//! - speed of the centre of mass;
//! - crossing angle: the angle in plan between the rock's horizontal velocity and the line, 0–90° (90° = square on,
//!   the direction fences are tested in; small = glancing). Ours: RocFall3 reports an impact angle at its barriers
//!   without a published definition;
//! - rock size: the diameter of the sphere of the rock's volume (for design heights).
//!
//! Each rock counts once per line (its first crossing of the line) and once per stretch (its first crossing of
//! that stretch). Per line and per stretch the collector reports the fraction of released rocks that cross, and
//! the 50th, 90th, 95th and 99th percentiles and the maximum of every quantity over those crossings, from fixed
//! bins ([`Dist`]: 50 logarithmic bins a decade for energies, heights, speeds and sizes, within 4.7 %; 0.5°
//! bins for angles), so memory does not grow with the number of rocks. A rock caught by a barrier on the line
//! counts as crossing it (it reached the line).

pub mod dist;
pub mod facts;
pub mod stats;
pub mod track;
pub mod write;

pub use dist::{Bins, Dist};
pub use stats::{CollectorStats, LineStats, Quantity, QuantityDists, StretchStats};
pub use track::{CollectorSet, CollectorTrack, Crossing, ProtectedZone, RockCrossings};

use crate::error::{Error, Result};
use crate::terrain::{horizontal_to_local, Terrain};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Default stretch length, m.
pub const DEFAULT_SEGMENT_M: f64 = 5.0;

/// The shortest stretch of a collector or a barrier line, m (ours: about a block's width; 10⁻⁹ m asked for 10¹¹
/// stretches and exhausted memory).
pub const MIN_SEGMENT_M: f64 = 0.5;

/// The most stretches of one collector line (ours: 50 km at the smallest `segment_m`, past any pit or road line).
pub const MAX_STRETCHES: usize = 100_000;

fn default_segment_m() -> f64 {
    DEFAULT_SEGMENT_M
}

/// `[[collectors]]` in a scenario: a line given inline or in a file.
///
/// ```toml
/// [[collectors]]
/// name = "road"
/// line = [[120.0, 0.0], [120.0, 100.0]]   # or: file = "road.geojson" (LineString) or "road.csv" (x,y)
/// segment_m = 5.0                          # stretch length (default 5)
/// ```
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CollectorSpec {
    /// Name for outputs (default: `collector_N`; a file's features keep their `name`).
    pub name: Option<String>,
    /// Polyline vertices (x, y) in the terrain's horizontal frame.
    #[serde(default)]
    pub line: Vec<[f64; 2]>,
    /// Or a GeoJSON (LineString, Feature or FeatureCollection) or CSV (x,y) file, relative to the scenario.
    pub file: Option<PathBuf>,
    /// Stretch length, m (default 5).
    #[serde(default = "default_segment_m")]
    pub segment_m: f64,
}

impl CollectorSpec {
    /// Checks the spec (`field` locates it in errors) and makes its file path absolute (relative to `base`).
    pub fn check(&mut self, field: &str, base: &Path) -> Result<()> {
        if !(self.segment_m.is_finite() && self.segment_m >= MIN_SEGMENT_M) {
            return Err(Error::invalid(
                format!("{field}.segment_m"),
                format!("must be at least {MIN_SEGMENT_M} m, got {}", self.segment_m),
                "give a stretch length in m, e.g. 5",
            ));
        }
        match (&self.file, self.line.is_empty()) {
            (Some(_), false) => return Err(Error::invalid(field, "has both line and file", "keep one of them")),
            (None, true) => {
                return Err(Error::invalid(
                    field,
                    "has neither line nor file",
                    "give line = [[x1, y1], [x2, y2], ...] or file = \"line.geojson\"",
                ))
            }
            (None, false) => {
                if self.line.len() < 2 {
                    return Err(Error::invalid(
                        format!("{field}.line"),
                        format!("has {} vertices", self.line.len()),
                        "give at least 2 [x, y] vertices",
                    ));
                }
                if let Some(i) = self.line.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
                    return Err(Error::invalid(
                        format!("{field}.line[{i}]"),
                        "is not a finite [x, y] pair",
                        "give plain numbers",
                    ));
                }
            }
            (Some(f), true) => {
                let p = base.join(f);
                if !p.is_file() {
                    return Err(Error::invalid(
                        format!("{field}.file"),
                        format!("{} does not exist", p.display()),
                        "paths are relative to the scenario file",
                    ));
                }
                crate::io::geojson::read_lines(&p)?;
                self.file = Some(p);
            }
        }
        Ok(())
    }

    /// The collectors of this spec (one per line of its file) in the terrain's local frame; `index` numbers
    /// default names.
    pub fn build(&self, index: usize, terrain: &Terrain) -> Result<Vec<Collector>> {
        let base_name = self.name.clone().unwrap_or_else(|| format!("collector_{index}"));
        let lines: Vec<(String, Vec<[f64; 2]>)> = match &self.file {
            None => vec![(base_name, self.line.clone())],
            Some(p) => {
                let lines = crate::io::geojson::read_lines(p)?;
                let n = lines.len();
                lines
                    .into_iter()
                    .enumerate()
                    .map(|(k, l)| {
                        let name = match (l.name, n) {
                            (Some(name), _) => name,
                            (None, 1) => base_name.clone(),
                            (None, _) => format!("{base_name}_{k}"),
                        };
                        (name, l.xy)
                    })
                    .collect()
            }
        };
        Ok(lines
            .into_iter()
            .map(|(name, xy)| {
                let local = xy.iter().map(|p| horizontal_to_local(terrain.up, &terrain.origin, *p)).collect();
                Collector::new(name, local, self.segment_m)
            })
            .collect())
    }
}

/// A collector line in the terrain's local frame, cut into stretches.
#[derive(Debug, Clone, PartialEq)]
pub struct Collector {
    /// Name for outputs.
    pub name: String,
    /// Vertices (x, y), local frame, m.
    pub line_m: Vec<[f64; 2]>,
    /// Stretch length, m.
    pub segment_m: f64,
    /// Distance along the line at each vertex, m.
    cum_m: Vec<f64>,
}

impl Collector {
    /// A collector on `line_m` (local frame) with stretches of `segment_m`. Repeated vertices are dropped.
    pub fn new(name: impl Into<String>, line_m: Vec<[f64; 2]>, segment_m: f64) -> Self {
        let mut line: Vec<[f64; 2]> = Vec::with_capacity(line_m.len());
        for p in line_m {
            if line.last() != Some(&p) {
                line.push(p);
            }
        }
        let mut cum = Vec::with_capacity(line.len());
        let mut d = 0.0;
        for (i, p) in line.iter().enumerate() {
            if i > 0 {
                d += dist(line[i - 1], *p);
            }
            cum.push(d);
        }
        Collector { name: name.into(), line_m: line, segment_m, cum_m: cum }
    }

    /// Length along the line, m.
    pub fn length_m(&self) -> f64 {
        self.cum_m.last().copied().unwrap_or(0.0)
    }

    /// True if the line ends where it starts.
    pub fn is_closed(&self) -> bool {
        self.line_m.len() > 3 && dist(self.line_m[0], self.line_m[self.line_m.len() - 1]) < 1e-9
    }

    /// Number of stretches (at least 1).
    pub fn stretch_count(&self) -> usize {
        ((self.length_m() / self.segment_m).ceil() as usize).max(1)
    }

    /// The stretch holding distance `d_m` along the line.
    pub fn stretch_of(&self, d_m: f64) -> usize {
        ((d_m / self.segment_m).floor().max(0.0) as usize).min(self.stretch_count() - 1)
    }

    /// Start and end distance of stretch `k`, m.
    pub fn stretch_span_m(&self, k: usize) -> (f64, f64) {
        let a = k as f64 * self.segment_m;
        (a.min(self.length_m()), ((k + 1) as f64 * self.segment_m).min(self.length_m()))
    }

    /// Distance along the line at the start of segment `i` (vertex i), m.
    pub fn distance_at_vertex(&self, i: usize) -> f64 {
        self.cum_m[i]
    }

    /// The point at distance `d_m` along the line.
    pub fn point_at(&self, d_m: f64) -> [f64; 2] {
        let d = d_m.clamp(0.0, self.length_m());
        let i = match self.cum_m.partition_point(|&c| c <= d) {
            0 => 0,
            k => (k - 1).min(self.line_m.len().saturating_sub(2)),
        };
        if self.line_m.len() < 2 {
            return self.line_m[0];
        }
        let seg = self.cum_m[i + 1] - self.cum_m[i];
        let f = if seg > 0.0 { (d - self.cum_m[i]) / seg } else { 0.0 };
        let (a, b) = (self.line_m[i], self.line_m[i + 1]);
        [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]
    }

    /// The part of the line between distances `from_m` and `to_m` (from ≤ to), with its inner vertices.
    pub fn sub_line(&self, from_m: f64, to_m: f64) -> Vec<[f64; 2]> {
        let (a, b) = (from_m.clamp(0.0, self.length_m()), to_m.clamp(0.0, self.length_m()));
        let mut out = vec![self.point_at(a)];
        for (i, &c) in self.cum_m.iter().enumerate() {
            if c > a && c < b {
                out.push(self.line_m[i]);
            }
        }
        out.push(self.point_at(b));
        out
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
}

/// The collectors of a scenario's `[[collectors]]`, in the terrain's local frame.
///
/// # Errors
/// Two collectors of one name (their rows could not be told apart), or a line with no point over the terrain
/// (coordinates in another frame, most likely), named by its entry.
pub fn scenario_collectors(specs: &[CollectorSpec], terrain: &Terrain) -> Result<Vec<Collector>> {
    let mut out: Vec<Collector> = Vec::new();
    for (i, s) in specs.iter().enumerate() {
        for c in s.build(i, terrain)? {
            let field = format!("collectors[{i}] ({})", c.name);
            if out.iter().any(|o| o.name == c.name) {
                return Err(Error::invalid(
                    field,
                    "another collector has this name",
                    "give every collector its own name (collectors.csv has one row per name)",
                ));
            }
            if c.stretch_count() > MAX_STRETCHES {
                return Err(Error::invalid(
                    format!("collectors[{i}].segment_m"),
                    format!(
                        "cuts the {} m line '{}' into {} stretches, more than {MAX_STRETCHES}",
                        crate::error::number_text(c.length_m()),
                        c.name,
                        c.stretch_count()
                    ),
                    "give a longer segment_m, or check the line's coordinates (the terrain's CRS)",
                ));
            }
            if !terrain.surface.any_point_over(&c.line_m, 1.0) {
                return Err(Error::invalid(
                    field,
                    "no point of the line lies over the terrain",
                    "give the line in the terrain's coordinates (the CRS of the DEM, or the mesh's x and y)",
                ));
            }
            out.push(c);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stretches_points_and_sub_lines() {
        let c = Collector::new("c", vec![[0.0, 0.0], [10.0, 0.0], [10.0, 0.0], [10.0, 7.0]], 5.0);
        assert_eq!(c.line_m.len(), 3);
        assert_eq!(c.length_m(), 17.0);
        assert_eq!(c.stretch_count(), 4);
        assert_eq!(c.stretch_span_m(3), (15.0, 17.0));
        assert_eq!(c.stretch_of(12.0), 2);
        assert_eq!(c.stretch_of(17.0), 3);
        assert_eq!(c.point_at(12.0), [10.0, 2.0]);
        assert_eq!(c.sub_line(5.0, 15.0), vec![[5.0, 0.0], [10.0, 0.0], [10.0, 5.0]]);
        assert!(!c.is_closed());
    }
}
