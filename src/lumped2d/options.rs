//! Engine options: the optional physics (off by default, as in RocFall) and the thresholds of the event-driven
//! engine, each with its default.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// How the tangential velocity changes at an impact.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Rotation {
    /// v_t′ = Rt·v_t; spin is not tracked (default, RocFall's lumped mass).
    #[default]
    Off,
    /// RocFall's "consider rotational velocity" (physics.md §3):
    /// v_t′ = √(R²(Iω² + m v_t²)·Rt / (I + mR²)), ω′ = v_t′/R, for a solid sphere.
    Rocfall,
    /// The full CRSP form (physics.md §4): Rt above is replaced by Ff·SF with
    /// Ff = Rt + (1 − Rt)/(((v_t − ωR)/6.096)² + 1.2) and SF = Rt/((v_n/(76.2·Rn))² + 1), speeds in m/s.
    Crsp,
}

/// A project-wide override of the materials' friction rule (RocFall's friction-angle setting).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionSource {
    /// Each material's own rule (default).
    #[default]
    Material,
    /// φ = atan((1 − Rt)/Rt) on every material.
    FromRt,
    /// φ = 0 (rolling) on every material.
    Zero,
}

/// Options of the 2D lumped-mass engine. Everything not done by RocFall by default is off.
///
/// # Units
/// Speeds in m/s, times in s, density in kg/m³.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options2d {
    /// Scale Rn by the normal impact speed (Pfeiffer & Bowen 1989): Rn′ = Rn/(1 + (|v_n|/K)²), K =
    /// `rn_velocity_scale_mps` (default: false).
    pub scale_rn_by_velocity: bool,
    /// K of the Pfeiffer–Bowen rule, the normal speed at which Rn is halved, m/s (default: their 9.144 m/s).
    pub rn_velocity_scale_mps: f64,
    /// Scale Rn by the rock's mass: Rn′ = min(1, Rn (m/m_ref)^−β) with β this exponent (default: 0 = off;
    /// physics.md §8's f_m, RocFall's "scale Rn by mass"; negative β makes heavier rocks bounce more).
    pub rn_mass_exponent: f64,
    /// m_ref of the mass rule, kg (default: 1000).
    pub rn_reference_mass_kg: f64,
    /// Tangential impact rule with or without spin (default: [`Rotation::Off`]).
    pub rotation: Rotation,
    /// Override of the materials' friction rule (default: [`FrictionSource::Material`]).
    pub friction_angle: FrictionSource,
    /// Rock density used to size the rock as a solid sphere (radius for the arrow-height switch and the rotational
    /// forms), kg/m³ (default: 2650).
    pub rock_density_kg_m3: f64,
    /// Switch from flight to sliding when the normal speed leaving an impact is below this, m/s (default: 0.5).
    pub switch_speed_mps: f64,
    /// Switch from flight to sliding when the next parabola's arrow height (its greatest distance from the
    /// segment line) is below this fraction of the rock radius (default: 0.1, PlatRock's rule; 0 disables it).
    pub arrow_height_ratio: f64,
    /// A touch-down with an incoming normal speed below this is a transition to sliding that keeps the tangential
    /// speed, not an impact, m/s (default: 0 = off, every touch-down is an impact as in RocFall). Setting it to
    /// about `switch_speed_mps` stops rocks losing (1 − Rt) of their speed at each small convex kink of a sampled
    /// profile.
    pub soft_landing_mps: f64,
    /// A sliding rock stops when its speed is below this, it is not accelerating, and friction can hold it on the
    /// segment (tan θ ≤ tan φ), m/s (default: 0.1). Above this speed the stopping point is found in closed form.
    pub stop_speed_mps: f64,
    /// Largest number of events (flights, impacts and slide pieces) per rock (default: 10,000).
    pub max_events: u32,
    /// Largest travel time per rock, s (default: 600).
    pub max_time_s: f64,
}

impl Default for Options2d {
    fn default() -> Self {
        Options2d {
            scale_rn_by_velocity: false,
            rn_velocity_scale_mps: super::engine::PFEIFFER_BOWEN_MPS,
            rn_mass_exponent: 0.0,
            rn_reference_mass_kg: 1000.0,
            rotation: Rotation::Off,
            friction_angle: FrictionSource::Material,
            rock_density_kg_m3: 2650.0,
            switch_speed_mps: 0.5,
            arrow_height_ratio: 0.1,
            soft_landing_mps: 0.0,
            stop_speed_mps: 0.1,
            max_events: 10_000,
            max_time_s: 600.0,
        }
    }
}

impl Options2d {
    /// The factor on Rn for a rock of `mass_kg` (1 when the mass rule is off).
    pub fn rn_mass_factor(&self, mass_kg: f64) -> f64 {
        if self.rn_mass_exponent == 0.0 {
            1.0
        } else {
            (mass_kg / self.rn_reference_mass_kg).powf(-self.rn_mass_exponent)
        }
    }

    /// Radius of a solid sphere of `mass_kg` at the rock density, m.
    pub fn radius_m(&self, mass_kg: f64) -> f64 {
        (3.0 * mass_kg / (4.0 * std::f64::consts::PI * self.rock_density_kg_m3)).cbrt()
    }

    /// Checks ranges; `prefix` (e.g. `options.`) is prepended to field names in errors.
    ///
    /// # Errors
    /// A negative or non-finite threshold, a non-positive density or time limit, or `max_events` of 0.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let check = |name: &str, v: f64, positive: bool| {
            let ok = v.is_finite() && if positive { v > 0.0 } else { v >= 0.0 };
            if ok {
                Ok(())
            } else {
                Err(Error::invalid(
                    format!("{prefix}{name}"),
                    format!("must be a {} number, got {v}", if positive { "positive" } else { "non-negative" }),
                    "fix the value or leave it out for the default",
                ))
            }
        };
        check("rock_density_kg_m3", self.rock_density_kg_m3, true)?;
        check("rn_velocity_scale_mps", self.rn_velocity_scale_mps, true)?;
        check("rn_reference_mass_kg", self.rn_reference_mass_kg, true)?;
        if !self.rn_mass_exponent.is_finite() {
            return Err(Error::invalid(
                format!("{prefix}rn_mass_exponent"),
                format!("must be a finite number, got {}", self.rn_mass_exponent),
                "e.g. 0.3, or leave it out (0 = off)",
            ));
        }
        check("switch_speed_mps", self.switch_speed_mps, false)?;
        check("arrow_height_ratio", self.arrow_height_ratio, false)?;
        check("soft_landing_mps", self.soft_landing_mps, false)?;
        check("stop_speed_mps", self.stop_speed_mps, false)?;
        check("max_time_s", self.max_time_s, true)?;
        if self.max_events == 0 {
            return Err(Error::invalid(format!("{prefix}max_events"), "must be at least 1", "e.g. 10000"));
        }
        Ok(())
    }
}
