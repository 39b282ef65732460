//! `talus run`: a whole scenario, from files to end points, hazard rasters and a run manifest.

use crate::ensemble::{RockRecord, Setup};
use crate::error::{Error, Result};
use crate::hazard::{CellTrack, EndpointDensity, HazardAccumulator, LogBins, RasterFrame};
use crate::raster::Grid;
use crate::scenario::Scenario;
use crate::sim::{Observer, Sample, StopReason};
use crate::source::Sources;
use crate::terrain::build::build_terrain;
use crate::terrain::Terrain;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Command-line overrides of the scenario.
#[derive(Debug, Clone, Default)]
pub struct RunOverrides {
    /// Total rocks.
    pub rocks: Option<usize>,
    /// Seed.
    pub seed: Option<u64>,
    /// Threads (0 or `None`: all cores).
    pub threads: Option<usize>,
    /// Paths of the first N rocks.
    pub paths: Option<usize>,
}

/// The run manifest written as `summary.json`.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunSummary {
    /// talus version.
    pub talus_version: String,
    /// Scenario file.
    pub scenario: String,
    /// Scenario title.
    pub title: String,
    /// SHA-256 of every input file.
    pub input_sha256: BTreeMap<String, String>,
    /// Seed used.
    pub seed: u64,
    /// Rocks run.
    pub rocks: usize,
    /// Threads used (0 = all cores).
    pub threads: usize,
    /// Rocks per source.
    pub rocks_per_source: BTreeMap<String, usize>,
    /// The scenario as used (overrides applied, defaults filled in).
    pub parameters: serde_json::Value,
    /// Materials as used.
    pub materials: Vec<crate::terrain::Material>,
    /// Terrain facts.
    pub terrain: TerrainFacts,
    /// Raster geometry.
    pub raster: RasterFacts,
    /// Rocks by stop reason.
    pub stop_reasons: BTreeMap<String, usize>,
    /// Of the rocks that left the terrain, those that left over a gap inside it: the surface resumes ahead of where
    /// they left, within [`GAP_PROBE_M`] past the teeth of its edge (nodata cells or missing triangles in their way;
    /// [`crate::terrain::Surface::resumes_ahead`]).
    pub left_over_gaps: usize,
    /// Of the rocks that stopped, those stopped in place ([`crate::sim::SimParams::stop_in_place_s`]): their centre
    /// stayed within their bounding radius of one place that long, in contact, as they spun or rocked.
    pub stopped_in_place: usize,
    /// Run-out statistics over all rocks, m.
    pub runout_m: Stats,
    /// Travel time statistics, s.
    pub travel_time_s: Stats,
    /// Largest kinetic energy per rock statistics, kJ.
    pub max_kinetic_kj: Stats,
    /// Largest bounce height per rock statistics, m.
    pub max_bounce_m: Stats,
    /// Impacts in which the energy guard re-solved with Cr = 0.
    pub energy_guards: u64,
    /// Contact steps over all rocks.
    pub contact_steps: u64,
    /// Contact-solver sweeps over all rocks.
    pub solver_sweeps: u64,
    /// Wall-clock time from the terrain built to the outputs written, s.
    pub wall_time_s: f64,
    /// Rocks per second of wall-clock time.
    pub rocks_per_second: f64,
    /// Files written.
    pub outputs: Vec<String>,
    /// The scenario's collector lines: rocks crossing, energies and heights.
    pub collectors: Vec<crate::collector::facts::CollectorFacts>,
    /// The barriers: rocks caught and rocks that broke through.
    pub barriers: Vec<crate::collector::facts::BarrierFacts>,
    /// What building the terrain noticed ([`Terrain::notes`]): keys it does not use, area closed over; then what the
    /// run noticed (rocks that left over gaps in the terrain).
    pub warnings: Vec<String>,
}

/// How far ahead of a rock that left the terrain the surface is looked for, past twice the size of the triangle it
/// left, m (ours: a gap narrower than that, in the rock's direction, is a hole in the terrain rather than its edge).
pub const GAP_PROBE_M: f64 = 20.0;

