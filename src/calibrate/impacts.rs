//! Impacts read from a tracked path (ours): where a track shows a bounce, the velocity of the centre of mass just
//! before and just after it, and from them the apparent coefficients of restitution that field campaigns
//! back-calculate impact by impact (normal: outgoing over incoming normal speed; tangential: the same for the speed
//! along the ground). `talus calibrate` reads the observed tracks and the models' simulated paths of the same runs
//! the same way ([`simulated_summary`]) and sets them side by side: what is read is biased (low bounces are missed,
//! and a rigid body's centre does not come back at Cr), so a track is compared with simulated tracks, not with
//! the model's coefficients (docs/calibration.md, "Impacts read from tracks").
//!
//! Between two impacts a rock flies freely: its horizontal coordinates are linear in time and its height a parabola
//! of curvature −g, so w(t) = z(t) + g t²/2 is linear in time too. An impact is a corner of w: the slope of a line
//! fitted to w just after a point exceeds that of a line fitted just before it by the impact's gain in vertical
//! speed. The reading:
//! 1. **candidates**: at each point, least-squares lines through w over the [`WINDOW_S`] before and after it (at
//!    least two points a side); a candidate where the gain exceeds [`MIN_GAIN_MPS`] and five standard errors of the
//!    gain under the track's noise, and is the largest within the window;
//! 2. **flights**: the points strictly between consecutive candidates (and before the first and after the last),
//!    kept when there are at least [`MIN_FLIGHT_POINTS`] and a free parabola through their heights bends as a free
//!    flight does: curvature within a quarter of −g/2 (plus two standard errors), its standard error at most a
//!    quarter of g/2 (rolling and sliding, which bend otherwise, are not flights);
//! 3. **impacts**: a candidate with a kept flight on each side, read where the two flights' w-lines cross (the
//!    impact time between samples); the velocities come from the flights' lines in x, y and w, the ground normal
//!    from the terrain's heights half a metre around the impact point. A bounce needs the rock to approach the
//!    ground before and leave it after; the last landing (after which the rock rolls) has no outgoing flight and is
//!    not an impact here.

use super::diagnose::Diagnostic;
use super::model::Model;
use super::params::Candidate;
use super::runs::FieldRun;
use super::stats::{median, quantile_sorted, sorted, spearman_permutation};
use crate::campaign::TrackPoint;
use crate::error::Result;
use crate::random::{standard_normal, stream, Rng};
use crate::sim::GRAVITY_MPS2;
use serde::{Deserialize, Serialize};

/// Half-width of the windows that find candidate impacts, s (ours: shorter than any flight worth reading, long
/// enough to average a 1 kHz track's noise over 100 points).
pub const WINDOW_S: f64 = 0.1;
/// Smallest gain in vertical speed read as an impact, m/s (ours).
pub const MIN_GAIN_MPS: f64 = 0.5;
/// Fewest points of a flight (three fix a parabola; one more checks it).
pub const MIN_FLIGHT_POINTS: usize = 4;
/// Smallest speed along the ground for a tangential restitution, m/s (ours: below it the ratio is noise).
const MIN_TANGENTIAL_MPS: f64 = 0.1;
/// Half the step of the finite differences that give the ground normal, m.
const NORMAL_STEP_M: f64 = 0.5;

/// One impact read from a track.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Impact {
    /// Time since the track's first point, s.
    pub time_s: f64,
    /// Index of the track point nearest the impact.
    pub point: usize,
    /// That point's position, m (in the track's frame).
    pub position_m: [f64; 3],
    /// Speed into the ground along its normal, m/s (> 0).
    pub normal_speed_in_mps: f64,
    /// Speed along the ground before the impact, m/s.
    pub tangential_speed_in_mps: f64,
    /// Angle between the incoming velocity and the ground, degrees (90: head-on).
    pub incidence_deg: f64,
    /// Outgoing over incoming normal speed.
    pub normal_restitution: f64,
    /// Outgoing over incoming speed along the ground; `None` when the incoming one is under 0.1 m/s.
    pub tangential_restitution: Option<f64>,
}

