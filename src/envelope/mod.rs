//! An envelope over models: several scenarios of one terrain (the fold models of `talus calibrate --kfold`, say)
//! run with the same seed, and each hazard raster combined cell by cell into the lowest, median and highest value
//! over the models, with the number of models whose rocks reach the cell. Ours: it shows a barrier designer how
//! far a map moves between models that fit the field data about equally well, in one raster per statistic.

pub mod profile;

use crate::collector::facts::CollectorFacts;
use crate::error::{Error, Result};
use crate::raster::Grid;
use crate::report::maps;
use crate::run::{quantile_sorted, run_scenario_with, RunExtras, RunOverrides, Stats, RASTERS};
use crate::scenario::{Scenario, ScenarioFile};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The statistics over models written for each raster (file-name suffixes): the lowest, median and highest value
/// over the models with a value in the cell (see [`combine`]).
pub const STATISTICS: [&str; 3] = ["min", "median", "max"];

/// File stem of the raster counting the models whose rocks reach each cell.
pub const REACHING: &str = "models_reaching";

/// File stem of a run's hazard zone levels, combined into `_min` and `_max` (see [`ZoneSpread`]).
pub const ZONES: &str = "hazard_zones";

/// One model of an envelope, as it ran.
#[derive(Debug, Clone, Serialize)]
pub struct EnvelopeModel {
    /// Name (its run is in `models/NAME/`).
    pub name: String,
    /// Scenario file.
    pub scenario: String,
    /// Scenario title.
    pub title: String,
    /// Seed of its run.
    pub seed: u64,
    /// Rocks run.
    pub rocks: usize,
    /// Run-out over rocks, m.
    pub runout_m: Stats,
    /// Each rock's largest kinetic energy, kJ.
    pub max_kinetic_kj: Stats,
    /// Each rock's largest bounce height, m.
    pub max_bounce_m: Stats,
    /// Wall-clock time of its run, s.
    pub wall_time_s: f64,
    /// Its collector lines (the scenario's `[[collectors]]`).
    pub collectors: Vec<CollectorFacts>,
    /// Its run's warnings (`summary.json` `warnings`).
    pub warnings: Vec<String>,
}

/// A figure's lowest, median and highest value over the runs that have it.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Spread3 {
    /// Lowest.
    pub min: Option<f64>,
    /// Median.
    pub median: Option<f64>,
    /// Highest.
    pub max: Option<f64>,
}

/// `v` with `decimals` decimals, `-` when there is none (the tables and lines of `talus envelope`).
pub fn fmt_opt(v: Option<f64>, decimals: usize) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.decimals$}"))
}

impl Spread3 {
    /// Over the values that are there.
    pub fn of(values: impl IntoIterator<Item = Option<f64>>) -> Spread3 {
        let mut v: Vec<f64> = values.into_iter().flatten().filter(|x| x.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        if v.is_empty() {
            return Spread3::default();
        }
        Spread3 { min: Some(v[0]), median: Some(quantile_sorted(&v, 0.5)), max: Some(v[v.len() - 1]) }
    }
}

/// One collector line over the runs: what a barrier there would face under each model.
#[derive(Debug, Clone, Serialize)]
pub struct CollectorSpread {
    /// Collector name (the same in every run).
    pub name: String,
    /// Fraction of the rocks that cross it.
    pub fraction_crossing: Spread3,
    /// 95th percentile of the kinetic energy at the crossings, kJ.
    pub kinetic_kj_p95: Spread3,
    /// 95th percentile of the passing height, m.
    pub passing_height_m_p95: Spread3,
}

/// How far one raster moves between the models.
#[derive(Debug, Clone, Serialize)]
pub struct RasterSpread {
    /// Raster file stem (see [`RASTERS`]).
    pub raster: String,
    /// Cells that at least [`WELL_SAMPLED_ROCKS`] rocks reach in every model and where every model has a positive
    /// value: the cells the spread is taken over.
    pub cells: usize,
    /// Median over those cells of (max − min) / median over the models.
    pub relative_spread_p50: Option<f64>,
    /// 95th percentile over those cells of the same.
    pub relative_spread_p95: Option<f64>,
    /// Largest value of the `min` raster.
    pub highest_min: Option<f64>,
    /// Largest value of the `median` raster.
    pub highest_median: Option<f64>,
    /// Largest value of the `max` raster.
    pub highest_max: Option<f64>,
}

/// How the hazard zones of the runs (`hazard_zones.tif`: 0 not reached, 1 low, 2 medium, 3 high) differ.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ZoneSpread {
    /// Area of the low (yellow) zone over the runs, m²: lowest, median, highest.
    pub low_m2: Spread3,
    /// Area of the medium (blue) zone, m².
    pub medium_m2: Spread3,
    /// Area of the high (red) zone, m².
    pub high_m2: Spread3,
    /// Cells that some run puts in a zone (level 1 or more).
    pub cells_zoned: usize,
    /// Of those, the cells whose level is not the same in every run.
    pub cells_differing: usize,
    /// Of the zoned cells, those that at least [`WELL_SAMPLED_ROCKS`] rocks of every run reach.
    pub well_sampled_zoned: usize,
    /// Of those, the cells whose level is not the same in every run.
    pub well_sampled_differing: usize,
}