/// Terrain facts for the manifest.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TerrainFacts {
    /// Triangles used.
    pub triangles: usize,
    /// Degenerate triangles dropped.
    pub degenerate_dropped: usize,
    /// Vertical triangles (contact only).
    pub vertical: usize,
    /// Local origin subtracted at load (z-up axes), m.
    pub origin_m: [f64; 3],
    /// Up axis of the files.
    pub up: crate::terrain::UpAxis,
    /// EPSG code, if known.
    pub crs_epsg: Option<u32>,
}

/// Raster facts for the manifest.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RasterFacts {
    /// Cell size, m.
    pub cell_size_m: f64,
    /// Columns.
    pub ncols: usize,
    /// Rows.
    pub nrows: usize,
    /// West edge, m.
    pub x_min_m: f64,
    /// North edge, m.
    pub y_max_m: f64,
    /// End-point kernel bandwidth, m.
    pub endpoint_bandwidth_m: f64,
}

/// Percentiles of a quantity over rocks.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Stats {
    /// Smallest.
    pub min: f64,
    /// Median.
    pub p50: f64,
    /// 90th percentile.
    pub p90: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Largest.
    pub max: f64,
    /// Mean.
    pub mean: f64,
}

impl Stats {
    /// Statistics of `values` (NaN-free); all zero when empty.
    pub fn of(values: &mut [f64]) -> Stats {
        if values.is_empty() {
            return Stats::default();
        }
        values.sort_by(f64::total_cmp);
        Stats {
            min: values[0],
            p50: quantile_sorted(values, 0.5),
            p90: quantile_sorted(values, 0.9),
            p95: quantile_sorted(values, 0.95),
            max: values[values.len() - 1],
            mean: values.iter().sum::<f64>() / values.len() as f64,
        }
    }
}

/// Rocks whose values [`StatsAccumulator`] keeps for exact percentiles (ours): 3.2 MB for four quantities.
pub const EXACT_STATS_ROCKS: usize = 100_000;

/// Bins of [`StatsAccumulator`] past [`EXACT_STATS_ROCKS`]: 1,000 a decade from 10⁻³ to 10⁷ (ours), so a
/// percentile is read to within 0.23 % (values below 10⁻³ to within 10⁻³).
const STATS_BINS: LogBins = LogBins { min: 1e-3, per_decade: 1000, n: 10_000 };

/// [`Stats`] of a quantity accumulated rock by rock in memory that does not grow with the run: the values of the
/// first [`EXACT_STATS_ROCKS`] rocks are kept and give exact percentiles; past them the percentiles are read from
/// log-spaced bins (1,000 a decade from 10⁻³ to 10⁷) and the smallest, largest and mean stay exact.
#[derive(Debug, Clone)]
pub struct StatsAccumulator {
    values: Vec<f64>,
    counts: Vec<u32>,
    n: usize,
    min: f64,
    max: f64,
    sum: f64,
}

impl Default for StatsAccumulator {
    fn default() -> Self {
        StatsAccumulator {
            values: Vec::new(),
            counts: vec![0; STATS_BINS.len()],
            n: 0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            sum: 0.0,
        }
    }
}

impl StatsAccumulator {
    /// Adds a value (NaN-free).
    pub fn add(&mut self, v: f64) {
        if self.n < EXACT_STATS_ROCKS {
            self.values.push(v);
        } else if self.n == EXACT_STATS_ROCKS {
            self.values = Vec::new(); // From here on the bins give the percentiles.
        }
        self.counts[STATS_BINS.bin(v)] += 1;
        self.n += 1;
        self.min = self.min.min(v);
        self.max = self.max.max(v);
        self.sum += v;
    }

    /// The statistics of the values added; all zero when none was.
    pub fn stats(mut self) -> Stats {
        if self.n <= EXACT_STATS_ROCKS {
            return Stats::of(&mut self.values);
        }
        let q = |q| STATS_BINS.quantile(&self.counts, self.n as u32, q, self.max).max(self.min);
        Stats { min: self.min, p50: q(0.5), p90: q(0.9), p95: q(0.95), max: self.max, mean: self.sum / self.n as f64 }
    }
}

