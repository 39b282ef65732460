//! What calibration needs from an engine: simulate one observed run under a candidate model, from the run's own
//! release state, with a random stream fixed by (seed, run, repeat), and summarise the simulated path.
//!
//! **Common random numbers.** Repeat `k` of run `i` always draws from `stream(seed, i·2²⁴ + k)`, with `i` the run's
//! position in the campaign file. Every candidate parameter set therefore sees the same orientations and the same
//! standard-normal draws behind its restitution coefficients, so differences between candidates are differences of
//! the model, not of luck (physics.md §5), and a run gets the same streams in every split and fold.

use super::config::{CalibrationConfig, ModelKind};
use super::params::Candidate;
use super::runs::{FieldRun, ReleaseGroups, NOT_STARTED_M};
use super::stats::{median, quantile_sorted, sorted};
use crate::campaign::TrackPoint;
use crate::error::Result;
use crate::raster::Grid;
use std::ops::Range;
use std::path::Path;

/// What a simulated path looked like, for the residual diagnosis.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PathSummary {
    /// Mean slope of the ground under the path, weighted by horizontal distance, degrees.
    pub slope_mean_deg: f64,
    /// Share of the horizontal path over ground gentler than 30° (physics.md §4: where rolling resistance shows).
    pub gentle_fraction: f64,
    /// Slope of the ground under the rest point, degrees.
    pub end_slope_deg: f64,
    /// Mean normal approach speed of the impacts, m/s (0 without impacts).
    pub impact_speed_mean_mps: f64,
    /// Largest normal approach speed, m/s.
    pub impact_speed_max_mps: f64,
    /// Mean impact angle between the incoming velocity and the ground, degrees.
    pub impact_angle_mean_deg: f64,
    /// Number of impacts.
    pub impacts: u32,
    /// Rebound height of the centre of mass ([`super::rebound`]), m.
    pub rebound_height_m: f64,
    /// Share of the horizontal path over each material of the model (declared materials first, then zones).
    pub material_fraction: Vec<f64>,
    /// The tangential restitutions of the bounces read from the path as its run's track was
    /// ([`super::impacts::tangential_restitutions_as_tracked`]), for the bounce score ([`super::objective::bounce_crps`]); empty where
    /// the model does not read them (untracked runs, a 3DRB model not asked to: [`Model::reads_bounces`]).
    pub tangential_restitutions: Vec<f64>,
}

/// How a simulation ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimEnd {
    /// At rest.
    Rest,
    /// Left the terrain (3DRB: no surface under the centre) or either end of the profile (2DLM).
    LeftTerrain,
    /// Ran to `max_time_s` (or, in 2DLM, to the profile engine's event limit).
    Limit,
}

/// One simulation of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct Sim {
    /// Horizontal distance from release to rest (or to where the rock left the terrain), m.
    pub runout_m: f64,
    /// End position in the campaign's frame, m.
    pub rest_m: [f64; 3],
    /// How it ended.
    pub end: SimEnd,
    /// Path summary.
    pub summary: PathSummary,
    /// The horizontal path, thinned to about 1 m spacing, campaign frame (y = 0 on a profile).
    pub path: Vec<[f32; 2]>,
}

impl Sim {
    /// True if the simulated rock ended within [`NOT_STARTED_M`] of its release: it did not start.
    pub fn stalled(&self) -> bool {
        self.runout_m < NOT_STARTED_M
    }
}

/// All simulations of one run under one candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSims {
    /// Index of the run in the model's run list.
    pub run: usize,
    /// One per repeat.
    pub sims: Vec<Sim>,
}

/// How many of `sims` ended as `which` says, and how many there are.
pub fn count_ends(sims: &[RunSims], which: impl Fn(SimEnd) -> bool) -> (usize, usize) {
    let all = || sims.iter().flat_map(|r| &r.sims);
    (all().filter(|x| which(x.end)).count(), all().count())
}

/// How many of `sims` did not come to rest (left the terrain or ran to the time limit), and how many there are.
pub fn not_at_rest(sims: &[RunSims]) -> (usize, usize) {
    count_ends(sims, |e| e != SimEnd::Rest)
}

impl RunSims {
    /// The repeats in `range`, cut to the repeats there are.
    pub fn repeats_in(&self, range: std::ops::Range<usize>) -> &[Sim] {
        let n = self.sims.len();
        &self.sims[range.start.min(n)..range.end.min(n)]
    }

    /// The simulated run-outs.
    pub fn runouts(&self) -> Vec<f64> {
        self.sims.iter().map(|s| s.runout_m).collect()
    }