/// The zone levels of the runs compared cell by cell (`sampled`: the well-sampled cells).
pub fn zone_spread(levels: &[Grid], sampled: &[bool]) -> ZoneSpread {
    let areas: Vec<[f64; 3]> = levels.iter().map(crate::zones::areas_m2).collect();
    let area = |level: usize| Spread3::of(areas.iter().map(|a| Some(a[level])));
    let mut z = ZoneSpread { low_m2: area(0), medium_m2: area(1), high_m2: area(2), ..Default::default() };
    for (k, &well) in sampled.iter().enumerate() {
        let v: Vec<f32> = levels.iter().map(|g| g.values[k]).collect();
        if v.iter().any(|x| x.is_nan()) || v.iter().all(|&x| x < 1.0) {
            continue;
        }
        let differs = v.iter().any(|&x| x != v[0]);
        z.cells_zoned += 1;
        z.cells_differing += differs as usize;
        if well {
            z.well_sampled_zoned += 1;
            z.well_sampled_differing += differs as usize;
        }
    }
    z
}

/// What `talus envelope` writes as `envelope.json`.
#[derive(Debug, Clone, Serialize)]
pub struct EnvelopeSummary {
    /// talus version.
    pub talus_version: String,
    /// The models, in the order given.
    pub models: Vec<EnvelopeModel>,
    /// Each raster's spread between the models.
    pub rasters: Vec<RasterSpread>,
    /// How the hazard zones differ between the models.
    pub zones: ZoneSpread,
    /// The collector lines every run has, over the runs.
    pub collectors: Vec<CollectorSpread>,
    /// With `--floor`: the first model's runs with other seeds, summarised alike.
    pub floor: Option<FloorSpread>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// Files written (besides the models' own runs in `models/`).
    pub outputs: Vec<String>,
}

/// The spread between runs of the first model with other seeds (`--floor`).
#[derive(Debug, Clone, Serialize)]
pub struct FloorSpread {
    /// The first model's runs, one per seed.
    pub models: Vec<EnvelopeModel>,
    /// Each raster's spread.
    pub rasters: Vec<RasterSpread>,
    /// The hazard zones'.
    pub zones: ZoneSpread,
    /// Each collector line's.
    pub collectors: Vec<CollectorSpread>,
}

/// The collector lines of the first model that every model has, each over the models.
pub fn collector_spread(models: &[EnvelopeModel]) -> Vec<CollectorSpread> {
    let Some(first) = models.first() else { return Vec::new() };
    first
        .collectors
        .iter()
        .filter_map(|c| {
            let per_model: Vec<&CollectorFacts> =
                models.iter().filter_map(|m| m.collectors.iter().find(|x| x.name == c.name)).collect();
            (per_model.len() == models.len()).then(|| CollectorSpread {
                name: c.name.clone(),
                fraction_crossing: Spread3::of(per_model.iter().map(|x| Some(x.fraction_crossing))),
                kinetic_kj_p95: Spread3::of(per_model.iter().map(|x| x.kinetic_kj_p95)),
                passing_height_m_p95: Spread3::of(per_model.iter().map(|x| x.passing_height_m_p95)),
            })
        })
        .collect()
}

/// Refuses `b` (of model `name_b`) unless it covers the same cells as `a` (of `name_a`).
pub fn check_frame(a: &Grid, name_a: &str, b: &Grid, name_b: &str) -> Result<()> {
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-6 * (1.0 + x.abs().max(y.abs()));
    let same = a.ncols == b.ncols
        && a.nrows == b.nrows
        && close(a.x_min_m, b.x_min_m)
        && close(a.y_max_m, b.y_max_m)
        && close(a.cell_x_m, b.cell_x_m)
        && close(a.cell_y_m, b.cell_y_m);
    if same {
        return Ok(());
    }
    let describe = |g: &Grid| {
        format!("{} × {} cells of {} m from x {:.2}, y {:.2}", g.ncols, g.nrows, g.cell_x_m, g.x_min_m, g.y_max_m)
    };
    Err(Error::invalid(
        format!("{name_b}: rasters"),
        format!("they cover {}, while {name_a}'s cover {}", describe(b), describe(a)),
        "an envelope combines models of one terrain: give every scenario the same terrain files, terrain settings \
         and [output] cell_size_m",
    ))
}