/// Linear-interpolation quantile of sorted values (the "type 7" definition of R and NumPy).
pub fn quantile_sorted(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let h = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// Loads the terrain of a scenario, with its barriers.
///
/// # Errors
/// Beside the terrain's own: a barrier with no point of its line over the terrain (coordinates in another frame,
/// most likely: it would catch nothing, and say so as if no rock came), as collectors are refused.
pub fn load_terrain(sc: &Scenario) -> Result<Terrain> {
    let mut terrain = build_terrain(&sc.terrain_files, &sc.file.terrain, &sc.materials, &sc.path)?;
    let mut barriers = Vec::new();
    for (i, b) in sc.file.barriers.iter().enumerate() {
        let name = b.name.clone().unwrap_or_else(|| format!("barrier_{i}"));
        let line_m: Vec<[f64; 2]> =
            b.line.iter().map(|p| crate::terrain::horizontal_to_local(terrain.up, &terrain.origin, *p)).collect();
        if !terrain.surface.any_point_over(&line_m, 1.0) {
            return Err(Error::invalid(
                format!("{}: barriers[{i}] ({name})", sc.path.display()),
                "no point of the line lies over the terrain",
                "give the line in the terrain's coordinates (the CRS of the DEM, or the mesh's x and y)",
            ));
        }
        barriers.push(crate::sim::Barrier { name, line_m, height_m: b.height_m, capacity_j: b.capacity_kj * 1000.0 });
    }
    terrain.barriers = barriers;
    Ok(terrain)
}

/// Builds the run setup (terrain, sources, shapes) of a scenario with overrides applied.
pub fn setup(sc: &Scenario, overrides: &RunOverrides) -> Result<Setup> {
    let mut terrain = load_terrain(sc)?;
    let total = overrides.rocks.or(sc.file.simulation.rocks);
    let sources = Sources::build(&sc.file.sources, &terrain, total, &format!("{}: sources", sc.path.display()))?;
    // The run's warnings are the terrain's notes (printed before the rocks run, kept in summary.json).
    terrain.notes.extend(sources.notes.iter().cloned());
    Setup::new(sc, terrain, sources, overrides.seed.unwrap_or(sc.file.simulation.seed))
}

/// Checks what a run of `sc` with `overrides` checks before its first rock (the terrain with its barriers, the
/// sources, the rock shapes, the collector lines, the raster frame) without running or writing anything, so that a
/// command running several scenarios refuses a bad one before the first runs. Returns an empty grid of the run's
/// raster frame.
pub fn check_run(sc: &Scenario, overrides: &RunOverrides) -> Result<Grid> {
    let setup = setup(sc, overrides)?;
    crate::collector::scenario_collectors(&sc.file.collectors, &setup.terrain)?;
    let field = format!("{}: output", sc.path.display());
    Ok(RasterFrame::covering(&setup.terrain, &sc.file.output, &field)?.empty_grid())
}

/// Records a rock's samples (for `--paths`).
#[derive(Debug, Default)]
struct PathRecorder(Vec<Sample>);

impl Observer for PathRecorder {
    fn sample(&mut self, s: &Sample) {
        self.0.push(*s);
    }
}

/// Raster products, in output order: (file stem, description).
pub const RASTERS: [(&str, &str); 6] = [
    ("endpoint_density", "probability per cell that a rock stops there"),
    ("reach_probability", "fraction of rocks that pass over the cell"),
    ("kinetic_energy_p95_kj", "95th percentile over rocks of their largest kinetic energy in the cell, kJ"),
    ("kinetic_energy_max_kj", "largest kinetic energy in the cell, kJ"),
    ("bounce_height_p95_m", "95th percentile over rocks of their largest passing height in the cell, m"),
    ("bounce_height_max_m", "largest passing height in the cell, m"),
];

/// Runs a scenario and writes its outputs into `out_dir`. `progress` is called with the number of rocks done.
pub fn run_scenario(
    sc: &Scenario,
    overrides: &RunOverrides,
    out_dir: &Path,
    progress: &dyn Fn(usize, usize),
) -> Result<RunSummary> {
    Ok(run_scenario_with(sc, overrides, out_dir, progress, &RunExtras::default(), &mut |_, _| {})?.summary)
}

/// What a run tracks besides the scenario's own collectors (used by `talus barrier`).
#[derive(Debug, Clone, Default)]
pub struct RunExtras {
    /// More collector lines (local frame), after the scenario's; they are not drawn on the maps.
    pub collectors: Vec<crate::collector::Collector>,
    /// The protected zone tracked for every rock.
    pub zone: Option<crate::collector::ProtectedZone>,
}

/// A run's summary and what the caller may want to look at further.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// The manifest.
    pub summary: RunSummary,
    /// The rasters, in [`RASTERS`] order.
    pub grids: Vec<Grid>,
    /// The terrain (with its barriers).
    pub terrain: Terrain,
    /// The collectors (the scenario's, then the extras).
    pub collectors: crate::collector::CollectorSet,
    /// Their statistics.
    pub collector_stats: crate::collector::CollectorStats,
}