    /// Median simulated run-out.
    pub fn median_runout(&self) -> f64 {
        median(&self.runouts())
    }

    /// The simulated rebound heights ([`super::rebound`]; 0 where the model did not measure them), m.
    pub fn rebound_heights(&self) -> Vec<f64> {
        self.sims.iter().map(|s| s.summary.rebound_height_m).collect()
    }

    /// Quantile `p` of the simulated run-outs.
    pub fn runout_quantile(&self, p: f64) -> f64 {
        quantile_sorted(&sorted(&self.runouts()), p)
    }

    /// Coordinate-wise median of the simulated rest points (x, y), m (ours: simple and robust).
    pub fn median_rest_xy(&self) -> [f64; 2] {
        let xs: Vec<f64> = self.sims.iter().map(|s| s.rest_m[0]).collect();
        let ys: Vec<f64> = self.sims.iter().map(|s| s.rest_m[1]).collect();
        [median(&xs), median(&ys)]
    }

    /// Median over repeats of a path-summary value.
    pub fn median_of(&self, f: impl Fn(&Sim) -> f64) -> f64 {
        median(&self.sims.iter().map(f).collect::<Vec<_>>())
    }
}

/// Where maps of a model's residuals are drawn: the extent and cell size of the residual grid, and the terrain
/// to shade under it.
#[derive(Debug, Clone)]
pub struct MapFrame {
    /// Elevation grid for the hillshade (a DEM terrain), in the campaign frame.
    pub dem: Option<Grid>,
    /// Extent (x_min, y_min, x_max, y_max) in the campaign frame, m.
    pub extent_m: [f64; 4],
    /// Cell size of residual maps, m.
    pub cell_m: f64,
    /// True for a profile (maps are 1-D along x).
    pub profile: bool,
}

/// A model ready to simulate: a candidate applied to the engine's terrain or profile.
pub trait Prepared: Sync {
    /// Simulates repeat `repeat` of `run` with streams from `seed`.
    fn simulate(&self, run: &FieldRun, repeat: usize, seed: u64) -> Sim;
    /// The path of that simulation (time since release, centre of mass in the campaign's frame) as a tracking
    /// system records it (3DRB every millisecond, 2DLM as its recorder samples); empty where the model records none.
    fn path(&self, _run: &FieldRun, _repeat: usize, _seed: u64) -> Vec<TrackPoint> {
        Vec::new()
    }
}

/// How a model releases its simulated rocks and reads them as the field measured them: the settings both engines'
/// bindings share.
#[derive(Debug, Clone, PartialEq)]
pub struct Reading {
    /// Releases of a simulated rock, at most ([`super::config::CalibrationConfig::release_attempts`]; 1 by default).
    pub release_attempts: usize,
    /// Measure each simulated path's rebound height (only a tracked run needs it; by default: if a run has one; it
    /// makes a 2DLM simulation about a third slower).
    pub rebounds: bool,
    /// Read the bounces of each simulated path of a run whose track shows bounces with a tangential restitution,
    /// for the bounce score (off by default; a campaign read from files turns it on in 2DLM unless the settings give
    /// `bounce_weight = 0`, in 3DRB only where they give a positive `bounce_weight`, since it records every such
    /// simulation's path every millisecond).
    pub bounce_reads: bool,
    /// The tracking error's sd, m, when simulated paths are read as the tracks were (`track_noise_m`).
    pub track_noise_m: Option<f64>,
    /// The survey's error on each rest point coordinate, sd in m (`rest_noise_m`).
    pub rest_noise_m: Option<f64>,
}

impl Reading {
    /// The defaults for `runs`: one release, rebound heights measured where a run has an observed one.
    pub fn for_runs(runs: &[FieldRun]) -> Reading {
        Reading {
            release_attempts: 1,
            rebounds: runs.iter().any(|r| r.rebound_height_m.is_some()),
            bounce_reads: false,
            track_noise_m: None,
            rest_noise_m: None,
        }
    }
}

