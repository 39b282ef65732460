//! Splitting terrain triangles at a polygon's edges, so that a `clip` ends the terrain, and a zone its material,
//! exactly on its polygon rather than on the whole triangles whose centre lies inside it (ours).
//!
//! Each triangle that an edge of the polygon crosses is cut by the vertical plane through that edge (Sutherland–
//! Hodgman against one line at a time): the pieces are convex and on one side of every such edge, so each lies wholly
//! inside or wholly outside the polygon, and its centre tells which. The pieces are fanned back into triangles on the
//! original triangle's plane, so the surface's heights do not change; triangles no edge crosses are kept as they are.

use super::{point_in_polygon, Surface, SurfaceStats, Terrain};
use nalgebra::Vector3;

/// A vertex of a piece: its position and, for a corner of the original triangle, its index.
type Corner = (Vector3<f64>, Option<u32>);

/// Splits the triangles that an edge of `poly` (horizontal, the vertices' frame) crosses, appending the new vertices
/// to `vertices`. Returns the triangles and their `tags` (a name or material; each piece takes its triangle's).
pub fn split_at_polygon<T: Clone>(
    vertices: &mut Vec<Vector3<f64>>,
    triangles: Vec<[u32; 3]>,
    tags: Vec<T>,
    poly: &[[f64; 2]],
) -> (Vec<[u32; 3]>, Vec<T>) {
    let edges: Vec<([f64; 2], [f64; 2])> = (0..poly.len()).map(|i| (poly[i], poly[(i + 1) % poly.len()])).collect();
    // The edges binned by rows of y, so that each triangle meets only the few edges near it (a circle of 360
    // vertices clipping a 1,000 × 1,000 DEM, 2·10⁶ triangles, adds about 0.5 s to the build; 2.2 s without the rows).
    let (y_lo, y_hi) = poly.iter().fold((f64::MAX, f64::MIN), |(l, h), p| (l.min(p[1]), h.max(p[1])));
    let n_rows = edges.len().min(4096);
    let row_m = ((y_hi - y_lo) / n_rows as f64).max(1e-9);
    let row = |y: f64| (((y - y_lo) / row_m).max(0.0) as usize).min(n_rows - 1);
    let mut rows = vec![Vec::new(); n_rows];
    for (i, (a, b)) in edges.iter().enumerate() {
        (row(a[1].min(b[1]))..=row(a[1].max(b[1]))).for_each(|r| rows[r].push(i));
    }
    let mut out = (Vec::with_capacity(triangles.len()), Vec::with_capacity(tags.len()));
    let mut near = Vec::new();
    for (tri, tag) in triangles.into_iter().zip(tags) {
        let corners = tri.map(|k| vertices[k as usize]);
        let (lo, hi) = corners.iter().fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), c| {
            ([lo[0].min(c.x), lo[1].min(c.y)], [hi[0].max(c.x), hi[1].max(c.y)])
        });
        // Cutting by an edge's whole line where only its segment's box meets the triangle's may cut more than
        // needed (near the segment's ends): harmless, each piece still lies on one side of the segment.
        near.clear();
        if hi[1] >= y_lo && lo[1] <= y_hi {
            for &i in (row(lo[1])..=row(hi[1])).flat_map(|r| &rows[r]) {
                let (a, b) = edges[i];
                let boxes_meet = a[0].min(b[0]) <= hi[0]
                    && a[0].max(b[0]) >= lo[0]
                    && a[1].min(b[1]) <= hi[1]
                    && a[1].max(b[1]) >= lo[1];
                if boxes_meet && !near.contains(&i) {
                    near.push(i);
                }
            }
        }
        // No piece at all (no allocation) for a triangle no edge is near, one for a triangle no edge crosses.
        let mut pieces: Vec<Vec<Corner>> = Vec::new();
        if !near.is_empty() {
            pieces.push((0..3).map(|i| (corners[i], Some(tri[i]))).collect());
        }
        for &i in &near {
            let (a, b) = edges[i];
            pieces = pieces.into_iter().flat_map(|p| cut(p, a, b)).collect();
        }
        if pieces.len() <= 1 {
            out.0.push(tri);
            out.1.push(tag);
            continue;
        }
        for piece in pieces {
            let index: Vec<u32> = piece
                .iter()
                .map(|&(v, k)| {
                    k.unwrap_or_else(|| {
                        vertices.push(v);
                        (vertices.len() - 1) as u32
                    })
                })
                .collect();
            for k in 1..index.len() - 1 {
                out.0.push([index[0], index[k], index[k + 1]]);
                out.1.push(tag.clone());
            }
        }
    }
    out
}