/// [`run_scenario`] with extra collectors and a protected zone; `on_rock` sees every rock's record and crossings,
/// in rock order.
pub fn run_scenario_with(
    sc: &Scenario,
    overrides: &RunOverrides,
    out_dir: &Path,
    progress: &dyn Fn(usize, usize),
    extras: &RunExtras,
    on_rock: &mut dyn FnMut(&RockRecord, &crate::collector::RockCrossings),
) -> Result<RunOutput> {
    run_setup(sc, setup(sc, overrides)?, overrides, out_dir, progress, extras, on_rock)
}

/// [`run_scenario_with`] on a setup already built by [`setup`] (so that a caller can show the terrain's notes
/// before the rocks run).
pub fn run_setup(
    sc: &Scenario,
    setup: Setup,
    overrides: &RunOverrides,
    out_dir: &Path,
    progress: &dyn Fn(usize, usize),
    extras: &RunExtras,
    on_rock: &mut dyn FnMut(&RockRecord, &crate::collector::RockCrossings),
) -> Result<RunOutput> {
    let t0 = Instant::now();
    let mut collector_lines = crate::collector::scenario_collectors(&sc.file.collectors, &setup.terrain)?;
    let n_user_collectors = collector_lines.len();
    collector_lines.extend(extras.collectors.iter().cloned());
    let collectors = crate::collector::CollectorSet::new(collector_lines, extras.zone.clone());
    let mut collector_stats = crate::collector::CollectorStats::new(&collectors, setup.terrain.barriers.len());
    let cell = sc.file.output.cell_size_m;
    let frame = RasterFrame::covering(&setup.terrain, &sc.file.output, &format!("{}: output", sc.path.display()))?;
    let earlier_outputs = earlier_run_outputs(out_dir);
    crate::io::create_folder(out_dir)?;
    prepare_folder(out_dir)?;
    let n = setup.rock_count();
    let threads = overrides.threads.or(sc.file.simulation.threads).unwrap_or(0);
    let n_paths = overrides.paths.unwrap_or(sc.file.output.paths).min(n);
    let bandwidth = sc.file.output.endpoint_bandwidth_m.unwrap_or(2.0 * cell);
    let mut acc = HazardAccumulator::new(frame);
    let terrain = &setup.terrain;

    let endpoints_path = out_dir.join("endpoints.csv");
    let endpoints_tmp = crate::io::atomic::temp_path(&endpoints_path);
    let mut csv = BufWriter::new(File::create(&endpoints_tmp).map_err(|e| Error::io(&endpoints_tmp, e))?);
    let io_err = |e: std::io::Error| Error::io(&endpoints_tmp, e);
    writeln!(
        csv,
        "rock_id,source_id,shape,mass_kg,release_x_m,release_y_m,release_z_m,end_x_m,end_y_m,end_z_m,stop_reason,runout_m,travel_time_s,max_kinetic_j,max_bounce_m"
    )
    .map_err(io_err)?;
    let mut stopped_xy = crate::report::maps::ThinnedPoints::default();
    let mut density = EndpointDensity::new(&frame, bandwidth);
    let mut paths: Vec<(usize, Vec<Sample>)> = Vec::new();
    let mut reasons: BTreeMap<String, usize> = StopReason::ALL.iter().map(|r| (r.as_str().to_string(), 0)).collect();
    let [mut runouts, mut times, mut energies, mut bounces] = [(); 4].map(|_| StatsAccumulator::default());
    let (mut guards, mut contact_steps, mut sweeps, mut in_place) = (0u64, 0u64, 0u64, 0usize);
    let mut gaps: (usize, Option<[f64; 3]>) = (0, None);
    let mut write_error = None;
    crate::parallel::map_in_order(
        n,
        threads,
        128,
        |i| {
            let (draw, rng) = setup.draw(i);
            // The rock's size, reported at collector crossings.
            let size_m = 2.0 * draw.body.equivalent_radius_m();
            let mut track = (
                CellTrack::new(&frame),
                ((i < n_paths).then(PathRecorder::default), crate::collector::CollectorTrack::new(&collectors, size_m)),
            );
            let rec = setup.run_drawn(draw, rng, &mut track);
            (rec, track.0.into_visits(), track.1 .0.map(|p| p.0), track.1 .1.into_crossings())
        },
        |i, (rec, visits, path, crossings): (RockRecord, _, Option<Vec<Sample>>, crate::collector::RockCrossings)| {
            acc.add(&visits);
            collector_stats.add(&crossings);
            on_rock(&rec, &crossings);
            let o = &rec.outcome;
            let end = o.final_state.position_m;
            if o.stop_reason == StopReason::Stopped {
                stopped_xy.add([end.x, end.y]);
                density.add([end.x, end.y]);
            }
            *reasons.entry(o.stop_reason.as_str().to_string()).or_insert(0) += 1;
            let v = o.final_state.velocity_mps;
            if o.stop_reason == StopReason::LeftTerrain
                && terrain.surface.resumes_ahead(end.x, end.y, [v.x, v.y], GAP_PROBE_M)
            {
                gaps.0 += 1;
                gaps.1.get_or_insert(terrain.to_file_frame(&end));
            }
            runouts.add(rec.runout_m);
            times.add(o.travel_time_s);
            energies.add(o.max_kinetic_j / 1000.0);
            bounces.add(o.max_bounce_m);
            guards += o.energy_guards as u64;
            in_place += usize::from(o.stopped_in_place);
            contact_steps += o.contact_steps;
            sweeps += o.solver_sweeps;
            let r = terrain.to_file_frame(&rec.release_m);
            let e = terrain.to_file_frame(&end);
            let line = format!(
                "{},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{},{:.3},{:.3},{:.1},{:.3}\n",
                rec.index,
                setup.sources.sources[rec.source].name,
                rec.shape,
                rec.mass_kg,
                r[0],
                r[1],
                r[2],
                e[0],
                e[1],
                e[2],
                o.stop_reason.as_str(),
                rec.runout_m,
                o.travel_time_s,
                o.max_kinetic_j,
                o.max_bounce_m
            );
            if write_error.is_none() {
                if let Err(e) = csv.write_all(line.as_bytes()) {
                    write_error = Some(e);
                }
            }
            if let Some(p) = path {
                paths.push((i, p));
            }
            progress(i + 1, n);
        },
    );
    if let Some(e) = write_error {
        let _ = std::fs::remove_file(&endpoints_tmp);
        return Err(io_err(e));
    }
    if let Err(e) = csv.flush() {
        let _ = std::fs::remove_file(&endpoints_tmp);
        return Err(io_err(e));
    }
    drop(csv);
    std::fs::rename(&endpoints_tmp, &endpoints_path).map_err(|e| Error::io(&endpoints_path, e))?;

    let mut outputs = vec!["endpoints.csv".to_string()];
    let crs = crate::terrain::frame::output_crs(sc.file.terrain.crs_epsg, &terrain.crs);
    let grids = hazard_grids(&acc, terrain, density.finish(n), n, &crs);
    for ((stem, _), grid) in RASTERS.iter().zip(&grids) {
        let name = format!("{stem}.tif");
        crate::io::geotiff::write_grid(&out_dir.join(&name), grid)?;
        outputs.push(name);
    }
    if !paths.is_empty() {
        write_paths(out_dir, terrain, &paths)?;
        outputs.push("paths.csv".into());
        outputs.push("paths.vtk".into());
    }
    let products = crate::report::RunProducts {
        dir: out_dir,
        scenario: sc,
        terrain,
        grids: &grids,
        stopped_xy: &stopped_xy,
        paths: &paths,
        collectors: &collectors,
        n_user_collectors,
        collector_stats: &collector_stats,
    };
    outputs.extend(crate::report::write_run_products(&products)?);

    let wall = t0.elapsed().as_secs_f64();
    let mut file = sc.file.clone();
    file.simulation.seed = setup.seed;
    file.simulation.rocks = Some(n);
    let threads = crate::parallel::threads_used(threads);
    file.simulation.threads = Some(threads);
    file.output.paths = n_paths;
    file.output.endpoint_bandwidth_m = Some(bandwidth);
    let summary = RunSummary {
        talus_version: env!("CARGO_PKG_VERSION").to_string(),
        scenario: sc.path.display().to_string(),
        title: sc.file.title.clone(),
        input_sha256: input_hashes(sc)?,
        seed: setup.seed,
        rocks: n,
        threads,
        rocks_per_source: setup.sources.sources.iter().map(|s| (s.name.clone(), s.count)).collect(),
        parameters: serde_json::to_value(&file).unwrap_or(serde_json::Value::Null),
        materials: terrain.materials.clone(),
        terrain: TerrainFacts {
            triangles: terrain.stats.triangles,
            degenerate_dropped: terrain.stats.degenerate_dropped,
            vertical: terrain.stats.vertical,
            origin_m: [terrain.origin.x, terrain.origin.y, terrain.origin.z],
            up: terrain.up,
            crs_epsg: grids[0].crs.epsg,
        },
        raster: RasterFacts {
            cell_size_m: cell,
            ncols: frame.ncols,
            nrows: frame.nrows,
            x_min_m: frame.x_min_m,
            y_max_m: frame.y_max_m,
            endpoint_bandwidth_m: bandwidth,
        },
        stop_reasons: reasons,
        runout_m: runouts.stats(),
        travel_time_s: times.stats(),
        max_kinetic_kj: energies.stats(),
        max_bounce_m: bounces.stats(),
        energy_guards: guards,
        contact_steps,
        solver_sweeps: sweeps,
        wall_time_s: wall,
        rocks_per_second: n as f64 / wall.max(1e-9),
        outputs: {
            outputs.push("summary.json".into());
            outputs.push("index.html".into());
            outputs
        },
        collectors: crate::collector::facts::collector_facts(
            &collectors.collectors[..n_user_collectors],
            &collector_stats,
        ),
        barriers: crate::collector::facts::barrier_facts(&terrain.barriers, &collector_stats),
        left_over_gaps: gaps.0,
        stopped_in_place: in_place,
        warnings: terrain.notes.iter().cloned().chain(gaps.1.map(|at| gap_warning(gaps.0, at))).collect(),
    };
    crate::io::write_json_atomic(&out_dir.join("summary.json"), &summary)?;
    crate::report::write_run_index(&products, &summary)?;
    remove_stale_outputs(out_dir, &earlier_outputs, &summary.outputs)?;
    Ok(RunOutput { summary, grids, terrain: setup.terrain.clone(), collectors, collector_stats })
}