/// Refuses, before anything runs or is written, a model that its run would refuse ([`crate::run::check_run`]: its
/// terrain, sources, rocks, collectors and raster frame), so that a bad model leaves no run of the others behind,
/// or whose rasters would not cover the first model's cells ([`check_frame`] after the runs would find it only
/// when every model has run).
fn check_models_before(models: &[(Scenario, String)], overrides: &RunOverrides) -> Result<()> {
    let mut first_frame = None;
    for (sc, name) in models {
        let frame = crate::run::check_run(sc, overrides)?;
        match &first_frame {
            None => first_frame = Some(frame),
            Some(first) => check_frame(first, &models[0].1, &frame, name)?,
        }
    }
    Ok(())
}

/// The lowest, median and highest value in each cell over `grids` (one per model, named by `names`), counting
/// only the models with a value there (`NaN` is no value: no rock passed, or outside the terrain).
pub fn combine(grids: &[Grid], names: &[String]) -> Result<[Grid; 3]> {
    let Some(first) = grids.first() else {
        return Err(Error::invalid("models", "no raster to combine", "give at least one model"));
    };
    for (g, name) in grids.iter().zip(names).skip(1) {
        check_frame(first, &names[0], g, name)?;
    }
    let mut out = [first.clone(), first.clone(), first.clone()];
    let mut values = Vec::with_capacity(grids.len());
    for k in 0..first.values.len() {
        values.clear();
        values.extend(grids.iter().map(|g| g.values[k] as f64).filter(|v| v.is_finite()));
        values.sort_by(f64::total_cmp);
        let stats = match (values.first(), values.last()) {
            (Some(&lo), Some(&hi)) => [lo, quantile_sorted(&values, 0.5), hi],
            _ => [f64::NAN; 3],
        };
        for (g, v) in out.iter_mut().zip(stats) {
            g.values[k] = v as f32;
        }
    }
    Ok(out)
}

/// The number of models whose rocks reach each cell, from their `reach_probability` rasters (`NaN` where no model
/// has a value: outside the terrain). The frames must agree (see [`combine`]).
pub fn models_reaching(reach: &[Grid]) -> Grid {
    let mut out = reach[0].clone();
    for (k, v) in out.values.iter_mut().enumerate() {
        *v = if reach.iter().all(|g| g.values[k].is_nan()) {
            f32::NAN
        } else {
            reach.iter().filter(|g| g.values[k] > 0.0).count() as f32
        };
    }
    out
}

/// Runs every model (a scenario and its name, see [`model_names`]) into `out_dir/models/NAME/` with the same seed
/// (`overrides.seed`, else the first scenario's), so the maps differ by the models alone, then writes each raster's `_min`, `_median` and `_max`
/// over the models (GeoTIFF and PNG), [`REACHING`], `envelope.json` and `envelope.md` into `out_dir`.
///
/// With `floor`, also runs the first scenario once per model with the seeds that follow (`out_dir/floor/`, laid
/// out the same way): the spread that the random draws alone give at this number of rocks, beside which the
/// models' spread is read. `progress(run, rocks_done, rocks)` follows the runs (the floor's after the models').
pub fn run_envelope(
    models: &[(Scenario, String)],
    overrides: &RunOverrides,
    out_dir: &Path,
    floor: bool,
    progress: &dyn Fn(usize, usize, usize),
) -> Result<EnvelopeSummary> {
    let t0 = Instant::now();
    let n = models.len();
    if n < 2 {
        return Err(Error::invalid(
            "scenarios",
            format!("an envelope needs at least two models, got {n}"),
            "give two or more scenario files, e.g. every fold_*/calibrated.toml of `talus calibrate --kfold`",
        ));
    }
    check_models_before(models, overrides)?;
    let seed = overrides.seed.unwrap_or(models[0].0.file.simulation.seed);
    let runs: Vec<Member> =
        models.iter().map(|(scenario, name)| Member { scenario, name: name.clone(), seed }).collect();
    let mut summary = envelope_of(&runs, overrides, out_dir, progress)?;
    if floor {
        let runs: Vec<Member> = (floor_seeds(seed, n).into_iter())
            .map(|(name, seed)| Member { scenario: &models[0].0, name, seed })
            .collect();
        let floor_dir = out_dir.join("floor");
        let f = envelope_of(&runs, overrides, &floor_dir, &|i, d, t| progress(n + i, d, t))?;
        write_summary(
            &floor_dir,
            &f,
            &format!("the first model, {}, with seeds {seed} to {}", models[0].1, seed.wrapping_add(n as u64 - 1)),
        )?;
        summary.outputs.push("floor/".into());
        summary.floor =
            Some(FloorSpread { models: f.models, rasters: f.rasters, zones: f.zones, collectors: f.collectors });
    }
    summary.wall_time_s = t0.elapsed().as_secs_f64();
    write_summary(out_dir, &summary, &format!("{n} models, each with seed {seed}"))?;
    Ok(summary)
}