/// An engine bound to a campaign.
pub trait Model: Sync {
    /// Which engine.
    fn kind(&self) -> ModelKind;
    /// The observed runs.
    fn runs(&self) -> &[FieldRun];
    /// The release groups (names indexed by [`FieldRun::group`]).
    fn groups(&self) -> &ReleaseGroups;
    /// The declared materials.
    fn materials(&self) -> &[String];
    /// Height of a run's release point above the ground under it, m.
    fn release_height_m(&self, run: &FieldRun) -> f64;
    /// The material covering most of `region`, for a new zone's starting values.
    fn dominant_material(&self, region: &super::params::Region) -> String;
    /// Where residual maps go.
    fn map_frame(&self) -> MapFrame;
    /// True if the settings' `[terrain] level_beyond` shapes this model's ground (a 3DRB model read from files; a
    /// synthetic one builds its own).
    fn levelled_by_settings(&self) -> bool {
        false
    }
    /// The model with its ground levelled past `polygon` (`[terrain] level_beyond = "field"`), built again from its
    /// files with `cfg`; `None` where the settings do not shape the ground ([`Self::levelled_by_settings`]).
    fn relevelled(&self, _cfg: &CalibrationConfig, _polygon: Vec<[f64; 2]>) -> Result<Option<Box<dyn Model>>> {
        Ok(None)
    }
    /// How the model releases and reads its simulations.
    fn reading(&self) -> &Reading;
    /// Releases of a simulated rock, at most ([`super::config::CalibrationConfig::release_attempts`]).
    fn release_attempts(&self) -> usize {
        self.reading().release_attempts
    }
    /// The declared tracking noise under which simulated paths of tracked runs are read, m
    /// ([`super::config::CalibrationConfig::track_noise_m`] for a campaign read from files, the case's own for a
    /// synthetic one).
    fn track_noise_m(&self) -> Option<f64> {
        self.reading().track_noise_m
    }
    /// The declared survey error of each rest point coordinate, sd in m, with which simulated rest points are read
    /// ([`super::config::CalibrationConfig::rest_noise_m`]; [`as_measured`]).
    fn rest_noise_m(&self) -> Option<f64> {
        self.reading().rest_noise_m
    }
    /// The bounces of `track` (campaign frame) over this model's ground, read under height noise of sd `noise_m`
    /// ([`super::impacts::read_impacts`]); none where the model has no ground to read them on.
    fn read_impacts(&self, _track: &[TrackPoint], _noise_m: f64) -> Vec<super::impacts::Impact> {
        Vec::new()
    }
    /// True if the simulations of a tracked run read their bounces as its track was
    /// ([`PathSummary::tangential_restitutions`], for the bounce score).
    fn reads_bounces(&self) -> bool {
        self.reading().bounce_reads
    }
    /// What reading the inputs noticed: releases without a rest point ([`crate::campaign::Campaign::unobserved_note`])
    /// and, in 3DRB, the terrain's notes ([`crate::terrain::Terrain::notes`]: keys it does not use, area closed
    /// over).
    fn input_notes(&self) -> &[String];
    /// The material parameters the tracks of runs `which` measure directly ([`super::measured`]); none by default.
    fn measured_by_tracks(&self, _which: &[usize]) -> Vec<super::measured::Measured> {
        Vec::new()
    }
    /// Applies a candidate.
    fn prepare<'a>(&'a self, candidate: &Candidate) -> Result<Box<dyn Prepared + 'a>>;
    /// The model at `candidate` as a scenario for `talus run` (3DRB) or `talus profile` (2DLM) with `repeats`
    /// simulations per campaign run and `seed`: (file name, text) pairs, the scenario first, naming their files
    /// relative to the existing folder `dir` they will be written into (see [`super::scenario_file`]); none for a
    /// model not read from files (synthetic ones).
    fn scenario_files(
        &self,
        _candidate: &Candidate,
        _repeats: usize,
        _seed: u64,
        _dir: &Path,
    ) -> Result<Vec<(String, String)>> {
        Ok(Vec::new())
    }
}

/// A model whose observed runs and release groups are replaced (a calibration's own groups, the zone check's
/// null draws); everything else is the inner model's.
pub struct WithRuns<'a> {
    inner: &'a dyn Model,
    runs: std::borrow::Cow<'a, [FieldRun]>,
    groups: ReleaseGroups,
}

impl<'a> WithRuns<'a> {
    /// `inner` with `runs` (the same runs, in the same order, as `inner`'s but for what is replaced) and `groups`.
    pub fn new(
        inner: &'a dyn Model,
        runs: impl Into<std::borrow::Cow<'a, [FieldRun]>>,
        groups: ReleaseGroups,
    ) -> WithRuns<'a> {
        WithRuns { inner, runs: runs.into(), groups }
    }
}

