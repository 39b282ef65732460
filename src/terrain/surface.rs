//! The terrain surface as rocks see it: a 2.5D triangulated surface z(x, y) with a uniform grid index.
//!
//! Rock contact needs one question answered fast and exactly: how high is the ground under this (x, y), and which
//! way does it face? Every triangle is binned by its horizontal bounding box into a uniform grid; a query tests the
//! few triangles of one bin. Where several triangles lie over one point (an overhang), the highest is the surface:
//! talus treats terrain as 2.5D, like DEM-based codes (RAMMS, Rockyfor3D). A pyramid of per-bin maximum heights
//! bounds the ground under a whole rectangle, which lets free-flying rocks take long exact steps; a plane per bin
//! bounds it under a point, which settles most hull vertices of a rock on a slope without a triangle test.
//!
//! # Units
//! Metres, in the terrain's local frame (origin subtracted, z up).

use nalgebra::Vector3;

/// Where a vertical line meets the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Surface height, m.
    pub z_m: f64,
    /// Upward unit normal of the triangle.
    pub normal: Vector3<f64>,
    /// Triangle index.
    pub triangle: u32,
}

/// Per-triangle data for point location and height: barycentric inverse and plane z = a·x + b·y + c. Vertical
/// triangles have no footprint (`vertical` is set and the rest is unused): they take part in contact only.
#[derive(Debug, Clone, Copy)]
struct TriPlane {
    vertical: bool,
    x0: f64,
    y0: f64,
    inv: [f64; 4],
    a: f64,
    b: f64,
    c: f64,
}

/// The most bins a surface's grid index may take (ours: about 3 GB; a 4,000 × 4,000 DEM takes 64 million).
pub const MAX_INDEX_BINS: f64 = 1e8;

/// About how many bins [`Surface::new`] would index `triangles` with, and the width and height of their bounding
/// box, m: the box over bins of half the typical triangle leg. Far above the triangle count when the triangles lie
/// far apart (files in different CRSs, a stray vertex far from the rest), which the index cannot hold.
pub fn index_bins(vertices: &[Vector3<f64>], triangles: &[[u32; 3]]) -> (f64, f64, f64) {
    let (lo, hi, area) = footprint(vertices, triangles);
    let bin_m = bin_size_m(area, triangles.len());
    let (width_m, height_m) = (hi.x - lo.x, hi.y - lo.y);
    ((width_m / bin_m + 1.0) * (height_m / bin_m + 1.0), width_m, height_m)
}

/// The lowest and highest corners of the bounding box of `triangles` and their horizontal footprint area, m².
fn footprint(vertices: &[Vector3<f64>], triangles: &[[u32; 3]]) -> (Vector3<f64>, Vector3<f64>, f64) {
    let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
    let mut area = 0.0;
    for t in triangles {
        for &k in t {
            lo = lo.inf(&vertices[k as usize]);
            hi = hi.sup(&vertices[k as usize]);
        }
        let (a, b, c) = (vertices[t[0] as usize], vertices[t[1] as usize], vertices[t[2] as usize]);
        area += 0.5 * ((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y)).abs();
    }
    (lo, hi, area)
}

/// The index's bin size for `triangles` with a footprint of `area_m2`: half the typical triangle leg (half a DEM
/// cell), so that with exact overlap tests a bin holds one or two triangles.
fn bin_size_m(area_m2: f64, triangles: usize) -> f64 {
    (0.5 * area_m2 / triangles as f64).sqrt().max(1e-3)
}

/// A 2.5D triangulated surface with a grid index. Build it with [`Surface::new`].
#[derive(Debug, Clone)]
pub struct Surface {
    vertices: Vec<Vector3<f64>>,
    triangles: Vec<[u32; 3]>,
    planes: Vec<TriPlane>,
    normals: Vec<Vector3<f64>>,
    x0: f64,
    y0: f64,
    bin_m: f64,
    nx: usize,
    ny: usize,
    /// CSR: triangles of bin k are `items[offsets[k]..offsets[k + 1]]`.
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// Max-height pyramid; level 0 has nx × ny bins, each next level halves both sizes (rounded up).
    zmax: Vec<(usize, usize, Vec<f64>)>,
    /// Per bin, a plane (a, b, c) with z ≤ a·x + b·y + c for every triangle of the bin over the bin: on a slope far
    /// tighter than the bin's highest point (`c` infinite where the bin has no triangle with a footprint). Single
    /// precision, half the memory: `c` is computed with the rounded slopes and rounded up.
    upper: Vec<[f32; 3]>,
    z_min_m: f64,
    z_max_m: f64,
    extent: (f64, f64, f64, f64),
}

