//! Numerical and stopping settings of the 3DRB engine.

use crate::error::{Error, Result};

/// When a material's coefficient of restitution is drawn from its distribution.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CrDraw {
    /// Once per rock and material (the rock keeps its draw for the whole run).
    #[default]
    PerRock,
    /// Anew at every impact.
    PerImpact,
}

/// Engine settings. Defaults follow physics.md §6 and §8; values marked "ours" are our own choice.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimParams {
    /// Time step while the rock is near or on the ground, s (default: 0.001; RAMMS uses 0.002, PlatRock 0.001).
    pub dt_s: f64,
    /// Longest exact ballistic step while the rock is clear of the ground, s (default: 0.25, ours).
    pub max_flight_step_s: f64,
    /// Simulated time after which a rock is stopped with reason `max_time`, s (default: 120).
    pub max_time_s: f64,
    /// Normal approach speed below which a contact gets no bounce (restitution 0), m/s (default: 0.3; physics.md
    /// §8 gives 0.2–0.5).
    pub bounce_threshold_mps: f64,
    /// Rest test: speed of the centre of mass below this, m/s (default: 0.1, physics.md §8).
    pub stop_speed_mps: f64,
    /// Rest test: angular speed below this, rad/s (default: 0.2, physics.md §8).
    pub stop_spin_radps: f64,
    /// Rest test: how long both must hold, s (default: 0.5, physics.md §8).
    pub stop_duration_s: f64,
    /// Penetration left uncorrected, m (default: 0.002, ours). Deeper penetration is projected out (position only,
    /// never velocity).
    pub penetration_slop_m: f64,
    /// Most Gauss–Seidel sweeps of the contact solver (default: 100; sweeps stop earlier once converged).
    pub solver_iterations: usize,
    /// When restitution coefficients are drawn (default: per rock).
    pub cr_draw: CrDraw,
    /// Horizontal spacing of the path samples that feed rasters and collectors, m (default: 0.5).
    pub sample_spacing_m: f64,
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            dt_s: 0.002,
            max_flight_step_s: 0.25,
            max_time_s: 120.0,
            bounce_threshold_mps: 0.3,
            stop_speed_mps: 0.1,
            stop_spin_radps: 0.2,
            stop_duration_s: 0.5,
            penetration_slop_m: 0.002,
            solver_iterations: 100,
            cr_draw: CrDraw::PerRock,
            sample_spacing_m: 0.5,
        }
    }
}

impl SimParams {
    /// Checks ranges; `prefix` is prepended to field names in errors (e.g. `simulation.`).
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let pos = |name: &str, v: f64, hint: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(format!("{prefix}{name}"), format!("must be a positive number, got {v}"), hint))
            }
        };
        pos("dt_s", self.dt_s, "use a step of 0.0005 to 0.002 s")?;
        if self.dt_s > 0.01 {
            return Err(Error::invalid(format!("{prefix}dt_s"), format!("{} s is too coarse for contact", self.dt_s), "use 0.0005 to 0.002 s"));
        }
        pos("max_flight_step_s", self.max_flight_step_s, "use about 0.25 s")?;
        pos("max_time_s", self.max_time_s, "use for example 120 s")?;
        pos("stop_speed_mps", self.stop_speed_mps, "use about 0.1 m/s")?;
        pos("stop_spin_radps", self.stop_spin_radps, "use about 0.2 rad/s")?;
        pos("stop_duration_s", self.stop_duration_s, "use about 0.5 s")?;
        pos("sample_spacing_m", self.sample_spacing_m, "use half the raster cell size or less")?;
        for (name, v) in [
            ("bounce_threshold_mps", self.bounce_threshold_mps),
            ("penetration_slop_m", self.penetration_slop_m),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(format!("{prefix}{name}"), format!("must be 0 or more, got {v}"), "give a small non-negative number"));
            }
        }
        if self.solver_iterations == 0 {
            return Err(Error::invalid(format!("{prefix}solver_iterations"), "must be at least 1", "use for example 100"));
        }
        Ok(())
    }
}
