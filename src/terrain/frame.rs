//! The frames results are written in.
//!
//! Hazard rasters, maps and GeoJSON use map coordinates: talus's z-up axes plus the terrain origin, i.e. the
//! terrain files' own coordinates for z-up files (every GIS DEM), and (x, −z, y) of the files for y-up meshes,
//! like the rasters ([`crate::hazard::RasterFrame`]).

use super::{Terrain, UpAxis};
use crate::raster::Crs;
use nalgebra::Vector3;

/// Map coordinates (x, y) of a local-frame horizontal point.
pub fn map_xy(terrain: &Terrain, p: [f64; 2]) -> [f64; 2] {
    [p[0] + terrain.origin.x, p[1] + terrain.origin.y]
}

/// Map coordinates (x, y, z) of a local-frame point.
pub fn map_xyz(terrain: &Terrain, p: &Vector3<f64>) -> [f64; 3] {
    [p.x + terrain.origin.x, p.y + terrain.origin.y, p.z + terrain.origin.z]
}

/// Map coordinates (x, y, ground z) of a local-frame horizontal point (z is `NaN` off the terrain).
pub fn ground_xyz(terrain: &Terrain, p: [f64; 2]) -> [f64; 3] {
    let z = terrain.surface.height(p[0], p[1]).map_or(f64::NAN, |z| z + terrain.origin.z);
    [p[0] + terrain.origin.x, p[1] + terrain.origin.y, z]
}

/// The horizontal point as the user gives it ((x, y) for z-up files, (x, z) for y-up ones) of a local-frame point:
/// the inverse of [`super::horizontal_to_local`].
pub fn local_to_horizontal(up: UpAxis, origin: &Vector3<f64>, p: [f64; 2]) -> [f64; 2] {
    let (x, y) = (p[0] + origin.x, p[1] + origin.y);
    match up {
        UpAxis::Z => [x, y],
        UpAxis::Y => [x, -y],
    }
}

/// The CRS written with a run's outputs: the scenario's EPSG code if given, else the terrain's; the terrain's
/// GeoKeys are kept when they name the same code (or none), and the WKT of its `.prj` always (it describes the
/// same data).
pub fn output_crs(scenario_epsg: Option<u32>, terrain: &Crs) -> Crs {
    match scenario_epsg {
        None => terrain.clone(),
        Some(code) => Crs {
            epsg: Some(code),
            geokeys: terrain.geokeys.clone().filter(|_| terrain.epsg.is_none_or(|e| e == code)),
            wkt: terrain.wkt.clone(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::horizontal_to_local;

    #[test]
    fn horizontal_round_trip() {
        let o = Vector3::new(100.0, -50.0, 7.0);
        for up in [UpAxis::Z, UpAxis::Y] {
            let p = [3.5, -8.25];
            let back = local_to_horizontal(up, &o, horizontal_to_local(up, &o, p));
            assert!((back[0] - p[0]).abs() < 1e-12 && (back[1] - p[1]).abs() < 1e-12, "{up:?}");
        }
    }
}