/// Counts of what [`Surface::new`] kept and dropped.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SurfaceStats {
    /// Triangles used.
    pub triangles: usize,
    /// Triangles dropped because they have (almost) no area or repeat a vertex.
    pub degenerate_dropped: usize,
    /// Vertical triangles (no horizontal footprint): they give no height but still stop rocks that hit them.
    pub vertical: usize,
}

impl Surface {
    /// Builds the surface from local-frame vertices and triangles (any winding). Returns the surface, the
    /// original indices of the triangles kept (so callers can carry per-triangle data) and what was dropped.
    /// Returns `None` if no triangle is usable.
    pub fn new(vertices: Vec<Vector3<f64>>, triangles: &[[u32; 3]]) -> Option<(Surface, Vec<usize>, SurfaceStats)> {
        Self::binned(vertices, triangles, None)
    }

    /// As [`Surface::new`], with the bins of `like`, a surface over the same ground (the same surface with some
    /// triangles split): its queries, and so a rock's steps, stay those of `like` away from the split triangles.
    pub fn new_like(
        vertices: Vec<Vector3<f64>>,
        triangles: &[[u32; 3]],
        like: &Surface,
    ) -> Option<(Surface, Vec<usize>, SurfaceStats)> {
        Self::binned(vertices, triangles, Some(like))
    }

    fn binned(
        vertices: Vec<Vector3<f64>>,
        triangles: &[[u32; 3]],
        like: Option<&Surface>,
    ) -> Option<(Surface, Vec<usize>, SurfaceStats)> {
        let mut stats = SurfaceStats::default();
        let mut kept = Vec::with_capacity(triangles.len());
        let mut tris = Vec::with_capacity(triangles.len());
        let mut planes = Vec::with_capacity(triangles.len());
        for (i, t) in triangles.iter().enumerate() {
            let [ia, ib, ic] = t.map(|k| k as usize);
            if ia == ib || ib == ic || ia == ic || ia.max(ib).max(ic) >= vertices.len() {
                stats.degenerate_dropped += 1;
                continue;
            }
            let (a, b, c) = (vertices[ia], vertices[ib], vertices[ic]);
            let n = (b - a).cross(&(c - a));
            let scale = (b - a).norm_squared().max((c - a).norm_squared()).max((c - b).norm_squared());
            if n.norm().is_nan() || n.norm() <= 1e-10 * scale || !n.iter().all(|v| v.is_finite()) {
                stats.degenerate_dropped += 1;
                continue;
            }
            // Horizontal footprint: 2 × signed area in xy.
            let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
            if det.abs() <= 1e-9 * scale {
                stats.vertical += 1;
                planes.push(TriPlane { vertical: true, x0: a.x, y0: a.y, inv: [0.0; 4], a: 0.0, b: 0.0, c: 0.0 });
                tris.push(*t);
                kept.push(i);
                continue;
            }
            let inv = [(c.y - a.y) / det, -(c.x - a.x) / det, -(b.y - a.y) / det, (b.x - a.x) / det];
            // z = a.z + u (b.z − a.z) + v (c.z − a.z), (u, v) = inv · (p − a)
            let (dz1, dz2) = (b.z - a.z, c.z - a.z);
            let pa = dz1 * inv[0] + dz2 * inv[2];
            let pb = dz1 * inv[1] + dz2 * inv[3];
            let pc = a.z - pa * a.x - pb * a.y;
            planes.push(TriPlane { vertical: false, x0: a.x, y0: a.y, inv, a: pa, b: pb, c: pc });
            tris.push(*t);
            kept.push(i);
        }
        stats.triangles = tris.len();
        if stats.triangles == stats.vertical {
            return None;
        }
        let (lo, hi, area) = footprint(&vertices, &tris);
        let (bin_m, nx, ny) = match like {
            Some(like) => (like.bin_m, like.nx, like.ny),
            None => {
                let bin_m = bin_size_m(area, stats.triangles - stats.vertical);
                let nx = (((hi.x - lo.x) / bin_m).floor() as usize + 1).min(1 << 15);
                let ny = (((hi.y - lo.y) / bin_m).floor() as usize + 1).min(1 << 15);
                (bin_m.max((hi.x - lo.x) / nx as f64).max((hi.y - lo.y) / ny as f64) * (1.0 + 1e-9), nx, ny)
            }
        };
        let normals = tris
            .iter()
            .zip(&planes)
            .map(|(t, p)| {
                if p.vertical {
                    let [a, b, c] = t.map(|k| vertices[k as usize]);
                    (b - a).cross(&(c - a)).normalize()
                } else {
                    Vector3::new(-p.a, -p.b, 1.0).normalize()
                }
            })
            .collect();
        let mut surface = Surface {
            vertices,
            triangles: tris,
            planes,
            normals,
            x0: lo.x,
            y0: lo.y,
            bin_m,
            nx,
            ny,
            offsets: Vec::new(),
            items: Vec::new(),
            zmax: Vec::new(),
            upper: Vec::new(),
            z_min_m: lo.z,
            z_max_m: hi.z,
            extent: (lo.x, lo.y, hi.x, hi.y),
        };
        surface.build_index();
        Some((surface, kept, stats))
    }

