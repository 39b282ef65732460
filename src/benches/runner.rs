//! Running a study: every model × configuration × repeat × rock, in parallel, deterministically.
//!
//! Rock i of repeat r draws from the stream `(seed + r, i)` whatever the configuration and the number of threads
//! ([`crate::parallel::map_in_order`]), so results are identical for any thread count.
//!
//! # How a rock is counted (ours, following [`BenchGeometry::bench_at`])
//! Bench k (1 = first below the release) holds the rocks whose centre of mass ends between the middle of face k
//! and the middle of face k + 1: resting against the toe of face k, on the catch bench, or hung on its outer edge
//! (the upper half of face k + 1). Bench 0 holds the rocks that end past the last catch bench, including those
//! that leave the terrain beyond the toe floor. A 3DRB rock that leaves the stack by a side (it has a finite
//! width) after passing bench 1 counts on the bench it left over (smarties rolling like wheels along a bench
//! floor): it was not caught by the benches above. Two outcomes are not counted in the fractions, and are
//! reported instead:
//! - `left`: the rock left the terrain by the back, or by a side before passing bench 1; whether bench 1 would
//!   have caught it on a wider stack is unknown.
//! - `crest`: the rock ended before the middle of face 1: on the crest floor, or hung on the crest edge of the
//!   top face (a large 3DRB block resting across the edge): it never went down the slope.

use super::config::{ResolvedMaterials, StudyConfig};
use super::release::{draw_release, mass_index, shape_index};
use crate::error::Result;
use crate::lumped2d::{simulate_rock, Options2d, Profile, RockStart2d, Slope2d, StopReason as Stop2d};
use crate::parallel::map_in_order;
use crate::random::stream;
use crate::rock::{random_orientation, RockBody, RockSize};
use crate::sim::{simulate, RigidState, SimParams, StopReason as Stop3d};
use crate::source::place_above_ground;
use crate::terrain::{BenchGeometry, Terrain};
use nalgebra::Vector3;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

/// A rockfall model of the study.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub enum Model {
    /// 2D lumped mass (RocFall semantics, [`crate::lumped2d`]).
    #[serde(rename = "2DLM")]
    Lumped2d,
    /// 3D rigid body ([`crate::sim`]).
    #[serde(rename = "3DRB")]
    Rigid3d,
}

impl Model {
    /// Both models, in output order.
    pub const ALL: [Model; 2] = [Model::Lumped2d, Model::Rigid3d];

    /// `2DLM` or `3DRB`, as written in outputs.
    pub fn label(self) -> &'static str {
        match self {
            Model::Lumped2d => "2DLM",
            Model::Rigid3d => "3DRB",
        }
    }
}

/// One bench configuration of the study.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Configuration {
    /// Face angle, degrees.
    pub face_angle_deg: f64,
    /// Catch-bench width, m.
    pub bench_width_m: f64,
}

/// Where a rock ended, as the study counts it (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RockClass {
    /// On bench k (1..=n_benches), or 0: past the last bench.
    Bench(usize),
    /// Left the terrain by the back, or by a side before passing bench 1: not counted.
    Left,
    /// Ended before the middle of the first face (on the crest floor or hung on its edge): not counted.
    Crest,
}

/// One simulated rock (a row of `rocks.csv`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RockRow {
    /// The model.
    pub model: Model,
    /// Index into [`StudyResult::configurations`].
    pub config: usize,
    /// Repeat (0-based).
    pub repeat: usize,
    /// Run index within the configuration.
    pub rock: usize,
    /// Shape index into the study's 3DRB shapes (`None` for the 2DLM point mass).
    pub shape: Option<usize>,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Release speed, m/s.
    pub speed_mps: f64,
    /// End x (downslope, from the back of the crest floor), m.
    pub end_x_m: f64,
    /// End y (across the stack), m; 2DLM has none.
    pub end_y_m: Option<f64>,
    /// The engine's stop reason.
    pub stop_reason: &'static str,
    /// How the study counts it.
    pub class: RockClass,
}

