//! Checks shared by the grid writers: a grid must be consistent before it is written.

use crate::error::{Error, Result};
use crate::raster::Grid;
use std::path::Path;

/// Checks that `grid` can be written to `path`: at least one cell, one value per cell, finite origin and positive
/// finite cell sizes.
pub(crate) fn check_writable(path: &Path, grid: &Grid) -> Result<()> {
    let field = |f: &str| format!("{}: grid.{f}", path.display());
    if grid.ncols == 0 || grid.nrows == 0 {
        return Err(Error::invalid(
            field("ncols/nrows"),
            format!("the grid is {} × {} cells", grid.ncols, grid.nrows),
            "a raster needs at least one row and one column",
        ));
    }
    if grid.ncols.checked_mul(grid.nrows) != Some(grid.values.len()) {
        return Err(Error::invalid(
            field("values"),
            format!("{} values for {} × {} cells", grid.values.len(), grid.ncols, grid.nrows),
            "this is a bug in the code that built the grid; please report it",
        ));
    }
    let cells_ok = [grid.cell_x_m, grid.cell_y_m].iter().all(|c| c.is_finite() && *c > 0.0);
    if !cells_ok || !grid.x_min_m.is_finite() || !grid.y_max_m.is_finite() {
        return Err(Error::invalid(
            field("cell_x_m/cell_y_m"),
            format!(
                "origin ({}, {}) and cell size ({}, {}) must be finite, with positive cell sizes",
                grid.x_min_m, grid.y_max_m, grid.cell_x_m, grid.cell_y_m
            ),
            "check the grid definition (cell size, extent)",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_inconsistent_grids() {
        let p = Path::new("out.tif");
        let mut g = Grid::filled(2, 2, 0.0, 10.0, 1.0, 1.0);
        assert!(check_writable(p, &g).is_ok());
        g.values.pop();
        assert!(check_writable(p, &g).unwrap_err().to_string().contains("grid.values"));
        let mut g = Grid::filled(2, 2, 0.0, 10.0, 1.0, 1.0);
        g.cell_y_m = 0.0;
        assert!(check_writable(p, &g).unwrap_err().to_string().contains("out.tif: grid.cell"));
        let g = Grid::filled(0, 2, 0.0, 10.0, 1.0, 1.0);
        assert!(check_writable(p, &g).is_err());
    }
}
