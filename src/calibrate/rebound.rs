//! Rebound height: what a tracked path says about the bounces that run-out alone cannot.
//!
//! A run's **rebound height** is the largest rise of its centre of mass's height above the ground (measured
//! vertically, under the centre) over the lowest such height earlier on the path: max over t of
//! h(t) − min over s ≤ t of h(s) (ours). The fall from the release point counts for nothing (h only falls), the
//! first rebound counts from the impact, and later bounces from the lowest the rock has been, which is about its
//! resting height once it has touched the ground. The same function reads a simulated path and a tracked one, so
//! the two compare like for like. Noise on a tracked path raises it (by a median 0.13 m for Gaussian noise of sd
//! 0.1 m on every point of a 52-point path; docs/calibration.md, "Tracked paths"). With the tracking noise declared
//! (`track_noise_m`), a simulated path is measured as its run's track was ([`ReboundMeter::at_track_times`]): at the
//! track's own times, each height plus noise of that sd, so the noise raises both alike (ours: a forward model of
//! the tracking system, in place of smoothing the track).

use super::impacts::Impact;
use super::runs::FieldRun;
use super::stats::median;
use crate::campaign::TrackPoint;
use crate::error::{Error, Result};
use crate::random::{standard_normal, stream, Rng};
use std::collections::BTreeMap;

/// Streams heights above the ground and keeps the largest rise over the lowest earlier height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rebound {
    lowest_m: f64,
    rise_m: f64,
}

impl Default for Rebound {
    fn default() -> Self {
        Rebound { lowest_m: f64::INFINITY, rise_m: 0.0 }
    }
}

impl Rebound {
    /// Offers the next height of the centre above the ground, m (non-finite heights, off the terrain, are skipped).
    pub fn offer(&mut self, height_m: f64) {
        if !height_m.is_finite() {
            return;
        }
        self.lowest_m = self.lowest_m.min(height_m);
        self.rise_m = self.rise_m.max(height_m - self.lowest_m);
    }

    /// The rebound height so far, m (0 before any rise).
    pub fn height_m(&self) -> f64 {
        self.rise_m
    }
}

/// Measures a simulated path's rebound height: from every sample of the path, or as its run's track measured it.
pub struct ReboundMeter<'a> {
    rebound: Rebound,
    track: Option<TrackSampling<'a>>,
}

/// The path read at the track's times, with the tracking noise.
struct TrackSampling<'a> {
    /// Times of the track's points since its first one (taken as the release), s, ascending.
    times_s: &'a [f64],
    /// The next of them to read.
    next: usize,
    /// The last sample offered: (time since release, s; height, m).
    last: Option<(f64, f64)>,
    noise_sd_m: f64,
    rng: Rng,
}

impl<'a> ReboundMeter<'a> {
    /// Every sample of the path counts, as it is.
    pub fn every_sample() -> Self {
        ReboundMeter { rebound: Rebound::default(), track: None }
    }

    /// The path is read at `times_s` (since the release; linear between samples, the resting height after the
    /// path's end), each height plus Gaussian noise of sd `noise_sd_m` drawn from `rng`.
    pub fn at_track_times(times_s: &'a [f64], noise_sd_m: f64, rng: Rng) -> Self {
        let track = TrackSampling { times_s, next: 0, last: None, noise_sd_m, rng };
        ReboundMeter { rebound: Rebound::default(), track: Some(track) }
    }

    /// Offers the path's height above the ground at `t_s` since the release, m (samples in time order).
    pub fn offer(&mut self, t_s: f64, height_m: f64) {
        let Some(tr) = &mut self.track else {
            self.rebound.offer(height_m);
            return;
        };
        let (t0, h0) = tr.last.unwrap_or((t_s, height_m));
        while let Some(&tau) = tr.times_s.get(tr.next).filter(|&&tau| tau <= t_s) {
            let h = if t_s > t0 && tau > t0 { h0 + (height_m - h0) * (tau - t0) / (t_s - t0) } else { h0 };
            self.rebound.offer(h + tr.noise_sd_m * standard_normal(&mut tr.rng));
            tr.next += 1;
        }
        tr.last = Some((t_s, height_m));
    }

    /// The rebound height of the path, m: the track's times after the path's end read its last height.
    pub fn finish(mut self) -> f64 {
        if let Some(tr) = &mut self.track {
            let h = tr.last.map_or(f64::NAN, |l| l.1);
            for _ in tr.next..tr.times_s.len() {
                self.rebound.offer(h + tr.noise_sd_m * standard_normal(&mut tr.rng));
            }
        }
        self.rebound.height_m()
    }
}