/// Counts of one model, configuration and repeat.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// The model.
    pub model: Model,
    /// Index into [`StudyResult::configurations`].
    pub config: usize,
    /// Repeat (0-based).
    pub repeat: usize,
    /// Seed of the repeat.
    pub seed: u64,
    /// `per_bench[k]`: rocks on bench k (1..=n_benches); `per_bench[0]`: past the last bench.
    pub per_bench: Vec<usize>,
    /// Rocks that left the terrain by the back, or by a side before passing bench 1 (not counted in `per_bench`).
    pub left: usize,
    /// Rocks that ended before the middle of the first face: on the crest floor or hung on its edge (not counted in
    /// `per_bench`).
    pub crest: usize,
    /// Rocks by engine stop reason.
    pub stop_reasons: BTreeMap<&'static str, usize>,
}

impl Cell {
    /// Rocks counted in `per_bench`.
    pub fn counted(&self) -> usize {
        self.per_bench.iter().sum()
    }

    /// Fraction of the counted rocks on bench `k` (0 = past the last bench); `None` when none was counted.
    pub fn fraction(&self, k: usize) -> Option<f64> {
        let n = self.counted();
        (n > 0).then(|| self.per_bench.get(k).copied().unwrap_or(0) as f64 / n as f64)
    }
}

/// Wall time of one model over the whole study.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ModelTiming {
    /// The model.
    pub model: Model,
    /// Rocks simulated.
    pub rocks: usize,
    /// Wall time, s (setup, simulation and counting).
    pub wall_time_s: f64,
    /// Rocks per second of wall time.
    pub rocks_per_second: f64,
}

/// Everything a study produced; [`super::write_outputs`] turns it into files.
#[derive(Debug, Clone)]
pub struct StudyResult {
    /// The settings as used.
    pub config: StudyConfig,
    /// Configurations, face angles outer, widths inner, both ascending.
    pub configurations: Vec<Configuration>,
    /// Counts, by model, then repeat, then configuration.
    pub cells: Vec<Cell>,
    /// Every rock, in the order of `cells`, then by rock index.
    pub rocks: Vec<RockRow>,
    /// Wall time per model that ran.
    pub timings: Vec<ModelTiming>,
    /// Threads used.
    pub threads: usize,
}

impl StudyResult {
    /// Number of rocks per configuration and repeat of `model` (0 if it did not run): for 2DLM, `runs` per mass.
    pub fn runs(&self, model: Model) -> usize {
        self.config.rocks_per_configuration(model)
    }

    /// The models that ran.
    pub fn models(&self) -> Vec<Model> {
        Model::ALL.into_iter().filter(|&m| self.runs(m) > 0).collect()
    }

    /// The cells of `model` and configuration `config`, one per repeat.
    pub fn cells_of(&self, model: Model, config: usize) -> impl Iterator<Item = &Cell> {
        self.cells.iter().filter(move |c| c.model == model && c.config == config)
    }

    /// Counts of `model` and `config` pooled over the repeats: rocks per bench (0 = past the last) and counted
    /// rocks.
    pub fn pooled(&self, model: Model, config: usize) -> (Vec<usize>, usize) {
        let mut per_bench = vec![0; self.config.n_benches + 1];
        for c in self.cells_of(model, config) {
            for (k, n) in c.per_bench.iter().enumerate() {
                per_bench[k] += n;
            }
        }
        let n = per_bench.iter().sum();
        (per_bench, n)
    }

    /// Name of the shape of a rock row (`point` for 2DLM).
    pub fn shape_name(&self, row: &RockRow) -> &str {
        row.shape.and_then(|s| self.config.rigid3d.shapes.get(s)).map_or("point", String::as_str)
    }
}

/// Progress callback: model, rocks done, rocks in total for that model.
pub type Progress<'a> = &'a dyn Fn(Model, usize, usize);

