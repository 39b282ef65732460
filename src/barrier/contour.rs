//! Contour lines of the terrain: marching squares over a [`HeightGrid`], stitched into polylines, with every
//! vertex then moved onto the exact level of the triangulated surface.
//!
//! Marching squares (Lorensen & Cline 1987 in 2D): a node counts as above the level when its height is at or above
//! it; an edge whose ends differ carries a crossing point, placed by linear interpolation; the two saddle cases are
//! resolved by the mean of the four corners. Cells with a node off the terrain are skipped, so lines end at holes
//! and edges. Segments are joined through their shared edge points into open or closed polylines.
//!
//! The grid interpolation puts a vertex off the level where the surface bends inside a grid cell (a bench crest),
//! so each vertex is then moved by up to three Newton steps along the gradient of the triangle under it,
//! z(p) − L → 0, each step at most one grid spacing, kept only while it brings the height closer to the level
//! (ours).

use super::grid::HeightGrid;
use crate::terrain::Terrain;
use std::collections::HashMap;

/// A grid edge: its id and its two nodes (i, j).
type Edge = (u64, (usize, usize), (usize, usize));

/// The contour polylines of `grid` at level `level` (local frame, m). Closed lines repeat their first vertex.
pub fn contour_lines(grid: &HeightGrid, level: f64) -> Vec<Vec<[f64; 2]>> {
    let (nx, ny) = (grid.nx, grid.ny);
    if nx < 2 || ny < 2 {
        return Vec::new();
    }
    let above = |v: f64| v >= level;
    // Edge ids: horizontal edge (i, j)–(i+1, j) is j·nx + i; vertical edge (i, j)–(i, j+1) is nx·ny + j·nx + i.
    let h_edge = |i: usize, j: usize| (j * nx + i) as u64;
    let v_edge = |i: usize, j: usize| (nx * ny + j * nx + i) as u64;
    let mut points: HashMap<u64, [f64; 2]> = HashMap::new();
    let mut segments: Vec<(u64, u64)> = Vec::new();
    let mut point = |id: u64, a: (usize, usize), b: (usize, usize)| {
        points.entry(id).or_insert_with(|| {
            let (za, zb) = (grid.at(a.0, a.1), grid.at(b.0, b.1));
            let t = if zb != za { ((level - za) / (zb - za)).clamp(0.0, 1.0) } else { 0.5 };
            let (pa, pb) = (grid.node(a.0, a.1), grid.node(b.0, b.1));
            [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])]
        });
        id
    };
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let (z00, z10, z11, z01) = (grid.at(i, j), grid.at(i + 1, j), grid.at(i + 1, j + 1), grid.at(i, j + 1));
            if z00.is_nan() || z10.is_nan() || z11.is_nan() || z01.is_nan() {
                continue;
            }
            let case = above(z00) as u8 | (above(z10) as u8) << 1 | (above(z11) as u8) << 2 | (above(z01) as u8) << 3;
            if case == 0 || case == 15 {
                continue;
            }
            let bottom = || (h_edge(i, j), (i, j), (i + 1, j));
            let right = || (v_edge(i + 1, j), (i + 1, j), (i + 1, j + 1));
            let top = || (h_edge(i, j + 1), (i, j + 1), (i + 1, j + 1));
            let left = || (v_edge(i, j), (i, j), (i, j + 1));
            let centre_above = above(0.25 * (z00 + z10 + z11 + z01));
            let pairs: Vec<(Edge, Edge)> = match case {
                1 | 14 => vec![(bottom(), left())],
                2 | 13 => vec![(bottom(), right())],
                3 | 12 => vec![(left(), right())],
                4 | 11 => vec![(right(), top())],
                6 | 9 => vec![(bottom(), top())],
                7 | 8 => vec![(left(), top())],
                5 if centre_above => vec![(bottom(), right()), (top(), left())],
                5 => vec![(bottom(), left()), (right(), top())],
                10 if centre_above => vec![(bottom(), left()), (right(), top())],
                _ => vec![(bottom(), right()), (top(), left())],
            };
            for (a, b) in pairs {
                let ia = point(a.0, a.1, a.2);
                let ib = point(b.0, b.1, b.2);
                segments.push((ia, ib));
            }
        }
    }
    stitch(&segments, &points)
}