impl Model for WithRuns<'_> {
    fn kind(&self) -> ModelKind {
        self.inner.kind()
    }
    fn runs(&self) -> &[FieldRun] {
        &self.runs
    }
    fn groups(&self) -> &ReleaseGroups {
        &self.groups
    }
    fn materials(&self) -> &[String] {
        self.inner.materials()
    }
    fn release_height_m(&self, run: &FieldRun) -> f64 {
        self.inner.release_height_m(run)
    }
    fn dominant_material(&self, region: &super::params::Region) -> String {
        self.inner.dominant_material(region)
    }
    fn map_frame(&self) -> MapFrame {
        self.inner.map_frame()
    }
    fn levelled_by_settings(&self) -> bool {
        self.inner.levelled_by_settings()
    }
    fn reading(&self) -> &Reading {
        self.inner.reading()
    }
    fn read_impacts(&self, track: &[TrackPoint], noise_m: f64) -> Vec<super::impacts::Impact> {
        self.inner.read_impacts(track, noise_m)
    }
    fn input_notes(&self) -> &[String] {
        self.inner.input_notes()
    }
    fn measured_by_tracks(&self, which: &[usize]) -> Vec<super::measured::Measured> {
        self.inner.measured_by_tracks(which)
    }
    fn prepare<'b>(&'b self, candidate: &Candidate) -> Result<Box<dyn Prepared + 'b>> {
        self.inner.prepare(candidate)
    }
    fn scenario_files(
        &self,
        candidate: &Candidate,
        repeats: usize,
        seed: u64,
        dir: &Path,
    ) -> Result<Vec<(String, String)>> {
        self.inner.scenario_files(candidate, repeats, seed, dir)
    }
}

/// The random stream index of repeat `repeat` of the run at campaign position `index`.
pub fn stream_index(index: usize, repeat: usize) -> u64 {
    ((index as u64) << 24) | repeat as u64
}

/// Release k of a simulation uses the seed `seed ^ k·RELEASE_SEED_STEP`: an odd multiplier (the 64-bit golden
/// ratio) keeps these seeds apart from `seed + 1`, `seed + 2`, ... that other searches use.
const RELEASE_SEED_STEP: u64 = 0x9E37_79B9_7F4A_7C15;

/// Repeat `repeat` of `run`, released again with fresh random numbers while it ends within
/// [`NOT_STARTED_M`] of its release and the field rock ran farther, `attempts` releases at most (ours). The first
/// release uses the streams of `seed` (so one attempt is the plain simulation); release k those of a seed derived
/// from `seed` and k. Field campaigns record the blocks that ran: a block that stayed where it was put was pushed
/// again, so a simulated rock that stays is a release that did not happen, not a run-out of zero.
pub fn simulate_released(prepared: &dyn Prepared, run: &FieldRun, repeat: usize, seed: u64, attempts: usize) -> Sim {
    let mut sim = prepared.simulate(run, repeat, seed);
    for k in 1..attempts as u64 {
        if !run.ran() || !sim.stalled() {
            break;
        }
        sim = prepared.simulate(run, repeat, seed ^ k.wrapping_mul(RELEASE_SEED_STEP));
    }
    sim
}

/// Repeat `repeat` of `run` ([`simulate_released`]) read as its rest point was measured: with a declared survey
/// error of sd σ ([`Model::rest_noise_m`]) each horizontal coordinate of the simulated rest point (x alone on a
/// profile) gets a Gaussian error of sd σ, drawn from a stream of its own fixed by (seed, run, repeat) like the
/// simulation's (common random numbers: every candidate is read with the same errors), and the run-out is measured
/// from the release to that point, as the field run's was (ours: the simulated run-outs then predict measured
/// ones, so coverage, CRPS and W1 compare like with like). A stall is judged on the simulation before the error
/// ([`Sim::stalled`] on the plain simulation, for the releases); reports that count stalls see the measured value.
pub fn as_measured(model: &dyn Model, prepared: &dyn Prepared, run: &FieldRun, repeat: usize, seed: u64) -> Sim {
    let mut sim = simulate_released(prepared, run, repeat, seed, model.release_attempts());
    if let Some(sd) = model.rest_noise_m().filter(|&sd| sd > 0.0) {
        let mut rng = crate::random::stream(seed ^ REST_NOISE_SEED, stream_index(run.index, repeat));
        let dx = sd * crate::random::standard_normal(&mut rng);
        let dy = if model.kind() == ModelKind::Lumped2d { 0.0 } else { sd * crate::random::standard_normal(&mut rng) };
        sim.rest_m[0] += dx;
        sim.rest_m[1] += dy;
        sim.runout_m = (sim.rest_m[0] - run.release_m[0]).hypot(sim.rest_m[1] - run.release_m[1]);
    }
    sim
}

/// Seed offset of the survey errors [`as_measured`] draws (ours: any fixed number apart from the simulations').
const REST_NOISE_SEED: u64 = 0x5EED_0F0F_2E57;

