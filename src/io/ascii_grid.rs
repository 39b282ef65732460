//! ESRI ASCII grids (`.asc`): a short header, then the values row by row from north to south.
//!
//! ```text
//! ncols 4
//! nrows 3
//! xllcorner 2600000
//! yllcorner 1200000
//! cellsize 2
//! NODATA_value -9999
//! 512.5 513 513.25 -9999
//! ...
//! ```
//! Header keys are case-insensitive and may come in any order: `ncols`, `nrows`, `xllcorner` or `xllcenter`,
//! `yllcorner` or `yllcenter`, `cellsize` (or `dx` and `dy` for rectangular cells) and the optional
//! `nodata_value`. Values are separated by any whitespace, with any line breaks (LF or CRLF); a leading UTF-8
//! byte-order mark is skipped. A value is nodata when it equals the nodata value at `f32` precision, the precision
//! heights are kept at (so `-3.4028235e+38` in the header matches `-3.4028234663852886e+38` in the data); any other
//! value must be finite and fit a float32 (`nan`, `inf` or `1e308` in the data are refused at their line). A `.prj`
//! file with the same stem holds the CRS as WKT; it is read into [`Crs::wkt`] and written back from it.

use crate::error::{Error, Result};
use crate::io::grid_check::check_writable;
use crate::io::write_atomic;
use crate::raster::{Crs, Grid};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The nodata value written to our ASCII grids.
pub const NODATA_VALUE: f32 = -9999.0;

/// Header keys we understand, lower case.
const KEYS: [&str; 10] =
    ["ncols", "nrows", "xllcorner", "xllcenter", "yllcorner", "yllcenter", "cellsize", "dx", "dy", "nodata_value"];