/// The meter of simulation `repeat` of `run` under `seed`: at the run's track times with noise of sd
/// `track_noise_m` if that is set and the run has a track, otherwise every sample. The noise has its own random
/// stream, so the simulation draws the same numbers either way.
pub fn rebound_meter(track_noise_m: Option<f64>, run: &FieldRun, repeat: usize, seed: u64) -> ReboundMeter<'_> {
    match track_noise_m {
        Some(sd) if !run.track_times_s.is_empty() => ReboundMeter::at_track_times(
            &run.track_times_s,
            sd,
            stream(seed ^ TRACK_NOISE_SEED, super::model::stream_index(run.index, repeat)),
        ),
        _ => ReboundMeter::every_sample(),
    }
}

/// Seeds the tracking-noise streams apart from the simulations' (`seed ^ this`).
const TRACK_NOISE_SEED: u64 = 0x7472_6163_6b5f_6e6f;

/// Track scatter ([`track_scatter_m`]) from which `talus calibrate` suggests declaring it as `track_noise_m` when
/// none is declared, m (ours: 1 cm, far above the 0.3 mm of heights rounded to the millimetre).
pub const TRACK_SCATTER_HINT_M: f64 = 0.01;

/// How far a track's heights scatter around a smooth path, an estimate of the tracking noise's sd in m (ours): each
/// point's deviation from the parabola through the two points before it and the one after it (by time), divided by
/// what that deviation's sd would be for independent noise of sd 1 (√(1 + ΣLᵢ²), Lᵢ the three points' Lagrange
/// weights), then 1.4826 × the median absolute deviation of these around their median. A parabola in time follows
/// any motion of constant vertical acceleration exactly: a free flight, and rolling or sliding down a plane; the
/// few points near impacts do not move a median, so what remains is the tracking noise. `None` for a track of
/// fewer than 6 points.
pub fn track_scatter_m(track: &[TrackPoint]) -> Option<f64> {
    let dev: Vec<f64> = track
        .windows(4)
        .filter_map(|w| {
            let t = w[2].time_s;
            if !(w[0].time_s < w[1].time_s && w[1].time_s < t && t < w[3].time_s) {
                return None;
            }
            let others = [&w[0], &w[1], &w[3]];
            let mut predicted = 0.0;
            let mut sum_sq = 0.0;
            for (i, p) in others.iter().enumerate() {
                let mut weight = 1.0;
                for (j, q) in others.iter().enumerate() {
                    if i != j {
                        weight *= (t - q.time_s) / (p.time_s - q.time_s);
                    }
                }
                predicted += weight * p.position_m[2];
                sum_sq += weight * weight;
            }
            Some((w[2].position_m[2] - predicted) / (1.0 + sum_sq).sqrt())
        })
        .collect();
    if dev.len() < 3 {
        return None;
    }
    let centre = median(&dev);
    let spread: Vec<f64> = dev.iter().map(|d| (d - centre).abs()).collect();
    Some(1.4826 * median(&spread))
}

/// The rebound height of a sequence of heights above the ground, m.
pub fn rebound_height_m(heights_m: impl IntoIterator<Item = f64>) -> f64 {
    let mut r = Rebound::default();
    for h in heights_m {
        r.offer(h);
    }
    r.height_m()
}

/// Gives each run of `runs` that has a track in `tracks` (by run id) its tracked path ([`attach_track`], with
/// `height_m` the height of a track point above the ground, non-finite off it) and the bounces `read` reads from
/// it under the declared tracking noise `track_noise_m` or, undeclared, the track's own scatter. True if any run
/// is tracked.
///
/// # Errors
/// As [`attach_track`].
pub fn attach_tracks(
    runs: &mut [FieldRun],
    tracks: &BTreeMap<String, Vec<TrackPoint>>,
    track_noise_m: Option<f64>,
    height_m: impl Fn(&TrackPoint) -> f64,
    read: impl Fn(&[TrackPoint], f64) -> Vec<Impact>,
) -> Result<bool> {
    let mut any = false;
    for run in runs.iter_mut() {
        if let Some(track) = tracks.get(&run.id) {
            attach_track(run, track, track.iter().map(&height_m).collect())?;
            run.impacts = read(track, track_noise_m.or(run.track_scatter_m).unwrap_or(0.0));
            any = true;
        }
    }
    Ok(any)
}

