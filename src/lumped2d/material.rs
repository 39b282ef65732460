//! Slope materials of the lumped-mass model: restitution, friction and roughness, drawn per impact as RocFall does.
//!
//! # TOML form ([`MaterialSpec`])
//! ```toml
//! [materials.face]
//! preset = "face_all"          # a Table 1 row (see `Material2d::PRESETS`); fields below override it
//! roughness_sd_deg = 2.0
//!
//! [materials.floor]
//! rn = { mean = 0.30, sd = 0.058 }   # truncated at ±3 sd and to [0, 1] unless min/max are given
//! rt = 0.622                         # a plain number is a fixed value
//! friction_angle_deg = 25            # or: friction = "from_rt" | "zero"
//! ```

use crate::error::{Error, Result};
use crate::random::{Rng, TruncNormal};
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

/// Where the friction angle used for sliding comes from (RocFall's three options, physics.md §3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "mode", content = "angle_deg")]
pub enum FrictionAngle {
    /// Given per material, in degrees (drawn from the distribution each time a rock starts sliding on a segment).
    Given(TruncNormal),
    /// φ = atan((1 − Rt)/Rt), with Rt drawn from the material's Rt distribution.
    FromRt,
    /// φ = 0: pure rolling without resistance.
    Zero,
}

/// A slope material of the 2D lumped-mass model.
///
/// Rn, Rt and the friction angle are drawn from their distributions at every impact (and the friction angle each
/// time a rock starts sliding on a segment), as RocFall does.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Material2d {
    /// Normal coefficient of restitution, dimensionless in [0, 1].
    pub rn: TruncNormal,
    /// Tangential coefficient of restitution, dimensionless in [0, 1].
    pub rt: TruncNormal,
    /// Friction angle for sliding.
    pub friction: FrictionAngle,
    /// Slope roughness: standard deviation of the random segment-angle perturbation at each impact, degrees
    /// (truncated at ±3 sd; 0 = smooth).
    pub roughness_sd_deg: f64,
}

/// Table 1 of the seed paper: (name, Rn mean, Rn sd, Rt mean, Rt sd, friction angle in degrees).
const TABLE_1: [(&str, f64, f64, f64, f64, f64); 6] = [
    ("floor_weathered", 0.240, 0.055, 0.570, 0.110, 25.0),
    ("floor_fresh", 0.314, 0.050, 0.634, 0.120, 25.0),
    ("floor_all", 0.300, 0.058, 0.622, 0.119, 25.0),
    ("face_sandstone", 0.379, 0.061, 0.825, 0.083, 25.0),
    ("face_siltstone", 0.440, 0.055, 0.810, 0.055, 26.0),
    ("face_all", 0.404, 0.061, 0.837, 0.073, 25.0),
];

