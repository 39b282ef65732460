//! The terrain surface sampled on a regular grid (local frame), for contour lines and bench detection.

use crate::terrain::Terrain;

/// Surface heights at the nodes of a regular grid over the terrain, local frame; `NaN` off the terrain.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightGrid {
    /// x of node column 0, m.
    pub x0: f64,
    /// y of node row 0, m.
    pub y0: f64,
    /// Node spacing, m.
    pub h: f64,
    /// Nodes along x.
    pub nx: usize,
    /// Nodes along y.
    pub ny: usize,
    /// Heights, `z[j * nx + i]`, m.
    pub z: Vec<f64>,
}

impl HeightGrid {
    /// Samples `terrain` every `h` metres, or coarser so that there are at most `max_nodes` nodes.
    pub fn sample(terrain: &Terrain, h: f64, max_nodes: usize) -> HeightGrid {
        let (x0, y0, x1, y1) = terrain.surface.bounds_xy();
        let area = ((x1 - x0) * (y1 - y0)).max(1e-9);
        let h = h.max((area / max_nodes.max(4) as f64).sqrt());
        // Nodes stay a hair inside the bounds so that the ones on the edges still find the surface.
        let eps = 1e-6 * h;
        let nx = ((x1 - x0 - 2.0 * eps) / h).floor().max(0.0) as usize + 1;
        let ny = ((y1 - y0 - 2.0 * eps) / h).floor().max(0.0) as usize + 1;
        let (x0, y0) = (x0 + eps, y0 + eps);
        let mut z = vec![f64::NAN; nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = (x0 + i as f64 * h, y0 + j as f64 * h);
                if let Some(v) = terrain.surface.height(x.min(x1 - eps), y.min(y1 - eps)) {
                    z[j * nx + i] = v;
                }
            }
        }
        HeightGrid { x0, y0, h, nx, ny, z }
    }

    /// Height at node (i, j).
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.z[j * self.nx + i]
    }

    /// Position of node (i, j).
    pub fn node(&self, i: usize, j: usize) -> [f64; 2] {
        [self.x0 + i as f64 * self.h, self.y0 + j as f64 * self.h]
    }

    /// Slope at node (i, j) from central differences (one-sided at edges and next to holes), degrees; `NaN` where
    /// the node or both neighbours along an axis are missing.
    pub fn slope_deg(&self, i: usize, j: usize) -> f64 {
        let z0 = self.at(i, j);
        if z0.is_nan() {
            return f64::NAN;
        }
        let d = |a: Option<f64>, b: Option<f64>, span: f64| -> Option<f64> {
            match (a.filter(|v| !v.is_nan()), b.filter(|v| !v.is_nan())) {
                (Some(a), Some(b)) => Some((b - a) / (2.0 * span)),
                (Some(a), None) => Some((z0 - a) / span),
                (None, Some(b)) => Some((b - z0) / span),
                (None, None) => None,
            }
        };
        let gx = d((i > 0).then(|| self.at(i - 1, j)), (i + 1 < self.nx).then(|| self.at(i + 1, j)), self.h);
        let gy = d((j > 0).then(|| self.at(i, j - 1)), (j + 1 < self.ny).then(|| self.at(i, j + 1)), self.h);
        match (gx, gy) {
            (Some(a), Some(b)) => (a * a + b * b).sqrt().atan().to_degrees(),
            _ => f64::NAN,
        }
    }

    /// Lowest and highest height, `None` if every node is off the terrain.
    pub fn z_range(&self) -> Option<(f64, f64)> {
        self.z.iter().filter(|v| !v.is_nan()).fold(None, |acc, &v| match acc {
            None => Some((v, v)),
            Some((a, b)) => Some((a.min(v), b.max(v))),
        })
    }
}