/// The impacts of `track` (positions with z up, x and y horizontal, in the frame of `ground_m`, which gives the
/// ground's height at (x, y) or `None` off the terrain), read under tracking noise of sd `noise_m` on the heights.
pub fn read_impacts(track: &[TrackPoint], noise_m: f64, ground_m: &dyn Fn(f64, f64) -> Option<f64>) -> Vec<Impact> {
    let g = GRAVITY_MPS2;
    let n = track.len();
    if n < 2 * MIN_FLIGHT_POINTS + 1 || track.windows(2).any(|w| w[1].time_s <= w[0].time_s) {
        return Vec::new();
    }
    let t0 = track[0].time_s;
    let t: Vec<f64> = track.iter().map(|p| p.time_s - t0).collect();
    let w: Vec<f64> = track.iter().zip(&t).map(|(p, &t)| p.position_m[2] + 0.5 * g * t * t).collect();
    let sigma = noise_m.max(1e-3);
    // 1. Candidates.
    // The window of each point: the points within WINDOW_S before it (at least one) and after it (at least one),
    // found in one sweep (times ascend, so both ends only move forward).
    let (mut before, mut after) = (vec![0; n], vec![0; n]);
    let (mut lo, mut hi) = (0, 0);
    for k in 0..n {
        while t[k] - t[lo] > WINDOW_S {
            lo += 1;
        }
        while hi + 1 < n && t[hi + 1] - t[k] <= WINDOW_S {
            hi += 1;
        }
        before[k] = lo.min(k.saturating_sub(1));
        after[k] = hi.max((k + 1).min(n - 1));
    }
    let sums = PrefixSums::new(&t, &w);
    let gain: Vec<f64> = (0..n)
        .map(|k| {
            if k == 0 || k + 1 == n {
                return 0.0;
            }
            let (l, r) = (sums.line(before[k]..k + 1), sums.line(k..after[k] + 1));
            let se = sigma * (1.0 / l.sxx + 1.0 / r.sxx).sqrt();
            let gain = r.slope - l.slope;
            if gain >= MIN_GAIN_MPS.max(5.0 * se) {
                gain
            } else {
                0.0
            }
        })
        .collect();
    let candidates: Vec<usize> = (1..n - 1)
        .filter(|&k| {
            gain[k] > 0.0 && (before[k]..after[k] + 1).all(|j| gain[j] < gain[k] || (gain[j] == gain[k] && j >= k))
        })
        .collect();
    // 2. Flights between them.
    let mut bounds = vec![0usize];
    bounds.extend(&candidates);
    bounds.push(n - 1);
    let flight = |a: usize, b: usize, open_start: bool, open_end: bool| -> Option<Flight> {
        let lo = if open_start { a + 1 } else { a };
        let hi = if open_end { b } else { b + 1 };
        if hi < lo + MIN_FLIGHT_POINTS {
            return None;
        }
        Flight::fit(&t, track, &w, lo..hi, sigma)
    };
    // 3. Impacts.
    let mut out = Vec::new();
    for (i, &k) in candidates.iter().enumerate() {
        let (before, after) = (bounds[i], bounds[i + 2]);
        let Some(inc) = flight(before, k, i > 0, true) else { continue };
        let Some(out_f) = flight(k, after, true, i + 1 < candidates.len()) else { continue };
        let (lo, hi) = (t[k - 1], t[k + 1]);
        let cross = (out_f.w.intercept - inc.w.intercept) / (inc.w.slope - out_f.w.slope);
        let tc = if cross.is_finite() { cross.clamp(lo, hi) } else { t[k] };
        let (x, y) = (inc.x.at(tc), inc.y.at(tc));
        let normal = match ground_normal(ground_m, x, y) {
            Some(nrm) => nrm,
            None => continue,
        };
        let v_in = [inc.x.slope, inc.y.slope, inc.w.slope - g * tc];
        let v_out = [out_f.x.slope, out_f.y.slope, out_f.w.slope - g * tc];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let (vn_in, vn_out) = (-dot(v_in, normal), dot(v_out, normal));
        if vn_in <= 0.0 || vn_out <= 0.0 {
            continue;
        }
        let along = |v: [f64; 3], vn: f64| {
            let u = [v[0] - vn * normal[0], v[1] - vn * normal[1], v[2] - vn * normal[2]];
            dot(u, u).sqrt()
        };
        let (vt_in, vt_out) = (along(v_in, -vn_in), along(v_out, vn_out));
        let nearest = if tc - t[k - 1] < t[k] - tc { k - 1 } else { k };
        out.push(Impact {
            time_s: tc,
            point: nearest,
            position_m: track[nearest].position_m,
            normal_speed_in_mps: vn_in,
            tangential_speed_in_mps: vt_in,
            incidence_deg: vn_in.atan2(vt_in).to_degrees(),
            normal_restitution: vn_out / vn_in,
            tangential_restitution: (vt_in >= MIN_TANGENTIAL_MPS).then(|| vt_out / vt_in),
        });
    }
    out
}