/// True if the horizontal centre of triangle `tri` lies inside `poly`: after [`split_at_polygon`] at `poly`, true
/// exactly for the triangles that lie inside it.
pub fn centre_inside(vertices: &[Vector3<f64>], tri: &[u32; 3], poly: &[[f64; 2]]) -> bool {
    let c = tri.iter().fold(Vector3::zeros(), |acc, &k| acc + vertices[k as usize]) / 3.0;
    point_in_polygon(c.x, c.y, poly)
}

/// Splits `triangles` at `poly` ([`split_at_polygon`]) and gives `tag` to the pieces inside it. Returns how many
/// triangles took it.
pub fn paint_polygon<T: Clone>(
    vertices: &mut Vec<Vector3<f64>>,
    triangles: &mut Vec<[u32; 3]>,
    tags: &mut Vec<T>,
    poly: &[[f64; 2]],
    tag: T,
) -> usize {
    (*triangles, *tags) = split_at_polygon(vertices, std::mem::take(triangles), std::mem::take(tags), poly);
    let mut taken = 0;
    for (tri, t) in triangles.iter().zip(tags.iter_mut()) {
        if centre_inside(vertices, tri, poly) {
            *t = tag.clone();
            taken += 1;
        }
    }
    taken
}

impl Terrain {
    /// Gives material `material` to the ground under `poly` (horizontal, local frame), the triangles its edges cross
    /// split first, so that the zone ends exactly on the polygon as a scenario's `[[terrain.zones]]` entry does (the
    /// calibration's zones). Returns the number of triangles the zone took (0 if the polygon misses the terrain).
    pub fn paint_zone(&mut self, poly: &[[f64; 2]], material: u16) -> crate::Result<usize> {
        let mut vertices = self.surface.vertices().to_vec();
        let mut triangles = self.surface.triangles().to_vec();
        let mut tags = self.triangle_material.clone();
        let taken = paint_polygon(&mut vertices, &mut triangles, &mut tags, poly, material);
        let (surface, kept, stats) = Surface::new_like(vertices, &triangles, &self.surface).ok_or_else(|| {
            crate::Error::invalid("terrain zone", "no usable triangle after the split", "check the zone's polygon")
        })?;
        self.triangle_material = kept.iter().map(|&i| tags[i]).collect();
        self.stats =
            SurfaceStats { degenerate_dropped: self.stats.degenerate_dropped + stats.degenerate_dropped, ..stats };
        self.surface = surface;
        Ok(taken)
    }
}