impl Material2d {
    /// Names of the presets: the rows of the seed paper's Table 1 (2DLM calibrated parameters).
    pub const PRESETS: [&'static str; 6] =
        ["floor_weathered", "floor_fresh", "floor_all", "face_sandstone", "face_siltstone", "face_all"];

    /// A material with Rn and Rt given as mean ± sd (truncated at ±3 sd and to [0, 1]), a fixed friction angle in
    /// degrees, and a smooth slope.
    pub fn new(rn_mean: f64, rn_sd: f64, rt_mean: f64, rt_sd: f64, friction_angle_deg: f64) -> Material2d {
        Material2d {
            rn: TruncNormal::three_sigma(rn_mean, rn_sd, 0.0, 1.0),
            rt: TruncNormal::three_sigma(rt_mean, rt_sd, 0.0, 1.0),
            friction: FrictionAngle::Given(TruncNormal::fixed(friction_angle_deg)),
            roughness_sd_deg: 0.0,
        }
    }

    /// A Table 1 preset by name (see [`Material2d::PRESETS`]), with a smooth slope (roughness 0).
    pub fn preset(name: &str) -> Option<Material2d> {
        TABLE_1.iter().find(|r| r.0 == name).map(|r| Material2d::new(r.1, r.2, r.3, r.4, r.5))
    }

    /// Bench floor, weathered rock: Rn 0.240 ± 0.055, Rt 0.570 ± 0.110, φ 25°.
    pub fn floor_weathered() -> Material2d {
        Material2d::new(0.240, 0.055, 0.570, 0.110, 25.0)
    }

    /// Bench floor, fresh rock: Rn 0.314 ± 0.050, Rt 0.634 ± 0.120, φ 25°.
    pub fn floor_fresh() -> Material2d {
        Material2d::new(0.314, 0.050, 0.634, 0.120, 25.0)
    }

    /// Bench floor, all data: Rn 0.300 ± 0.058, Rt 0.622 ± 0.119, φ 25°.
    pub fn floor_all() -> Material2d {
        Material2d::new(0.300, 0.058, 0.622, 0.119, 25.0)
    }

    /// Bench face, sandstone: Rn 0.379 ± 0.061, Rt 0.825 ± 0.083, φ 25°.
    pub fn face_sandstone() -> Material2d {
        Material2d::new(0.379, 0.061, 0.825, 0.083, 25.0)
    }

    /// Bench face, siltstone: Rn 0.440 ± 0.055, Rt 0.810 ± 0.055, φ 26°.
    pub fn face_siltstone() -> Material2d {
        Material2d::new(0.440, 0.055, 0.810, 0.055, 26.0)
    }

    /// Bench face, all data: Rn 0.404 ± 0.061, Rt 0.837 ± 0.073, φ 25°.
    pub fn face_all() -> Material2d {
        Material2d::new(0.404, 0.061, 0.837, 0.073, 25.0)
    }

    /// The same material with slope roughness `sd_deg` (standard deviation of the segment angle, degrees).
    #[must_use]
    pub fn with_roughness_sd_deg(mut self, sd_deg: f64) -> Material2d {
        self.roughness_sd_deg = sd_deg;
        self
    }

    /// The same material with another friction rule.
    #[must_use]
    pub fn with_friction(mut self, friction: FrictionAngle) -> Material2d {
        self.friction = friction;
        self
    }

    /// Checks ranges; `field` (e.g. `materials.face`) prefixes the names in errors.
    ///
    /// # Errors
    /// Rn or Rt outside [0, 1], a friction angle outside [0, 89.9]°, or a roughness outside [0, 30]°.
    pub fn validate(&self, field: &str) -> Result<()> {
        self.rn.validate(&format!("{field}.rn"), 0.0, 1.0)?;
        self.rt.validate(&format!("{field}.rt"), 0.0, 1.0)?;
        if let FrictionAngle::Given(d) = &self.friction {
            d.validate(&format!("{field}.friction_angle_deg"), 0.0, 89.9)?;
        }
        if !(self.roughness_sd_deg.is_finite() && (0.0..=30.0).contains(&self.roughness_sd_deg)) {
            return Err(Error::invalid(
                format!("{field}.roughness_sd_deg"),
                format!("must be between 0 and 30 degrees, got {}", self.roughness_sd_deg),
                "give the standard deviation of the slope angle in degrees, e.g. 2",
            ));
        }
        Ok(())
    }

    /// Draws tan φ for a slide: from the distribution, from a drawn Rt, or 0.
    pub fn draw_tan_friction(&self, rng: &mut Rng) -> f64 {
        match &self.friction {
            FrictionAngle::Given(d) => d.sample(rng).to_radians().tan(),
            FrictionAngle::FromRt => tan_friction_from_rt(self.rt.sample(rng)),
            FrictionAngle::Zero => 0.0,
        }
    }
}

/// tan φ from Rt by RocFall's rule φ = atan((1 − Rt)/Rt): tan φ = (1 − Rt)/Rt (Rt floored at 1e-6).
pub fn tan_friction_from_rt(rt: f64) -> f64 {
    let rt = rt.clamp(1e-6, 1.0);
    (1.0 - rt) / rt
}

/// A distribution as written in TOML: a plain number (fixed) or `{ mean, sd, min, max }` with `sd` defaulting to 0
/// and `min`/`max` to mean ∓ 3 sd, clipped to the parameter's range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DistSpec {
    /// Mean.
    pub mean: f64,
    /// Standard deviation (default 0).
    pub sd: f64,
    /// Lower bound (default mean − 3 sd, clipped to the parameter's range).
    pub min: Option<f64>,
    /// Upper bound (default mean + 3 sd, clipped to the parameter's range).
    pub max: Option<f64>,
}