/// The warning for `n` rocks that left the terrain over gaps in it, the first at `at` (file frame).
fn gap_warning(n: usize, at: [f64; 3]) -> String {
    format!(
        "{n} rocks left the terrain over a gap inside it (the surface resumes ahead of where they left; the first \
         at x = {:.1}, y = {:.1}): nodata cells or missing triangles end them there; fill the \
         holes (gdal_fillnodata for a DEM, close the mesh) or clip the terrain to the ground you have",
        at[0], at[1]
    )
}

/// The files an earlier run listed in `out_dir/summary.json` (none if there is no such run): plain file names only.
fn earlier_run_outputs(out_dir: &Path) -> Vec<String> {
    let Ok(text) = std::fs::read_to_string(out_dir.join("summary.json")) else { return Vec::new() };
    let Ok(json) = serde_json::from_str::<serde_json::Value>(&text) else { return Vec::new() };
    let names = json["outputs"].as_array().into_iter().flatten().filter_map(|v| v.as_str());
    names.filter(|n| Path::new(n).file_name().is_some_and(|f| f == *n)).map(String::from).collect()
}

/// Every name a run may write into its folder (those it wrote are listed in its `summary.json`).
fn run_output_names() -> Vec<String> {
    let stems = RASTERS.iter().chain(&crate::report::ZONE_RASTERS).map(|r| r.0);
    let mut names: Vec<String> = stems.flat_map(|s| ["tif", "png", "asc", "prj"].map(|e| format!("{s}.{e}"))).collect();
    names.extend(
        ["endpoints.csv", "summary.json", "index.html", "terrain.png", "collectors.csv", "collectors.geojson"]
            .into_iter()
            .chain(["paths.csv", "paths.vtk", "paths.geojson"])
            .map(String::from),
    );
    names
}

