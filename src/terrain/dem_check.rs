//! Checks that a DEM read from a GeoTIFF or an ESRI ASCII grid holds what talus will treat it as: heights in
//! metres over a grid in metres, with its missing cells marked. Each of these mistakes otherwise runs to the end
//! and writes plausible-looking files with wrong numbers in them:
//! - a **geographic or non-metre CRS** (a DEM in degrees, or in feet): the grid is read as metres, so the slope is
//!   wrong (by a factor of about 10⁵ for degrees). Refused when the GeoTIFF's GeoKeys or the `.prj` say so.
//! - **inconsistent units** with no CRS to tell: refused when the median slope between neighbouring cells (of
//!   different heights) is steeper than [`MAX_MEDIAN_SLOPE_DEG`], which no terrain has.
//! - **undeclared nodata**: cells holding a usual nodata marker (−9999, −32768, …) that the file does not declare
//!   as nodata would be ground thousands of metres deep. Refused.

use crate::error::{Error, Result};
use crate::raster::Grid;
use std::path::Path;

/// The steepest median slope between neighbouring DEM cells we accept, degrees (ours: real terrain, even a
/// benched open pit or a cliff band, has a median far below this; a DEM in degrees read as metres has about
/// 89.99°).
pub const MAX_MEDIAN_SLOPE_DEG: f64 = 85.0;

/// At most this many neighbour pairs enter the median slope (ours: enough for a stable median, bounded work).
const MAX_SLOPE_SAMPLES: usize = 1 << 20;

/// Values that exporters use for missing cells (GDAL, ESRI, SRTM/USGS, and the float32 lowest value). Any value at
/// or below [`NODATA_FLOOR_M`] counts too.
pub const NODATA_MARKERS: [f32; 4] = [-9999.0, -99999.0, -32767.0, -32768.0];

/// Heights at or below this are nodata markers (ours: −3.4·10³⁸ and the like; no ground lies below −11 km).
pub const NODATA_FLOOR_M: f32 = -1.0e30;

/// Runs every check on a DEM read from `path`; the error names the file, what is wrong and how to fix it.
pub fn check_dem(path: &Path, grid: &Grid) -> Result<()> {
    check_crs_units(path, grid)?;
    check_undeclared_nodata(path, grid)?;
    check_median_slope(path, grid)
}

/// Refuses a DEM whose CRS (GeoTIFF GeoKeys, or the WKT of its `.prj`) says its coordinates are not metres.
fn check_crs_units(path: &Path, grid: &Grid) -> Result<()> {
    let problem = grid
        .crs
        .geokeys
        .as_ref()
        .and_then(|k| crate::io::geotiff::non_metre_units(&k.directory))
        .or_else(|| grid.crs.wkt.as_deref().and_then(non_metre_wkt));
    match problem {
        None => Ok(()),
        Some(why) => Err(Error::format(
            path.display().to_string(),
            format!("the DEM cannot be used as it is: {why}; talus reads coordinates and heights as metres"),
            "reproject it to a projected CRS in metres (heights in metres too), e.g. \
             `gdalwarp -t_srs EPSG:<code of the local UTM zone or national grid> -tr 2 2 -r bilinear in.tif out.tif`",
        )),
    }
}

/// Why the WKT of a `.prj` describes coordinates that are not metres: a geographic CRS, or a projected one whose
/// linear unit (its last `UNIT`/`LENGTHUNIT`) is not 1 m. `None` when it is metres or cannot be read.
pub fn non_metre_wkt(wkt: &str) -> Option<String> {
    let text = wkt.trim_start();
    let head: String = text.chars().take_while(|c| c.is_ascii_alphabetic()).collect::<String>().to_ascii_uppercase();
    if matches!(head.as_str(), "GEOGCS" | "GEOGCRS" | "GEODCRS" | "GEOGRAPHICCRS") {
        return Some(format!("its .prj describes a geographic CRS ({head}): the coordinates are degrees, not metres"));
    }
    if !matches!(head.as_str(), "PROJCS" | "PROJCRS" | "PROJECTEDCRS") {
        return None;
    }
    // The linear unit is the last UNIT[...] (WKT1) or LENGTHUNIT[...] (WKT2) of the projected CRS.
    let upper = text.to_ascii_uppercase();
    let at = upper.rfind("UNIT[")? + "UNIT[".len();
    let rest = &text[at..];
    let (name, after) = match rest.trim_start().strip_prefix('"') {
        Some(r) => {
            let end = r.find('"')?;
            (&r[..end], &r[end + 1..])
        }
        None => return None,
    };
    let factor_text = after.trim_start().strip_prefix(',')?;
    let end = factor_text.find([',', ']']).unwrap_or(factor_text.len());
    let factor: f64 = factor_text[..end].trim().parse().ok()?;
    ((factor - 1.0).abs() > 1e-9)
        .then(|| format!("its .prj gives the linear unit \"{name}\" ({factor} m), not the metre"))
}