/// Runs the study: checks the settings, then simulates every model that has runs.
///
/// # Errors
/// Invalid settings (naming the key) and geometry errors.
///
/// # Examples
/// ```
/// use talus::benches::{run_study, Model, StudyConfig};
/// let mut c = StudyConfig::default();
/// c.face_angles_deg = vec![75.0];
/// c.bench_widths_m = vec![4.0, 10.0];
/// c.lumped2d.runs = 40;
/// c.rigid3d.runs = 0;
/// let r = run_study(&c, &|_, _, _| {}).unwrap();
/// let (narrow, n) = r.pooled(Model::Lumped2d, 0);
/// let (wide, _) = r.pooled(Model::Lumped2d, 1);
/// assert_eq!(n, 120); // 40 per mass, 3 masses
/// assert!(wide[1] >= narrow[1]);
/// ```
pub fn run_study(config: &StudyConfig, progress: Progress) -> Result<StudyResult> {
    let resolved = config.validate()?;
    let mut angles = config.face_angles_deg.clone();
    angles.sort_by(f64::total_cmp);
    let mut widths = config.bench_widths_m.clone();
    widths.sort_by(f64::total_cmp);
    let configurations: Vec<Configuration> = angles
        .iter()
        .flat_map(|&a| widths.iter().map(move |&w| Configuration { face_angle_deg: a, bench_width_m: w }))
        .collect();
    let geometries: Vec<BenchGeometry> =
        configurations.iter().map(|c| config.geometry(c.face_angle_deg, c.bench_width_m)).collect();
    for g in &geometries {
        g.validate("")?;
    }
    let mut result = StudyResult {
        config: config.clone(),
        configurations,
        cells: Vec::new(),
        rocks: Vec::new(),
        timings: Vec::new(),
        threads: crate::parallel::threads_used(config.threads),
    };
    if config.lumped2d.runs > 0 {
        let t0 = Instant::now();
        let ctx = Lumped2dCtx::new(config, &resolved, &geometries)?;
        let runs = config.rocks_per_configuration(Model::Lumped2d);
        let n = run_model(&mut result, Model::Lumped2d, runs, &geometries, progress, |c, seed, i| {
            ctx.run(&geometries[c], c, seed, i)
        });
        result.timings.push(timing(Model::Lumped2d, n, t0));
    }
    if config.rigid3d.runs > 0 {
        let t0 = Instant::now();
        let ctx = Rigid3dCtx::new(config, &resolved, &geometries)?;
        let n = run_model(&mut result, Model::Rigid3d, config.rigid3d.runs, &geometries, progress, |c, seed, i| {
            ctx.run(&geometries[c], c, seed, i)
        });
        result.timings.push(timing(Model::Rigid3d, n, t0));
    }
    Ok(result)
}

fn timing(model: Model, rocks: usize, t0: Instant) -> ModelTiming {
    let wall = t0.elapsed().as_secs_f64();
    ModelTiming { model, rocks, wall_time_s: wall, rocks_per_second: rocks as f64 / wall.max(1e-12) }
}

/// Runs every repeat × configuration × rock of one model and appends the cells and rocks; returns the number of
/// rocks.
fn run_model(
    result: &mut StudyResult,
    model: Model,
    runs: usize,
    geometries: &[BenchGeometry],
    progress: Progress,
    rock: impl Fn(usize, u64, usize) -> RockRow + Sync + Send,
) -> usize {
    let (n_configs, repeats, n_benches) = (geometries.len(), result.config.repeats, result.config.n_benches);
    let (seed, threads) = (result.config.seed, result.config.threads);
    let seed_of = |r: usize| seed.wrapping_add(r as u64);
    let first_cell = result.cells.len();
    for r in 0..repeats {
        for c in 0..n_configs {
            result.cells.push(Cell {
                model,
                config: c,
                repeat: r,
                seed: seed_of(r),
                per_bench: vec![0; n_benches + 1],
                left: 0,
                crest: 0,
                stop_reasons: BTreeMap::new(),
            });
        }
    }
    let total = repeats * n_configs * runs;
    // 2DLM rocks take microseconds, 3DRB rocks milliseconds: smaller chunks keep both threads busy.
    let chunk = if model == Model::Lumped2d { 4096 } else { 128 };
    let (cells, rocks) = (&mut result.cells, &mut result.rocks);
    rocks.reserve(total);
    map_in_order(
        total,
        threads,
        chunk,
        |j| {
            let (r, rest) = (j / (n_configs * runs), j % (n_configs * runs));
            let (c, i) = (rest / runs, rest % runs);
            let mut row = rock(c, seed_of(r), i);
            row.repeat = r;
            row
        },
        |j, row| {
            let cell = &mut cells[first_cell + j / runs];
            match row.class {
                RockClass::Bench(k) => cell.per_bench[k] += 1,
                RockClass::Left => cell.left += 1,
                RockClass::Crest => cell.crest += 1,
            }
            *cell.stop_reasons.entry(row.stop_reason).or_insert(0) += 1;
            rocks.push(row);
            progress(model, j + 1, total);
        },
    );
    total
}