/// Before the rocks run: refuses a folder inside `out_dir` named like a file the run writes (found only when the
/// run's last file was written, the others left), and removes the temporary files (`.NAME.tmp`) of a run into it
/// that was killed before it renamed them.
fn prepare_folder(out_dir: &Path) -> Result<()> {
    for name in run_output_names() {
        let path = out_dir.join(&name);
        if path.is_dir() {
            return Err(Error::invalid(
                "--out",
                format!("{} is a folder, where the run writes its file {name}", path.display()),
                "remove or rename that folder, or give another --out",
            ));
        }
        let tmp = crate::io::atomic::temp_path(&path);
        if tmp.is_file() {
            std::fs::remove_file(&tmp).map_err(|e| Error::io(&tmp, e))?;
        }
    }
    Ok(())
}

/// Removes the files an earlier run into the same folder wrote (`earlier`) that this run did not (`now`), so that
/// the folder holds one run (a run with `--paths` followed by one without left the old `paths.*`). Only files an
/// earlier talus run listed are touched (ours).
fn remove_stale_outputs(out_dir: &Path, earlier: &[String], now: &[String]) -> Result<()> {
    for name in earlier.iter().filter(|n| !now.contains(n)) {
        let path = out_dir.join(name);
        if path.is_file() {
            std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
        }
    }
    Ok(())
}

