//! North-up georeferenced grids: DEMs read from disk and hazard rasters written to it.
//!
//! # Units
//! Coordinates and cell sizes in metres of the grid's own CRS. Values are `f32`; `NaN` marks nodata in memory
//! (files carry an explicit nodata value instead).

/// A coordinate reference system, carried from input to output as faithfully as we can without GDAL.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Crs {
    /// EPSG code, when known (from the scenario, or from a GeoTIFF's ProjectedCSType/GeographicType key).
    pub epsg: Option<u32>,
    /// GeoTIFF GeoKeys of an input DEM, passed through verbatim to the rasters we write.
    pub geokeys: Option<GeoKeys>,
    /// WKT from an ESRI `.prj` beside an input grid, written beside our ASCII grids.
    pub wkt: Option<String>,
}

impl Crs {
    /// A CRS known only by its EPSG code.
    pub fn epsg(code: u32) -> Self {
        Crs { epsg: Some(code), ..Default::default() }
    }

    /// True if nothing is known about the CRS.
    pub fn is_unknown(&self) -> bool {
        self.epsg.is_none() && self.geokeys.is_none() && self.wkt.is_none()
    }
}

/// The three GeoTIFF georeferencing tags that hold the CRS (GeoKeyDirectory, GeoDoubleParams, GeoAsciiParams).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GeoKeys {
    /// Tag 34735, as read.
    pub directory: Vec<u16>,
    /// Tag 34736, as read (may be empty).
    pub double_params: Vec<f64>,
    /// Tag 34737, as read (may be empty).
    pub ascii_params: String,
}

/// A north-up raster: row 0 is the northern edge, column 0 the western edge.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// Number of columns (x).
    pub ncols: usize,
    /// Number of rows (y).
    pub nrows: usize,
    /// x of the western edge of column 0, in m.
    pub x_min_m: f64,
    /// y of the northern edge of row 0, in m.
    pub y_max_m: f64,
    /// Cell width in x, in m (positive).
    pub cell_x_m: f64,
    /// Cell height in y, in m (positive; rows go south).
    pub cell_y_m: f64,
    /// Row-major values, `values[row * ncols + col]`; `NaN` is nodata.
    pub values: Vec<f32>,
    /// The CRS, if known.
    pub crs: Crs,
}

impl Grid {
    /// A grid filled with `value`.
    pub fn filled(ncols: usize, nrows: usize, x_min_m: f64, y_max_m: f64, cell_m: f64, value: f32) -> Self {
        Grid {
            ncols,
            nrows,
            x_min_m,
            y_max_m,
            cell_x_m: cell_m,
            cell_y_m: cell_m,
            values: vec![value; ncols * nrows],
            crs: Crs::default(),
        }
    }

    /// Value at (col, row), `None` outside the grid or at nodata.
    pub fn get(&self, col: usize, row: usize) -> Option<f32> {
        if col >= self.ncols || row >= self.nrows {
            return None;
        }
        let v = self.values[row * self.ncols + col];
        (!v.is_nan()).then_some(v)
    }

    /// Centre of cell (col, row) in the grid's CRS.
    pub fn cell_centre(&self, col: usize, row: usize) -> (f64, f64) {
        (self.x_min_m + (col as f64 + 0.5) * self.cell_x_m, self.y_max_m - (row as f64 + 0.5) * self.cell_y_m)
    }

    /// The cell (col, row) holding the point (x, y), if inside.
    pub fn cell_of(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        let c = ((x - self.x_min_m) / self.cell_x_m).floor();
        let r = ((self.y_max_m - y) / self.cell_y_m).floor();
        (c >= 0.0 && r >= 0.0 && (c as usize) < self.ncols && (r as usize) < self.nrows)
            .then_some((c as usize, r as usize))
    }

    /// Number of cells that hold data.
    pub fn count_valid(&self) -> usize {
        self.values.iter().filter(|v| !v.is_nan()).count()
    }

    /// Minimum and maximum of the valid values, `None` if there are none.
    pub fn min_max(&self) -> Option<(f32, f32)> {
        self.values.iter().filter(|v| !v.is_nan()).fold(None, |acc, &v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
    }
}