/// The upward unit normal of the ground at (x, y) from central differences of its heights, or `None` where a
/// neighbouring height is off the terrain.
fn ground_normal(ground_m: &dyn Fn(f64, f64) -> Option<f64>, x: f64, y: f64) -> Option<[f64; 3]> {
    let h = NORMAL_STEP_M;
    let zx = (ground_m(x + h, y)? - ground_m(x - h, y)?) / (2.0 * h);
    let zy = (ground_m(x, y + h)? - ground_m(x, y - h)?) / (2.0 * h);
    let len = (1.0 + zx * zx + zy * zy).sqrt();
    Some([-zx / len, -zy / len, 1.0 / len])
}

/// A least-squares line v = intercept + slope·t, with Σ(t − t̄)² for its slope's standard error.
#[derive(Debug, Clone, Copy)]
struct Line {
    intercept: f64,
    slope: f64,
    sxx: f64,
}

impl Line {
    fn at(&self, t: f64) -> f64 {
        self.intercept + self.slope * t
    }
}

fn line(t: &[f64], v: &[f64], range: std::ops::Range<usize>) -> Line {
    let m = range.len() as f64;
    let tm = t[range.clone()].iter().sum::<f64>() / m;
    let vm = v[range.clone()].iter().sum::<f64>() / m;
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for i in range {
        sxx += (t[i] - tm) * (t[i] - tm);
        sxy += (t[i] - tm) * (v[i] - vm);
    }
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    Line { intercept: vm - slope * tm, slope, sxx: sxx.max(f64::MIN_POSITIVE) }
}

/// Running sums of t, t², v and t·v, for least-squares lines over any range in constant time (the candidates'
/// windows hold a hundred points of a millisecond track).
struct PrefixSums {
    /// `sums[i]`: the sums over points `0..i`, each time taken from the first point.
    sums: Vec<[f64; 4]>,
}

impl PrefixSums {
    fn new(t: &[f64], v: &[f64]) -> Self {
        let mut sums = vec![[0.0; 4]];
        let mut acc = [0.0; 4];
        for (&ti, &vi) in t.iter().zip(v) {
            for (a, x) in acc.iter_mut().zip([ti, ti * ti, vi, ti * vi]) {
                *a += x;
            }
            sums.push(acc);
        }
        PrefixSums { sums }
    }

    /// The least-squares line through the points of `range`.
    fn line(&self, range: std::ops::Range<usize>) -> Line {
        let (a, b) = (self.sums[range.start], self.sums[range.end]);
        let m = range.len() as f64;
        let [st, stt, sv, stv] = std::array::from_fn(|i| b[i] - a[i]);
        let sxx = stt - st * st / m;
        let sxy = stv - st * sv / m;
        let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
        Line { intercept: (sv - slope * st) / m, slope, sxx: sxx.max(f64::MIN_POSITIVE) }
    }
}

/// A free flight: lines through x, y and w over its points.
struct Flight {
    x: Line,
    y: Line,
    w: Line,
}

impl Flight {
    /// The flight through the points `range` of the track, if their heights bend as a free flight's do.
    fn fit(t: &[f64], track: &[TrackPoint], w: &[f64], range: std::ops::Range<usize>, sigma: f64) -> Option<Flight> {
        let half_g = 0.5 * GRAVITY_MPS2;
        let (curvature, se) = curvature(t, track, range.clone(), sigma)?;
        if se > 0.25 * half_g || (curvature + half_g).abs() > 0.25 * half_g + 2.0 * se {
            return None;
        }
        let coord = |c: usize| -> Vec<f64> { track.iter().map(|p| p.position_m[c]).collect() };
        Some(Flight {
            x: line(t, &coord(0), range.clone()),
            y: line(t, &coord(1), range.clone()),
            w: line(t, w, range),
        })
    }
}

/// The coefficient c of the least-squares parabola z = a + b τ + c τ² through the heights of `range` (τ the time
/// from their mean) and its standard error under noise of sd `sigma`; `None` when the times cannot fix it.
fn curvature(t: &[f64], track: &[TrackPoint], range: std::ops::Range<usize>, sigma: f64) -> Option<(f64, f64)> {
    let m = range.len() as f64;
    let tm = t[range.clone()].iter().sum::<f64>() / m;
    // Normal equations in (1, τ, τ²).
    let mut s = [0.0; 5];
    let mut r = [0.0; 3];
    for i in range {
        let tau = t[i] - tm;
        let z = track[i].position_m[2];
        let mut p = 1.0;
        for (k, sk) in s.iter_mut().enumerate() {
            *sk += p;
            if k < 3 {
                r[k] += p * z;
            }
            p *= tau;
        }
    }
    let a = [[s[0], s[1], s[2]], [s[1], s[2], s[3]], [s[2], s[3], s[4]]];
    let det = det3(a);
    if det <= 0.0 || !det.is_finite() {
        return None;
    }
    let mut a2 = a;
    for (row, rv) in a2.iter_mut().zip(r) {
        row[2] = rv;
    }
    let c = det3(a2) / det;
    // (AᵀA)⁻¹ at (2, 2): the cofactor over the determinant.
    let cof = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    Some((c, sigma * (cof / det).max(0.0).sqrt()))
}

