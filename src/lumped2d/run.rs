//! Ensembles: many rocks on one slope, with rayon over rocks when the `parallel` feature is on. Rock `i` draws from
//! the stream `(seed, i)` and results are gathered in rock order, so they are identical for any thread count.

use super::engine::{simulate_rock, RockResult2d, StopReason};
use super::gauges::{GaugeEnsemble, GaugeLayout, GaugeRecorder, GaugeStats, LogHistogram};
use super::material::Material2d;
use super::options::Options2d;
use super::path::PathObserver;
use super::profile::Profile;
use super::release::Release2d;
use super::scenario::ProfileScenario;
use super::slope::Slope2d;
use crate::error::{Error, Result};
use crate::io::write_atomic;
use crate::random::stream;
use crate::terrain::BenchGeometry;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

/// Rocks simulated per parallel batch in [`run_profile`]; results are written and binned between batches, so memory
/// stays bounded.
const BATCH: usize = 4096;

/// `f(0..n)` in parallel (with the `parallel` feature) or serially, in index order either way.
fn map_indexed<T: Send>(range: std::ops::Range<usize>, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        range.into_par_iter().map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        range.map(f).collect()
    }
}

/// Rock `i` of an ensemble: its start from the stream `(seed, i)`, then the engine on the same stream.
pub fn simulate_ensemble_rock<O: PathObserver + ?Sized>(
    slope: &Slope2d,
    release: &Release2d,
    options: &Options2d,
    seed: u64,
    i: u64,
    observer: &mut O,
) -> RockResult2d {
    let mut rng = stream(seed, i);
    let start = release.sample(slope.profile(), &mut rng);
    let mut r = simulate_rock(slope, &start, options, &mut rng, observer);
    r.rock_id = i;
    r
}

/// Simulates `n` rocks released by `release` on `slope`, without writing anything. Same seed, same results,
/// whatever the number of threads.
///
/// # Errors
/// When the release or the options are out of range.
///
/// # Examples
/// ```
/// use talus::lumped2d::{simulate_rocks, Material2d, Options2d, Profile, Release2d, Slope2d};
/// use talus::terrain::BenchGeometry;
/// let profile = Profile::from_bench(&BenchGeometry::default()).unwrap();
/// let slope = Slope2d::new(profile, vec![Material2d::face_all(), Material2d::floor_all()]).unwrap();
/// let release = Release2d::point(10.2, 0.5, 1000.0).with_vx_mps(1.0, 2.0);
/// let rocks = simulate_rocks(&slope, &release, &Options2d::default(), 50, 7).unwrap();
/// assert_eq!(rocks.len(), 50);
/// assert!(rocks.iter().all(|r| r.end_x_m > 10.0));
/// ```
pub fn simulate_rocks(
    slope: &Slope2d,
    release: &Release2d,
    options: &Options2d,
    n: usize,
    seed: u64,
) -> Result<Vec<RockResult2d>> {
    release.validate(slope.profile(), "release.")?;
    options.validate("options.")?;
    Ok(map_indexed(0..n, |i| simulate_ensemble_rock(slope, release, options, seed, i as u64, &mut ())))
}

/// Rocks captured per bench of a benched slope.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct BenchCapture {
    /// `per_bench[k]` for k in 1..=n_benches: rocks that ended on bench k (its face or catch bench, as
    /// [`BenchGeometry::bench_at`]). `per_bench[0]`: rocks no bench caught (past the last bench, or off the
    /// profile).
    pub per_bench: Vec<usize>,
    /// Number of rocks.
    pub rocks: usize,
}

impl BenchCapture {
    /// Counts where each rock ended.
    pub fn from_results(geometry: &BenchGeometry, results: &[RockResult2d]) -> BenchCapture {
        let mut per_bench = vec![0; geometry.n_benches + 1];
        for r in results {
            per_bench[Self::bench_of(geometry, r)] += 1;
        }
        BenchCapture { per_bench, rocks: results.len() }
    }

    fn bench_of(geometry: &BenchGeometry, r: &RockResult2d) -> usize {
        if r.stop_reason == StopReason::LeftProfile {
            0
        } else {
            geometry.bench_at(r.end_x_m)
        }
    }

    /// Fraction of the rocks caught by bench `k` (1-based; 0 = not caught).
    pub fn fraction(&self, k: usize) -> f64 {
        if self.rocks == 0 {
            0.0
        } else {
            self.per_bench.get(k).copied().unwrap_or(0) as f64 / self.rocks as f64
        }
    }
}

