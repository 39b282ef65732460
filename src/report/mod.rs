//! A run's products for people and other tools: PNG maps of every raster over the hillshade, hazard zones,
//! collector tables, ESRI ASCII grids, rock paths as GeoJSON, and `index.html` that shows it all.
//!
//! - [`maps`]: raster styles, the hillshade DEM and the overlays (end points, barriers, collectors).
//! - [`html`]: the static page writer.
//! - [`paths`]: rock paths as GeoJSON LineStrings.
//! - [`run_index`]: a run's `index.html`.

pub mod html;
pub mod maps;
pub mod paths;
pub mod run_index;

pub use run_index::write_run_index;

use crate::collector::{CollectorSet, CollectorStats};
use crate::error::Result;
use crate::raster::Grid;
use crate::render::{render_hillshade, Class, Colormap, ValueScale};
use crate::run::RASTERS;
use crate::scenario::Scenario;
use crate::sim::Sample;
use crate::terrain::Terrain;
use crate::zones::{IntensityEnergy, LEVELS};
use std::path::Path;

/// Everything a run leaves for its products.
#[derive(Debug, Clone, Copy)]
pub struct RunProducts<'a> {
    /// Output folder.
    pub dir: &'a Path,
    /// The scenario.
    pub scenario: &'a Scenario,
    /// The terrain, with its barriers.
    pub terrain: &'a Terrain,
    /// The rasters, in [`RASTERS`] order.
    pub grids: &'a [Grid],
    /// End points of the rocks that stopped, local frame, thinned for the maps.
    pub stopped_xy: &'a maps::ThinnedPoints,
    /// Recorded paths: (rock index, samples).
    pub paths: &'a [(usize, Vec<Sample>)],
    /// All collectors (the scenario's first).
    pub collectors: &'a CollectorSet,
    /// How many of them come from the scenario (the others are not drawn).
    pub n_user_collectors: usize,
    /// Their statistics.
    pub collector_stats: &'a CollectorStats,
}

/// Extra rasters of a run beyond [`RASTERS`]: (file stem, description).
pub const ZONE_RASTERS: [(&str, &str); 2] = [
    ("hazard_zones", "hazard level: 0 not reached, 1 low (yellow), 2 medium (blue), 3 high (red)"),
    (
        "hazard_matrix",
        "intensity × probability cell: 10 × intensity class + probability class (1 weak/low to 3 strong/high)",
    ),
];

/// The style of the hazard zone map.
pub fn zone_style(sc: &Scenario) -> maps::Style {
    let z = &sc.file.hazard_zones;
    let which = match z.energy {
        IntensityEnergy::P95 => "P95",
        IntensityEnergy::Max => "max",
    };
    maps::Style {
        title: format!(
            "Hazard zones: energy ({which}) {}/{} kJ x reach {}/{} %",
            maps::fmt_num(z.energy_kj[0]),
            maps::fmt_num(z.energy_kj[1]),
            maps::fmt_num(100.0 * z.reach[0]),
            maps::fmt_num(100.0 * z.reach[1])
        ),
        unit: "hazard level".into(),
        colormap: Colormap::Viridis,
        scale: ValueScale::Linear,
        classes: Some(LEVELS.iter().map(|(code, name, colour)| Class::new(*name, *colour, *code as f32)).collect()),
        range: Some((0.0, 3.0)),
    }
}

/// Writes a run's products besides its rasters and manifest; returns the file names written.
pub fn write_run_products(p: &RunProducts) -> Result<Vec<String>> {
    let mut out = Vec::new();
    let dir = p.dir;
    let crs = p.grids[0].crs.clone();
    if !p.collectors.collectors.is_empty() {
        crate::collector::write::write_collectors(dir, &p.collectors.collectors, p.collector_stats, p.terrain, &crs)?;
        out.extend(["collectors.csv".to_string(), "collectors.geojson".to_string()]);
    }
    let (levels, matrix) = p.scenario.file.hazard_zones.run_grids(p.grids);
    for ((stem, _), g) in ZONE_RASTERS.iter().zip([&levels, &matrix]) {
        crate::io::geotiff::write_grid(&dir.join(format!("{stem}.tif")), g)?;
        out.push(format!("{stem}.tif"));
    }
    if p.scenario.file.output.ascii_grids {
        let all = RASTERS
            .iter()
            .map(|r| r.0)
            .zip(p.grids.iter())
            .chain(ZONE_RASTERS.iter().map(|r| r.0).zip([&levels, &matrix]));
        for (stem, g) in all {
            out.extend(crate::io::ascii_grid::write_grid_in(dir, stem, g)?);
        }
    }
    if !p.paths.is_empty() {
        paths::write_paths_geojson(&dir.join("paths.geojson"), p.terrain, p.paths, &crs)?;
        out.push("paths.geojson".into());
    }
    let dem = maps::dem_for(p.terrain, &p.grids[0]);
    let overlays = maps::run_overlays(p.terrain, p.stopped_xy, &p.collectors.collectors[..p.n_user_collectors]);
    for ((stem, _), g) in RASTERS.iter().zip(p.grids) {
        maps::render(&dir.join(format!("{stem}.png")), g, &maps::raster_style(stem), Some(&dem), &overlays)?;
        out.push(format!("{stem}.png"));
    }
    maps::render(&dir.join("hazard_zones.png"), &levels, &zone_style(p.scenario), Some(&dem), &overlays)?;
    out.push("hazard_zones.png".into());
    let terrain_overlays = crate::render::Overlays { points: Vec::new(), point_label: None, ..overlays };
    render_hillshade(&dir.join("terrain.png"), &dem, &terrain_overlays)?;
    out.push("terrain.png".into());
    Ok(out)
}
