//! The raster frame of a run's hazard maps: a north-up grid over the terrain's horizontal extent, in the terrain's
//! own coordinates, with cell edges on multiples of the cell size (or on the DEM's cell edges, `align_to_dem`).

use crate::error::{number_text, round_up_3_digits, Error, Result};
use crate::raster::Grid;
use crate::scenario::OutputSpec;
use crate::terrain::Terrain;

/// Most cells of a run's raster frame. Ours: 10⁸ cells is a 10 km × 10 km site at 1 m, finer than the terrain
/// models a run is usually given, and the frame's per-cell arrays (the accumulator's 16 bytes, six f32 rasters
/// and the f64 end-point density: about 50 bytes a cell) then stay near 5 GB. Beyond it a cell size typo (1e-4
/// for 1) would allocate terabytes.
pub const MAX_RASTER_CELLS: usize = 100_000_000;

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

/// Columns and rows (as f64, so that any cell size can be counted without overflow) of the frame with cell edges
/// at `anchor` plus multiples of `cell_m` covering `extent` = [x_min, y_min, x_max, y_max].
fn cell_counts(extent: [f64; 4], cell_m: f64, anchor: [f64; 2]) -> [f64; 2] {
    let count = |lo: f64, hi: f64, a: f64| {
        let (lo, hi) = (((lo - a) / cell_m).floor(), ((hi - a) / cell_m).ceil());
        (hi - lo).round().max(1.0)
    };
    [count(extent[0], extent[2], anchor[0]), count(extent[1], extent[3], anchor[1])]
}

/// The smallest cell size (rounded up to 3 significant digits) whose frame over `extent` has at most
/// [`MAX_RASTER_CELLS`] cells.
fn smallest_cell_m(extent: [f64; 4]) -> f64 {
    let area_m2 = (extent[2] - extent[0]) * (extent[3] - extent[1]);
    let mut cell_m = round_up_3_digits((area_m2 / MAX_RASTER_CELLS as f64).sqrt().max(1e-9));
    // Snapping the edges to whole cells adds up to a row and a column: grow by 1 % until it fits.
    while {
        let c = cell_counts(extent, cell_m, [0.0, 0.0]);
        c[0] * c[1] > MAX_RASTER_CELLS as f64
    } {
        cell_m = round_up_3_digits(cell_m * 1.01);
    }
    cell_m
}

impl RasterFrame {
    /// The frame covering `terrain` with the cells `output` asks for: edges on multiples of the cell size, or with
    /// `align_to_dem` on the cell edges of the terrain's DEM ([`Terrain::grid_anchor_xy`]). `field` locates
    /// `[output]` in messages.
    ///
    /// # Errors
    /// More than [`MAX_RASTER_CELLS`] cells (the error names the cell size key, the terrain's extent, the cell
    /// count and the smallest cell size allowed), or `align_to_dem` on a terrain with no DEM.
    pub fn covering(terrain: &Terrain, output: &OutputSpec, field: &str) -> Result<RasterFrame> {
        let cell_m = output.cell_size_m;
        let anchor = match (output.align_to_dem, terrain.grid_anchor_xy) {
            (false, _) => [0.0, 0.0],
            (true, Some(a)) => a,
            (true, None) => {
                return Err(Error::invalid(
                    format!("{field}.align_to_dem"),
                    "the terrain has no DEM file whose cells the rasters could follow",
                    "leave it out for a mesh terrain (OBJ, STL)",
                ))
            }
        };
        let (x0, y0, x1, y1) = terrain.surface.bounds_xy();
        let o = [terrain.origin.x, terrain.origin.y];
        let extent = [x0 + o[0], y0 + o[1], x1 + o[0], y1 + o[1]];
        let cells = cell_counts(extent, cell_m, anchor);
        if cells[0] * cells[1] > MAX_RASTER_CELLS as f64 {
            let (width, height) = (extent[2] - extent[0], extent[3] - extent[1]);
            return Err(Error::invalid(
                format!("{field}.cell_size_m"),
                format!(
                    "{} m cells over the terrain's {width:.1} m × {height:.1} m would make {} raster cells, more \
                     than the limit of {MAX_RASTER_CELLS}",
                    number_text(cell_m),
                    number_text(cells[0] * cells[1])
                ),
                format!("use cells of at least {} m", number_text(smallest_cell_m(extent))),
            ));
        }
        let x_min = anchor[0] + ((extent[0] - anchor[0]) / cell_m).floor() * cell_m;
        let y_max = anchor[1] + ((extent[3] - anchor[1]) / cell_m).ceil() * cell_m;
        Ok(RasterFrame {
            ncols: cells[0] as usize,
            nrows: cells[1] as usize,
            cell_m,
            x_min_m: x_min,
            y_max_m: y_max,
            origin_xy: o,
        })
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