/// Simulates runs `which` (indices into `model.runs()`) `repeats` times each under `candidate`, in parallel over
/// runs × repeats on `threads` threads (0 = all cores). Results are in the order of `which` and do not depend on
/// the thread count.
pub fn evaluate(
    model: &dyn Model,
    candidate: &Candidate,
    which: &[usize],
    repeats: usize,
    seed: u64,
    threads: usize,
) -> Result<Vec<RunSims>> {
    evaluate_repeats(model, candidate, which, 0..repeats, seed, threads)
}

/// [`evaluate`] of the repeats numbered `repeats` only: each repeat draws its own random numbers (from the run,
/// its number and `seed`), so repeats `a..b` are those that `evaluate` with `b` repeats ends with.
pub fn evaluate_repeats(
    model: &dyn Model,
    candidate: &Candidate,
    which: &[usize],
    repeats: Range<usize>,
    seed: u64,
    threads: usize,
) -> Result<Vec<RunSims>> {
    let prepared = model.prepare(candidate)?;
    let runs = model.runs();
    let n = repeats.len();
    let flat = crate::parallel::collect_in_order(which.len() * n, threads, |k| {
        as_measured(model, prepared.as_ref(), &runs[which[k / n]], repeats.start + k % n, seed)
    });
    let mut out: Vec<RunSims> = which.iter().map(|&i| RunSims { run: i, sims: Vec::with_capacity(n) }).collect();
    for (k, s) in flat.into_iter().enumerate() {
        out[k / n].sims.push(s);
    }
    Ok(out)
}

/// Keeps the path points every `spacing_m` of horizontal travel (and always the last point).
#[derive(Debug, Clone, Default)]
pub struct PathThinner {
    /// Points kept.
    pub points: Vec<[f32; 2]>,
    last: Option<[f64; 2]>,
}

impl PathThinner {
    /// Offers a point; keeps it if it is at least `spacing_m` from the last kept one.
    pub fn offer(&mut self, x: f64, y: f64, spacing_m: f64) {
        match self.last {
            Some([a, b]) if (x - a).hypot(y - b) < spacing_m => {}
            _ => {
                self.points.push([x as f32, y as f32]);
                self.last = Some([x, y]);
            }
        }
    }

    /// Adds the final point.
    pub fn finish(mut self, x: f64, y: f64) -> Vec<[f32; 2]> {
        if self.last != Some([x, y]) {
            self.points.push([x as f32, y as f32]);
        }
        self.points
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// Stalls (run-out 0) for every seed but `runs_on`, and records the seeds it was asked for.
    struct Stalling {
        runs_on: u64,
        seeds: Mutex<Vec<u64>>,
    }

    impl Prepared for Stalling {
        fn simulate(&self, _run: &FieldRun, _repeat: usize, seed: u64) -> Sim {
            self.seeds.lock().unwrap().push(seed);
            let runout_m = if seed == self.runs_on { 50.0 } else { 0.0 };
            Sim { runout_m, rest_m: [0.0; 3], end: SimEnd::Rest, summary: PathSummary::default(), path: Vec::new() }
        }
    }

    fn field_run(runout_m: f64) -> FieldRun {
        crate::calibrate::metrics::tests::run(0, 0, runout_m)
    }

    #[test]
    fn a_stalled_simulation_is_released_again_only_where_the_field_rock_ran() {
        let third = 7 ^ 2u64.wrapping_mul(RELEASE_SEED_STEP);
        let model = Stalling { runs_on: third, seeds: Mutex::new(Vec::new()) };
        let seeds = |m: &Stalling| std::mem::take(&mut *m.seeds.lock().unwrap());
        // One attempt: the plain simulation, on the seed given.
        assert_eq!(simulate_released(&model, &field_run(80.0), 0, 7, 1).runout_m, 0.0);
        assert_eq!(seeds(&model), vec![7]);
        // The third release runs; the search stops there.
        assert_eq!(simulate_released(&model, &field_run(80.0), 0, 7, 10).runout_m, 50.0);
        assert_eq!(seeds(&model).len(), 3);
        // A field rock that did not run: its stall is the prediction, not a release to repeat.
        assert_eq!(simulate_released(&model, &field_run(0.5), 0, 7, 10).runout_m, 0.0);
        assert_eq!(seeds(&model), vec![7]);
        // Every release stalls: the last is kept after `attempts` tries.
        let never = Stalling { runs_on: 1, seeds: Mutex::new(Vec::new()) };
        assert_eq!(simulate_released(&never, &field_run(80.0), 0, 7, 4).runout_m, 0.0);
        let tried = seeds(&never);
        assert_eq!(tried.len(), 4);
        assert!(tried.iter().skip(1).all(|&s| s != 7 && s != 8), "{tried:?}");
    }
}