/// The runs of a floor: `n` seeds from `seed` on, each named `seed_S` (its folder under `floor/models/`), for
/// `talus envelope --floor` and `talus barrier --floor`.
pub fn floor_seeds(seed: u64, n: usize) -> Vec<(String, u64)> {
    (0..n as u64).map(|i| seed.wrapping_add(i)).map(|s| (format!("seed_{s}"), s)).collect()
}

/// One run of an envelope.
struct Member<'a> {
    scenario: &'a Scenario,
    name: String,
    seed: u64,
}

/// Runs `members` into `out_dir/models/NAME/` and writes their combined rasters into `out_dir`.
fn envelope_of(
    members: &[Member],
    overrides: &RunOverrides,
    out_dir: &Path,
    progress: &dyn Fn(usize, usize, usize),
) -> Result<EnvelopeSummary> {
    let t0 = Instant::now();
    let names: Vec<String> = members.iter().map(|m| m.name.clone()).collect();
    let mut models = Vec::new();
    let mut first = None;
    for (i, m) in members.iter().enumerate() {
        let dir = out_dir.join("models").join(&m.name);
        let overrides = RunOverrides { seed: Some(m.seed), ..overrides.clone() };
        let run = run_scenario_with(
            m.scenario,
            &overrides,
            &dir,
            &|d, n| progress(i, d, n),
            &RunExtras::default(),
            &mut |_, _| {},
        )?;
        let s = &run.summary;
        models.push(EnvelopeModel {
            name: m.name.clone(),
            scenario: m.scenario.path.display().to_string(),
            title: m.scenario.file.title.clone(),
            seed: m.seed,
            rocks: s.rocks,
            runout_m: s.runout_m.clone(),
            max_kinetic_kj: s.max_kinetic_kj.clone(),
            max_bounce_m: s.max_bounce_m.clone(),
            wall_time_s: s.wall_time_s,
            collectors: s.collectors.clone(),
            warnings: s.warnings.clone(),
        });
        // The frames agree: checked before the runs (`check_models_before`), and again by `combine`.
        if first.is_none() {
            first = Some(run);
        }
    }
    let first = first.expect("an envelope has members");
    let crs = first.grids[0].crs.clone();
    let dem = maps::dem_for(&first.terrain, &first.grids[0]);
    let overlays = maps::run_overlays(&first.terrain, &maps::ThinnedPoints::default(), &[]);
    let n = members.len();
    let mut outputs = Vec::new();
    let ascii = members[0].scenario.file.output.ascii_grids;
    let mut write = |stem: String, grid: &Grid, style: &maps::Style| -> Result<()> {
        crate::io::geotiff::write_grid(&out_dir.join(format!("{stem}.tif")), grid)?;
        maps::render(&out_dir.join(format!("{stem}.png")), grid, style, Some(&dem), &overlays)?;
        outputs.extend([format!("{stem}.tif"), format!("{stem}.png")]);
        if ascii {
            outputs.extend(crate::io::ascii_grid::write_grid_in(out_dir, &stem, grid)?);
        }
        Ok(())
    };
    // Read back one raster of every model at a time: memory holds one raster per model, not six.
    let read = |stem: &str| {
        names
            .iter()
            .map(|name| {
                let mut g =
                    crate::io::geotiff::read_grid(&out_dir.join("models").join(name).join(format!("{stem}.tif")))?;
                g.crs = crs.clone();
                Ok(g)
            })
            .collect::<Result<Vec<Grid>>>()
    };
    let rocks: Vec<usize> = models.iter().map(|m| m.rocks).collect();
    // The reach rasters decide which cells are well sampled; read once, combined in turn below.
    let reach_grids = read("reach_probability")?;
    let sampled = well_sampled(&reach_grids, &rocks);
    let mut reach = Some(reach_grids);
    let mut rasters = Vec::new();
    for (stem, _) in RASTERS {
        let grids = match reach.take_if(|_| stem == "reach_probability") {
            Some(g) => g,
            None => read(stem)?,
        };
        let combined = combine(&grids, &names)?;
        let style = maps::raster_style(stem);
        // One colour bar for the three maps of a raster, so they compare by eye.
        let range = maps::log_range(&combined[2]);
        for (stat, grid) in STATISTICS.iter().zip(&combined) {
            let title = format!("{}: {stat} of {n} models", style.title);
            write(format!("{stem}_{stat}"), grid, &maps::Style { title, range, ..style.clone() })?;
        }
        if stem == "reach_probability" {
            let reaching = models_reaching(&grids);
            let style = maps::Style {
                title: format!("Models whose rocks reach the cell (of {n})"),
                unit: "models".into(),
                colormap: crate::render::Colormap::Viridis,
                scale: crate::render::ValueScale::Linear,
                classes: None,
                range: Some((0.0, n as f32)),
            };
            write(REACHING.to_string(), &reaching, &style)?;
        }
        rasters.push(spread(stem, &grids, &combined, &sampled));
    }
    let levels = read(ZONES)?;
    let [lowest, _, highest] = combine(&levels, &names)?;
    let style = crate::report::zone_style(members[0].scenario);
    for (stat, grid, which) in [("min", &lowest, "lowest"), ("max", &highest, "highest")] {
        let title = format!("{} ({which} level of {n} models)", style.title);
        write(format!("{ZONES}_{stat}"), grid, &maps::Style { title, ..style.clone() })?;
    }
    outputs.extend(["envelope.json".to_string(), "envelope.md".to_string()]);
    Ok(EnvelopeSummary {
        talus_version: env!("CARGO_PKG_VERSION").to_string(),
        collectors: collector_spread(&models),
        models,
        rasters,
        zones: zone_spread(&levels, &sampled),
        floor: None,
        wall_time_s: t0.elapsed().as_secs_f64(),
        outputs,
    })
}