/// Counts a rock by its end x; `left_terrain` when the engine stopped it for leaving the terrain.
fn classify(g: &BenchGeometry, end_x_m: f64, left_terrain: bool) -> RockClass {
    let (crest, toe) = g.face_span_m(1);
    let down_the_slope = end_x_m >= 0.5 * (crest + toe);
    match (left_terrain, down_the_slope, g.bench_at(end_x_m)) {
        // Left past bench 1 (past the last bench, or by a side over bench k): the benches above did not catch it.
        (true, true, k) if k != 1 => RockClass::Bench(k),
        (true, _, _) => RockClass::Left,
        (false, false, _) => RockClass::Crest,
        (false, true, k) => RockClass::Bench(k),
    }
}

struct Lumped2dCtx {
    slopes: Vec<Slope2d>,
    options: Options2d,
    masses_kg: Vec<f64>,
    release: super::config::ReleaseSpec,
}

impl Lumped2dCtx {
    fn new(config: &StudyConfig, m: &ResolvedMaterials, geometries: &[BenchGeometry]) -> Result<Lumped2dCtx> {
        let mut slopes = Vec::with_capacity(geometries.len());
        for g in geometries {
            slopes.push(Slope2d::new(Profile::from_bench(g)?, vec![m.face_2d, m.floor_2d])?);
        }
        Ok(Lumped2dCtx {
            slopes,
            options: config.lumped2d.options.clone(),
            masses_kg: config.masses_kg.clone(),
            release: config.release.clone(),
        })
    }

    fn run(&self, g: &BenchGeometry, c: usize, seed: u64, i: usize) -> RockRow {
        let mut rng = stream(seed, i as u64);
        let rel = &self.release;
        let start = draw_release(g.crest_floor_m, rel.setback_m, rel.clearance_m, rel.speed_mps, &mut rng);
        // Rock i has mass i mod M: exactly `runs` rocks per mass.
        let mass = self.masses_kg[i % self.masses_kg.len()];
        let rock = RockStart2d {
            x_m: start.x_m,
            z_m: g.total_height_m() + start.clearance_m,
            vx_mps: start.speed_mps,
            vz_mps: 0.0,
            spin_radps: 0.0,
            mass_kg: mass,
        };
        let r = simulate_rock(&self.slopes[c], &rock, &self.options, &mut rng, &mut ());
        let class = classify(g, r.end_x_m, r.stop_reason == Stop2d::LeftProfile);
        RockRow {
            model: Model::Lumped2d,
            config: c,
            repeat: 0,
            rock: i,
            shape: None,
            mass_kg: mass,
            speed_mps: start.speed_mps,
            end_x_m: r.end_x_m,
            end_y_m: None,
            stop_reason: r.stop_reason.as_str(),
            class,
        }
    }
}

struct Rigid3dCtx {
    terrains: Vec<Terrain>,
    /// Bodies by shape (outer) and mass (inner).
    bodies: Vec<RockBody>,
    params: SimParams,
    masses_kg: Vec<f64>,
    n_masses: usize,
    n_shapes: usize,
    release: super::config::ReleaseSpec,
}

