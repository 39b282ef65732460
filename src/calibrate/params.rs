//! Candidate models: named parameter values plus the effects switched on, and the free parameters an optimiser
//! moves.
//!
//! Parameter names are `MATERIAL.PARAM` for materials (e.g. `default.cr_mean`), `EFFECT.PARAM` for effects (e.g.
//! `speed_restitution.k_mps`, `zone1.cr_mean`), and `mobility` for the global mobility factor the effects loop uses
//! to re-centre a model (see [`apply_mobility_3d`]).

use super::config::{ModelKind, STATIC_EXCESS};
use super::effects::EffectKind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Named parameter values.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Params(pub BTreeMap<String, f64>);

impl Params {
    /// The value of `name`, if set.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.get(name).copied()
    }

    /// The value of `name`, or `default`.
    pub fn get_or(&self, name: &str, default: f64) -> f64 {
        self.get(name).unwrap_or(default)
    }

    /// Sets `name`.
    pub fn set(&mut self, name: impl Into<String>, value: f64) {
        self.0.insert(name.into(), value);
    }

    /// The global mobility factor (1 when unset).
    pub fn mobility(&self) -> f64 {
        self.get_or(MOBILITY, 1.0)
    }
}

/// Name of the global mobility factor.
pub const MOBILITY: &str = "mobility";

/// Where a zone lies.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// A polygon (x, y) in the campaign's frame (3DRB).
    Polygon(Vec<[f64; 2]>),
    /// An interval [x0, x1] along the profile (2DLM).
    Interval([f64; 2]),
}

impl Region {
    /// True if the horizontal point lies inside.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        match self {
            Region::Polygon(p) => crate::terrain::point_in_polygon(x, y, p),
            Region::Interval([a, b]) => x >= *a && x <= *b,
        }
    }

    /// Bounding box (x_min, y_min, x_max, y_max).
    pub fn bbox(&self) -> [f64; 4] {
        match self {
            Region::Polygon(p) => crate::terrain::bbox_xy(p.iter().copied()),
            Region::Interval([a, b]) => [*a, f64::NEG_INFINITY, *b, f64::INFINITY],
        }
    }
}

/// One effect switched on. Its parameter values live in the candidate's [`Params`] under `label.PARAM`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectSpec {
    /// Which effect.
    pub kind: EffectKind,
    /// Its name in parameters and reports (`speed_restitution`, `zone1`, `soft_drag_floor`, ...).
    pub label: String,
    /// The material a material-bound effect (soft drag) acts on.
    pub material: Option<String>,
    /// Where a zone lies.
    pub region: Option<Region>,
}

/// A model to simulate: parameter values and the effects switched on.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Parameter values.
    pub params: Params,
    /// Effects switched on, in the order they were added.
    pub effects: Vec<EffectSpec>,
}

impl Candidate {
    /// The effect labelled `label`.
    pub fn effect(&self, label: &str) -> Option<&EffectSpec> {
        self.effects.iter().find(|e| e.label == label)
    }

    /// The first effect of `kind`.
    pub fn effect_of(&self, kind: EffectKind) -> Option<&EffectSpec> {
        self.effects.iter().find(|e| e.kind == kind)
    }
}

/// A parameter the optimiser moves, within bounds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FreeParam {
    /// Name (see the module docs).
    pub name: String,
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
}

impl FreeParam {
    /// The value at unit coordinate `u` ∈ [0, 1].
    pub fn from_unit(&self, u: f64) -> f64 {
        self.min + u.clamp(0.0, 1.0) * (self.max - self.min)
    }

    /// The unit coordinate of `v`.
    pub fn to_unit(&self, v: f64) -> f64 {
        if self.max > self.min {
            ((v - self.min) / (self.max - self.min)).clamp(0.0, 1.0)
        } else {
            0.5
        }
    }
}

/// Sets every tied static friction angle to its dynamic one plus the excess (see [`STATIC_EXCESS`]), then caps every
/// dynamic friction angle at its static one (3DRB), as the engine requires, so that reported values are the values
/// simulated.
pub fn normalize(params: &mut Params) {
    let tied: Vec<(String, f64)> = params
        .0
        .iter()
        .filter_map(|(k, e)| {
            let p = k.strip_suffix(&format!(".{STATIC_EXCESS}"))?;
            let d = params.get(&format!("{p}.dynamic_friction_deg"))?;
            Some((format!("{p}.static_friction_deg"), (d + e).min(89.0)))
        })
        .collect();
    for (k, s) in tied {
        params.set(k, s);
    }
    let caps: Vec<(String, f64)> = params
        .0
        .iter()
        .filter_map(|(k, v)| {
            k.strip_suffix(".dynamic_friction_deg")
                .and_then(|p| params.get(&format!("{p}.static_friction_deg")).filter(|s| v > s).map(|s| (k.clone(), s)))
        })
        .collect();
    for (k, s) in caps {
        params.set(k, s);
    }
}