/// Writes `dir/envelope.json` and `dir/envelope.md`; `members` says what was run.
fn write_summary(dir: &Path, summary: &EnvelopeSummary, members: &str) -> Result<()> {
    crate::io::write_json_atomic(&dir.join("envelope.json"), summary)?;
    crate::io::write_bytes_atomic(&dir.join("envelope.md"), markdown(summary, members).as_bytes())
}

/// A calibrated model carried to another site: `site` with the materials and engine settings (`[simulation]`, its
/// effects included) of `model`, keeping the site's seed, rock count and threads. Ours. What a model ties to its
/// own terrain (a zone the loop found, drawn with the terrain's material polygons) does not carry over: the site's
/// terrain and zoning are used, so every material the site names must be one of the model's (`model_name` says
/// which model in the error).
pub fn on_site(site: &ScenarioFile, model: &ScenarioFile, model_name: &str) -> Result<ScenarioFile> {
    let missing: Vec<&str> =
        site.materials.keys().filter(|m| !model.materials.contains_key(*m)).map(String::as_str).collect();
    if !missing.is_empty() {
        return Err(Error::invalid(
            format!("{model_name}: materials"),
            format!(
                "the site uses {} that the model does not define (it has {})",
                missing.join(", "),
                model.materials.keys().cloned().collect::<Vec<_>>().join(", ")
            ),
            "name the site's materials as the model's (a model calibrated with one material calls it `default`: \
             use materials_by = \"single\" and [materials.default] at the site)",
        ));
    }
    let mut s = site.clone();
    s.title = format!("{} on {}", model.title, site.title);
    s.materials = model.materials.clone();
    s.simulation.params = model.simulation.params.clone();
    Ok(s)
}

/// Model names: the scenario files' stems, else (when those repeat, as `fold_*/calibrated.toml` do) their
/// folders' names, else the last two or three folders' (`repeat_2_fold_1`), else `model_1`, `model_2`, ...
pub fn model_names(paths: &[&Path]) -> Vec<String> {
    let unique = |names: &[String]| {
        let mut sorted = names.to_vec();
        sorted.sort();
        sorted.dedup();
        sorted.len() == names.len() && names.iter().all(|n| !n.is_empty())
    };
    let stems: Vec<String> =
        paths.iter().map(|p| p.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()).collect();
    if unique(&stems) {
        return stems;
    }
    for depth in 1..=3 {
        let folders: Vec<String> = paths
            .iter()
            .map(|path| {
                let parts: Vec<String> = path
                    .parent()
                    .map(|p| {
                        // Folder names only: never a root or `..`, which would put a model's run outside `models/`.
                        p.components()
                            .filter_map(|c| match c {
                                std::path::Component::Normal(n) => Some(n.to_string_lossy().into_owned()),
                                _ => None,
                            })
                            .collect()
                    })
                    .unwrap_or_default();
                parts[parts.len().saturating_sub(depth)..].join("_")
            })
            .collect();
        if unique(&folders) {
            return folders;
        }
    }
    (1..=paths.len()).map(|i| format!("model_{i}")).collect()
}

