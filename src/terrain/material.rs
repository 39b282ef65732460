//! 3DRB ground materials: one coefficient of restitution plus static and dynamic friction angles (Trajec3D's
//! parameter set, used by the seed paper), and the paper's Table 2 rows as named presets.

use crate::error::{Error, Result};
use crate::random::{Rng, TruncNormal};

/// A ground material for 3D rigid-body rocks.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Material {
    /// Name used in scenarios and outputs.
    pub name: String,
    /// Coefficient of restitution Cr (Newton, normal contact velocity), truncated to [0, 1].
    pub cr: TruncNormal,
    /// Static friction angle, degrees: a sticking contact holds while |P_t| ≤ tan(φ_s)·P_n.
    pub static_friction_deg: f64,
    /// Dynamic friction angle, degrees: a slipping contact gets |P_t| = tan(φ_d)·P_n.
    pub dynamic_friction_deg: f64,
    /// Spread of the dynamic friction angle between rocks, degrees (0 = none): each rock draws its own angle once,
    /// from a normal of this sd truncated at ±3 sd and to [0, 89]°, and its static angle is raised to the drawn
    /// one where that is larger. RocFall draws its material inputs from normal distributions truncated at ±3σ
    /// (physics.md §3); one draw per rock (not per contact), standing for ground that differs from path to path,
    /// is ours.
    pub dynamic_friction_sd_deg: f64,
    /// Soft-ground drag: while a rock touches this material its velocity and spin decay as exp(−c·t), c this
    /// rate, 1/s (0 = none; a linear stand-in for RAMMS's scarring drag, Lu et al. 2019, physics.md §2; ours).
    pub drag_per_s: f64,
}

/// The seed paper's Table 2 (3DRB calibrated parameters): (preset name, Cr mean, Cr sd, static °, dynamic °).
/// Friction columns are merged cells in the source; floors 65/60 and faces 50/40 is the reading of the layout.
pub const TABLE2_PRESETS: [(&str, f64, f64, f64, f64); 6] = [
    ("floor_bench", 0.037, 0.021, 65.0, 60.0),
    ("floor_haul_road", 0.074, 0.021, 65.0, 60.0),
    ("floor_all", 0.049, 0.028, 65.0, 60.0),
    ("face_weathered", 0.125, 0.028, 50.0, 40.0),
    ("face_fresh", 0.164, 0.065, 50.0, 40.0),
    ("face_all", 0.155, 0.060, 50.0, 40.0),
];

impl Material {
    /// A Table 2 preset under its own name, Cr truncated at ±3 sd and to [0, 1].
    pub fn preset(preset: &str) -> Option<Material> {
        TABLE2_PRESETS.iter().find(|p| p.0 == preset).map(|&(n, m, sd, s, d)| Material {
            name: n.to_string(),
            cr: TruncNormal::three_sigma(m, sd, 0.0, 1.0),
            static_friction_deg: s,
            dynamic_friction_deg: d,
            dynamic_friction_sd_deg: 0.0,
            drag_per_s: 0.0,
        })
    }

    /// Checks ranges; `field` is the material's place in the scenario (e.g. `materials.face`).
    pub fn validate(&self, field: &str) -> Result<()> {
        self.cr.validate(&format!("{field}.cr"), 0.0, 1.0)?;
        for (name, v) in
            [("static_friction_deg", self.static_friction_deg), ("dynamic_friction_deg", self.dynamic_friction_deg)]
        {
            if !(v.is_finite() && (0.0..90.0).contains(&v)) {
                return Err(Error::invalid(
                    format!("{field}.{name}"),
                    format!("must be in [0, 90) degrees, got {v}"),
                    "give a friction angle such as 40",
                ));
            }
        }
        if !(self.dynamic_friction_sd_deg.is_finite() && (0.0..=30.0).contains(&self.dynamic_friction_sd_deg)) {
            return Err(Error::invalid(
                format!("{field}.dynamic_friction_sd_deg"),
                format!("must be in [0, 30] degrees, got {}", self.dynamic_friction_sd_deg),
                "give 0 (every rock the same) or a spread such as 3",
            ));
        }
        if !(self.drag_per_s.is_finite() && self.drag_per_s >= 0.0) {
            return Err(Error::invalid(
                format!("{field}.drag_per_s"),
                format!("must be a non-negative rate, got {}", self.drag_per_s),
                "give 0 (no drag) or a rate such as 3",
            ));
        }
        if self.dynamic_friction_deg > self.static_friction_deg {
            return Err(Error::invalid(
                format!("{field}.dynamic_friction_deg"),
                format!(
                    "{} is larger than the static friction angle {}",
                    self.dynamic_friction_deg, self.static_friction_deg
                ),
                "dynamic friction cannot exceed static friction; lower it or raise static_friction_deg",
            ));
        }
        Ok(())
    }

    /// tan of the static friction angle.
    pub fn mu_static(&self) -> f64 {
        self.static_friction_deg.to_radians().tan()
    }

    /// tan of the dynamic friction angle.
    pub fn mu_dynamic(&self) -> f64 {
        self.dynamic_friction_deg.to_radians().tan()
    }

    /// (tan φ_s, tan φ_d) for one rock: `cached` (this material's [`Self::mu_static`], [`Self::mu_dynamic`]) when
    /// there is no spread, else a drawn dynamic angle (see [`Self::dynamic_friction_sd_deg`]). Draws nothing from
    /// `rng` without a spread, so runs without one keep their random sequence.
    pub fn friction_for_rock(&self, cached: (f64, f64), rng: &mut Rng) -> (f64, f64) {
        if self.dynamic_friction_sd_deg <= 0.0 {
            return cached;
        }
        let d =
            TruncNormal::three_sigma(self.dynamic_friction_deg, self.dynamic_friction_sd_deg, 0.0, 89.0).sample(rng);
        (self.static_friction_deg.max(d).to_radians().tan(), d.to_radians().tan())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid_and_bad_values_are_caught() {
        for p in TABLE2_PRESETS {
            Material::preset(p.0).unwrap().validate("m").unwrap();
        }
        let mut m = Material::preset("face_all").unwrap();
        m.cr.mean = 1.5;
        let e = m.validate("materials.face").unwrap_err().to_string();
        assert!(e.contains("materials.face.cr") && e.contains("1.5"), "{e}");
    }

    #[test]
    fn friction_without_a_spread_draws_nothing() {
        let m = Material::preset("face_all").unwrap();
        let cached = (m.mu_static(), m.mu_dynamic());
        let (mut a, mut b) = (crate::random::stream(3, 0), crate::random::stream(3, 0));
        assert_eq!(m.friction_for_rock(cached, &mut a), cached);
        assert_eq!(crate::random::uniform(&mut a), crate::random::uniform(&mut b));
        let spread = Material { dynamic_friction_sd_deg: 2.0, ..m };
        let (s, d) = spread.friction_for_rock(cached, &mut a);
        assert!(d != cached.1 && s >= d, "{s} {d}");
        let e = Material { dynamic_friction_sd_deg: -1.0, ..spread }.validate("materials.face").unwrap_err();
        assert!(e.to_string().contains("materials.face.dynamic_friction_sd_deg"), "{e}");
    }
}