/// The six hazard rasters (in [`RASTERS`] order). Cells off the terrain are nodata; on the terrain, probabilities
/// are 0 where nothing came, energies and heights nodata where no rock passed.
pub fn hazard_grids(
    acc: &HazardAccumulator,
    terrain: &Terrain,
    density: Vec<f64>,
    n_rocks: usize,
    crs: &crate::raster::Crs,
) -> Vec<Grid> {
    let frame = &acc.frame;
    let mut grids: Vec<Grid> = (0..RASTERS.len()).map(|_| frame.empty_grid()).collect();
    for (k, &dens) in density.iter().enumerate() {
        let (x, y) = frame.local_centre(k);
        if terrain.surface.at(x, y).is_none() {
            continue;
        }
        let values = [
            dens,
            acc.reach_count(k) as f64 / n_rocks.max(1) as f64,
            acc.kinetic_quantile_j(k, 0.95) / 1000.0,
            acc.kinetic_max_j(k) / 1000.0,
            acc.height_quantile_m(k, 0.95),
            acc.height_max_m(k),
        ];
        for (g, v) in grids.iter_mut().zip(values) {
            g.values[k] = v as f32;
        }
    }
    for g in grids.iter_mut() {
        g.crs = crs.clone();
    }
    grids
}

fn input_hashes(sc: &Scenario) -> Result<BTreeMap<String, String>> {
    let mut files: Vec<PathBuf> = vec![sc.path.clone()];
    files.extend(sc.terrain_files.iter().cloned());
    for s in &sc.shapes {
        if let crate::scenario::ShapeRef::Hull(p) = s {
            files.push(p.clone());
        }
    }
    let mut out = BTreeMap::new();
    for f in files {
        let bytes = std::fs::read(&f).map_err(|e| Error::io(&f, e))?;
        let digest = Sha256::digest(&bytes);
        out.insert(f.display().to_string(), digest.iter().map(|b| format!("{b:02x}")).collect());
    }
    Ok(out)
}

