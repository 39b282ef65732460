//! The raster frame of a run's hazard maps: a north-up grid over the terrain's horizontal extent, in the terrain's
//! own coordinates, with cell edges on multiples of the cell size.

use crate::raster::Grid;
use crate::terrain::Terrain;

/// Geometry of the hazard rasters, and the mapping from local-frame positions to cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RasterFrame {
    /// Columns.
    pub ncols: usize,
    /// Rows.
    pub nrows: usize,
    /// Cell size, m.
    pub cell_m: f64,
    /// West edge in the terrain's frame, m.
    pub x_min_m: f64,
    /// North edge in the terrain's frame, m.
    pub y_max_m: f64,
    /// Local-frame origin (x, y) of the terrain, so that frame = local + origin.
    pub origin_xy: [f64; 2],
}

impl RasterFrame {
    /// The frame covering `terrain` with cells of `cell_m`.
    pub fn covering(terrain: &Terrain, cell_m: f64) -> RasterFrame {
        let (x0, y0, x1, y1) = terrain.surface.bounds_xy();
        let o = [terrain.origin.x, terrain.origin.y];
        let x_min = ((x0 + o[0]) / cell_m).floor() * cell_m;
        let y_min = ((y0 + o[1]) / cell_m).floor() * cell_m;
        let x_max = ((x1 + o[0]) / cell_m).ceil() * cell_m;
        let y_max = ((y1 + o[1]) / cell_m).ceil() * cell_m;
        RasterFrame {
            ncols: (((x_max - x_min) / cell_m).round() as usize).max(1),
            nrows: (((y_max - y_min) / cell_m).round() as usize).max(1),
            cell_m,
            x_min_m: x_min,
            y_max_m: y_max,
            origin_xy: o,
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.ncols * self.nrows
    }

    /// True if the frame has no cell.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Cell index of a local-frame position, if inside.
    #[inline]
    pub fn cell_of_local(&self, x: f64, y: f64) -> Option<u32> {
        let c = ((x + self.origin_xy[0] - self.x_min_m) / self.cell_m).floor();
        let r = ((self.y_max_m - (y + self.origin_xy[1])) / self.cell_m).floor();
        if c >= 0.0 && r >= 0.0 && (c as usize) < self.ncols && (r as usize) < self.nrows {
            Some((r as usize * self.ncols + c as usize) as u32)
        } else {
            None
        }
    }

    /// Centre of cell `k` in the local frame.
    pub fn local_centre(&self, k: usize) -> (f64, f64) {
        let (r, c) = (k / self.ncols, k % self.ncols);
        (
            self.x_min_m + (c as f64 + 0.5) * self.cell_m - self.origin_xy[0],
            self.y_max_m - (r as f64 + 0.5) * self.cell_m - self.origin_xy[1],
        )
    }

    /// An empty grid (all nodata) of this frame.
    pub fn empty_grid(&self) -> Grid {
        Grid::filled(self.ncols, self.nrows, self.x_min_m, self.y_max_m, self.cell_m, f32::NAN)
    }
}
