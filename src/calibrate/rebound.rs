//! Rebound height: what a tracked path says about the bounces that run-out alone cannot.
//!
//! A run's **rebound height** is the largest rise of its centre of mass's height above the ground (measured
//! vertically, under the centre) over the lowest such height earlier on the path: max over t of
//! h(t) − min over s ≤ t of h(s) (ours). The fall from the release point counts for nothing (h only falls), the
//! first rebound counts from the impact, and later bounces from the lowest the rock has been, which is about its
//! resting height once it has touched the ground. The same function reads a simulated path and a tracked one, so
//! the two compare like for like. Noise on a tracked path raises it (by a median 0.13 m for Gaussian noise of sd
//! 0.1 m on every point of a 52-point path; docs/calibration.md, "Tracked paths").

use crate::error::{Error, Result};

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

/// The rebound height of a sequence of heights above the ground, m.
pub fn rebound_height_m(heights_m: impl IntoIterator<Item = f64>) -> f64 {
    let mut r = Rebound::default();
    for h in heights_m {
        r.offer(h);
    }
    r.height_m()
}

/// The rebound height of run `run_id`'s tracked path from its heights above the ground (non-finite where a point is
/// off the terrain or profile), m.
///
/// # Errors
/// No point of the path lies over the terrain: the track is in another frame, or lacks `y_m`.
pub fn observed_rebound_m(run_id: &str, heights_m: impl IntoIterator<Item = f64>) -> Result<f64> {
    let heights_m: Vec<f64> = heights_m.into_iter().collect();
    if !heights_m.iter().any(|h| h.is_finite()) {
        return Err(Error::invalid(
            format!("observed_trajectories.csv, run {run_id}"),
            "no tracked point lies over the terrain",
            "give the track in the frame of release_points.csv, with y_m on a 3D terrain",
        ));
    }
    Ok(rebound_height_m(heights_m))
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
}