fn det3(a: [[f64; 3]; 3]) -> f64 {
    a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
}

/// What the bounces read from a set of paths say: how many per path, and their median restitutions. Only bounces
/// whose flights on both sides are readable count, so low bounces (short flights) are missed, more so on noisy
/// tracks, and on a rigid body the centre's restitution is not Cr (spin gives and takes): compare the observed
/// tracks with the model's simulated paths read the same way ([`simulated_summary`]), not with the model's
/// coefficients. For the same reason the correlation of restitution with impact speed is not reported as such: at
/// a given incoming speed only bounces that leave fast enough are read, which alone makes the restitution fall with
/// speed; [`bounce_diagnostics`] compares each observed bounce with simulated ones at its speed instead.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImpactSummary {
    /// Tracked paths read (simulated: runs × repeats).
    pub paths: usize,
    /// Bounces read.
    pub n: usize,
    /// Bounces per path.
    pub per_path: f64,
    /// Median normal restitution (with at least [`MIN_IMPACTS`] bounces).
    pub normal_restitution_median: Option<f64>,
    /// Its 25th and 75th percentiles.
    pub normal_restitution_iqr: Option<[f64; 2]>,
    /// Median tangential restitution (of the bounces with one).
    pub tangential_restitution_median: Option<f64>,
    /// Median normal impact speed, m/s.
    pub normal_speed_in_median_mps: Option<f64>,
}

/// The bounces of one set of runs: observed, and the baseline's and the final model's simulated paths read the
/// same way.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BounceComparison {
    /// `calibration` or `holdout`.
    pub set: String,
    /// From the tracks.
    pub observed: ImpactSummary,
    /// From the baseline's simulated paths.
    pub baseline: Option<ImpactSummary>,
    /// From the final model's.
    #[serde(rename = "final")]
    pub final_model: Option<ImpactSummary>,
    /// The observed bounces ranked among the baseline's ([`bounce_ranks`]; for the charts, not in report.json).
    #[serde(skip)]
    pub baseline_ranks: Vec<BounceRanks>,
    /// The same among the final model's.
    #[serde(skip)]
    pub final_ranks: Vec<BounceRanks>,
}

/// Fewest bounces for medians.
pub const MIN_IMPACTS: usize = 5;

/// The summary of `impacts` read from `paths` paths; `None` without a path.
pub fn summarise(impacts: &[&Impact], paths: usize) -> Option<ImpactSummary> {
    if paths == 0 {
        return None;
    }
    let enough = impacts.len() >= MIN_IMPACTS;
    let en = sorted(&impacts.iter().map(|i| i.normal_restitution).collect::<Vec<_>>());
    let vn: Vec<f64> = impacts.iter().map(|i| i.normal_speed_in_mps).collect();
    let et: Vec<f64> = impacts.iter().filter_map(|i| i.tangential_restitution).collect();
    Some(ImpactSummary {
        paths,
        n: impacts.len(),
        per_path: impacts.len() as f64 / paths as f64,
        normal_restitution_median: enough.then(|| quantile_sorted(&en, 0.5)),
        normal_restitution_iqr: enough.then(|| [quantile_sorted(&en, 0.25), quantile_sorted(&en, 0.75)]),
        tangential_restitution_median: (et.len() >= MIN_IMPACTS).then(|| median(&et)),
        normal_speed_in_median_mps: enough.then(|| median(&vn)),
    })
}

/// The observed bounces of the tracked runs among `runs` (indices into the model's runs).
pub fn observed_summary(model: &dyn Model, runs: &[usize]) -> Option<ImpactSummary> {
    let tracked: Vec<&FieldRun> =
        runs.iter().map(|&i| &model.runs()[i]).filter(|r| !r.track_times_s.is_empty()).collect();
    let impacts: Vec<&Impact> = tracked.iter().flat_map(|r| &r.impacts).collect();
    summarise(&impacts, tracked.len())
}

/// Seeds the simulated tracks' noise apart from the simulations' (`seed ^ this`).
const SIMULATED_TRACK_SEED: u64 = 0x696d_7061_6374_735f;

