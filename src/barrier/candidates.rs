//! Candidate barrier lines, from the terrain alone (before any rock runs):
//!
//! - **contours**: contour lines every `contour_interval_m` (default: a 1-2-5 step giving at most 30 levels over the
//!   relief), kept only where the ground under them is at most `max_slope_deg` steep (default 45°; ours: flexible
//!   barriers are anchored on slopes rather than on cliffs), cut into pieces there; pieces shorter than two
//!   stretches are dropped;
//! - **benches** (pits and benched slopes): flat bands (ground under 10° over at least 2 % of the area at one
//!   elevation, ±0.5 m; ours) are benches; each gets its crest line, the contour 0.25 m below its floor (the top of
//!   the face under it), and its toe line, the contour 0.25 m above its floor (the foot of the face above). The toe
//!   of the lowest bench (the pit floor) is also offset onto the floor by `offsets_m`;
//! - **offsets**: the user's toe line offset downslope, and the asset line offset upslope, by `offsets_m`
//!   (horizontal parallel offsets with mitred corners, cut where they leave the terrain).
//!
//! Contour levels within 1 m of a bench floor are skipped (the bench lines cover them).

use super::contour::{contour_lines, refine_onto_level};
use super::grid::HeightGrid;
use super::settings::DesignSpec;
use crate::render::nice_step;
use crate::terrain::{horizontal_to_local, Terrain};
use serde::Serialize;

/// Where a candidate comes from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "type")]
pub enum CandidateKind {
    /// A contour line at `elevation_m` (map elevation).
    Contour {
        /// Elevation, m.
        elevation_m: f64,
    },
    /// The crest of the bench whose floor is at `floor_m`.
    BenchCrest {
        /// Floor elevation, m.
        floor_m: f64,
    },
    /// The toe of the face above the bench whose floor is at `floor_m`.
    BenchToe {
        /// Floor elevation, m.
        floor_m: f64,
    },
    /// The lowest bench's toe offset onto its floor.
    FloorOffset {
        /// Offset, m.
        offset_m: f64,
    },
    /// The user's toe line offset downslope.
    ToeOffset {
        /// Offset, m.
        offset_m: f64,
    },
    /// The asset line offset upslope.
    AssetOffset {
        /// Offset, m.
        offset_m: f64,
    },
}

/// A candidate line, local frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// Name for outputs, e.g. `contour 1650 m` or `bench 80 m crest`.
    pub name: String,
    /// Where it comes from.
    pub kind: CandidateKind,
    /// Vertices (x, y), local frame, m.
    pub line_m: Vec<[f64; 2]>,
}

/// Slope under which ground counts as flat for bench detection, degrees (ours).
const FLAT_DEG: f64 = 10.0;
/// A bench holds at least this share of the terrain's area at one elevation (ours).
const BENCH_AREA_SHARE: f64 = 0.02;
/// Bench crest and toe lines sit this far below and above the floor, m (ours).
const BENCH_EDGE_M: f64 = 0.25;

