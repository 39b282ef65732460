//! `talus run`.

use super::progress;
use clap::Args;
use std::path::PathBuf;
use talus::run::{run_setup, RunExtras};

/// Run a 3D rigid-body rockfall scenario and write end points, hazard rasters (GeoTIFF, PNG maps), hazard zones,
/// collector tables, a run manifest and index.html.
///
/// Example:
///   talus run examples/bench_stack.toml --out outputs/bench_stack --rocks 500 --seed 7
///   talus run examples/tyrol.toml --out outputs/tyrol --paths 50 --ascii-grids
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct RunArgs {
    /// Scenario file (TOML; see README.md for every key).
    scenario: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    control: super::RunControl,
    /// Also write the paths of the first N rocks (paths.csv, paths.vtk and paths.geojson).
    #[arg(long)]
    paths: Option<usize>,
    /// Also write every raster as an ESRI ASCII grid (.asc, with .prj when the CRS WKT is known).
    #[arg(long)]
    ascii_grids: bool,
}

pub fn run(a: RunArgs) -> anyhow::Result<()> {
    a.control.check()?;
    let mut sc = super::read_3d(&a.scenario, "run")?.resolve(&a.scenario)?;
    sc.file.output.ascii_grids |= a.ascii_grids;
    let overrides = a.control.overrides(a.paths);
    if let Some(prj) = prj_without_geotiff_crs(&sc) {
        eprintln!(
            "note: the GeoTIFFs will carry no CRS: {} holds it as WKT, which talus cannot turn into GeoTIFF keys \
             without a CRS database; set `crs_epsg = <code>` in [terrain] (e.g. 31287 for MGI / Austria Lambert) \
             so that a GIS places them (--ascii-grids copies the .prj)",
            prj.display()
        );
    }
    let pb = progress::bar(0, "rocks");
    let progress = |done: usize, total: usize| {
        if done == 1 {
            // Rates and time left count from the first rock, not from the terrain loading.
            pb.set_length(total as u64);
            pb.reset_elapsed();
            pb.reset_eta();
        }
        pb.set_position(done as u64);
    };
    // The terrain's notes (a material no triangle has, a terrain closed over) come before the rocks run.
    let setup = talus::run::setup(&sc, &overrides).map_err(|e| super::running(&a.scenario, e))?;
    for w in &setup.terrain.notes {
        pb.suspend(|| eprintln!("warning: {w}"));
    }
    let n_notes = setup.terrain.notes.len();
    let summary = run_setup(&sc, setup, &overrides, &a.out, &progress, &RunExtras::default(), &mut |_, _| {})
        .map_err(|e| super::running(&a.scenario, e))?
        .summary;
    pb.finish_and_clear();
    // What the run noticed, after the terrain's notes printed above.
    for w in &summary.warnings[n_notes..] {
        eprintln!("warning: {w}");
    }
    let reason = |r: &str| summary.stop_reasons.get(r).copied().unwrap_or(0);
    say!(
        "{} rocks in {:.1} s ({:.0} rocks/s): {} stopped, {} left the terrain, {} hit the time limit{}",
        summary.rocks,
        summary.wall_time_s,
        summary.rocks_per_second,
        reason("stopped"),
        reason("left_terrain"),
        reason("max_time"),
        if reason("barrier") > 0 { format!(", {} caught by a barrier", reason("barrier")) } else { String::new() }
    );
    say!(
        "run-out median {:.1} m (P95 {:.1} m, max {:.1} m); largest kinetic energy P95 {:.1} kJ",
        summary.runout_m.p50,
        summary.runout_m.p95,
        summary.runout_m.max,
        summary.max_kinetic_kj.p95
    );
    for b in &summary.barriers {
        say!("barrier {}: {} rocks caught, {} broke through", b.name, b.caught, b.broke_through);
    }
    for c in &summary.collectors {
        say!(
            "collector {}: {} rocks crossed ({:.1} %), kinetic energy P95 {} kJ, passing height P95 {} m",
            c.name,
            c.rocks_crossing,
            100.0 * c.fraction_crossing,
            c.kinetic_kj_p95.map_or("-".into(), |v| format!("{v:.1}")),
            c.passing_height_m_p95.map_or("-".into(), |v| format!("{v:.2}"))
        );
    }
    say!(
        "wrote {} files to {}; open {} to see them",
        summary.outputs.len(),
        a.out.display(),
        a.out.join("index.html").display()
    );
    Ok(())
}

/// The `.prj` of an ESRI ASCII DEM when it is the only CRS the run's GeoTIFFs could have had: no `crs_epsg` in the
/// scenario and no GeoTIFF DEM (whose GeoKeys would be passed through).
fn prj_without_geotiff_crs(sc: &talus::scenario::Scenario) -> Option<PathBuf> {
    if sc.file.terrain.crs_epsg.is_some() {
        return None;
    }
    let ext = |p: &std::path::Path| p.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if sc.terrain_files.iter().any(|p| matches!(ext(p).as_str(), "tif" | "tiff")) {
        return None;
    }
    sc.terrain_files
        .iter()
        .filter(|p| ext(p) == "asc")
        .flat_map(|p| [p.with_extension("prj"), p.with_extension("PRJ")])
        .find(|p| p.is_file())
}