/// The parts of the convex `piece` on either side of the vertical plane through the line a → b: the piece itself if
/// the line does not cross it (corners within 10⁻⁹ of the piece's size of the line count as on it).
fn cut(piece: Vec<Corner>, a: [f64; 2], b: [f64; 2]) -> Vec<Vec<Corner>> {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len = dx.hypot(dy);
    if len == 0.0 {
        return vec![piece];
    }
    let side = |v: &Vector3<f64>| (dx * (v.y - a[1]) - dy * (v.x - a[0])) / len;
    let size = piece.iter().map(|(v, _)| (v.xy() - piece[0].0.xy()).norm()).fold(0.0, f64::max);
    let eps = 1e-9 * size.max(1e-9);
    let d: Vec<f64> = piece.iter().map(|(v, _)| side(v)).map(|s| if s.abs() <= eps { 0.0 } else { s }).collect();
    if d.iter().all(|&s| s >= 0.0) || d.iter().all(|&s| s <= 0.0) {
        return vec![piece];
    }
    let (mut left, mut right) = (Vec::new(), Vec::new());
    for i in 0..piece.len() {
        let j = (i + 1) % piece.len();
        if d[i] >= 0.0 {
            left.push(piece[i]);
        }
        if d[i] <= 0.0 {
            right.push(piece[i]);
        }
        if d[i] * d[j] < 0.0 {
            let t = d[i] / (d[i] - d[j]);
            let p = (piece[i].0 + t * (piece[j].0 - piece[i].0), None);
            left.push(p);
            right.push(p);
        }
    }
    vec![left, right]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::point_in_polygon;

    /// A 10 m square of two triangles, the plane z = x + 2y.
    fn square() -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
        let v = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        (v.iter().map(|p| Vector3::new(p[0], p[1], p[0] + 2.0 * p[1])).collect(), vec![[0, 1, 2], [0, 2, 3]])
    }

    fn area_xy(v: &[Vector3<f64>], t: &[u32; 3]) -> f64 {
        let [a, b, c] = t.map(|k| v[k as usize]);
        0.5 * ((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y)).abs()
    }

    #[test]
    fn the_pieces_inside_a_polygon_cover_exactly_its_part_of_the_terrain_on_the_same_plane() {
        // A concave polygon (an L) cutting across both triangles, partly beyond the square.
        let poly = [[3.0, -5.0], [7.5, -5.0], [7.5, 4.0], [15.0, 4.0], [15.0, 6.5], [3.0, 6.5]];
        let (mut v, t) = square();
        let (tris, names) = split_at_polygon(&mut v, t, vec!["a", "b"], &poly);
        assert_eq!(tris.len(), names.len());
        let inside: f64 = tris
            .iter()
            .filter(|t| {
                let c = t.iter().fold(Vector3::zeros(), |s, &k| s + v[k as usize]) / 3.0;
                point_in_polygon(c.x, c.y, &poly)
            })
            .map(|t| area_xy(&v, t))
            .sum();
        // Within the square: x 3–7.5 over y 0–6.5, plus x 7.5–10 over y 4–6.5.
        let expected = 4.5 * 6.5 + 2.5 * 2.5;
        assert!((inside - expected).abs() < 1e-9, "{inside} against {expected}");
        let total: f64 = tris.iter().map(|t| area_xy(&v, t)).sum();
        assert!((total - 100.0).abs() < 1e-9, "{total}");
        // Every piece lies wholly on one side: points just inside each of its corners are where its centre is.
        for t in &tris {
            assert!(area_xy(&v, t) > 1e-12);
            let c = t.iter().fold(Vector3::zeros(), |s, &k| s + v[k as usize]) / 3.0;
            for &k in t {
                let p = c + 0.999 * (v[k as usize] - c);
                assert_eq!(point_in_polygon(p.x, p.y, &poly), point_in_polygon(c.x, c.y, &poly), "{t:?}");
            }
        }
        assert!(v.iter().all(|p| (p.z - p.x - 2.0 * p.y).abs() < 1e-12), "a new vertex off the plane");
        assert!(v.len() > 4);
    }

    #[test]
    fn triangles_no_edge_crosses_are_kept_as_they_were() {
        let (mut v, t) = square();
        let poly = [[-1.0, -1.0], [11.0, -1.0], [11.0, 11.0], [-1.0, 11.0]];
        let (tris, names) = split_at_polygon(&mut v, t.clone(), vec!["a", "b"], &poly);
        assert_eq!((tris, names, v.len()), (t.clone(), vec!["a", "b"], 4));
        // An edge along the square's diagonal, the triangles' shared edge, cuts neither.
        let poly = [[0.0, 0.0], [10.0, 10.0], [-5.0, 10.0]];
        let (tris, _) = split_at_polygon(&mut v, t.clone(), vec!["a", "b"], &poly);
        assert_eq!(tris, t);
    }
}