/// The bounces of `candidate`'s simulated paths of the tracked runs among `runs`, `repeats` each (the same
/// simulations as [`super::model::evaluate`]'s with `seed`, their first release), on `threads` threads (0: all
/// cores; the result does not depend on it): one entry per tracked run, its index and the bounces of all its
/// repeats. As for rebound heights ([`super::rebound`]): with the tracking noise declared (`noise_m`) each path is
/// read as its run's track was, at the track's times since release (linear between the recorded path's points, at
/// rest after its end), each height plus Gaussian noise of that sd; undeclared, as recorded
/// ([`Prepared::path`](super::model::Prepared::path): 3DRB every millisecond, 2DLM as its recorder samples), right
/// for exact tracks recorded the same way, such as the synthetic ones.
///
/// # Errors
/// The candidate does not fit the model.
pub fn simulated_impacts(
    model: &dyn Model,
    candidate: &Candidate,
    runs: &[usize],
    repeats: usize,
    seed: u64,
    noise_m: Option<f64>,
    threads: usize,
) -> Result<Vec<(usize, Vec<Impact>)>> {
    let prepared = model.prepare(candidate)?;
    let tracked: Vec<&FieldRun> =
        runs.iter().map(|&i| &model.runs()[i]).filter(|r| !r.track_times_s.is_empty()).collect();
    let read: Vec<Vec<Impact>> = crate::parallel::collect_in_order(tracked.len() * repeats, threads, |k| {
        let (run, repeat) = (tracked[k / repeats], k % repeats);
        read_as_tracked(model, run, repeat, seed, &prepared.path(run, repeat, seed), noise_m)
    });
    Ok(tracked
        .iter()
        .zip(read.chunks(repeats.max(1)))
        .map(|(run, per_repeat)| (run.index, per_repeat.iter().flatten().cloned().collect()))
        .collect())
}

/// The bounces of `path`, the simulated path of repeat `repeat` of the tracked `run` with `seed`, read as the run's
/// track was (see [`simulated_impacts`]).
pub fn read_as_tracked(
    model: &dyn Model,
    run: &FieldRun,
    repeat: usize,
    seed: u64,
    path: &[TrackPoint],
    noise_m: Option<f64>,
) -> Vec<Impact> {
    match noise_m {
        Some(sd) => {
            let mut rng = stream(seed ^ SIMULATED_TRACK_SEED, super::model::stream_index(run.index, repeat));
            model.read_impacts(&at_times(path, &run.track_times_s, sd, &mut rng), sd)
        }
        None => model.read_impacts(path, 0.0),
    }
}

/// The tangential restitutions of the bounces of `path`, the simulated path of repeat `repeat` of the tracked `run`
/// with `seed`, read as the run's track was under the model's declared tracking noise ([`read_as_tracked`]): what
/// the bounce score compares ([`super::objective::bounce_crps`]).
pub fn tangential_restitutions_as_tracked(
    model: &dyn Model,
    run: &FieldRun,
    repeat: usize,
    seed: u64,
    path: &[TrackPoint],
) -> Vec<f64> {
    let read = read_as_tracked(model, run, repeat, seed, path, model.track_noise_m());
    read.iter().filter_map(|i| i.tangential_restitution).collect()
}

/// The summary of [`simulated_impacts`]'s bounces, `repeats` paths per run.
pub fn simulated_summary(simulated: &[(usize, Vec<Impact>)], repeats: usize) -> Option<ImpactSummary> {
    let impacts: Vec<&Impact> = simulated.iter().flat_map(|(_, i)| i).collect();
    summarise(&impacts, simulated.len() * repeats)
}

/// The residual name of [`bounce_diagnostics`].
pub const BOUNCE_RESIDUAL: &str = "bounce_restitution";
/// Its covariates: the normal impact speed and the incidence of an observed bounce.
pub const BOUNCE_NORMAL_SPEED: &str = "bounce_normal_speed_mps";
/// See [`BOUNCE_NORMAL_SPEED`].
pub const BOUNCE_INCIDENCE: &str = "bounce_incidence_deg";
/// The permutations' random stream (with the settings' seed).
const BOUNCE_STREAM: u64 = u64::MAX - 7000;
/// Simulated bounces of its own run an observed bounce is ranked among (ours).
pub const BOUNCE_NEIGHBOURS: usize = 15;
/// Fewest observed bounces for a bounce diagnostic (ours).
pub const MIN_BOUNCES_DIAGNOSED: usize = 20;

/// The observed bounces' ranks among a model's against one covariate ([`bounce_ranks`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BounceRanks {
    /// [`BOUNCE_NORMAL_SPEED`] or [`BOUNCE_INCIDENCE`].
    pub covariate: &'static str,
    /// (the observed bounce's covariate, its rank u in [0, 1]), one per observed bounce ranked.
    pub points: Vec<[f64; 2]>,
}