/// End points and capture per bench of one bench configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchRun {
    /// One result per rock, in rock order.
    pub rocks: Vec<RockResult2d>,
    /// Rocks captured per bench.
    pub capture: BenchCapture,
}

/// Simulates `n` rocks on a benched slope with `face` and `floor` materials and counts the capture per bench; no
/// files are written (for design studies that run many configurations).
///
/// # Errors
/// When the geometry, materials, release or options are out of range.
///
/// # Examples
/// ```
/// use talus::lumped2d::{simulate_bench, Material2d, Options2d, Release2d};
/// use talus::terrain::BenchGeometry;
/// let g = BenchGeometry { bench_width_m: 10.0, ..Default::default() };
/// let release = Release2d::point(g.crest_floor_m + 0.2, 0.5, 1000.0).with_vx_mps(1.0, 2.0);
/// let face = Material2d::face_all().with_roughness_sd_deg(2.0);
/// let floor = Material2d::floor_all().with_roughness_sd_deg(2.0);
/// let run = simulate_bench(&g, &face, &floor, &release, &Options2d::default(), 100, 1).unwrap();
/// assert_eq!(run.capture.per_bench.iter().sum::<usize>(), 100);
/// ```
pub fn simulate_bench(
    geometry: &BenchGeometry,
    face: &Material2d,
    floor: &Material2d,
    release: &Release2d,
    options: &Options2d,
    n: usize,
    seed: u64,
) -> Result<BenchRun> {
    let slope = Slope2d::new(Profile::from_bench(geometry)?, vec![*face, *floor])?;
    let rocks = simulate_rocks(&slope, release, options, n, seed)?;
    let capture = BenchCapture::from_results(geometry, &rocks);
    Ok(BenchRun { rocks, capture })
}

/// Counts of rocks by stop reason.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct StopCounts {
    /// Came to rest.
    pub stopped: usize,
    /// Left the profile.
    pub left_profile: usize,
    /// Hit the event cap.
    pub max_events: usize,
    /// Hit the time cap.
    pub max_time: usize,
}

impl StopCounts {
    fn add(&mut self, r: StopReason) {
        match r {
            StopReason::Stopped => self.stopped += 1,
            StopReason::LeftProfile => self.left_profile += 1,
            StopReason::MaxEvents => self.max_events += 1,
            StopReason::MaxTime => self.max_time += 1,
        }
    }
}

/// P50, P90, P95 and maximum of a quantity (from fixed bins, within ±0.55 %; the maximum is exact).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Percentiles {
    /// Median.
    pub p50: Option<f64>,
    /// 90th percentile.
    pub p90: Option<f64>,
    /// 95th percentile.
    pub p95: Option<f64>,
    /// Maximum.
    pub max: Option<f64>,
}

impl Percentiles {
    fn of(h: &LogHistogram) -> Percentiles {
        Percentiles { p50: h.quantile(0.5), p90: h.quantile(0.9), p95: h.quantile(0.95), max: h.max() }
    }
}

/// Facts about the profile used.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProfileInfo {
    /// `bench` or the CSV path.
    pub source: String,
    /// Number of vertices.
    pub vertices: usize,
    /// x range, m.
    pub x_range_m: [f64; 2],
    /// Material names.
    pub material_names: Vec<String>,
}

/// Capture per bench, for a benched profile.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BenchCaptureSummary {
    /// Counts (see [`BenchCapture::per_bench`]).
    pub per_bench: Vec<usize>,
    /// Fractions of all rocks, same indexing.
    pub fraction_per_bench: Vec<f64>,
    /// Fraction caught on the first bench.
    pub first_bench_fraction: f64,
}

/// What [`run_profile`] did: every parameter as used, the counts, and the timing. Also written as `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProfileSummary {
    /// talus version.
    pub talus_version: String,
    /// Scenario name.
    pub name: Option<String>,
    /// Scenario file.
    pub scenario: Option<String>,
    /// The profile.
    pub profile: ProfileInfo,
    /// The bench geometry, for a benched profile.
    pub bench: Option<BenchGeometry>,
    /// Materials as resolved.
    pub materials: BTreeMap<String, Material2d>,
    /// The release (for a campaign: the ranges its runs span and their mean mass).
    pub release: Release2d,
    /// The campaign whose runs were released, if any.
    pub campaign: Option<super::scenario::CampaignRelease>,
    /// Engine options.
    pub options: Options2d,
    /// Rock radius (sphere at the rock density; for a campaign, of its mean mass), m.
    pub rock_radius_m: f64,
    /// Number of rocks.
    pub rocks: usize,
    /// Random seed.
    pub seed: u64,
    /// Envelope station spacing, m.
    pub envelope_spacing_m: f64,
    /// Collector positions, m.
    pub collectors_x_m: Vec<f64>,
    /// Rocks by stop reason.
    pub stop_reasons: StopCounts,
    /// Run-out (horizontal distance from release to end), m.
    pub runout_m: Percentiles,
    /// Capture per bench (benched profiles only).
    pub bench_capture: Option<BenchCaptureSummary>,
    /// Threads used.
    pub threads: usize,
    /// Wall time of the simulation and the outputs, s.
    pub wall_time_s: f64,
    /// Rocks per second of wall time.
    pub rocks_per_second: f64,
    /// Files written in the output folder.
    pub outputs: Vec<String>,
    /// What the run noticed: materials the scenario defines but no segment of the profile has (as when a
    /// calibrated model's zone is carried to a design profile without it).
    pub warnings: Vec<String>,
}