/// Reads an ESRI ASCII grid, and the WKT of a `.prj` beside it if there is one. Nodata values become `NaN`.
pub fn read_grid(path: &Path) -> Result<Grid> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let text = String::from_utf8_lossy(&bytes);
    // A byte-order mark (Windows editors write one) would glue itself to the first header key.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut lines = text.split('\n').enumerate().map(|(i, l)| (i + 1, l)).peekable();

    // Header: lines whose first token is a key (not a number).
    let mut header: Vec<(String, f64, String, usize)> = Vec::new();
    while let Some(&(line_no, line)) = lines.peek() {
        let mut tokens = line.split_whitespace();
        let Some(first) = tokens.next() else {
            lines.next();
            continue;
        };
        if first.parse::<f64>().is_ok() {
            break;
        }
        let key = first.to_ascii_lowercase();
        if !KEYS.contains(&key.as_str()) {
            return Err(Error::at_line(
                path,
                line_no,
                format!("unknown header key '{first}'"),
                format!("use only the keys {} (any case), one per line with its value", KEYS.join(", ")),
            ));
        }
        if header.iter().any(|h| h.0 == key) {
            return Err(Error::at_line(path, line_no, format!("header key '{first}' appears twice"), "keep one"));
        }
        let (Some(value), None) = (tokens.next(), tokens.next()) else {
            return Err(Error::at_line(
                path,
                line_no,
                format!("header line for '{first}' must hold the key and exactly one value"),
                format!("write it as `{first} <number>`"),
            ));
        };
        let number = value.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
            Error::at_line(
                path,
                line_no,
                format!("value '{value}' of header key '{first}' is not a number"),
                format!("write it as `{first} <number>`"),
            )
        })?;
        header.push((key, number, value.to_string(), line_no));
        lines.next();
    }

    let find = |k: &str| header.iter().find(|h| h.0 == k);
    let missing = |k: &str| {
        Error::format(
            format!("{}: header", path.display()),
            format!("missing header key '{k}'"),
            "an ESRI ASCII grid header needs ncols, nrows, xllcorner (or xllcenter), yllcorner (or yllcenter) \
             and cellsize (or dx and dy)",
        )
    };
    let count = |k: &str| -> Result<usize> {
        let (_, _, text, line) = find(k).ok_or_else(|| missing(k))?;
        text.parse::<usize>().ok().filter(|&n| n > 0).ok_or_else(|| {
            Error::at_line(
                path,
                *line,
                format!("{k} must be a positive whole number, found '{text}'"),
                format!(
                    "give {k} as the number of {}: a whole number such as 40",
                    if k == "ncols" { "columns" } else { "rows" }
                ),
            )
        })
    };
    let ncols = count("ncols")?;
    let nrows = count("nrows")?;
    let (cell_x_m, cell_y_m) = match (find("cellsize"), find("dx"), find("dy")) {
        (Some(c), None, None) => (c.1, c.1),
        (None, Some(dx), Some(dy)) => (dx.1, dy.1),
        (None, None, None) => return Err(missing("cellsize")),
        (None, Some(_), None) => return Err(missing("dy")),
        (None, None, Some(_)) => return Err(missing("dx")),
        (Some(c), _, _) => {
            return Err(Error::at_line(
                path,
                c.3,
                "the header has both cellsize and dx/dy",
                "keep either cellsize (square cells) or dx and dy",
            ))
        }
    };
    for (k, v) in [("cellsize/dx", cell_x_m), ("cellsize/dy", cell_y_m)] {
        if v <= 0.0 {
            return Err(Error::format(
                format!("{}: {k}", path.display()),
                format!("cell size must be positive, found {v}"),
                "fix the cell size in the header",
            ));
        }
    }
    let corner = |corner_key: &str, centre_key: &str, cell: f64| -> Result<f64> {
        match (find(corner_key), find(centre_key)) {
            (Some(c), None) => Ok(c.1),
            (None, Some(c)) => Ok(c.1 - 0.5 * cell),
            (None, None) => Err(missing(corner_key)),
            (Some(_), Some(c)) => Err(Error::at_line(
                path,
                c.3,
                format!("the header has both {corner_key} and {centre_key}"),
                "keep one of them",
            )),
        }
    };
    let x_min_m = corner("xllcorner", "xllcenter", cell_x_m)?;
    let y_min_m = corner("yllcorner", "yllcenter", cell_y_m)?;
    let nodata = find("nodata_value").map(|h| h.1);

    let n = ncols.checked_mul(nrows).ok_or_else(|| {
        Error::format(
            format!("{}: header", path.display()),
            format!("{ncols} × {nrows} cells is too many"),
            "check ncols and nrows",
        )
    })?;
    let mut values = Vec::with_capacity(n.min(1 << 28));
    let mut found = 0usize;
    let mut last_line = header.last().map_or(1, |h| h.3);
    let mut first_extra_line = None;
    for (line_no, line) in lines {
        for token in line.split_whitespace() {
            found += 1;
            last_line = line_no;
            if found > n {
                first_extra_line.get_or_insert(line_no);
                continue;
            }
            // The nodata value as declared, or a finite value a float32 holds (the grid's precision): `nan`, `inf`
            // and 1e308 are refused.
            let parsed = token.parse::<f64>().ok();
            let is_nodata = |v: f64| nodata.is_some_and(|nd| v as f32 == nd as f32);
            let v =
                parsed.filter(|&v| is_nodata(v) || (v.is_finite() && v.abs() <= f32::MAX as f64)).ok_or_else(|| {
                    Error::at_line(
                        path,
                        line_no,
                        format!(
                            "'{token}' is not a number a float32 grid holds (value {found} of {n}, row {}, column {})",
                            (found - 1) / ncols + 1,
                            (found - 1) % ncols + 1
                        ),
                        "fix the value; mark missing data with the NODATA_value",
                    )
                })?;
            values.push(if is_nodata(v) { f32::NAN } else { v as f32 });
        }
    }
    if let Some(line) = first_extra_line {
        return Err(Error::at_line(
            path,
            line,
            format!("too many values: expected ncols × nrows = {ncols} × {nrows} = {n}, found {found}"),
            "check ncols and nrows in the header against the data",
        ));
    }
    if found < n {
        return Err(Error::at_line(
            path,
            last_line,
            format!("too few values: expected ncols × nrows = {ncols} × {nrows} = {n}, found {found}"),
            "check ncols and nrows in the header; the file may be truncated",
        ));
    }

    let wkt = read_prj(path)?;
    Ok(Grid {
        ncols,
        nrows,
        x_min_m,
        y_max_m: y_min_m + nrows as f64 * cell_y_m,
        cell_x_m,
        cell_y_m,
        values,
        crs: Crs { wkt, ..Default::default() },
    })
}