    fn bin_range(&self, lo: f64, hi: f64, origin: f64, n: usize) -> (usize, usize) {
        // `as` truncates and saturates (negative and NaN to 0): the floor clamped at 0, without a call to `floor`.
        let a = ((lo - origin) / self.bin_m) as usize;
        let b = ((hi - origin) / self.bin_m) as usize;
        (a.min(n - 1), b.min(n - 1))
    }

    fn build_index(&mut self) {
        let (nx, ny) = (self.nx, self.ny);
        // (bin, triangle) pairs for every bin the triangle's footprint touches (closed sets, with a small margin
        // so that points on shared edges find a triangle in their bin).
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(self.triangles.len() * 4);
        let mut zmax = vec![f64::NEG_INFINITY; nx * ny];
        let eps = 1e-9 * self.bin_m;
        for (t, tri) in self.triangles.iter().enumerate() {
            let p = tri.map(|k| self.vertices[k as usize]);
            let (x_lo, x_hi) = (p[0].x.min(p[1].x).min(p[2].x), p[0].x.max(p[1].x).max(p[2].x));
            let (y_lo, y_hi) = (p[0].y.min(p[1].y).min(p[2].y), p[0].y.max(p[1].y).max(p[2].y));
            let tz = p[0].z.max(p[1].z).max(p[2].z);
            let (i0, i1) = self.bin_range(x_lo - eps, x_hi + eps, self.x0, nx);
            let (j0, j1) = self.bin_range(y_lo - eps, y_hi + eps, self.y0, ny);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let bx = self.x0 + i as f64 * self.bin_m;
                    let by = self.y0 + j as f64 * self.bin_m;
                    if triangle_overlaps_box(&p, bx - eps, by - eps, bx + self.bin_m + eps, by + self.bin_m + eps) {
                        let k = j * nx + i;
                        pairs.push((k as u32, t as u32));
                        zmax[k] = zmax[k].max(tz);
                    }
                }
            }
        }
        pairs.sort_unstable();
        let mut counts = vec![0u32; nx * ny + 1];
        for &(k, _) in &pairs {
            counts[k as usize + 1] += 1;
        }
        for k in 1..counts.len() {
            counts[k] += counts[k - 1];
        }
        let items: Vec<u32> = pairs.into_iter().map(|(_, t)| t).collect();
        self.offsets = counts;
        self.items = items;
        self.upper = (0..nx * ny).map(|k| self.upper_plane(k)).collect();
        let mut levels = vec![(nx, ny, zmax)];
        while levels.last().map(|(w, h, _)| *w > 1 || *h > 1).unwrap_or(false) {
            let (w, h, prev) = levels.last().expect("non-empty");
            let (w2, h2) = (w.div_ceil(2), h.div_ceil(2));
            let mut next = vec![f64::NEG_INFINITY; w2 * h2];
            for j in 0..*h {
                for i in 0..*w {
                    let k = (j / 2) * w2 + i / 2;
                    next[k] = next[k].max(prev[j * w + i]);
                }
            }
            levels.push((w2, h2, next));
        }
        self.zmax = levels;
    }

    /// A plane over bin `k`'s triangles (those with a footprint) within the bin: their mean slope, raised to clear
    /// the highest of them at the corners of its part in the bin (where a linear function over a convex polygon
    /// peaks), plus a margin for rounding and for the small tolerance with which [`Surface::at`] counts a point on
    /// a triangle's edge as inside it.
    fn upper_plane(&self, k: usize) -> [f32; 3] {
        let tris = || {
            self.items[self.offsets[k] as usize..self.offsets[k + 1] as usize]
                .iter()
                .map(|&t| t as usize)
                .filter(|&t| !self.planes[t].vertical)
        };
        let n = tris().count() as f64;
        if n == 0.0 {
            return [0.0, 0.0, f32::INFINITY];
        }
        // The slopes as stored, so that the offset below is computed for them.
        let slope = |f: fn(&TriPlane) -> f64| (tris().map(|t| f(&self.planes[t])).sum::<f64>() / n) as f32;
        let (a32, b32) = (slope(|p| p.a), slope(|p| p.b));
        let (a, b) = (a32 as f64, b32 as f64);
        let (i, j) = (k % self.nx, k / self.nx);
        let (bx, by) = (self.x0 + i as f64 * self.bin_m, self.y0 + j as f64 * self.bin_m);
        let (mut c, mut margin) = (f64::NEG_INFINITY, 0.0f64);
        for t in tris() {
            let p = &self.planes[t];
            let corners = self.triangles[t].map(|v| [self.vertices[v as usize].x, self.vertices[v as usize].y]);
            // How far outside its footprint `at` may count a point as inside (1e-9 of its size, its longest edge),
            // with rounding: the bin is widened by ten times that, so the triangle's point nearest such a point lies
            // in the part kept.
            let size = (0..3).map(|e| {
                let (u, v) = (corners[e], corners[(e + 1) % 3]);
                (u[0] - v[0]).hypot(u[1] - v[1])
            });
            let reach = 1e-8 * (size.fold(0.0, f64::max) + self.bin_m + 1.0);
            let widened = [bx - reach, by - reach, bx + self.bin_m + reach, by + self.bin_m + reach];
            let (clipped, len) = clip_to_box(&corners, widened);
            // With nothing kept, no point of the bin is counted as inside it; its own corners bound it all the same.
            let part = if len == 0 { &corners[..] } else { &clipped[..len] };
            for &[x, y] in part {
                c = c.max(p.a * x + p.b * y + p.c - a * x - b * y);
            }
            // The triangle's height above the plane may rise by its gradient times that reach.
            margin = margin.max(((p.a - a).abs() + (p.b - b).abs()) * reach);
        }
        let offset = c + margin + 1e-6;
        let mut c32 = offset as f32;
        if (c32 as f64) < offset {
            c32 = c32.next_up();
        }
        [a32, b32, c32]
    }

    /// The index of the bin holding (x, y), `None` outside the grid.
    #[inline]
    fn bin_at(&self, x: f64, y: f64) -> Option<usize> {
        let fi = (x - self.x0) / self.bin_m;
        let fj = (y - self.y0) / self.bin_m;
        if !(fi >= 0.0 && fj >= 0.0) {
            return None;
        }
        let (i, j) = (fi as usize, fj as usize);
        (i < self.nx && j < self.ny).then_some(j * self.nx + i)
    }

    /// The surface under (x, y): the highest triangle whose footprint holds the point. `None` over holes and
    /// outside the surface.
    #[inline]
    pub fn at(&self, x: f64, y: f64) -> Option<SurfacePoint> {
        let k = self.bin_at(x, y)?;
        let mut best: Option<(f64, u32)> = None;
        for &t in &self.items[self.offsets[k] as usize..self.offsets[k + 1] as usize] {
            let p = &self.planes[t as usize];
            if p.vertical {
                continue;
            }
            let (dx, dy) = (x - p.x0, y - p.y0);
            let u = p.inv[0] * dx + p.inv[1] * dy;
            let v = p.inv[2] * dx + p.inv[3] * dy;
            const EPS: f64 = 1e-9;
            if u >= -EPS && v >= -EPS && u + v <= 1.0 + EPS {
                let z = p.a * x + p.b * y + p.c;
                if best.is_none_or(|(bz, _)| z > bz) {
                    best = Some((z, t));
                }
            }
        }
        best.map(|(z, t)| SurfacePoint { z_m: z, normal: self.normal(t), triangle: t })
    }

    /// An upper bound of the surface height at (x, y) from the bin holding it (`NEG_INFINITY` outside or over
    /// holes): the lower of the bin's highest point and its bounding plane, a one-lookup test that a point is above
    /// the ground.
    #[inline]
    pub fn upper_bound_at(&self, x: f64, y: f64) -> f64 {
        let Some(k) = self.bin_at(x, y) else { return f64::NEG_INFINITY };
        let [a, b, c] = self.upper[k];
        self.zmax[0].2[k].min(a as f64 * x + b as f64 * y + c as f64)
    }

    /// True if some point of the polyline `line` (local frame; each segment sampled at most `spacing_m` apart, at
    /// most 10,000 points a segment) lies over the surface: a line given in another frame has none.
    pub fn any_point_over(&self, line: &[[f64; 2]], spacing_m: f64) -> bool {
        let over = |p: [f64; 2]| self.at(p[0], p[1]).is_some();
        if let [p] = line {
            return over(*p);
        }
        line.windows(2).any(|w| {
            let (a, b) = (w[0], w[1]);
            let n = (((b[0] - a[0]).hypot(b[1] - a[1]) / spacing_m).ceil() as usize).clamp(1, 10_000);
            (0..=n).any(|k| {
                let t = k as f64 / n as f64;
                over([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
            })
        })
    }

    /// Whether the surface resumes ahead of (x, y), a point just off it, along the horizontal direction `dir` (need
    /// not be unit length): probed every 0.5 m over `max_m`, starting twice the longest horizontal edge of the
    /// triangle left behind (found within 1 m back) past the point, so that the teeth of an edge made of whole
    /// triangles (the staircase edge of a DEM's nodata margin) do not count. True means the point lies in a gap of
    /// the surface (nodata cells, missing triangles), not past its outer edge (ours). False for a zero direction.
    pub fn resumes_ahead(&self, x: f64, y: f64, dir: [f64; 2], max_m: f64) -> bool {
        let len = dir[0].hypot(dir[1]);
        if len < 1e-12 {
            return false;
        }
        let (ux, uy) = (dir[0] / len, dir[1] / len);
        let left = (1..=20).find_map(|k| self.at(x - 0.05 * k as f64 * ux, y - 0.05 * k as f64 * uy));
        let skip_m = left.map_or(0.0, |p| {
            let c = self.corners(p.triangle);
            let edge = |a: usize, b: usize| (c[a].x - c[b].x).hypot(c[a].y - c[b].y);
            2.0 * edge(0, 1).max(edge(1, 2)).max(edge(2, 0))
        });
        let at = |d: f64| [x + d * ux, y + d * uy];
        self.any_point_over(&[at(skip_m), at(skip_m + max_m)], 0.5)
    }

    /// Height of the surface under (x, y), `None` over holes.
    #[inline]
    pub fn height(&self, x: f64, y: f64) -> Option<f64> {
        self.at(x, y).map(|p| p.z_m)
    }

    /// Unit normal of triangle `t`, pointing up (out of the ground); for a vertical triangle, horizontal, on the
    /// side its winding gives.
    #[inline]
    pub fn normal(&self, t: u32) -> Vector3<f64> {
        self.normals[t as usize]
    }

    /// For a point below the surface: its depth (distance to the nearest point of the surface) and the direction
    /// out of the ground toward that point, with the triangle it lies on. `None` if the point is not below the
    /// surface. The nearest point lies within the vertical depth, so only triangles binned within that horizontal
    /// distance are examined; this finds the side of a thin wall a fast rock has just entered, where the vertical
    /// direction would push the rock over the wall.
    pub fn penetration(&self, p: &Vector3<f64>) -> Option<(f64, Vector3<f64>, u32)> {
        let top = self.at(p.x, p.y)?;
        let vertical_depth = top.z_m - p.z;
        if vertical_depth <= 0.0 {
            return None;
        }
        let plane_depth = vertical_depth * top.normal.z;
        let r = vertical_depth;
        let (i0, i1) = self.bin_range(p.x - r, p.x + r, self.x0, self.nx);
        let (j0, j1) = self.bin_range(p.y - r, p.y + r, self.y0, self.ny);
        let mut best = (plane_depth * plane_depth, top.triangle, None::<Vector3<f64>>);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let k = j * self.nx + i;
                for &t in &self.items[self.offsets[k] as usize..self.offsets[k + 1] as usize] {
                    if t == top.triangle {
                        continue;
                    }
                    let [a, b, c] = self.corners(t);
                    let q = closest_point_on_triangle(p, &a, &b, &c);
                    let d2 = (q - p).norm_squared();
                    if d2 < best.0 {
                        best = (d2, t, Some(q));
                    }
                }
            }
        }
        let (d2, t, q) = best;
        let depth = d2.sqrt();
        let normal = match q {
            // Pointing from the buried point to the surface: out of the ground. Oriented along the face normal when
            // the nearest point is inside a face.
            Some(q) if depth > 1e-12 => (q - p) / depth,
            _ => top.normal,
        };
        Some((depth, normal, t))
    }

    /// An upper bound of the surface height over the rectangle [x_lo, x_hi] × [y_lo, y_hi] (`NEG_INFINITY` where
    /// there is no surface at all). Conservative: it may overestimate, never underestimate.
    pub fn max_height_in(&self, x_lo: f64, x_hi: f64, y_lo: f64, y_hi: f64) -> f64 {
        let span = ((x_hi - x_lo).max(y_hi - y_lo) / self.bin_m).max(1.0);
        let mut level = (span.log2().ceil() as usize).min(self.zmax.len() - 1);
        loop {
            let (w, h, z) = &self.zmax[level];
            let size = self.bin_m * (1u64 << level) as f64;
            // The floor clamped at 0, as in `bin_range`.
            let to_i = |v: f64, origin: f64, n: usize| (((v - origin) / size) as usize).min(n - 1);
            let (i0, i1) = (to_i(x_lo, self.x0, *w), to_i(x_hi, self.x0, *w));
            let (j0, j1) = (to_i(y_lo, self.y0, *h), to_i(y_hi, self.y0, *h));
            if (i1 - i0 + 1) * (j1 - j0 + 1) <= 16 || level + 1 == self.zmax.len() {
                let mut m = f64::NEG_INFINITY;
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        m = m.max(z[j * w + i]);
                    }
                }
                return m;
            }
            level += 1;
        }
    }

    /// The edges of the triangles binned over [x_lo, x_hi] × [y_lo, y_hi], each once, into `out` as (lower
    /// vertex index, higher vertex index, a triangle it bounds), sorted.
    pub fn edges_in(&self, x_lo: f64, x_hi: f64, y_lo: f64, y_hi: f64, out: &mut Vec<(u32, u32, u32)>) {
        out.clear();
        let (i0, i1) = self.bin_range(x_lo, x_hi, self.x0, self.nx);
        let (j0, j1) = self.bin_range(y_lo, y_hi, self.y0, self.ny);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let k = j * self.nx + i;
                for &t in &self.items[self.offsets[k] as usize..self.offsets[k + 1] as usize] {
                    let [a, b, c] = self.triangles[t as usize];
                    for (u, v) in [(a, b), (b, c), (c, a)] {
                        out.push((u.min(v), u.max(v), t));
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup_by_key(|e| (e.0, e.1));
    }

    /// Horizontal bounds (x_min, y_min, x_max, y_max) of the surface's vertices, m.
    pub fn bounds_xy(&self) -> (f64, f64, f64, f64) {
        self.extent
    }

    /// Lowest and highest vertex heights, m.
    pub fn z_range_m(&self) -> (f64, f64) {
        (self.z_min_m, self.z_max_m)
    }

    /// The vertices (local frame).
    pub fn vertices(&self) -> &[Vector3<f64>] {
        &self.vertices
    }

    /// The triangles kept.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Slope of triangle `t` from horizontal, degrees.
    pub fn slope_deg(&self, t: u32) -> f64 {
        self.normal(t).z.clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// Horizontal (projected) area of triangle `t`, m².
    pub fn footprint_area_m2(&self, t: u32) -> f64 {
        let p = &self.planes[t as usize];
        0.5 / (p.inv[0] * p.inv[3] - p.inv[1] * p.inv[2]).abs()
    }

    /// The three corners of triangle `t`.
    pub fn corners(&self, t: u32) -> [Vector3<f64>; 3] {
        self.triangles[t as usize].map(|k| self.vertices[k as usize])
    }
}

/// Whether a triangle's horizontal footprint meets the box [x0, x1] × [y0, y1] (separating axes: the box axes
/// and the three edge normals).
fn triangle_overlaps_box(p: &[Vector3<f64>; 3], x0: f64, y0: f64, x1: f64, y1: f64) -> bool {
    if p.iter().all(|v| v.x < x0)
        || p.iter().all(|v| v.x > x1)
        || p.iter().all(|v| v.y < y0)
        || p.iter().all(|v| v.y > y1)
    {
        return false;
    }
    let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)];
    for e in 0..3 {
        let (a, b, c) = (p[e], p[(e + 1) % 3], p[(e + 2) % 3]);
        let (nx, ny) = (-(b.y - a.y), b.x - a.x);
        let side = |x: f64, y: f64| nx * (x - a.x) + ny * (y - a.y);
        let inner = side(c.x, c.y);
        if inner == 0.0 {
            continue;
        }
        if corners.iter().all(|&(x, y)| side(x, y) * inner < 0.0) {
            return false;
        }
    }
    true
}