impl Rigid3dCtx {
    fn new(config: &StudyConfig, m: &ResolvedMaterials, geometries: &[BenchGeometry]) -> Result<Rigid3dCtx> {
        let mut terrains = Vec::with_capacity(geometries.len());
        for g in geometries {
            let mesh = g.mesh();
            let vertices = mesh.vertices.iter().map(|v| Vector3::new(v[0], v[1], v[2])).collect();
            // Mesh groups: 0 = face, 1 = floor.
            let materials: Vec<u16> = mesh.group.iter().map(|&k| k as u16).collect();
            terrains.push(Terrain::from_local(
                vertices,
                &mesh.triangles,
                &materials,
                vec![m.face_3d.clone(), m.floor_3d.clone()],
            )?);
        }
        let mut bodies = Vec::new();
        for shape in &m.shapes {
            for &mass_kg in &config.masses_kg {
                let size = RockSize::Mass { mass_kg, density_kg_m3: config.rigid3d.density_kg_m3 };
                bodies.push(RockBody::new(shape, size, "rigid3d.shapes")?);
            }
        }
        Ok(Rigid3dCtx {
            terrains,
            bodies,
            params: config.rigid3d.simulation.clone(),
            masses_kg: config.masses_kg.clone(),
            n_masses: config.masses_kg.len(),
            n_shapes: m.shapes.len(),
            release: config.release.clone(),
        })
    }

    fn run(&self, g: &BenchGeometry, c: usize, seed: u64, i: usize) -> RockRow {
        let terrain = &self.terrains[c];
        let mut rng = stream(seed, i as u64);
        let rel = &self.release;
        let start = draw_release(g.crest_floor_m, rel.setback_m, rel.clearance_m, rel.speed_mps, &mut rng);
        let (si, mi) = (shape_index(i, self.n_shapes), mass_index(i, self.n_shapes, self.n_masses));
        let body = &self.bodies[si * self.n_masses + mi];
        let orientation = random_orientation(&mut rng);
        let mut state = RigidState {
            position_m: Vector3::new(start.x_m, 0.5 * g.lateral_width_m, g.total_height_m()),
            velocity_mps: Vector3::new(start.speed_mps, 0.0, 0.0),
            orientation,
            omega_body_radps: Vector3::zeros(),
        };
        place_above_ground(terrain, body, &mut state, start.clearance_m, self.params.terrain_edge_contacts);
        let out = simulate(terrain, body, state, &self.params, &mut rng, &mut ());
        let p = out.final_state.position_m;
        let class = classify(g, p.x, out.stop_reason == Stop3d::LeftTerrain);
        RockRow {
            model: Model::Rigid3d,
            config: c,
            repeat: 0,
            rock: i,
            shape: Some(si),
            mass_kg: self.masses_kg[mi],
            speed_mps: start.speed_mps,
            end_x_m: p.x,
            end_y_m: Some(p.y),
            stop_reason: out.stop_reason.as_str(),
            class,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rock_counts_where_it_rests_and_one_at_the_crest_or_lost_before_bench_1_does_not() {
        let g = BenchGeometry::default();
        let (crest, toe) = g.face_span_m(1);
        let (crest3, _) = g.face_span_m(3);
        // Hung across the top crest's edge (0.5 m past it, as 10 t blocks end): never went down.
        assert_eq!(classify(&g, crest + 0.5, false), RockClass::Crest);
        assert_eq!(classify(&g, crest - 2.0, false), RockClass::Crest);
        // Resting against the toe of face 1, on its catch bench, hung on its outer edge.
        assert_eq!(classify(&g, toe - 0.5, false), RockClass::Bench(1));
        assert_eq!(classify(&g, toe + 3.0, false), RockClass::Bench(1));
        assert_eq!(classify(&g, g.face_span_m(2).0 + 0.5, false), RockClass::Bench(1));
        // Left by a side over bench 3: the benches above did not catch it. Over bench 1, or by the back: unknown.
        assert_eq!(classify(&g, crest3 + 0.9 * g.face_run_m(), true), RockClass::Bench(3));
        assert_eq!(classify(&g, toe + 3.0, true), RockClass::Left);
        assert_eq!(classify(&g, crest - 2.0, true), RockClass::Left);
        assert_eq!(classify(&g, 1e4, true), RockClass::Bench(0));
    }
}
