//! 3DRB ground materials: one coefficient of restitution plus static and dynamic friction angles (Trajec3D's
//! parameter set, used by the seed paper), and the paper's Table 2 rows as named presets.

use crate::error::{Error, Result};
use crate::random::TruncNormal;

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
}