/// The part of the triangle `tri` inside the box [x0, x1] × [y0, y1] (Sutherland–Hodgman clipping), as its
/// corners and their count (0 when they do not overlap). A cut of a convex polygon adds at most one corner, and of
/// any polygon (should rounding bend it) at most doubles them: 3·2⁴ = 48 at most, kept on the stack (a terrain of
/// 10⁶ triangles clips about four million times as it is built).
fn clip_to_box(tri: &[[f64; 2]; 3], [x0, y0, x1, y1]: [f64; 4]) -> ([[f64; 2]; 48], usize) {
    // Two buffers, each cut reading one and writing the other (no copies of them).
    let (mut a, mut b) = ([[0.0; 2]; 48], [[0.0; 2]; 48]);
    a[..3].copy_from_slice(tri);
    let mut len = 3;
    // Each half-plane as (axis, bound, keep the side above the bound); four cuts leave the result in `a`.
    for (cut, (axis, bound, above)) in
        [(0, x0, true), (0, x1, false), (1, y0, true), (1, y1, false)].into_iter().enumerate()
    {
        let (input, out) = if cut % 2 == 0 { (&a, &mut b) } else { (&b, &mut a) };
        let inside = |p: &[f64; 2]| if above { p[axis] >= bound } else { p[axis] <= bound };
        let n = len;
        len = 0;
        for k in 0..n {
            let (p, q) = (&input[k], &input[(k + 1) % n]);
            if inside(p) {
                out[len] = *p;
                len += 1;
            }
            if inside(p) != inside(q) {
                let f = (bound - p[axis]) / (q[axis] - p[axis]);
                out[len] = [p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])];
                len += 1;
            }
        }
    }
    (a, len)
}

