//! Rock paths as GeoJSON LineStrings (for QGIS), beside `paths.csv` and `paths.vtk`.

use crate::error::Result;
use crate::io::geojson::{self, Feature, Geometry};
use crate::raster::Crs;
use crate::sim::Sample;
use crate::terrain::frame::map_xyz;
use crate::terrain::Terrain;
use std::path::Path;

/// Writes one LineString per rock (centre of mass, map coordinates with z) with its rock id, duration, largest
/// kinetic energy (kJ) and largest passing height (m).
pub fn write_paths_geojson(path: &Path, terrain: &Terrain, paths: &[(usize, Vec<Sample>)], crs: &Crs) -> Result<()> {
    let features: Vec<Feature> = paths
        .iter()
        .filter(|(_, s)| s.len() >= 2)
        .map(|(id, samples)| {
            let pts = samples.iter().map(|s| map_xyz(terrain, &s.position_m)).collect();
            let max_e = samples.iter().map(|s| s.kinetic_j).fold(0.0, f64::max);
            let max_h = samples.iter().map(|s| s.clearance_m).fold(0.0, f64::max);
            Feature::new(Geometry::LineString(pts))
                .with("rock_id", *id)
                .with("duration_s", samples.last().map_or(0.0, |s| s.t_s))
                .with("max_kinetic_kj", max_e / 1000.0)
                .with("max_passing_height_m", max_h)
        })
        .collect();
    geojson::write(path, "paths", crs, &features)
}
