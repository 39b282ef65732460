//! The effects the base model lacks (physics.md §4), as the calibration loop sees them: what each one does, its
//! formula and source, its parameter with the grid the loop tries, and the residual covariates that reveal it
//! (its "signature", physics.md §4's last column).
//!
//! The formulas live in the engines ([`crate::sim::Effects`] for 3DRB, [`crate::lumped2d::Options2d`] for 2DLM);
//! this file only describes them to the loop and the report.

use super::config::ModelKind;
use super::diagnose::{DEPOSITION_EXCESS, OUTSIDE_RANGE};
use super::impacts::{BOUNCE_INCIDENCE, BOUNCE_NORMAL_SPEED};
use serde::{Deserialize, Serialize};

/// An effect the loop can add.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// Restitution falling with impact speed.
    SpeedRestitution,
    /// Restitution depending on the impact angle.
    AngleRestitution,
    /// Restitution scaling with rock mass.
    MassRestitution,
    /// Ground roughness felt relative to rock size.
    Roughness,
    /// Rolling resistance.
    RollingResistance,
    /// Drag in soft ground on one material.
    SoftDrag,
    /// A linear drag force from low vegetation (light rocks slow most).
    VegetationDrag,
    /// A zone of the terrain that behaves differently from its declared material.
    Zone,
    /// The CRSP tangential rule with spin (2DLM).
    CrspRotation,
    /// RAMMS's slippage-dependent friction (3DRB; tried only when listed in `candidates` or declared).
    SlipFriction,
    /// A drag quadratic in speed from scarring soft soil (3DRB; tried only when listed in `candidates` or declared).
    ScarDrag,
}

/// What the loop knows about an effect.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectDef {
    /// Which effect.
    pub kind: EffectKind,
    /// Name in reports and settings.
    pub name: &'static str,
    /// Its parameter (`None` for an on/off effect).
    pub param: Option<&'static str>,
    /// Values the loop tries in the nested cross-validation.
    pub grid: &'static [f64],
    /// Bounds of the parameter when it is refitted.
    pub bounds: (f64, f64),
    /// Covariates whose correlation with the residuals points at it.
    pub signature: &'static [&'static str],
    /// Formula and source.
    pub formula: &'static str,
}

/// Mobility factors every arm of the nested cross-validation may choose to re-centre the model (ours): steps of
/// 1.2 on the log scale, up to ±44 % around the current fit.
pub const MOBILITY_GRID: [f64; 5] = [1.0 / 1.44, 1.0 / 1.2, 1.0, 1.2, 1.44];

/// Factors on every material's Cr that the arm of a restitution effect (speed, angle, mass) steps over instead of
/// the mobility factor (ours): such an effect changes the meaning of Cr, which may have to move far.
pub const CR_SCALE_GRID: [f64; 5] = [0.5, 0.7, 1.0, 1.4, 2.0];

/// How the arm of an effect re-centres the model in the loop's screening (ours).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Recentring {
    /// The mobility factor over [`MOBILITY_GRID`] (Cr, both friction angles).
    Mobility,
    /// Every Cr times [`CR_SCALE_GRID`]: a restitution effect (speed, angle, mass) changes the meaning of Cr,
    /// which may have to move far.
    CrScale,
    /// tan of every dynamic friction angle divided by [`MOBILITY_GRID`]: a resistance in contact (rolling
    /// resistance, soft-ground or vegetation drag) does the work part of the sliding friction did, and leaves the
    /// bounce (Cr) and the rest (static friction) as fitted. With the mobility factor instead, the Tschamut
    /// screening missed the fit's valley (dynamic friction 20 → 16°, static and Cr unchanged). Roughness too: it
    /// makes rocks more mobile (25 m longer mean run-outs at a Tschamut fold's parameters), which the joint fits
    /// offset with the dynamic angle (17–18° → 22–24°); with the mobility factor its arm lost (CV CRPS +6.6 %).
    DynamicFriction,
}

/// The re-centring of `kind`'s arm.
pub fn recentring(kind: EffectKind) -> Recentring {
    match kind {
        EffectKind::SpeedRestitution | EffectKind::AngleRestitution | EffectKind::MassRestitution => {
            Recentring::CrScale
        }
        EffectKind::RollingResistance
        | EffectKind::SoftDrag
        | EffectKind::VegetationDrag
        | EffectKind::Roughness
        | EffectKind::SlipFriction
        | EffectKind::ScarDrag => Recentring::DynamicFriction,
        EffectKind::Zone | EffectKind::CrspRotation => Recentring::Mobility,
    }
}

/// Zone mobility factors tried for a new zone, relative to the material it replaces (ours).
pub const ZONE_MOBILITY_GRID: [f64; 4] = [0.2, 0.4, 0.7, 1.5];