/// The point of triangle (a, b, c) nearest to p (Ericson, Real-Time Collision Detection, §5.1.5).
fn closest_point_on_triangle(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> Vector3<f64> {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane z = 0.5 x on [0, 10]², split into 2 × n × n triangles.
    fn tilted(n: usize) -> Surface {
        let mut v = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (10.0 * i as f64 / n as f64, 10.0 * j as f64 / n as f64);
                v.push(Vector3::new(x, y, 0.5 * x));
            }
        }
        let mut t = Vec::new();
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Surface::new(v, &t).unwrap().0
    }

    #[test]
    fn heights_normals_and_holes() {
        let s = tilted(7);
        for &(x, y) in &[(0.0, 0.0), (3.3, 7.1), (10.0, 10.0), (5.0, 5.0), (1.0 / 7.0 * 10.0, 2.0)] {
            let p = s.at(x, y).expect("inside");
            assert!((p.z_m - 0.5 * x).abs() < 1e-12);
            let n = Vector3::new(-0.5, 0.0, 1.0).normalize();
            assert!((p.normal - n).norm() < 1e-12);
        }
        assert!(s.at(-0.1, 5.0).is_none());
        assert!(s.at(5.0, 10.1).is_none());
        assert!((s.slope_deg(0) - 0.5f64.atan().to_degrees()).abs() < 1e-9);
    }

    #[test]
    fn max_height_bounds_the_surface() {
        let s = tilted(20);
        for &(a, b) in &[(0.0, 1.0), (2.0, 2.5), (0.0, 10.0), (9.0, 12.0)] {
            let m = s.max_height_in(a, b, 3.0, 4.0);
            assert!(m >= 0.5 * b.min(10.0) - 1e-12, "{a} {b} {m}");
            assert!(m <= 0.5 * b.min(10.0) + 2.0, "{a} {b} {m}: too loose");
        }
        assert_eq!(s.max_height_in(20.0, 30.0, 20.0, 30.0), s.max_height_in(20.0, 30.0, 20.0, 30.0));
    }

    #[test]
    fn the_bin_bound_lies_above_the_surface_and_hugs_a_plane() {
        // On a plane the bound is the plane (within its micrometre margin), where the bin's highest point is up
        // to a bin's rise above it.
        let s = tilted(20);
        for &(x, y) in &[(0.3, 0.3), (4.99, 7.2), (9.9, 0.1)] {
            let bound = s.upper_bound_at(x, y);
            assert!(bound >= 0.5 * x && bound < 0.5 * x + 1e-5, "{x} {y}: {bound}");
        }
        assert_eq!(s.upper_bound_at(-1.0, 5.0), f64::NEG_INFINITY);
        // A bumpy grid and a coarse irregular mesh whose triangles span many bins: never below the surface.
        let mut v = Vec::new();
        for j in 0..=12 {
            for i in 0..=12 {
                let (x, y) = (i as f64, j as f64);
                v.push(Vector3::new(x, y, 0.7 * x + (1.3 * x).sin() * (0.9 * y).cos() + 0.2 * ((i * j) % 3) as f64));
            }
        }
        let id = |i: usize, j: usize| (j * 13 + i) as u32;
        let grid: Vec<[u32; 3]> = (0..12 * 12)
            .flat_map(|k| {
                let (i, j) = (k % 12, k / 12);
                [[id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]]
            })
            .collect();
        let coarse = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(40.0, 3.0, 25.0),
            Vector3::new(7.0, 35.0, -4.0),
            Vector3::new(38.0, 41.0, 12.0),
            Vector3::new(20.0, 18.0, 30.0),
            Vector3::new(1.0, 1.0, 0.5),
        ];
        let fan = [[4, 0, 1], [4, 1, 3], [4, 3, 2], [4, 2, 0], [5, 0, 1]];
        for s in [Surface::new(v, &grid).unwrap().0, Surface::new(coarse, &fan).unwrap().0] {
            let (x0, y0, x1, y1) = s.bounds_xy();
            let mut checked = 0;
            for k in 0..40_000 {
                // An irrational lattice over the surface's box.
                let (fx, fy) = ((k as f64 * 0.618_033_988_75) % 1.0, (k as f64 * 0.414_213_562_37) % 1.0);
                let (x, y) = (x0 + fx * (x1 - x0), y0 + fy * (y1 - y0));
                if let Some(p) = s.at(x, y) {
                    let bound = s.upper_bound_at(x, y);
                    assert!(p.z_m <= bound, "({x}, {y}): ground {} above the bound {bound}", p.z_m);
                    checked += 1;
                }
            }
            assert!(checked > 10_000, "{checked}");
        }
    }

    #[test]
    fn degenerate_triangles_are_dropped_and_vertical_ones_give_no_height() {
        let v = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 1.0),
        ];
        let (s, kept, stats) = Surface::new(v, &[[0, 1, 2], [0, 1, 3], [0, 0, 2], [0, 1, 4]]).unwrap();
        assert_eq!(kept, vec![0, 3]);
        assert_eq!(stats, SurfaceStats { triangles: 2, degenerate_dropped: 2, vertical: 1 });
        assert!(s.at(0.2, 0.2).is_some());
    }
}