/// Gives `run` its tracked path: the observed rebound height from the heights of the track's points above the
/// ground (`heights_m`, one per point, non-finite where a point is off the terrain or profile) and the track's times
/// since its first point ([`ReboundMeter::at_track_times`]).
///
/// # Errors
/// No point of the path lies over the terrain: the track is in another frame, or lacks `y_m`.
pub fn attach_track(run: &mut FieldRun, track: &[TrackPoint], heights_m: Vec<f64>) -> Result<()> {
    if !heights_m.iter().any(|h| h.is_finite()) {
        return Err(Error::invalid(
            format!("observed_trajectories.csv, run {}", run.id),
            "no tracked point lies over the terrain",
            "give the track in the frame of release_points.csv, with y_m on a 3D terrain",
        ));
    }
    run.rebound_height_m = Some(rebound_height_m(heights_m));
    run.track_scatter_m = track_scatter_m(track);
    run.track_times_s = track.iter().map(|q| q.time_s - track[0].time_s).collect();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drop_counts_only_the_rise_after_the_impact() {
        // Dropped from 20 m, bounces to 3 m above the impact height 0.2 m, later rises 1 m off a lower rest.
        let path = [20.0, 15.0, 8.0, 0.2, 1.5, 3.2, 2.0, 0.2, 0.15, 1.15, 0.15];
        assert!((rebound_height_m(path) - 3.0).abs() < 1e-12);
        // Only falling: no rebound.
        assert_eq!(rebound_height_m([5.0, 4.0, 1.0, 0.2]), 0.0);
        // Off-terrain heights are skipped.
        assert!((rebound_height_m([f64::NAN, 2.0, 0.5, f64::INFINITY, 1.5]) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_scatter_of_a_track_estimates_its_noise_and_ignores_gravity_and_impacts() {
        // A block thrown up and bouncing on level ground (flights of 1 s and 0.6 s, an impact between), then
        // rolling for 1.4 s, tracked every millisecond: exact, the scatter is far below a millimetre; with Gaussian
        // noise of sd 0.05 m on every height, it is that sd within 10 %. Tracked at uneven times (0.04 s and 0.1 s
        // apart by turns), where gravity bends a flight by 20 mm between neighbours and rolling does not, an exact
        // track still scatters by under a millimetre (measured from the line through the neighbours: 23 mm), and a
        // noisy one rolling on for 27 s more (430 points) by its noise within 15 %.
        let g = crate::sim::GRAVITY_MPS2;
        let height = |t: f64| match t {
            t if t < 1.0 => 0.5 * g * t * (1.0 - t),
            t if t < 1.6 => 0.5 * g * (t - 1.0) * (1.6 - t),
            _ => 0.0,
        };
        let track = |steps_s: &[f64], sd: f64, end_s: f64| -> Vec<TrackPoint> {
            let mut rng = crate::random::stream(3, 0);
            let mut t = 0.0;
            let mut points = Vec::new();
            for k in 0.. {
                if t > end_s {
                    break;
                }
                points.push(TrackPoint { time_s: t, position_m: [t, 0.0, height(t) + sd * standard_normal(&mut rng)] });
                t += steps_s[k % steps_s.len()];
            }
            points
        };
        assert!(track_scatter_m(&track(&[0.001], 0.0, 3.0)).unwrap() < 1e-4);
        let noisy = track_scatter_m(&track(&[0.001], 0.05, 3.0)).unwrap();
        assert!((noisy / 0.05 - 1.0).abs() < 0.1, "{noisy}");
        assert!(track_scatter_m(&track(&[0.04, 0.1], 0.0, 3.0)).unwrap() < 1e-3);
        let sparse = track_scatter_m(&track(&[0.04, 0.1], 0.05, 30.0)).unwrap();
        assert!((sparse / 0.05 - 1.0).abs() < 0.15, "{sparse}");
        assert_eq!(track_scatter_m(&track(&[0.8], 0.0, 3.0)), None);
    }

    #[test]
    fn a_path_read_at_track_times_is_interpolated_and_rests_after_its_end() {
        // Impact at t = 1 s (height 0), apex 2 m at t = 1.5 s, down again at 2 s. A track read every 0.25 s from
        // the release to 3 s, without noise, reads the apex (1.5 s is one of its times).
        let path = [(0.0, 5.0), (1.0, 0.0), (1.5, 2.0), (2.0, 0.0)];
        let times: Vec<f64> = (0..=12).map(|i| 0.25 * i as f64).collect();
        let mut m = ReboundMeter::at_track_times(&times, 0.0, crate::random::stream(1, 0));
        for (t, h) in path {
            m.offer(t, h);
        }
        assert!((m.finish() - 2.0).abs() < 1e-12);
        // A track read only at 1.25 and 1.75 s sees half the apex (linear between the path's samples).
        let mut m = ReboundMeter::at_track_times(&[0.0, 1.0, 1.25, 1.75], 0.0, crate::random::stream(1, 0));
        for (t, h) in path {
            m.offer(t, h);
        }
        assert!((m.finish() - 1.0).abs() < 1e-12);
        // Noise of sd 0.1 m on a path at rest after its impact: the largest rise of 40 noisy readings, about the
        // range of 40 normal draws (≈ 4.5 sd), never read from the noise-free path (0).
        let times: Vec<f64> = (0..40).map(|i| 0.1 * i as f64).collect();
        let mut m = ReboundMeter::at_track_times(&times, 0.1, crate::random::stream(1, 0));
        m.offer(0.0, 0.0);
        let rise = m.finish();
        assert!(rise > 0.2 && rise < 0.8, "{rise}");
        let mut m = ReboundMeter::every_sample();
        for (t, h) in path {
            m.offer(t, h);
        }
        assert_eq!(m.finish(), 2.0);
    }
}