impl DistSpec {
    /// The truncated normal for a parameter with range [lo, hi].
    pub fn to_trunc_normal(&self, lo: f64, hi: f64) -> TruncNormal {
        let mut d = TruncNormal::three_sigma(self.mean, self.sd, lo, hi);
        if let Some(m) = self.min {
            d.min = m;
        }
        if let Some(m) = self.max {
            d.max = m;
        }
        d
    }
}

impl<'de> Deserialize<'de> for DistSpec {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Full {
            mean: f64,
            #[serde(default)]
            sd: f64,
            min: Option<f64>,
            max: Option<f64>,
        }
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = DistSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or a table { mean, sd, min, max }")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<DistSpec, E> {
                Ok(DistSpec { mean: v, sd: 0.0, min: None, max: None })
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<DistSpec, E> {
                self.visit_f64(v as f64)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<DistSpec, E> {
                self.visit_f64(v as f64)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> std::result::Result<DistSpec, A::Error> {
                let f = Full::deserialize(de::value::MapAccessDeserializer::new(map))?;
                Ok(DistSpec { mean: f.mean, sd: f.sd, min: f.min, max: f.max })
            }
        }
        deserializer.deserialize_any(V)
    }
}

/// How the friction angle is chosen in TOML (`friction = ...`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionMode {
    /// From `friction_angle_deg`.
    Given,
    /// φ = atan((1 − Rt)/Rt).
    FromRt,
    /// φ = 0.
    Zero,
}

/// A material as written in a scenario: a preset and/or explicit fields (explicit fields override the preset).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// A Table 1 preset name (see [`Material2d::PRESETS`]).
    pub preset: Option<String>,
    /// Normal coefficient of restitution, [0, 1].
    pub rn: Option<DistSpec>,
    /// Tangential coefficient of restitution, [0, 1].
    pub rt: Option<DistSpec>,
    /// Friction angle, degrees in [0, 89.9].
    pub friction_angle_deg: Option<DistSpec>,
    /// Friction rule: `given` (default when `friction_angle_deg` is set), `from_rt` or `zero`.
    pub friction: Option<FrictionMode>,
    /// Slope roughness (standard deviation of the segment angle), degrees (default: 0, or the preset's).
    pub roughness_sd_deg: Option<f64>,
}