#[cfg(test)]
mod penetration_tests {
    use super::*;

    #[test]
    fn penetration_finds_the_nearest_face() {
        // A step: floor z = 0 for x < 10, a 60° face up to z = 5, a floor z = 5 beyond.
        let run = 5.0 / 60f64.to_radians().tan();
        let xs = [0.0, 10.0, 10.0 + run, 30.0];
        let zs = [0.0, 0.0, 5.0, 5.0];
        let mut v = Vec::new();
        for y in [0.0, 10.0] {
            for (x, z) in xs.iter().zip(zs) {
                v.push(Vector3::new(*x, y, z));
            }
        }
        let t: Vec<[u32; 3]> = (0..3u32).flat_map(|i| [[i, i + 1, 5 + i], [i, 5 + i, 4 + i]]).collect();
        let (s, _, _) = Surface::new(v, &t).unwrap();
        // A point 1 cm inside the face, halfway up.
        let n = Vector3::new(-60f64.to_radians().sin(), 0.0, 60f64.to_radians().cos());
        let on_face = Vector3::new(10.0 + run / 2.0, 5.0, 2.5);
        let (depth, normal, _) = s.penetration(&(on_face - n * 0.01)).unwrap();
        assert!((depth - 0.01).abs() < 1e-9, "{depth}");
        assert!((normal - n).norm() < 1e-6, "{normal:?}");
        // Above the ground: nothing.
        assert!(s.penetration(&(on_face + n * 0.01)).is_none());
        // Just past the top crest, 5 cm below the upper floor and 1 cm from the crest: nearest is the crest edge.
        let p = Vector3::new(10.0 + run + 0.01, 5.0, 4.95);
        let (depth, _, _) = s.penetration(&p).unwrap();
        assert!(depth < 0.05, "{depth}");
    }
}