/// Soft-ground drag rates tried for a new 3DRB zone, 1/s (ours): soft ground stops a rolling block by drag, which
/// a lower Cr and a higher friction alone do not. Each is tried with the material unchanged and with it at
/// [`ZONE_SOFT_MOBILITY`].
pub const ZONE_DRAG_GRID: [f64; 3] = [3.0, 10.0, 30.0];

/// The mobility factor the drag rates are also tried at (ours): soft ground absorbs impacts as well as dragging
/// (Rockyfor3D's soil classes: Rn 0–0.28 for the softest three against 0.53 for bedrock, physics.md §4), and a
/// block that keeps its bounce hops across drag alone (with the impact sub-steps, boulders touch 40 m of the `zone`
/// case's soft ground for 0.3–0.7 s in all: docs/calibration.md, "The zone case and the impact sub-steps").
pub const ZONE_SOFT_MOBILITY: f64 = 0.4;

const SPEED_3D: EffectDef = EffectDef {
    kind: EffectKind::SpeedRestitution,
    name: "speed_restitution",
    param: Some("k_mps"),
    grid: &[3.0, 6.0, 12.0, 25.0],
    bounds: (1.0, 60.0),
    signature: &[
        "release_height_m",
        "drop_height_m",
        "impact_speed_mean_mps",
        "impact_speed_max_mps",
        "initial_speed_mps",
        BOUNCE_NORMAL_SPEED,
    ],
    formula: "Cr' = Cr / (1 + (v_n/K)^2), v_n the normal approach speed (Pfeiffer & Bowen 1989, physics.md §3-4; their K = 9.144 m/s)",
};

const ANGLE_3D: EffectDef = EffectDef {
    kind: EffectKind::AngleRestitution,
    name: "angle_restitution",
    param: Some("exponent"),
    grid: &[-0.6, -0.3, 0.3, 0.6],
    bounds: (-1.5, 1.5),
    signature: &["impact_angle_mean_deg", "path_slope_mean_deg", BOUNCE_INCIDENCE],
    formula: "Cr' = min(1, Cr (max(theta, 5 deg)/30 deg)^-a), theta the impact angle (after Wyllie 2014, e_n = 19.5 theta^-1.03; physics.md §4)",
};

const MASS_3D: EffectDef = EffectDef {
    kind: EffectKind::MassRestitution,
    name: "mass_restitution",
    param: Some("exponent"),
    grid: &[-0.6, -0.3, 0.3, 0.6],
    bounds: (-1.5, 1.5),
    signature: &["mass_kg", "size_m"],
    formula: "Cr' = min(1, Cr (m/m_ref)^-beta), m_ref the campaign's median block mass (physics.md §8, f_m; RocFall's 'scale Rn by mass')",
};

const ROUGH_3D: EffectDef = EffectDef {
    kind: EffectKind::Roughness,
    name: "roughness",
    param: Some("rough_m"),
    grid: &[0.03, 0.08, 0.15, 0.3],
    bounds: (0.0, 1.0),
    signature: &["size_m", "mass_kg", "flatness", "elongation", OUTSIDE_RANGE],
    formula:
        "at each impact the normal tilts by U(0,1) atan(rough/R), R the equivalent radius (PlatRock, physics.md §4)",
};

const ROLL_3D: EffectDef = EffectDef {
    kind: EffectKind::RollingResistance,
    name: "rolling_resistance",
    param: Some("mu_r"),
    grid: &[0.05, 0.1, 0.2, 0.35],
    bounds: (0.0, 1.0),
    signature: &["gentle_fraction", "end_slope_deg", "path_slope_mean_deg"],
    formula: "in contact the speed along the ground drops by mu_r g cos(alpha) per second (Azzoni et al. 1995, physics.md §4)",
};

const DRAG_3D: EffectDef = EffectDef {
    kind: EffectKind::SoftDrag,
    name: "soft_drag",
    param: Some("rate_per_s"),
    grid: &[0.3, 1.0, 3.0, 8.0],
    bounds: (0.0, 30.0),
    signature: &["path_fraction"],
    formula: "in contact with the material, velocity and spin decay as exp(-c t) (a linear stand-in for RAMMS's scarring drag, Lu et al. 2019, physics.md §2)",
};

const VEGETATION_DRAG_3D: EffectDef = EffectDef {
    kind: EffectKind::VegetationDrag,
    name: "vegetation_drag",
    param: Some("c_kg_s"),
    grid: &[3.0, 8.0, 20.0, 50.0],
    bounds: (0.0, 500.0),
    signature: &["mass_kg", "size_m", "flatness", "area_per_mass_m2_kg"],
    formula: "in contact with the ground a force -c v: velocity and spin decay as exp(-(c/m) t), light rocks slow most (RAMMS's forest drag F_d = -c_d v, Leine et al. 2014, physics.md §2; applied in contact for vegetation lower than the rock: ours)",
};