/// Does the model's normal restitution miss the tracks' in a way that changes with impact speed or incidence (ours)?
/// Each observed bounce is ranked among the [`BOUNCE_NEIGHBOURS`] simulated bounces of its own run (`simulated`,
/// from [`simulated_impacts`]) nearest to it in the covariate, each moved to the observed covariate along their
/// least-squares line of restitution on it: u = the share of them that came back slower (ties half). Where the
/// model is right, u is uniform whatever the covariate, because both sides are read the same way and compared at
/// the same speed or incidence: the reading's selection (only bounces that leave fast enough are read) and a rigid
/// body's apparent restitution falling with speed at constant Cr are in the simulated bounces too. A restitution
/// that falls with speed where the model's does not makes u fall with the speed. Runs with fewer than
/// [`BOUNCE_NEIGHBOURS`] simulated bounces are skipped.
pub fn bounce_ranks(runs: &[FieldRun], simulated: &[(usize, Vec<Impact>)]) -> Vec<BounceRanks> {
    type Key = fn(&Impact) -> f64;
    let covariates: [(&'static str, Key); 2] =
        [(BOUNCE_NORMAL_SPEED, |i| i.normal_speed_in_mps), (BOUNCE_INCIDENCE, |i| i.incidence_deg)];
    covariates
        .into_iter()
        .map(|(covariate, key)| {
            let mut points = Vec::new();
            for (run, sim) in simulated.iter().filter(|(_, s)| s.len() >= BOUNCE_NEIGHBOURS) {
                for o in &runs[*run].impacts {
                    let mut near: Vec<&Impact> = sim.iter().collect();
                    near.sort_by(|a, b| (key(a) - key(o)).abs().total_cmp(&(key(b) - key(o)).abs()));
                    let near = &near[..BOUNCE_NEIGHBOURS];
                    // Each neighbour moved to the observed bounce's covariate along the neighbours' own trend, so
                    // that a bounce at the edge of the simulated range is not ranked among bounces all on one side.
                    let c: Vec<f64> = near.iter().map(|s| key(s)).collect();
                    let e: Vec<f64> = near.iter().map(|s| s.normal_restitution).collect();
                    let trend = line(&c, &e, 0..near.len()).slope;
                    let below: f64 = c
                        .iter()
                        .zip(&e)
                        .map(|(c, e)| match (e + trend * (key(o) - c)).total_cmp(&o.normal_restitution) {
                            std::cmp::Ordering::Less => 1.0,
                            std::cmp::Ordering::Equal => 0.5,
                            std::cmp::Ordering::Greater => 0.0,
                        })
                        .sum();
                    points.push([key(o), below / BOUNCE_NEIGHBOURS as f64]);
                }
            }
            BounceRanks { covariate, points }
        })
        .collect()
}

/// Per covariate of `ranks` ([`bounce_ranks`]), Spearman's rho of the rank against the covariate with a
/// permutation p-value over the bounces (residual [`BOUNCE_RESIDUAL`]); nothing under [`MIN_BOUNCES_DIAGNOSED`]
/// bounces. Bounces of one path are treated as independent given the model (ours).
pub fn bounce_diagnostics(ranks: &[BounceRanks], permutations: usize, seed: u64) -> Vec<Diagnostic> {
    let mut rng = stream(seed, BOUNCE_STREAM);
    ranks
        .iter()
        .filter(|r| r.points.len() >= MIN_BOUNCES_DIAGNOSED)
        .map(|r| {
            let (x, u): (Vec<f64>, Vec<f64>) = r.points.iter().map(|p| (p[0], p[1])).unzip();
            let (rho, p) = spearman_permutation(&x, &u, permutations, &mut rng);
            Diagnostic {
                covariate: r.covariate.into(),
                residual: BOUNCE_RESIDUAL.into(),
                spearman_rho: rho,
                p_value: p,
                n: x.len(),
            }
        })
        .collect()
}

/// `path` (times since release) read at `times_s` (since release): linear between its samples, its last position
/// after its end, each height plus Gaussian noise of sd `noise_m`.
fn at_times(path: &[TrackPoint], times_s: &[f64], noise_m: f64, rng: &mut Rng) -> Vec<TrackPoint> {
    let Some(last) = path.last() else { return Vec::new() };
    let t0 = path[0].time_s;
    let mut k = 0;
    times_s
        .iter()
        .map(|&tau| {
            let t = t0 + tau;
            while k + 1 < path.len() && path[k + 1].time_s <= t {
                k += 1;
            }
            let mut p = if k + 1 < path.len() && t > path[k].time_s {
                let (a, b) = (&path[k], &path[k + 1]);
                let f = (t - a.time_s) / (b.time_s - a.time_s);
                std::array::from_fn(|c| a.position_m[c] + f * (b.position_m[c] - a.position_m[c]))
            } else if t >= last.time_s {
                last.position_m
            } else {
                path[k].position_m
            };
            p[2] += noise_m * standard_normal(rng);
            TrackPoint { time_s: t, position_m: p }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point bouncing down the plane z = −x tan α with normal and tangential restitution `en`, `et`, from
    /// (0, 0, 2) at 3 m/s along x, sampled every `dt_s` with Gaussian noise of sd `sd` on the heights, until it
    /// has bounced `bounces` times; then 0.5 s at rest. Returns the track and the true (normal speed in, incidence)
    /// of each bounce.
    fn bouncing(
        alpha_deg: f64,
        en: f64,
        et: f64,
        bounces: usize,
        dt_s: f64,
        sd: f64,
    ) -> (Vec<TrackPoint>, Vec<(f64, f64)>) {
        let g = GRAVITY_MPS2;
        let (s, c) = alpha_deg.to_radians().sin_cos();
        let normal = [s, 0.0, c];
        let mut p = [0.0, 0.0, 2.0];
        let mut v = [3.0, 0.0, 0.0];
        let mut t0 = 0.0;
        let mut events = Vec::new(); // (start time, start position, start velocity)
        let mut truth = Vec::new();
        for _ in 0..=bounces {
            events.push((t0, p, v));
            // Height above the plane along its normal: d(τ) = d0 + vn τ − (g c / 2) τ².
            let d0 = p[0] * s + p[2] * c;
            let vn = v[0] * s + v[2] * c;
            let tau = (vn + (vn * vn + 2.0 * g * c * d0).sqrt()) / (g * c);
            p = [p[0] + v[0] * tau, p[1], p[2] + v[2] * tau - 0.5 * g * tau * tau];
            v[2] -= g * tau;
            t0 += tau;
            let vn_in = -(v[0] * normal[0] + v[2] * normal[2]);
            let vt = [v[0] + vn_in * normal[0], 0.0, v[2] + vn_in * normal[2]];
            let vt_len = (vt[0] * vt[0] + vt[2] * vt[2]).sqrt();
            truth.push((vn_in, vn_in.atan2(vt_len).to_degrees()));
            v = [et * vt[0] + en * vn_in * normal[0], 0.0, et * vt[2] + en * vn_in * normal[2]];
        }
        truth.pop();
        let end = t0;
        let mut rng = stream(5, 0);
        let mut track = Vec::new();
        let mut time = 0.0;
        while time < end + 0.5 {
            let k = events.iter().rposition(|e| e.0 <= time).unwrap();
            let pos = if time >= end {
                p
            } else {
                let (ts, ps, vs) = events[k];
                let tau = time - ts;
                [ps[0] + vs[0] * tau, 0.0, ps[2] + vs[2] * tau - 0.5 * g * tau * tau]
            };
            track.push(TrackPoint {
                time_s: time,
                position_m: [pos[0], pos[1], pos[2] + sd * standard_normal(&mut rng)],
            });
            time += dt_s;
        }
        (track, truth)
    }

    #[test]
    fn the_bounces_of_an_exact_track_give_back_their_restitution() {
        // Down a 20° plane, e_n 0.7 and e_t 0.8 (flights of 0.98 s down to 0.34 s), sampled at 50 Hz: every bounce
        // is found, with its speed, incidence and restitutions to 1e-6. With e_n 0.5 the fourth bounce's flights
        // (0.17 and 0.09 s) are within a window of each other and of the landing: the third and fourth are lost.
        let (alpha, en, et) = (20.0f64, 0.7, 0.8);
        let plane = move |x: f64, _y: f64| Some(-x * alpha.to_radians().tan());
        let (track, truth) = bouncing(alpha, en, et, 4, 0.02, 0.0);
        let found = read_impacts(&track, 0.0, &plane);
        assert_eq!(found.len(), truth.len(), "{found:?}");
        assert_eq!(read_impacts(&bouncing(alpha, 0.5, et, 4, 0.02, 0.0).0, 0.0, &plane).len(), 2);
        for (imp, &(vn, inc)) in found.iter().zip(&truth) {
            assert!((imp.normal_restitution - en).abs() < 1e-6, "{imp:?}");
            assert!((imp.tangential_restitution.unwrap() - et).abs() < 1e-6, "{imp:?}");
            assert!((imp.normal_speed_in_mps - vn).abs() < 1e-6 && (imp.incidence_deg - inc).abs() < 1e-4, "{imp:?}");
        }
    }

    #[test]
    fn noisy_tracks_give_the_restitution_within_five_hundredths_and_rest_gives_no_impact() {
        // The same at 1 kHz with noise of sd 2 cm on the heights: every bounce, within 0.05 of e_n and e_t.
        let (alpha, en, et) = (20.0f64, 0.7, 0.8);
        let plane = move |x: f64, _y: f64| Some(-x * alpha.to_radians().tan());
        let (track, truth) = bouncing(alpha, en, et, 4, 0.001, 0.02);
        let found = read_impacts(&track, 0.02, &plane);
        assert_eq!(found.len(), truth.len(), "{found:?}");
        for imp in &found {
            assert!((imp.normal_restitution - en).abs() < 0.05, "{imp:?}");
            assert!((imp.tangential_restitution.unwrap() - et).abs() < 0.05, "{imp:?}");
        }
        // A rock rolling at 2 m/s on level ground, tracked at 1 kHz with noise of 5 cm: no impact.
        let rolling: Vec<TrackPoint> = {
            let mut rng = stream(9, 0);
            (0..3000)
                .map(|i| {
                    let t = i as f64 * 0.001;
                    TrackPoint { time_s: t, position_m: [2.0 * t, 0.0, 0.2 + 0.05 * standard_normal(&mut rng)] }
                })
                .collect()
        };
        assert!(read_impacts(&rolling, 0.05, &|_, _| Some(0.0)).is_empty());
    }

    /// A bounce at normal speed `v` and incidence `deg` with normal restitution `en`.
    fn bounce(v: f64, deg: f64, en: f64) -> Impact {
        Impact {
            time_s: 0.0,
            point: 0,
            position_m: [0.0; 3],
            normal_speed_in_mps: v,
            tangential_speed_in_mps: 1.0,
            incidence_deg: deg,
            normal_restitution: en,
            tangential_restitution: None,
        }
    }

    #[test]
    fn bounce_diagnostics_see_a_restitution_falling_with_speed_that_the_model_lacks_and_nothing_where_it_has_it() {
        // Ten runs; the model's bounces (60 per run) come back at Cr 0.6 minus a reading's fall with speed that both
        // sides share (−0.04 per m/s), with scatter; the tracks (8 bounces a run) either the same (null) or with a
        // restitution that also falls as 1 / (1 + (v/6)²) around the median speed (the hidden effect).
        let mut rng = stream(11, 0);
        let draw = |hidden: bool, rng: &mut Rng| {
            let v = crate::random::uniform_in(rng, 2.0, 12.0);
            let deg = crate::random::uniform_in(rng, 20.0, 70.0);
            let shared = 0.6 - 0.04 * (v - 7.0) + 0.05 * standard_normal(rng);
            let en = if hidden { shared * (1.0 + (7.0f64 / 6.0).powi(2)) / (1.0 + (v / 6.0).powi(2)) } else { shared };
            bounce(v, deg, en)
        };
        for hidden in [false, true] {
            let mut runs = Vec::new();
            let mut simulated = Vec::new();
            for i in 0..10 {
                let mut run = crate::calibrate::metrics::tests::run(i, 0, 50.0);
                run.impacts = (0..8).map(|_| draw(hidden, &mut rng)).collect();
                runs.push(run);
                simulated.push((i, (0..60).map(|_| draw(false, &mut rng)).collect::<Vec<_>>()));
            }
            let d = bounce_diagnostics(&bounce_ranks(&runs, &simulated), 999, 1);
            assert_eq!(d.len(), 2);
            let speed = d.iter().find(|d| d.covariate == BOUNCE_NORMAL_SPEED).unwrap();
            let incidence = d.iter().find(|d| d.covariate == BOUNCE_INCIDENCE).unwrap();
            assert_eq!((speed.n, speed.residual.as_str()), (80, BOUNCE_RESIDUAL));
            // The incidence is independent of the restitution here: no signal either way.
            assert!(incidence.p_value > 0.05, "{incidence:?}");
            if hidden {
                assert!(speed.spearman_rho < -0.4 && speed.p_value < 0.01, "{speed:?}");
            } else {
                assert!(speed.p_value > 0.05, "{speed:?}");
            }
        }
        // Too few bounces: nothing.
        let runs = vec![crate::calibrate::metrics::tests::run(0, 0, 50.0)];
        assert!(bounce_diagnostics(&bounce_ranks(&runs, &[(0, vec![bounce(5.0, 45.0, 0.5); 20])]), 99, 1).is_empty());
    }
}