/// Writes `grid` as an ESRI ASCII grid (corner registration, nodata −9999), atomically, and `stem.prj` beside it
/// when the CRS has WKT. The cells must be square.
pub fn write_grid(path: &Path, grid: &Grid) -> Result<()> {
    check_writable(path, grid)?;
    let (cx, cy) = (grid.cell_x_m, grid.cell_y_m);
    if (cx - cy).abs() > 1e-9 * cx.max(cy) {
        return Err(Error::invalid(
            format!("{}: grid cell size", path.display()),
            format!("an ESRI ASCII grid needs square cells, but they are {cx} × {cy} m"),
            "write a GeoTIFF instead (.tif), or resample to square cells",
        ));
    }
    let y_min_m = grid.y_max_m - grid.nrows as f64 * cy;
    write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        write!(
            w,
            "ncols {}\nnrows {}\nxllcorner {}\nyllcorner {}\ncellsize {}\nNODATA_value {}\n",
            grid.ncols, grid.nrows, grid.x_min_m, y_min_m, cx, NODATA_VALUE
        )
        .map_err(io)?;
        for row in grid.values.chunks_exact(grid.ncols) {
            for (i, &v) in row.iter().enumerate() {
                let v = if v.is_finite() { v } else { NODATA_VALUE };
                if i > 0 {
                    w.write_all(b" ").map_err(io)?;
                }
                write!(w, "{v}").map_err(io)?;
            }
            w.write_all(b"\n").map_err(io)?;
        }
        Ok(())
    })?;
    if let Some(wkt) = &grid.crs.wkt {
        let prj = prj_path(path);
        write_atomic(&prj, |w| w.write_all(wkt.as_bytes()).map_err(|e| Error::io(&prj, e)))?;
    }
    Ok(())
}

/// Writes `grid` as `dir/stem.asc` (and `stem.prj`, see [`write_grid`]); returns the names of the files written.
pub fn write_grid_in(dir: &Path, stem: &str, grid: &Grid) -> Result<Vec<String>> {
    write_grid(&dir.join(format!("{stem}.asc")), grid)?;
    let mut names = vec![format!("{stem}.asc")];
    if grid.crs.wkt.is_some() {
        names.push(format!("{stem}.prj"));
    }
    Ok(names)
}

/// `dir/stem.prj` for `dir/stem.asc`.
fn prj_path(path: &Path) -> PathBuf {
    path.with_extension("prj")
}

/// The trimmed text of the `.prj` (or `.PRJ`) beside `path`, if there is one and it is not empty.
fn read_prj(path: &Path) -> Result<Option<String>> {
    for prj in [prj_path(path), path.with_extension("PRJ")] {
        match std::fs::read(&prj) {
            Ok(bytes) => {
                let text = String::from_utf8_lossy(&bytes).trim().to_string();
                return Ok((!text.is_empty()).then_some(text));
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e) => return Err(Error::io(&prj, e)),
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_str(text: &str) -> Result<Grid> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.asc");
        std::fs::write(&p, text).unwrap();
        read_grid(&p)
    }

    #[test]
    fn header_any_case_any_order_and_centres() {
        let g = read_str("NROWS 2\nCellSize 10\nncols 3\nxllcenter 105\nYLLCENTER 205\nnodata_value -1\n1 2 -1\n4 5 6")
            .unwrap();
        assert_eq!((g.ncols, g.nrows), (3, 2));
        assert_eq!((g.x_min_m, g.y_max_m, g.cell_x_m, g.cell_y_m), (100.0, 220.0, 10.0, 10.0));
        assert!(g.values[2].is_nan());
        assert_eq!(g.values[5], 6.0);
        assert!(g.crs.is_unknown());
    }

    #[test]
    fn dx_dy_and_free_line_breaks() {
        let g = read_str("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ndx 2\ndy 3\n1\n2 3\n\n4\n").unwrap();
        assert_eq!((g.cell_x_m, g.cell_y_m, g.y_max_m), (2.0, 3.0, 6.0));
        assert_eq!(g.values, vec![1.0, 2.0, 3.0, 4.0]);
    }

    #[test]
    fn header_errors_name_line_and_key() {
        let err = read_str("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncelsize 1\n1 2 3 4").unwrap_err().to_string();
        assert!(err.contains("g.asc:5") && err.contains("unknown header key 'celsize'"), "{err}");
        let err = read_str("ncols 2\nnrows 2\nxllcorner 0\ncellsize 1\n1 2 3 4").unwrap_err().to_string();
        assert!(err.contains("missing header key 'yllcorner'"), "{err}");
        let err =
            read_str("ncols 2.5\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3 4").unwrap_err().to_string();
        assert!(err.contains("g.asc:1") && err.contains("ncols"), "{err}");
    }

    #[test]
    fn value_count_errors() {
        let h = "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n";
        let err = read_str(&format!("{h}1 2\n3")).unwrap_err().to_string();
        assert!(err.contains("g.asc:7") && err.contains("expected") && err.contains("= 4, found 3"), "{err}");
        let err = read_str(&format!("{h}1 2\n3 4\n5 6")).unwrap_err().to_string();
        assert!(err.contains("g.asc:8") && err.contains("= 4, found 6"), "{err}");
        let err = read_str(&format!("{h}1 2\n3 x4")).unwrap_err().to_string();
        assert!(err.contains("g.asc:7") && err.contains("'x4'") && err.contains("row 2, column 2"), "{err}");
    }
}