/// Joins segments sharing end points into polylines (deterministic: in the order segments were made).
fn stitch(segments: &[(u64, u64)], points: &HashMap<u64, [f64; 2]>) -> Vec<Vec<[f64; 2]>> {
    let mut at: HashMap<u64, Vec<usize>> = HashMap::new();
    for (k, (a, b)) in segments.iter().enumerate() {
        at.entry(*a).or_default().push(k);
        at.entry(*b).or_default().push(k);
    }
    let mut used = vec![false; segments.len()];
    let mut out = Vec::new();
    let next = |from: u64, used: &mut Vec<bool>| -> Option<u64> {
        let k = *at.get(&from)?.iter().find(|&&k| !used[k])?;
        used[k] = true;
        let (a, b) = segments[k];
        Some(if a == from { b } else { a })
    };
    for k in 0..segments.len() {
        if used[k] {
            continue;
        }
        used[k] = true;
        let (a, b) = segments[k];
        let mut forward = vec![a, b];
        while let Some(n) = next(*forward.last().unwrap_or(&b), &mut used) {
            forward.push(n);
            if n == a {
                break;
            }
        }
        let closed = forward.len() > 2 && forward.first() == forward.last();
        let mut ids = forward;
        if !closed {
            let mut backward = Vec::new();
            let mut from = a;
            while let Some(n) = next(from, &mut used) {
                backward.push(n);
                from = n;
            }
            backward.reverse();
            backward.extend(ids);
            ids = backward;
        }
        out.push(ids.iter().filter_map(|id| points.get(id).copied()).collect());
    }
    out
}

/// Moves `p` onto the surface level `level` (see the module notes); returns the moved point.
pub fn refine_onto_level(terrain: &Terrain, p: [f64; 2], level: f64, max_step_m: f64) -> [f64; 2] {
    let mut p = p;
    let Some(mut err) = terrain.surface.height(p[0], p[1]).map(|z| z - level) else { return p };
    for _ in 0..3 {
        if err.abs() < 1e-6 {
            break;
        }
        let Some(sp) = terrain.surface.at(p[0], p[1]) else { break };
        let n = sp.normal;
        if n.z.abs() < 1e-9 {
            break;
        }
        let (gx, gy) = (-n.x / n.z, -n.y / n.z);
        let g2 = gx * gx + gy * gy;
        if g2 < 1e-9 {
            break;
        }
        let (mut sx, mut sy) = (err * gx / g2, err * gy / g2);
        let len = (sx * sx + sy * sy).sqrt();
        if len > max_step_m {
            sx *= max_step_m / len;
            sy *= max_step_m / len;
        }
        let q = [p[0] - sx, p[1] - sy];
        match terrain.surface.height(q[0], q[1]) {
            Some(z) if (z - level).abs() < err.abs() => {
                p = q;
                err = z - level;
            }
            _ => break,
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cone() -> HeightGrid {
        // z = distance from (5, 5): circles.
        let (nx, ny, h) = (21, 21, 0.5);
        let z = (0..ny)
            .flat_map(|j| (0..nx).map(move |i| ((i as f64 * h - 5.0).powi(2) + (j as f64 * h - 5.0).powi(2)).sqrt()))
            .collect();
        HeightGrid { x0: 0.0, y0: 0.0, h, nx, ny, z }
    }

    #[test]
    fn circle_is_one_closed_line_near_the_radius() {
        let lines = contour_lines(&cone(), 3.0);
        assert_eq!(lines.len(), 1);
        let l = &lines[0];
        assert_eq!(l.first(), l.last());
        for p in l {
            let r = ((p[0] - 5.0).powi(2) + (p[1] - 5.0).powi(2)).sqrt();
            assert!((r - 3.0).abs() < 0.05, "{r}");
        }
    }

    #[test]
    fn open_line_across_a_ramp_and_holes_cut_it() {
        let (nx, ny, h) = (11, 6, 1.0);
        let mut z: Vec<f64> = (0..ny).flat_map(|_| (0..nx).map(|i| i as f64)).collect();
        let mut g = HeightGrid { x0: 0.0, y0: 0.0, h, nx, ny, z: z.clone() };
        let lines = contour_lines(&g, 4.5);
        assert_eq!(lines.len(), 1);
        assert_eq!(lines[0].len(), 6);
        assert!(lines[0].iter().all(|p| (p[0] - 4.5).abs() < 1e-12));
        // A hole at row 2 splits it in two.
        for i in 0..nx {
            z[2 * nx + i] = f64::NAN;
        }
        g.z = z;
        assert_eq!(contour_lines(&g, 4.5).len(), 2);
    }
}
