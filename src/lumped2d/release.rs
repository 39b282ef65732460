//! Where and how rocks are released on a profile: uniform draws in ranges, one stream per rock.
//!
//! # Units
//! Positions and heights in m, speeds in m/s, spin in rad/s, mass in kg.

use super::engine::RockStart2d;
use super::profile::Profile;
use crate::error::{number_text, Error, Result};
use crate::random::{uniform_in, Rng};
use crate::source::{MAX_RELEASE_HEIGHT_M, MAX_RELEASE_SPEED_MPS, MAX_RELEASE_SPIN_RADPS};
use serde::de::{self, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

/// A closed range `[min, max]` drawn uniformly; in TOML a number (fixed) or `[min, max]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ValueRange {
    /// Lower end.
    pub min: f64,
    /// Upper end (equal to `min` for a fixed value).
    pub max: f64,
}

impl Default for ValueRange {
    /// The fixed value 0.
    fn default() -> Self {
        ValueRange::fixed(0.0)
    }
}

impl ValueRange {
    /// A fixed value.
    pub const fn fixed(v: f64) -> Self {
        ValueRange { min: v, max: v }
    }

    /// The range `[min, max]`.
    pub const fn new(min: f64, max: f64) -> Self {
        ValueRange { min, max }
    }

    /// A uniform draw (no draw is consumed for a fixed value).
    pub fn sample(&self, rng: &mut Rng) -> f64 {
        uniform_in(rng, self.min, self.max)
    }

    fn check(&self, field: &str, lo: f64, hi: f64, what: &str) -> Result<()> {
        if !(self.min.is_finite() && self.max.is_finite()) || self.min > self.max {
            return Err(Error::invalid(
                field,
                format!("[{}, {}] is not an ordered pair of finite numbers", self.min, self.max),
                "give a number or [min, max] with min <= max",
            ));
        }
        if self.min < lo || self.max > hi {
            return Err(Error::invalid(
                field,
                format!("[{}, {}] is outside {what} [{lo}, {hi}]", number_text(self.min), number_text(self.max)),
                format!("keep it within {what}"),
            ));
        }
        Ok(())
    }
}

impl<'de> Deserialize<'de> for ValueRange {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ValueRange;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or [min, max]")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<ValueRange, E> {
                Ok(ValueRange::fixed(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<ValueRange, E> {
                Ok(ValueRange::fixed(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<ValueRange, E> {
                Ok(ValueRange::fixed(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<ValueRange, A::Error> {
                let min: f64 = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(0, &self))?;
                let max: f64 = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(1, &self))?;
                if seq.next_element::<f64>()?.is_some() {
                    return Err(de::Error::invalid_length(3, &self));
                }
                Ok(ValueRange { min, max })
            }
        }
        deserializer.deserialize_any(V)
    }
}

/// How rocks are released: each rock draws its position, height and velocity uniformly from these ranges.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Release2d {
    /// Release x, m.
    pub x_m: ValueRange,
    /// Height of the release point above the profile, measured vertically, m (0 = on the ground).
    pub height_m: ValueRange,
    /// Initial horizontal velocity, m/s.
    pub vx_mps: ValueRange,
    /// Initial vertical velocity (up positive), m/s.
    pub vz_mps: ValueRange,
    /// Initial spin, rad/s, clockwise positive in the x–z view (used only by the rotational rules).
    pub spin_radps: ValueRange,
    /// Rock mass, kg.
    pub mass_kg: f64,
}

impl Release2d {
    /// Rocks of `mass_kg` dropped from rest `height_m` above the profile at `x_m`.
    pub fn point(x_m: f64, height_m: f64, mass_kg: f64) -> Release2d {
        Release2d {
            x_m: ValueRange::fixed(x_m),
            height_m: ValueRange::fixed(height_m),
            vx_mps: ValueRange::fixed(0.0),
            vz_mps: ValueRange::fixed(0.0),
            spin_radps: ValueRange::fixed(0.0),
            mass_kg,
        }
    }

    /// The ranges that `starts` span (height above `profile`) and their mean mass: a description of a set of
    /// given starts, as `summary.json` reports them. `starts` must not be empty and must lie over `profile`.
    pub fn spanning(starts: &[RockStart2d], profile: &Profile) -> Release2d {
        let span = |f: &dyn Fn(&RockStart2d) -> f64| {
            let v = starts.iter().map(f);
            ValueRange::new(v.clone().fold(f64::INFINITY, f64::min), v.fold(f64::NEG_INFINITY, f64::max))
        };
        Release2d {
            x_m: span(&|s| s.x_m),
            height_m: span(&|s| s.z_m - profile.z_at(s.x_m).unwrap_or(s.z_m)),
            vx_mps: span(&|s| s.vx_mps),
            vz_mps: span(&|s| s.vz_mps),
            spin_radps: span(&|s| s.spin_radps),
            mass_kg: starts.iter().map(|s| s.mass_kg).sum::<f64>() / starts.len() as f64,
        }
    }

    /// The same release with the horizontal velocity drawn from `[min, max]` m/s.
    #[must_use]
    pub fn with_vx_mps(mut self, min: f64, max: f64) -> Release2d {
        self.vx_mps = ValueRange::new(min, max);
        self
    }

    /// The same release with x drawn from `[min, max]` m.
    #[must_use]
    pub fn with_x_m(mut self, min: f64, max: f64) -> Release2d {
        self.x_m = ValueRange::new(min, max);
        self
    }

    /// Checks the ranges against the profile; `prefix` (e.g. `release.`) is prepended to field names in errors.
    ///
    /// # Errors
    /// x outside the profile, a negative height, non-finite values, or a mass that is not positive.
    pub fn validate(&self, profile: &Profile, prefix: &str) -> Result<()> {
        let (x0, x1) = profile.x_range_m();
        self.x_m.check(&format!("{prefix}x_m"), x0, x1, "the profile's x range")?;
        let (h, v, w) = (MAX_RELEASE_HEIGHT_M, MAX_RELEASE_SPEED_MPS, MAX_RELEASE_SPIN_RADPS);
        self.height_m.check(&format!("{prefix}height_m"), 0.0, h, "the release heights above the ground, m")?;
        self.vx_mps.check(&format!("{prefix}vx_mps"), -v, v, "the release speeds, m/s")?;
        self.vz_mps.check(&format!("{prefix}vz_mps"), -v, v, "the release speeds, m/s")?;
        self.spin_radps.check(&format!("{prefix}spin_radps"), -w, w, "the release spins, rad/s")?;
        if !(self.mass_kg.is_finite() && self.mass_kg > 0.0) {
            return Err(Error::invalid(
                format!("{prefix}mass_kg"),
                format!("must be a positive number of kilograms, got {}", self.mass_kg),
                "give the rock mass in kg, e.g. 1000",
            ));
        }
        Ok(())
    }

    /// Draws one rock's start (x, height, vx, vz, spin, in that order).
    pub fn sample(&self, profile: &Profile, rng: &mut Rng) -> RockStart2d {
        let x = self.x_m.sample(rng);
        let h = self.height_m.sample(rng);
        let vx = self.vx_mps.sample(rng);
        let vz = self.vz_mps.sample(rng);
        let spin = self.spin_radps.sample(rng);
        let z = profile.z_at(x).unwrap_or(0.0) + h;
        RockStart2d { x_m: x, z_m: z, vx_mps: vx, vz_mps: vz, spin_radps: spin, mass_kg: self.mass_kg }
    }
}