fn num(v: f64) -> String {
    format!("{v:.6}")
}

fn opt(v: Option<f64>) -> String {
    v.map(num).unwrap_or_default()
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |e| Error::io(path, e)
}

/// Runs a profile scenario and writes into `out_dir` (created if needed):
/// - `endpoints.csv`: rock_id, end_x_m, end_z_m, stop_reason, runout_m, travel_time_s, max_kinetic_j, max_bounce_m,
///   impacts;
/// - `envelopes.csv`: per station (every `envelope_spacing_m`): rocks passing, P50/P90/P95/max of bounce height
///   (above the profile, vertical), speed and kinetic energy;
/// - `collectors.csv`: per collector: rocks passing, P50/P95/max of passing height, speed and kinetic energy;
/// - `profile.csv`: the profile used; `summary.json`: the [`ProfileSummary`].
///
/// Each rock counts once per station or collector, with its largest height and speed there. Percentiles come from
/// fixed logarithmic bins (within ±0.55 %), so memory does not grow with the number of rocks.
///
/// # Errors
/// Scenario errors (see [`ProfileScenario::resolve`]) and I/O errors.
pub fn run_profile(scenario: &ProfileScenario, out_dir: &Path) -> Result<ProfileSummary> {
    let start_time = std::time::Instant::now();
    let rs = scenario.resolve()?;
    crate::io::create_folder(out_dir)?;
    let profile = rs.slope.profile();
    let layout = GaugeLayout::new(profile, scenario.envelope_spacing_m, scenario.collectors_x_m.clone());
    let mut gauges = GaugeEnsemble::new(layout.clone());
    let mut stops = StopCounts::default();
    let mut runout = LogHistogram::default();
    let mut capture = rs.bench.as_ref().map(|g| vec![0usize; g.n_benches + 1]);
    let n = rs.rocks;
    let mass = rs.release.mass_kg;

    let path = out_dir.join("endpoints.csv");
    write_atomic(&path, |w| {
        let e = io_err(&path);
        writeln!(w, "rock_id,end_x_m,end_z_m,stop_reason,runout_m,travel_time_s,max_kinetic_j,max_bounce_m,impacts")
            .map_err(&e)?;
        for b0 in (0..n).step_by(BATCH) {
            let batch = map_indexed(b0..(b0 + BATCH).min(n), |i| {
                let mut rec = GaugeRecorder::new(&layout, profile);
                let r = match rs.starts.get(i) {
                    Some(start) => {
                        let mut rng = stream(scenario.seed, i as u64);
                        let r = simulate_rock(&rs.slope, start, &rs.options, &mut rng, &mut rec);
                        RockResult2d { rock_id: i as u64, ..r }
                    }
                    None => {
                        simulate_ensemble_rock(&rs.slope, &rs.release, &rs.options, scenario.seed, i as u64, &mut rec)
                    }
                };
                (r, rec.crossings)
            });
            for (r, mut crossings) in batch {
                writeln!(
                    w,
                    "{},{},{},{},{},{},{},{},{}",
                    r.rock_id,
                    num(r.end_x_m),
                    num(r.end_z_m),
                    r.stop_reason.as_str(),
                    num(r.runout_m),
                    num(r.travel_time_s),
                    num(r.max_kinetic_j),
                    num(r.max_bounce_m),
                    r.impacts
                )
                .map_err(&e)?;
                gauges.add_rock(&mut crossings, rs.starts.get(r.rock_id as usize).map_or(mass, |s| s.mass_kg));
                stops.add(r.stop_reason);
                runout.add(r.runout_m);
                if let (Some(c), Some(g)) = (capture.as_mut(), rs.bench.as_ref()) {
                    c[BenchCapture::bench_of(g, &r)] += 1;
                }
            }
        }
        Ok(())
    })?;

    let ground = |x: f64| profile.z_at(x).unwrap_or(f64::NAN);
    let path = out_dir.join("envelopes.csv");
    write_atomic(&path, |w| {
        let e = io_err(&path);
        let mut head = String::from("x_m,ground_z_m,rocks,fraction");
        for q in ["bounce", "speed", "kinetic"] {
            let unit = match q {
                "bounce" => "m",
                "speed" => "mps",
                _ => "j",
            };
            for p in ["p50", "p90", "p95", "max"] {
                head.push_str(&format!(",{q}_{p}_{unit}"));
            }
        }
        writeln!(w, "{head}").map_err(&e)?;
        for k in 0..layout.n_stations {
            let x = layout.x_of(k);
            let st = &gauges.stats[k];
            let mut row = format!("{},{},{},{}", num(x), num(ground(x)), st.rocks(), num(st.rocks() as f64 / n as f64));
            for h in [&st.height_m, &st.speed_mps, &st.kinetic_j] {
                for q in [Some(0.5), Some(0.9), Some(0.95), None] {
                    row.push(',');
                    row.push_str(&opt(q.map_or(h.max(), |q| h.quantile(q))));
                }
            }
            writeln!(w, "{row}").map_err(&e)?;
        }
        Ok(())
    })?;

    let path = out_dir.join("collectors.csv");
    write_atomic(&path, |w| {
        let e = io_err(&path);
        writeln!(
            w,
            "collector,x_m,ground_z_m,rocks,fraction,height_p50_m,height_p95_m,height_max_m,speed_p50_mps,\
             speed_p95_mps,speed_max_mps,kinetic_p50_j,kinetic_p95_j,kinetic_max_j"
        )
        .map_err(&e)?;
        for (j, &x) in layout.collectors_x_m.iter().enumerate() {
            let st: &GaugeStats = &gauges.stats[layout.n_stations + j];
            let mut row =
                format!("{},{},{},{},{}", j + 1, num(x), num(ground(x)), st.rocks(), num(st.rocks() as f64 / n as f64));
            for h in [&st.height_m, &st.speed_mps, &st.kinetic_j] {
                for q in [Some(0.5), Some(0.95), None] {
                    row.push(',');
                    row.push_str(&opt(q.map_or(h.max(), |q| h.quantile(q))));
                }
            }
            writeln!(w, "{row}").map_err(&e)?;
        }
        Ok(())
    })?;

    profile.write_csv(&out_dir.join("profile.csv"))?;

    let wall = start_time.elapsed().as_secs_f64();
    // The pool this runs in (`cli::with_threads` installs the one asked for).
    let threads = crate::parallel::threads_used(0);
    let (x0, x1) = profile.x_range_m();
    let warnings = (scenario.materials.keys())
        .filter(|m| !profile.material_names().contains(m))
        .map(|m| format!("[materials.{m}] is defined but no segment of the profile has it"))
        .collect();
    let summary = ProfileSummary {
        talus_version: env!("CARGO_PKG_VERSION").to_string(),
        name: scenario.name.clone(),
        scenario: scenario.source.clone(),
        profile: ProfileInfo {
            source: rs.profile_source.clone(),
            vertices: profile.n_vertices(),
            x_range_m: [x0, x1],
            material_names: profile.material_names().to_vec(),
        },
        bench: rs.bench.clone(),
        materials: rs.materials.clone(),
        release: rs.release,
        campaign: scenario.campaign.clone(),
        options: rs.options.clone(),
        rock_radius_m: rs.options.radius_m(mass),
        rocks: n,
        seed: scenario.seed,
        envelope_spacing_m: scenario.envelope_spacing_m,
        collectors_x_m: scenario.collectors_x_m.clone(),
        stop_reasons: stops,
        runout_m: Percentiles::of(&runout),
        bench_capture: capture.map(|c| {
            let fraction_per_bench: Vec<f64> = c.iter().map(|&k| k as f64 / n as f64).collect();
            BenchCaptureSummary { first_bench_fraction: fraction_per_bench[1], per_bench: c, fraction_per_bench }
        }),
        threads,
        wall_time_s: wall,
        rocks_per_second: n as f64 / wall.max(1e-12),
        outputs: ["endpoints.csv", "envelopes.csv", "collectors.csv", "profile.csv", "summary.json"]
            .map(String::from)
            .to_vec(),
        warnings,
    };
    crate::io::write_json_atomic(&out_dir.join("summary.json"), &summary)?;
    Ok(summary)
}