/// Refuses a DEM in which cells hold a usual nodata marker that the file does not declare as nodata (declared
/// nodata is `NaN` by now).
fn check_undeclared_nodata(path: &Path, grid: &Grid) -> Result<()> {
    let is_marker = |v: f32| v <= NODATA_FLOOR_M || NODATA_MARKERS.contains(&v);
    let Some(first) = grid.values.iter().copied().find(|&v| is_marker(v)) else { return Ok(()) };
    let count = grid.values.iter().filter(|&&v| v == first).count();
    let first = marker_text(first);
    let ascii = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("asc"));
    let hint = if ascii {
        format!("declare it in the header with a line `NODATA_value {first}`")
    } else {
        format!(
            "declare it as the nodata value, e.g. `gdal_edit.py -a_nodata {first} FILE` or \
             `gdal_translate -a_nodata {first} in.tif out.tif`"
        )
    };
    Err(Error::format(
        path.display().to_string(),
        format!(
            "{count} of {} cells hold {first}, a usual nodata marker, which the file does not declare as its nodata \
             value: they would be read as ground at {first} m",
            grid.values.len()
        ),
        hint,
    ))
}

/// A nodata marker as a file would hold it: in full, or in the shortest exact scientific notation when large.
fn marker_text(v: f32) -> String {
    if v.abs() < 1e6 {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Refuses a DEM whose median slope between neighbouring cells of different heights exceeds
/// [`MAX_MEDIAN_SLOPE_DEG`]: its horizontal and vertical units differ (a grid in degrees with heights in metres,
/// most often).
fn check_median_slope(path: &Path, grid: &Grid) -> Result<()> {
    let (nc, nr) = (grid.ncols, grid.nrows);
    let pairs = nc.saturating_sub(1) * nr + nc * nr.saturating_sub(1);
    let stride = pairs.div_ceil(MAX_SLOPE_SAMPLES).max(1);
    let mut gradients = Vec::with_capacity(pairs.min(MAX_SLOPE_SAMPLES) + 1);
    let mut k = 0usize;
    for r in 0..nr {
        for c in 0..nc {
            let Some(z) = grid.get(c, r) else { continue };
            for (dc, dr, cell) in [(1, 0, grid.cell_x_m), (0, 1, grid.cell_y_m)] {
                // Pairs of equal height are left out: a flat floor or a filled lake covering half the DEM would
                // otherwise make the median 0 whatever the units.
                if let Some(z2) = grid.get(c + dc, r + dr).filter(|&z2| z2 != z) {
                    k += 1;
                    if k.is_multiple_of(stride) {
                        gradients.push((f64::from(z2) - f64::from(z)).abs() / cell);
                    }
                }
            }
        }
    }
    if gradients.is_empty() {
        return Ok(());
    }
    let mid = gradients.len() / 2;
    let median = *gradients.select_nth_unstable_by(mid, f64::total_cmp).1;
    let slope_deg = median.atan().to_degrees();
    if slope_deg <= MAX_MEDIAN_SLOPE_DEG {
        return Ok(());
    }
    let (lo, hi) = grid.min_max().unwrap_or((f32::NAN, f32::NAN));
    Err(Error::format(
        path.display().to_string(),
        format!(
            "the median slope between neighbouring cells of different heights is {slope_deg:.2}° (cells of {} × {}, heights {lo} to \
             {hi}): no terrain is that steep, so the grid's horizontal unit is not that of its heights (a DEM in \
             degrees of latitude and longitude, most often); talus reads both as metres",
            crate::error::number_text(grid.cell_x_m),
            crate::error::number_text(grid.cell_y_m)
        ),
        "reproject it to a projected CRS in metres, e.g. \
         `gdalwarp -t_srs EPSG:<code of the local UTM zone or national grid> -tr 2 2 -r bilinear in.tif out.tif`",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::{Crs, GeoKeys};

    fn slope_grid(cell_m: f64) -> Grid {
        let mut g = Grid::filled(6, 5, 1000.0, 2000.0, cell_m, 0.0);
        for r in 0..g.nrows {
            for c in 0..g.ncols {
                g.values[r * g.ncols + c] = 500.0 + 2.0 * r as f32 + 0.5 * c as f32;
            }
        }
        g
    }

    #[test]
    fn wkt_units() {
        let esri = r#"PROJCS["MGI_Austria_Lambert",GEOGCS["GCS_MGI",UNIT["Degree",0.0174532925199433]],PROJECTION["Lambert_Conformal_Conic"],UNIT["Meter",1.0]]"#;
        assert_eq!(non_metre_wkt(esri), None);
        let feet = r#"PROJCS["NAD_1983_StatePlane_New_York_Long_Island_FIPS_3104_Feet",GEOGCS["GCS_North_American_1983",UNIT["Degree",0.0174532925199433]],UNIT["Foot_US",0.3048006096012192]]"#;
        let why = non_metre_wkt(feet).unwrap();
        assert!(why.contains("Foot_US") && why.contains("0.3048006096012192"), "{why}");
        let geo = r#"GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,298.257223563]],UNIT["Degree",0.0174532925199433]]"#;
        assert!(non_metre_wkt(geo).unwrap().contains("geographic"));
        let wkt2 = r#"PROJCRS["x",BASEGEOGCRS["y",ANGLEUNIT["degree",0.0174532925199433]],CS[Cartesian,2],AXIS["e",east,LENGTHUNIT["metre",1]]]"#;
        assert_eq!(non_metre_wkt(wkt2), None);
        assert_eq!(non_metre_wkt("LOCAL_CS[\"site grid\"]"), None);
    }

    #[test]
    fn geographic_and_foot_geokeys_are_refused() {
        let p = Path::new("dem.tif");
        let mut g = slope_grid(2.0);
        assert!(check_dem(p, &g).is_ok());
        g.crs = Crs {
            epsg: Some(4326),
            geokeys: Some(GeoKeys {
                directory: vec![1, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326],
                ..Default::default()
            }),
            wkt: None,
        };
        let err = check_dem(p, &g).unwrap_err().to_string();
        assert!(err.contains("dem.tif") && err.contains("geographic") && err.contains("EPSG:4326"), "{err}");
        assert!(err.contains("gdalwarp -t_srs"), "{err}");
        g.crs.geokeys = Some(GeoKeys {
            directory: vec![1, 1, 0, 3, 1024, 0, 1, 1, 3072, 0, 1, 2263, 3076, 0, 1, 9003],
            ..Default::default()
        });
        let err = check_dem(p, &g).unwrap_err().to_string();
        assert!(err.contains("US survey foot") && err.contains("9003"), "{err}");
        g.crs.geokeys = Some(GeoKeys {
            directory: vec![1, 1, 0, 3, 1024, 0, 1, 1, 3072, 0, 1, 31287, 3076, 0, 1, 9001],
            ..Default::default()
        });
        assert!(check_dem(p, &g).is_ok());
    }

    #[test]
    fn degrees_without_a_crs_are_refused_by_the_slope() {
        let p = Path::new("dem.asc");
        assert!(check_dem(p, &slope_grid(5.0)).is_ok());
        // A grid of 1/1200 degree cells with heights in metres.
        let err = check_dem(p, &slope_grid(1.0 / 1200.0)).unwrap_err().to_string();
        assert!(err.contains("median slope") && err.contains("89.9"), "{err}");
        // Also when most of it is a flat floor of one height.
        let mut g = slope_grid(1.0 / 1200.0);
        g.values[..20].fill(500.0);
        assert!(check_dem(p, &g).is_err());
        // The median pair is a step of 0.5 along a row: over 0.045 m cells 84.9°, accepted; over 0.04 m 85.4°.
        assert!(check_dem(p, &slope_grid(0.045)).is_ok());
        assert!(check_dem(p, &slope_grid(0.04)).is_err());
    }

    #[test]
    fn undeclared_nodata_markers_are_refused() {
        for marker in [-9999.0f32, -32768.0, -32767.0, -99999.0, f32::MIN, -3.4e38] {
            let mut g = slope_grid(2.0);
            g.values[7] = marker;
            g.values[8] = marker;
            let text = marker_text(marker);
            assert_eq!(text.parse::<f32>().unwrap(), marker);
            let err = check_dem(Path::new("dem.tif"), &g).unwrap_err().to_string();
            assert!(err.contains(&format!("2 of 30 cells hold {text}")) && err.contains("gdal_edit.py"), "{err}");
            let err = check_dem(Path::new("dem.ASC"), &g).unwrap_err().to_string();
            assert!(err.contains(&format!("NODATA_value {text}")), "{err}");
            // Declared (NaN by now): fine.
            g.values[7] = f32::NAN;
            g.values[8] = f32::NAN;
            assert!(check_dem(Path::new("dem.tif"), &g).is_ok());
        }
    }
}