/// Rocks that must pass a cell in every run for the cell to count in a [`RasterSpread`] (ours: the 95th
/// percentile of 30 values lies between the two largest; in cells that fewer rocks reach, the statistics are a
/// handful of rocks and their spread is mostly which rocks those were).
pub const WELL_SAMPLED_ROCKS: f64 = 30.0;

/// The cells that at least [`WELL_SAMPLED_ROCKS`] rocks reach in every run, from the runs' `reach_probability`
/// rasters and rock counts.
pub fn well_sampled(reach: &[Grid], rocks: &[usize]) -> Vec<bool> {
    (0..reach[0].values.len())
        .map(|k| reach.iter().zip(rocks).all(|(g, &n)| g.values[k] as f64 * n as f64 >= WELL_SAMPLED_ROCKS - 1e-3))
        .collect()
}

/// The spread of one raster between the models, over the `sampled` cells where every model has a positive value.
fn spread(stem: &str, grids: &[Grid], combined: &[Grid; 3], sampled: &[bool]) -> RasterSpread {
    let [min, median, max] = combined;
    let mut relative: Vec<f64> = (0..min.values.len())
        .filter(|&k| sampled[k] && grids.iter().all(|g| g.values[k] > 0.0))
        .map(|k| (max.values[k] - min.values[k]) as f64 / median.values[k] as f64)
        .collect();
    relative.sort_by(f64::total_cmp);
    let quantile = |q| (!relative.is_empty()).then(|| quantile_sorted(&relative, q));
    let highest = |g: &Grid| g.min_max().map(|(_, hi)| hi as f64);
    RasterSpread {
        raster: stem.to_string(),
        cells: relative.len(),
        relative_spread_p50: quantile(0.5),
        relative_spread_p95: quantile(0.95),
        highest_min: highest(min),
        highest_median: highest(median),
        highest_max: highest(max),
    }
}

/// The hazard zones' section of `envelope.md`.
fn zones_markdown(s: &EnvelopeSummary) -> String {
    let ha = |x: &Spread3, all: bool| {
        let v = if all { vec![x.min, x.median, x.max] } else { vec![x.min, x.max] };
        v.into_iter().map(|v| fmt_opt(v.map(|m2| m2 / 1e4), 2)).collect::<Vec<_>>().join(if all {
            " / "
        } else {
            " – "
        })
    };
    let share = |differing: usize, zoned: usize| {
        let pct = fmt_opt((zoned > 0).then(|| 100.0 * differing as f64 / zoned as f64), 1);
        format!("{differing} of {zoned} ({pct} %)")
    };
    let rows = |z: &ZoneSpread, all: bool| {
        [
            ha(&z.low_m2, all),
            ha(&z.medium_m2, all),
            ha(&z.high_m2, all),
            share(z.cells_differing, z.cells_zoned),
            share(z.well_sampled_differing, z.well_sampled_zoned),
        ]
    };
    let labels: [&str; 5] = [
        "low (yellow) zone, ha",
        "medium (blue) zone, ha",
        "high (red) zone, ha",
        "zoned cells whose level differs",
        &format!("… of those at least {WELL_SAMPLED_ROCKS} rocks of every run reach"),
    ];
    let mut md = String::from(
        "\n## Hazard zones\n\nEach run's `hazard_zones.tif` (its `[hazard_zones]` settings) compared cell by cell: \
         each zone's area over the runs, and the zoned cells (level 1 or more in some run) whose level is not the \
         same in every run. `hazard_zones_max` is the highest level any run gives a cell (the zoning that holds \
         under every run), `hazard_zones_min` the lowest.\n\n",
    );
    let ours = rows(&s.zones, true);
    match &s.floor {
        Some(f) => {
            md += "| | runs: lowest / median / highest | seeds alone: lowest – highest |\n|---|---|---|\n";
            for ((label, a), b) in labels.iter().zip(&ours).zip(rows(&f.zones, false)) {
                md += &format!("| {label} | {a} | {b} |\n");
            }
        }
        None => {
            md += "| | runs: lowest / median / highest |\n|---|---|\n";
            for (label, a) in labels.iter().zip(&ours) {
                md += &format!("| {label} | {a} |\n");
            }
        }
    }
    md
}