/// All candidates for `terrain` with the settings `spec`; `cell_m` is the run's raster cell (grid spacing is half
/// of it).
pub fn candidates(terrain: &Terrain, spec: &DesignSpec, cell_m: f64) -> Vec<Candidate> {
    let grid = HeightGrid::sample(terrain, 0.5 * cell_m, 2_000_000);
    let oz = terrain.origin.z;
    let min_len = 2.0 * spec.segment_m;
    let mut out = Vec::new();
    let benches = if spec.benches { bench_levels(&grid) } else { Vec::new() };
    for &floor in &benches {
        for (kind, level) in [
            (CandidateKind::BenchCrest { floor_m: floor + oz }, floor - BENCH_EDGE_M),
            (CandidateKind::BenchToe { floor_m: floor + oz }, floor + BENCH_EDGE_M),
        ] {
            let what = if matches!(kind, CandidateKind::BenchCrest { .. }) { "crest" } else { "toe" };
            for (k, line) in
                level_lines(terrain, &grid, level, None).into_iter().filter(|l| length(l) >= min_len).enumerate()
            {
                let name = format!("bench {} m {what}{}", fmt_level(floor + oz), suffix(k));
                out.push(Candidate { name, kind, line_m: line });
            }
        }
    }
    // The pit floor: the lowest bench with a toe line.
    if let Some(floor) = benches.first() {
        let toes = level_lines(terrain, &grid, floor + BENCH_EDGE_M, None);
        for &d in spec.offsets_m.iter().filter(|d| **d > 0.0) {
            for (k, toe) in toes.iter().filter(|l| length(l) >= min_len).enumerate() {
                for (m, line) in
                    offset_line(terrain, toe, d, Side::Down).into_iter().filter(|l| length(l) >= min_len).enumerate()
                {
                    let name = format!("floor {} m toe + {} m{}", fmt_level(floor + oz), fmt_level(d), suffix(k + m));
                    out.push(Candidate { name, kind: CandidateKind::FloorOffset { offset_m: d }, line_m: line });
                }
            }
        }
    }
    if spec.contours {
        if let Some((lo, hi)) = grid.z_range() {
            // At most 500 levels, whatever the interval asked for (ours: beyond that the candidates only cost time).
            let step = spec.contour_interval_m.unwrap_or_else(|| nice_step(hi - lo, 30)).max((hi - lo) / 500.0);
            let first = ((lo + oz) / step).ceil() as i64;
            let last = ((hi + oz) / step).floor() as i64;
            for k in first..=last {
                let elevation = k as f64 * step;
                let level = elevation - oz;
                if benches.iter().any(|b| (b - level).abs() < 1.0) {
                    continue;
                }
                let lines = level_lines(terrain, &grid, level, Some(spec.max_slope_deg));
                for (m, line) in lines.into_iter().filter(|l| length(l) >= min_len).enumerate() {
                    let name = format!("contour {} m{}", fmt_level(elevation), suffix(m));
                    out.push(Candidate { name, kind: CandidateKind::Contour { elevation_m: elevation }, line_m: line });
                }
            }
        }
    }
    let user = |pts: &[[f64; 2]]| -> Vec<[f64; 2]> {
        pts.iter().map(|p| horizontal_to_local(terrain.up, &terrain.origin, *p)).collect()
    };
    for (pts, side) in [(&spec.toe_line, Side::Down), (&spec.asset_line, Side::Up)] {
        if pts.is_empty() {
            continue;
        }
        let base = user(pts);
        for &d in spec.offsets_m.iter().filter(|d| **d > 0.0) {
            for (m, line) in
                offset_line(terrain, &base, d, side).into_iter().filter(|l| length(l) >= min_len).enumerate()
            {
                let (kind, name) = match side {
                    Side::Down => (
                        CandidateKind::ToeOffset { offset_m: d },
                        format!("toe line + {} m{}", fmt_level(d), suffix(m)),
                    ),
                    Side::Up => (
                        CandidateKind::AssetOffset { offset_m: d },
                        format!("asset line - {} m{}", fmt_level(d), suffix(m)),
                    ),
                };
                out.push(Candidate { name, kind, line_m: line });
            }
        }
    }
    out
}

fn suffix(k: usize) -> String {
    if k == 0 {
        String::new()
    } else {
        format!(" ({})", (b'a' + (k % 26) as u8) as char)
    }
}

/// An elevation or distance for names: integer when it is one, else one decimal.
fn fmt_level(v: f64) -> String {
    if (v - v.round()).abs() < 1e-6 {
        format!("{}", v.round() as i64)
    } else {
        format!("{v:.1}")
    }
}

/// Polyline length, m.
pub fn length(line: &[[f64; 2]]) -> f64 {
    line.windows(2).map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt()).sum()
}

/// Contour lines at local `level`, vertices refined onto the surface, cut where the ground is steeper than
/// `max_slope_deg` (if given).
fn level_lines(terrain: &Terrain, grid: &HeightGrid, level: f64, max_slope_deg: Option<f64>) -> Vec<Vec<[f64; 2]>> {
    let mut out = Vec::new();
    for line in contour_lines(grid, level) {
        let refined: Vec<[f64; 2]> = line.iter().map(|p| refine_onto_level(terrain, *p, level, grid.h)).collect();
        let Some(max) = max_slope_deg else {
            out.push(refined);
            continue;
        };
        out.extend(pieces_where(refined, |p| {
            terrain.surface.at(p[0], p[1]).is_some_and(|s| s.normal.z.clamp(-1.0, 1.0).acos().to_degrees() <= max)
        }));
    }
    out.retain(|l| l.len() >= 2);
    out
}

/// The runs of at least two consecutive vertices of `line` where `keep` holds.
fn pieces_where(line: Vec<[f64; 2]>, keep: impl Fn(&[f64; 2]) -> bool) -> Vec<Vec<[f64; 2]>> {
    let mut out = Vec::new();
    let mut piece: Vec<[f64; 2]> = Vec::new();
    for p in line {
        if keep(&p) {
            piece.push(p);
        } else if !piece.is_empty() {
            out.push(std::mem::take(&mut piece));
        }
    }
    out.push(piece);
    out.retain(|l| l.len() >= 2);
    out
}