impl MaterialSpec {
    /// Resolves the spec into a validated material; `field` (e.g. `materials.floor`) prefixes error names.
    ///
    /// # Errors
    /// An unknown preset, missing Rn/Rt/friction without a preset, conflicting friction settings, or values out of
    /// range (the error names the field, e.g. `materials.floor.rn`).
    pub fn resolve(&self, field: &str) -> Result<Material2d> {
        let base = match &self.preset {
            Some(name) => Some(Material2d::preset(name).ok_or_else(|| {
                Error::invalid(
                    format!("{field}.preset"),
                    format!("unknown preset '{name}'"),
                    format!("use one of: {}", Material2d::PRESETS.join(", ")),
                )
            })?),
            None => None,
        };
        let need = |name: &str| {
            Error::invalid(
                format!("{field}.{name}"),
                "is missing",
                format!("give {name}, or a preset ({})", Material2d::PRESETS.join(", ")),
            )
        };
        let rn = match (&self.rn, &base) {
            (Some(d), _) => d.to_trunc_normal(0.0, 1.0),
            (None, Some(b)) => b.rn,
            (None, None) => return Err(need("rn")),
        };
        let rt = match (&self.rt, &base) {
            (Some(d), _) => d.to_trunc_normal(0.0, 1.0),
            (None, Some(b)) => b.rt,
            (None, None) => return Err(need("rt")),
        };
        let friction = match (self.friction, &self.friction_angle_deg, &base) {
            (Some(FrictionMode::FromRt | FrictionMode::Zero), Some(_), _) => {
                return Err(Error::invalid(
                    format!("{field}.friction_angle_deg"),
                    "is given together with friction = \"from_rt\" or \"zero\"",
                    "remove one of the two",
                ))
            }
            (Some(FrictionMode::FromRt), None, _) => FrictionAngle::FromRt,
            (Some(FrictionMode::Zero), None, _) => FrictionAngle::Zero,
            (_, Some(d), _) => FrictionAngle::Given(d.to_trunc_normal(0.0, 89.9)),
            (_, None, Some(b)) => b.friction,
            (_, None, None) => return Err(need("friction_angle_deg")),
        };
        let roughness_sd_deg = self.roughness_sd_deg.or(base.map(|b| b.roughness_sd_deg)).unwrap_or(0.0);
        let m = Material2d { rn, rt, friction, roughness_sd_deg };
        m.validate(field)?;
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_table_1_truncated() {
        let m = Material2d::preset("floor_all").unwrap();
        assert_eq!(m, Material2d::floor_all());
        assert!((m.rn.min - (0.300 - 3.0 * 0.058)).abs() < 1e-12);
        assert!((m.rt.max - 0.979).abs() < 1e-12);
        assert_eq!(Material2d::face_all().rt.max, 1.0); // 0.837 + 3 × 0.073 > 1, clipped
        for name in Material2d::PRESETS {
            Material2d::preset(name).unwrap().validate(name).unwrap();
        }
        assert_eq!(Material2d::face_siltstone().friction, FrictionAngle::Given(TruncNormal::fixed(26.0)));
    }

    #[test]
    fn spec_resolves_and_names_bad_fields() {
        let spec: MaterialSpec = toml::from_str("preset = \"face_all\"\nroughness_sd_deg = 2\nrt = 0.9").unwrap();
        let m = spec.resolve("materials.face").unwrap();
        assert_eq!(m.rt, TruncNormal::fixed(0.9));
        assert_eq!(m.roughness_sd_deg, 2.0);
        assert_eq!(m.rn, Material2d::face_all().rn);

        let spec: MaterialSpec = toml::from_str("rn = 1.5\nrt = 0.5\nfriction_angle_deg = 30").unwrap();
        let e = spec.resolve("materials.floor").unwrap_err().to_string();
        assert!(e.contains("materials.floor.rn") && e.contains("1.5"), "{e}");

        let spec: MaterialSpec =
            toml::from_str("rn = { mean = 0.3, sd = 0.1 }\nrt = 0.5\nfriction = \"from_rt\"").unwrap();
        let m = spec.resolve("m").unwrap();
        assert_eq!(m.friction, FrictionAngle::FromRt);
        assert!((m.rn.min - 0.0).abs() < 1e-12 && (m.rn.max - 0.6).abs() < 1e-12);

        let e = toml::from_str::<MaterialSpec>("rn = 0.3\nrugosity = 2").unwrap_err().to_string();
        assert!(e.contains("rugosity"), "{e}");
        let e = MaterialSpec { rn: Some(DistSpec { mean: 0.3, sd: 0.0, min: None, max: None }), ..Default::default() }
            .resolve("m")
            .unwrap_err()
            .to_string();
        assert!(e.contains("m.rt") && e.contains("missing"), "{e}");
    }

    #[test]
    fn friction_from_rt() {
        assert!((tan_friction_from_rt(0.5) - 1.0).abs() < 1e-12);
        assert_eq!(tan_friction_from_rt(1.0), 0.0);
    }
}