const SLIP_3D: EffectDef = EffectDef {
    kind: EffectKind::SlipFriction,
    name: "slip_friction",
    param: Some("max_deg"),
    grid: &[30.0, 40.0, 50.0, 63.0],
    bounds: (0.0, 85.0),
    signature: &["gentle_fraction", "end_slope_deg", "path_slope_mean_deg"],
    formula: "mu(s) = mu_min + (2/pi)(mu_max - mu_min) atan(kappa s), s the distance travelled in contact, decaying as exp(-beta t) in flight; mu_min the dynamic friction, mu_max = tan(max_deg) (never below mu_min), kappa 0.7 1/m, beta 20 1/s (RAMMS, Leine et al. 2014 eqs. 46-47, physics.md §2)",
};

const SCAR_3D: EffectDef = EffectDef {
    kind: EffectKind::ScarDrag,
    name: "scar_drag",
    param: Some("coefficient"),
    grid: &[0.01, 0.05, 0.2, 1.0],
    bounds: (0.0, 10.0),
    signature: &["release_height_m", "drop_height_m", "impact_speed_max_mps", "mass_kg", "size_m", OUTSIDE_RANGE],
    formula: "in contact with the ground a force -(1/2) C rho pi R^2 |v| v, rho 1700 kg/m3, R the equivalent radius: speed and spin fall as v / (1 + k v t), k = (1/2) C rho pi R^2 / m, fast and light rocks slow most (after Lu et al. 2019's scarring drag (1/2) C_d rho A v^2, physics.md §2; C folds Lu's C_d and the share of the cross-section in the soil: ours)",
};

const ZONE: EffectDef = EffectDef {
    kind: EffectKind::Zone,
    name: "zone",
    param: None,
    grid: &ZONE_MOBILITY_GRID,
    bounds: (0.0, 0.0),
    signature: &[DEPOSITION_EXCESS],
    formula: "a polygon (3DRB) or interval (2DLM) where observed runs stop and simulated ones do not, given its own fitted material, in 3DRB with its own soft-ground drag (ours: derived from the residual and deposition maps)",
};

const SPEED_2D: EffectDef = EffectDef {
    formula: "Rn' = Rn / (1 + (v_n/K)^2), v_n the normal impact speed (Pfeiffer & Bowen 1989, RocFall's 'scale Rn by velocity' with their K = 9.144 m/s, physics.md §3)",
    ..SPEED_3D
};

const MASS_2D: EffectDef = EffectDef {
    formula: "Rn' = min(1, Rn (m/m_ref)^-beta), m_ref the campaign's median block mass (physics.md §8, f_m; RocFall's 'scale Rn by mass')",
    ..MASS_3D
};

const CRSP_2D: EffectDef = EffectDef {
    kind: EffectKind::CrspRotation,
    name: "crsp_rotation",
    param: None,
    grid: &[],
    bounds: (0.0, 0.0),
    signature: &["mass_kg", "size_m", "path_slope_mean_deg"],
    formula:
        "CRSP tangential rule with spin: v_t' from Ff = Rt + (1-Rt)/(((v_t - wR)/6.096)^2 + 1.2) and SF (physics.md §4)",
};

/// The effects a model supports, in the order the loop considers them.
pub fn effects_for(model: ModelKind) -> &'static [EffectDef] {
    const D3: [EffectDef; 10] =
        [SPEED_3D, ANGLE_3D, MASS_3D, ROUGH_3D, ROLL_3D, DRAG_3D, VEGETATION_DRAG_3D, ZONE, SLIP_3D, SCAR_3D];
    const D2: [EffectDef; 4] = [SPEED_2D, MASS_2D, CRSP_2D, ZONE];
    match model {
        ModelKind::Rigid3d => &D3,
        ModelKind::Lumped2d => &D2,
    }
}

/// True if the loop tries `kind` when the settings list no `candidates`. Slippage-dependent friction and the
/// scarring drag are tried only when listed: at Tschamut slippage friction widens the run-outs instead of trimming
/// their tail, and the synthetic study's controls have not been run with either (docs/calibration.md,
/// "Slippage-dependent friction" and "Scarring drag").
pub fn proposed_by_default(kind: EffectKind) -> bool {
    !matches!(kind, EffectKind::SlipFriction | EffectKind::ScarDrag)
}

/// The definition of `kind` for `model`.
pub fn definition(model: ModelKind, kind: EffectKind) -> Option<&'static EffectDef> {
    effects_for(model).iter().find(|d| d.kind == kind)
}

/// The definition named `name` for `model`.
pub fn by_name(model: ModelKind, name: &str) -> Option<&'static EffectDef> {
    effects_for(model).iter().find(|d| d.name == name)
}