/// `envelope.md`; `members` says what was run.
fn markdown(s: &EnvelopeSummary, members: &str) -> String {
    let n = s.models.len();
    let opt = |v: Option<f64>| fmt_opt(v, 3);
    let mut md = format!(
        "# Envelope over {n} runs\n\nThe runs: {members}. Each raster of `talus run` is combined cell by cell: \
         `_min`, `_median` and `_max` over the runs with a value in the cell (the energy and height rasters have \
         none where no rock of the run passed); `{REACHING}` counts the runs whose rocks reach the cell. Each run \
         is in `models/NAME/`.\n\n## Runs\n\n\
         | run | scenario | seed | rocks | run-out P50 (m) | run-out P95 (m) | largest energy P95 (kJ) | largest \
         bounce P50 (m) | largest bounce P95 (m) |\n|---|---|---:|---:|---:|---:|---:|---:|---:|\n"
    );
    for m in &s.models {
        md += &format!(
            "| {} | `{}` | {} | {} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} |\n",
            m.name,
            m.scenario,
            m.seed,
            m.rocks,
            m.runout_m.p50,
            m.runout_m.p95,
            m.max_kinetic_kj.p95,
            m.max_bounce_m.p50,
            m.max_bounce_m.p95
        );
    }
    md += &format!(
        "\n## How far each raster moves between the runs\n\nOver the cells that at least {WELL_SAMPLED_ROCKS} \
         rocks reach in every run and where every run has a positive value: the relative spread (max − min) / \
         median of the runs' values, its median and 95th percentile over those cells; then each combined raster's \
         largest value (over all cells)."
    );
    if s.floor.is_some() {
        md += " The floor columns give the same spread between runs of the first model with other seeds \
               (`floor/envelope.md`): what the random draws alone move at this number of rocks. A spread near its \
               floor is noise, not a difference between the models.";
    }
    md += "\n\n| raster | cells | spread P50 | spread P95 | highest min | highest median | highest max |";
    let floors: Vec<Option<&RasterSpread>> = match &s.floor {
        Some(f) => {
            md += " floor P50 | floor P95 |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
            s.rasters.iter().map(|r| f.rasters.iter().find(|x| x.raster == r.raster)).collect()
        }
        None => {
            md += "\n|---|---:|---:|---:|---:|---:|---:|\n";
            vec![None; s.rasters.len()]
        }
    };
    for (r, floor) in s.rasters.iter().zip(floors) {
        md += &format!(
            "| {} | {} | {} | {} | {} | {} | {} |",
            r.raster,
            r.cells,
            opt(r.relative_spread_p50),
            opt(r.relative_spread_p95),
            opt(r.highest_min),
            opt(r.highest_median),
            opt(r.highest_max)
        );
        if let Some(f) = floor {
            md += &format!(" {} | {} |", opt(f.relative_spread_p50), opt(f.relative_spread_p95));
        }
        md += "\n";
    }
    md += &zones_markdown(s);
    if !s.collectors.is_empty() {
        md += "\n## Collector lines\n\nEach line's figures over the runs, lowest / median / highest (the \
               scenarios' `[[collectors]]` of the same name in every run).";
        if s.floor.is_some() {
            md += " Beside them, the lowest and highest between seeds of the first model.";
        }
        md += "\n\n| collector | fraction crossing | kinetic energy P95 (kJ) | passing height P95 (m) |";
        md += if s.floor.is_some() {
            " seeds alone: fraction | energy | height |\n|---|---|---|---|---|---|---|\n"
        } else {
            "\n|---|---|---|---|\n"
        };
        for c in &s.collectors {
            let three = |x: &Spread3, digits: usize| [x.min, x.median, x.max].map(|v| fmt_opt(v, digits)).join(" / ");
            md += &format!(
                "| {} | {} | {} | {} |",
                c.name,
                three(&c.fraction_crossing, 3),
                three(&c.kinetic_kj_p95, 1),
                three(&c.passing_height_m_p95, 2)
            );
            if let Some(f) = s.floor.as_ref().and_then(|f| f.collectors.iter().find(|x| x.name == c.name)) {
                let two = |x: &Spread3, digits: usize| [x.min, x.max].map(|v| fmt_opt(v, digits)).join(" – ");
                md += &format!(
                    " {} | {} | {} |",
                    two(&f.fraction_crossing, 3),
                    two(&f.kinetic_kj_p95, 1),
                    two(&f.passing_height_m_p95, 2)
                );
            }
            md += "\n";
        }
    }
    md += &format!(
        "\n## Maps\n\n![runs reaching]({REACHING}.png)\n\n### {ZONES} (lowest and highest level)\n\n\
         ![{ZONES} min]({ZONES}_min.png)\n![{ZONES} max]({ZONES}_max.png)\n"
    );
    for (stem, description) in RASTERS {
        md += &format!("\n### {stem} ({description})\n\n");
        for stat in STATISTICS {
            md += &format!("![{stem} {stat}]({stem}_{stat}.png)\n");
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(values: &[f32]) -> Grid {
        let mut g = Grid::filled(values.len(), 1, 0.0, 1.0, 1.0, 0.0);
        g.values = values.to_vec();
        g
    }

    #[test]
    fn zones_compare_cell_by_cell_and_sum_areas() {
        let nan = f32::NAN;
        // Cells: outside, never zoned, the same level, levels differing (twice, one well sampled).
        let a = grid(&[nan, 0.0, 2.0, 1.0, 3.0, 0.0]);
        let b = grid(&[nan, 0.0, 2.0, 2.0, 3.0, 1.0]);
        let z = zone_spread(&[a, b], &[true, true, true, true, false, false]);
        assert_eq!((z.cells_zoned, z.cells_differing), (4, 2));
        assert_eq!((z.well_sampled_zoned, z.well_sampled_differing), (2, 1));
        // Cells of 1 m²: a has one low, one medium, one high; b one low, two medium, one high.
        assert_eq!((z.low_m2.min, z.low_m2.max), (Some(1.0), Some(1.0)));
        assert_eq!((z.medium_m2.min, z.medium_m2.max), (Some(1.0), Some(2.0)));
        assert_eq!((z.high_m2.min, z.high_m2.max), (Some(1.0), Some(1.0)));
    }

    #[test]
    fn the_envelope_takes_each_cell_over_the_models_with_a_value_there() {
        let nan = f32::NAN;
        let grids = [grid(&[1.0, nan, 4.0, nan]), grid(&[3.0, 2.0, 0.0, nan]), grid(&[2.0, nan, 8.0, nan])];
        let names: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        let [min, median, max] = combine(&grids, &names).unwrap();
        assert_eq!(&min.values[..3], &[1.0, 2.0, 0.0]);
        assert_eq!(&median.values[..3], &[2.0, 2.0, 4.0]);
        assert_eq!(&max.values[..3], &[3.0, 2.0, 8.0]);
        assert!(min.values[3].is_nan() && median.values[3].is_nan() && max.values[3].is_nan());
        let reaching = models_reaching(&grids);
        assert_eq!(&reaching.values[..3], &[3.0, 1.0, 2.0]);
        assert!(reaching.values[3].is_nan(), "outside the terrain stays nodata");
        let sampled = well_sampled(&grids, &[20, 10, 30]);
        assert_eq!(sampled, [false, false, false, false], "cell 0: 1 x 20 rocks is 20, under 30");
        assert_eq!(well_sampled(&grids, &[30, 30, 30]), [true, false, false, false]);
        // Only the first cell has a positive value in every model: (3 - 1) / 2.
        let s = spread("x", &grids, &[min, median, max], &[true; 4]);
        assert_eq!((s.cells, s.relative_spread_p50), (1, Some(1.0)));
        assert_eq!((s.highest_min, s.highest_median, s.highest_max), (Some(2.0), Some(4.0), Some(8.0)));
    }

    #[test]
    fn a_figure_spreads_over_the_runs_that_have_it() {
        let s = Spread3::of([Some(3.0), None, Some(1.0), Some(f64::NAN), Some(2.0)]);
        assert_eq!((s.min, s.median, s.max), (Some(1.0), Some(2.0), Some(3.0)));
        assert_eq!(Spread3::of([None, None]), Spread3::default());
    }

    #[test]
    fn models_on_different_frames_are_refused_with_both_names() {
        let a = grid(&[1.0, 2.0]);
        let mut b = a.clone();
        b.cell_x_m = 2.0;
        let err = combine(&[a, b], &["fold_1".into(), "fold_2".into()]).unwrap_err().to_string();
        assert!(err.contains("fold_2: rasters") && err.contains("fold_1's") && err.contains("cell_size_m"), "{err}");
    }
}