/// Material values of a 3DRB material after the mobility factor m (ours): Cr·m (at most 1), and friction angles
/// with tan φ / m, so that m > 1 makes every contact bouncier and more slippery and m < 1 the reverse. The dynamic
/// angle is capped at the static one. Returns (cr_mean, cr_sd, static °, dynamic °).
pub fn apply_mobility_3d(cr_mean: f64, cr_sd: f64, static_deg: f64, dynamic_deg: f64, m: f64) -> (f64, f64, f64, f64) {
    let (s, d) = (friction_over(static_deg, m), friction_over(dynamic_deg.min(static_deg), m));
    ((cr_mean * m).clamp(0.0, 1.0), cr_sd, s, d.min(s))
}

/// Material values of a 2DLM material after the mobility factor m (ours): Rn·m, the tangential loss (1 − Rt)/m,
/// tan φ / m (all clamped to their ranges). Returns (rn, rt, friction °).
pub fn apply_mobility_2d(rn: f64, rt: f64, friction_deg: f64, m: f64) -> (f64, f64, f64) {
    ((rn * m).clamp(0.0, 1.0), (1.0 - (1.0 - rt) / m).clamp(0.0, 1.0), friction_over(friction_deg, m))
}

/// The material parameters the mobility factor moves ([`apply_mobility_3d`], [`apply_mobility_2d`]).
pub fn mobility_scaled(model: ModelKind) -> &'static [&'static str] {
    match model {
        ModelKind::Rigid3d => &["cr_mean", "static_friction_deg", "dynamic_friction_deg"],
        ModelKind::Lumped2d => &["rn_mean", "rt_mean", "friction_angle_deg"],
    }
}

/// The friction angle whose tangent is tan(`deg`)/`m`, degrees: `m` > 1 makes the contact more slippery.
pub fn friction_over(deg: f64, m: f64) -> f64 {
    (deg.to_radians().tan() / m).atan().to_degrees()
}

/// The parameters with the mobility factor folded into the material (and zone) values, and the factor reset to 1.
pub fn fold_mobility(model: ModelKind, params: &Params, materials: &[String]) -> Params {
    let m = params.mobility();
    let mut out = params.clone();
    out.0.remove(MOBILITY);
    if m == 1.0 {
        return out;
    }
    // Materials and zones share parameter names; fold every prefix that has them.
    let mut prefixes: Vec<String> = materials.to_vec();
    for k in params.0.keys() {
        if let Some((p, _)) = k.split_once('.') {
            if p.starts_with("zone") && !prefixes.iter().any(|q| q == p) {
                prefixes.push(p.to_string());
            }
        }
    }
    for p in prefixes {
        let g = |n: &str| params.get(&format!("{p}.{n}"));
        match model {
            ModelKind::Rigid3d => {
                if let (Some(cr), Some(sd), Some(s), Some(d)) =
                    (g("cr_mean"), g("cr_sd"), g("static_friction_deg"), g("dynamic_friction_deg"))
                {
                    let (cr, _, s, d) = apply_mobility_3d(cr, sd, s, d, m);
                    out.set(format!("{p}.cr_mean"), cr);
                    out.set(format!("{p}.static_friction_deg"), s);
                    out.set(format!("{p}.dynamic_friction_deg"), d);
                    if g(STATIC_EXCESS).is_some() {
                        out.set(format!("{p}.{STATIC_EXCESS}"), s - d);
                    }
                }
            }
            ModelKind::Lumped2d => {
                if let (Some(rn), Some(rt), Some(f)) = (g("rn_mean"), g("rt_mean"), g("friction_angle_deg")) {
                    let (rn, rt, f) = apply_mobility_2d(rn, rt, f, m);
                    out.set(format!("{p}.rn_mean"), rn);
                    out.set(format!("{p}.rt_mean"), rt);
                    out.set(format!("{p}.friction_angle_deg"), f);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mobility_folds_into_materials() {
        let mut p = Params::default();
        for (k, v) in [
            ("a.cr_mean", 0.3),
            ("a.cr_sd", 0.05),
            ("a.static_friction_deg", 40.0),
            ("a.dynamic_friction_deg", 30.0),
            ("a.static_excess_deg", 10.0),
            (MOBILITY, 1.2),
        ] {
            p.set(k, v);
        }
        let f = fold_mobility(ModelKind::Rigid3d, &p, &["a".into()]);
        assert!(f.get(MOBILITY).is_none());
        assert!((f.get("a.cr_mean").unwrap() - 0.36).abs() < 1e-12);
        let d = f.get("a.dynamic_friction_deg").unwrap();
        assert!((d.to_radians().tan() - 30f64.to_radians().tan() / 1.2).abs() < 1e-12);
        // A tied static angle stays tied: the excess follows the folded angles.
        let (s, e) = (f.get("a.static_friction_deg").unwrap(), f.get("a.static_excess_deg").unwrap());
        assert!((s - d - e).abs() < 1e-12 && e < 10.0, "{s} {d} {e}");
        // Mobility 1 changes nothing.
        let (cr, sd, s, d) = apply_mobility_3d(0.3, 0.05, 40.0, 30.0, 1.0);
        assert!((cr - 0.3).abs() < 1e-15 && sd == 0.05 && (s - 40.0).abs() < 1e-12 && (d - 30.0).abs() < 1e-12);
    }
}