/// Floor elevations (local) of the benches: peaks of the flat-area histogram by elevation, lowest first.
fn bench_levels(grid: &HeightGrid) -> Vec<f64> {
    let Some((lo, hi)) = grid.z_range() else { return Vec::new() };
    let bin = 0.5;
    let n = ((hi - lo) / bin).floor() as usize + 1;
    let mut count = vec![0usize; n];
    let mut sum = vec![0.0; n];
    let mut valid = 0usize;
    for j in 0..grid.ny {
        for i in 0..grid.nx {
            let z = grid.at(i, j);
            if z.is_nan() {
                continue;
            }
            valid += 1;
            if grid.slope_deg(i, j) < FLAT_DEG {
                let k = (((z - lo) / bin).floor() as usize).min(n - 1);
                count[k] += 1;
                sum[k] += z;
            }
        }
    }
    let need = (BENCH_AREA_SHARE * valid as f64).max(1.0);
    let mut levels: Vec<f64> = Vec::new();
    for k in 0..n {
        let window = k.saturating_sub(1)..(k + 2).min(n);
        let c: usize = count[window.clone()].iter().sum();
        let is_peak = count[window.clone()].iter().all(|&x| x <= count[k]) && count[k] > 0;
        if is_peak && c as f64 >= need {
            let z = sum[window.clone()].iter().sum::<f64>() / c as f64;
            if levels.last().is_none_or(|l| z - l > 2.0 * bin) {
                levels.push(z);
            }
        }
    }
    levels
}

/// Which side of a line to offset to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    /// The lower side.
    Down,
    /// The higher side.
    Up,
}

/// `line` offset horizontally by `d` to its lower (or higher) side, mitred (miter at most 2 d), cut into the
/// pieces that lie on the terrain.
fn offset_line(terrain: &Terrain, line: &[[f64; 2]], d: f64, side: Side) -> Vec<Vec<[f64; 2]>> {
    let n = line.len();
    if n < 2 {
        return Vec::new();
    }
    let seg_normal = |k: usize| {
        let (a, b) = (line[k], line[k + 1]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l = (dx * dx + dy * dy).sqrt().max(1e-12);
        [-dy / l, dx / l]
    };
    // Which side is down: sample the ground a metre to the left of every segment's middle.
    let mut score = 0.0;
    for k in 0..n - 1 {
        let m = [(line[k][0] + line[k + 1][0]) / 2.0, (line[k][1] + line[k + 1][1]) / 2.0];
        let nrm = seg_normal(k);
        let h = |s: f64| terrain.surface.height(m[0] + s * nrm[0], m[1] + s * nrm[1]);
        if let (Some(l), Some(r)) = (h(1.0), h(-1.0)) {
            score += r - l;
        }
    }
    // score > 0: the left side is lower.
    let left_is_down = score > 0.0;
    let sign = match (side, left_is_down) {
        (Side::Down, true) | (Side::Up, false) => 1.0,
        _ => -1.0,
    };
    let mut pts = Vec::with_capacity(n);
    for (k, p) in line.iter().enumerate() {
        let nrm = match k {
            0 => seg_normal(0),
            k if k == n - 1 => seg_normal(n - 2),
            k => {
                let (a, b) = (seg_normal(k - 1), seg_normal(k));
                let s = [a[0] + b[0], a[1] + b[1]];
                let dot = (s[0] * a[0] + s[1] * a[1]).max(0.5);
                [s[0] / dot, s[1] / dot]
            }
        };
        pts.push([p[0] + sign * d * nrm[0], p[1] + sign * d * nrm[1]]);
    }
    pieces_where(pts, |p| terrain.surface.at(p[0], p[1]).is_some())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::TruncNormal;
    use crate::terrain::Material;

    #[test]
    fn offsets_go_downhill_and_stay_on_the_terrain() {
        let m = Material {
            name: "m".into(),
            cr: TruncNormal::fixed(0.3),
            static_friction_deg: 40.0,
            dynamic_friction_deg: 30.0,
            dynamic_friction_sd_deg: 0.0,
            drag_per_s: 0.0,
        };
        // Falls towards +x.
        let t = Terrain::from_function(100.0, 20, m, |x, _| 100.0 - 0.5 * x).unwrap();
        let line = vec![[50.0, 10.0], [50.0, 90.0]];
        let down = offset_line(&t, &line, 10.0, Side::Down);
        assert_eq!(down.len(), 1);
        assert!(down[0].iter().all(|p| (p[0] - 60.0).abs() < 1e-9));
        let up = offset_line(&t, &line, 10.0, Side::Up);
        assert!(up[0].iter().all(|p| (p[0] - 40.0).abs() < 1e-9));
        assert!(offset_line(&t, &line, 60.0, Side::Down).is_empty());
    }
}