/// Writes `paths.csv` and `paths.vtk` (legacy VTK polylines, for ParaView), in the terrain's frame.
fn write_paths(out_dir: &Path, terrain: &Terrain, paths: &[(usize, Vec<Sample>)]) -> Result<()> {
    let csv_path = out_dir.join("paths.csv");
    crate::io::write_atomic(&csv_path, |w| {
        let err = |e| Error::io(&csv_path, e);
        writeln!(w, "rock_id,t_s,x_m,y_m,z_m,speed_mps,kinetic_j,bounce_m").map_err(err)?;
        for (id, samples) in paths {
            for s in samples {
                let p = terrain.to_file_frame(&s.position_m);
                writeln!(
                    w,
                    "{id},{:.4},{:.3},{:.3},{:.3},{:.3},{:.1},{:.3}",
                    s.t_s,
                    p[0],
                    p[1],
                    p[2],
                    s.velocity_mps.norm(),
                    s.kinetic_j,
                    s.clearance_m
                )
                .map_err(err)?;
            }
        }
        Ok(())
    })?;
    let vtk_path = out_dir.join("paths.vtk");
    crate::io::write_atomic(&vtk_path, |w| {
        let err = |e| Error::io(&vtk_path, e);
        let total: usize = paths.iter().map(|(_, s)| s.len()).sum();
        writeln!(w, "# vtk DataFile Version 3.0\ntalus rock paths\nASCII\nDATASET POLYDATA\nPOINTS {total} double")
            .map_err(err)?;
        for (_, samples) in paths {
            for s in samples {
                let p = terrain.to_file_frame(&s.position_m);
                writeln!(w, "{:.3} {:.3} {:.3}", p[0], p[1], p[2]).map_err(err)?;
            }
        }
        let size: usize = paths.iter().map(|(_, s)| s.len() + 1).sum();
        writeln!(w, "LINES {} {size}", paths.len()).map_err(err)?;
        let mut k = 0;
        for (_, samples) in paths {
            write!(w, "{}", samples.len()).map_err(err)?;
            for _ in samples {
                write!(w, " {k}").map_err(err)?;
                k += 1;
            }
            writeln!(w).map_err(err)?;
        }
        writeln!(w, "POINT_DATA {total}\nSCALARS kinetic_j double 1\nLOOKUP_TABLE default").map_err(err)?;
        for (_, samples) in paths {
            for s in samples {
                writeln!(w, "{:.1}", s.kinetic_j).map_err(err)?;
            }
        }
        writeln!(w, "SCALARS rock_id int 1\nLOOKUP_TABLE default").map_err(err)?;
        for (id, samples) in paths {
            for _ in samples {
                writeln!(w, "{id}").map_err(err)?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic spread of values over five decades (a low-discrepancy walk, no RNG needed).
    fn values(n: usize) -> Vec<f64> {
        (0..n).map(|i| 10f64.powf(-1.0 + 5.0 * ((i as f64 * 0.618_033_988_75) % 1.0))).collect()
    }

    #[test]
    fn stats_are_exact_up_to_the_kept_rocks_and_within_a_bin_past_them() {
        for n in [0, 1, 7, EXACT_STATS_ROCKS] {
            let mut acc = StatsAccumulator::default();
            let mut v = values(n);
            v.iter().for_each(|&x| acc.add(x));
            let (a, b) = (acc.stats(), Stats::of(&mut v));
            assert_eq!([a.min, a.p50, a.p90, a.p95, a.max, a.mean], [b.min, b.p50, b.p90, b.p95, b.max, b.mean]);
        }
        let n = 2 * EXACT_STATS_ROCKS + 17;
        let mut acc = StatsAccumulator::default();
        let mut v = values(n);
        v.iter().for_each(|&x| acc.add(x));
        assert!(acc.values.is_empty(), "the values are dropped past the kept rocks");
        let (a, b) = (acc.stats(), Stats::of(&mut v));
        assert_eq!([a.min, a.max], [b.min, b.max]);
        assert!((a.mean - b.mean).abs() < 1e-9 * b.mean, "{} {}", a.mean, b.mean);
        for (x, y) in [(a.p50, b.p50), (a.p90, b.p90), (a.p95, b.p95)] {
            assert!((x / y - 1.0).abs() < 0.0024, "binned {x} against exact {y}");
        }
    }
}
