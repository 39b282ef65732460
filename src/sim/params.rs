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

/// Smallest `sample_spacing_m`, m. Ours: in flight a rock is sampled every spacing, so 1 cm is a sample every
/// 0.2 ms at 50 m/s (ten per contact time step), far finer than any raster cell or collector needs, while a spacing
/// of 1e-12 m would take 10¹² samples per flight step and never finish.
pub const MIN_SAMPLE_SPACING_M: f64 = 0.01;

/// Largest `solver_tolerance_mps`, m/s (ours): a tenth of the slip speed above which the solver's stick test counts
/// a contact as slipping (1 mm/s, [`super::contact`]), so that test reads a slip, not the solver's residual.
pub const MAX_SOLVER_TOLERANCE_MPS: f64 = 1e-4;

/// Most `impact_substeps` (ours: 64 sub-steps take a 2 ms impact step to about 0.03 ms).
pub const MAX_IMPACT_SUBSTEPS: usize = 64;

/// Shortest `max_contact_travel_m`, m (ours): a rock at 50 m/s then takes 10 sub-steps of each 2 ms contact step;
/// shorter only makes runs slow.
pub const MIN_CONTACT_TRAVEL_M: f64 = 0.01;

/// Smallest `dt_s`, s (ours): the contact steps converge by 0.25 ms (tests/engine.rs), and a rock rolling for the
/// default 120 s takes 1.2 million steps at 0.1 ms; at 10⁻¹² s a run never ends.
pub const MIN_DT_S: f64 = 1e-4;

/// Most `max_time_s`, s (ours): an hour, far beyond any rockfall (the Tschamut blocks ran for under a minute).
pub const MAX_TIME_S: f64 = 3600.0;

/// Most `solver_iterations` (ours): a hundred times the default; the contact solver converges in a few sweeps
/// (about 8 a contact step on Tschamut), so more only lets a run that cannot converge take forever.
pub const MAX_SOLVER_ITERATIONS: usize = 10_000;

/// Engine settings. Defaults follow physics.md §6 and §8; values marked "ours" are our own choice.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimParams {
    /// Time step while the rock is near or on the ground, s (default: 0.002, as RAMMS; physics.md §6 gives 1–2 ms.
    /// Halving it moves the median run-out of `examples/bench_stack.toml` by 0.03 % over 4,000 rocks and 3 % over its
    /// 1,000, where a changed step sends each rock on another path: README.md, "Convergence", stop 84).
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
    /// A rock in contact whose centre of mass stays this long within its bounding radius of where it was counts as
    /// at rest, however it spins, s (default: 10, ours). A point contact feels no slip of a spin about an axis
    /// through it, and the engine has no drilling friction over a contact patch: a cube wedged by two corners, or
    /// balanced on one, spinning about the line through them would otherwise spin in place, or precess round its
    /// corner, until `max_time_s` (one of the 1,000 rocks of `examples/tyrol.toml` did, at 2 rad/s for 100 s). A rock
    /// that goes no farther than its own size in that time is going nowhere on a hazard map.
    pub stop_in_place_s: f64,
    /// How long a touch of the ground counts as contact, s (default: 0.002, ours). The solver resolves a touch in
    /// one step, so without a duration what acts in contact (rolling resistance, the drags, the slippage of
    /// `slip_friction_max_deg`) would act for one step per impact, and a vertex that lifts off for a step would
    /// meet a new impact (a new roughness tilt, a new Cr when drawn per impact): all of it would scale with `dt_s`.
    /// What acts in contact acts for this long after the last step in contact (the step that ends it cut short);
    /// a touch counts as contact, for telling a new impact, for `contact_duration_s / dt_s` steps (rounded, at
    /// least 1). The default, the default step, keeps every result at that step as it was before this setting.
    pub contact_duration_s: f64,
    /// Penetration left uncorrected, m (default: 0.002, ours). Deeper penetration is projected out (position only,
    /// never velocity).
    pub penetration_slop_m: f64,
    /// Sub-steps of a contact step in which a hull vertex newly meets the ground faster than the bounce threshold
    /// (default: 8; 1 takes none; ours). A rock that hops and tumbles over uneven ground (relief, roughness tilts)
    /// runs too far at 2 ms without them: blocks launched down a bumpy 20° slope run a mean 93.5 / 84.9 / 83.2 /
    /// 83.0 m at 2 / 1 / 0.5 / 0.25 ms, and 81.3 m at 2 ms with 8 sub-steps, for 30 % more time
    /// (`examples/convergence.rs`; README, "Performance and convergence"). The rest of the motion keeps `dt_s`.
    /// The default was 1 until 2026-11-27: a model fitted before then keeps its figures with `impact_substeps = 1`.
    pub impact_substeps: usize,
    /// Farthest a point of the rock may move in one Moreau step near the ground, m (default: 0.2; ours). A contact
    /// step in which a hull vertex, at its speed from the centre's velocity and the spin, would move farther is
    /// taken as enough equal sub-steps to keep within it, so a vertex is never met deeper below the ground than
    /// this and a face it enters is the one it is pushed back out of: terrain thicker than twice it (a wall, a
    /// fin, a boulder in the mesh) is not passed through at any speed. At the default `dt_s` it acts only on
    /// vertices faster than 100 m/s; at `dt_s = 0.01` without impact sub-steps, rocks fired at 100 m/s passed
    /// through a 0.5 m wall (9 of 100) without it.
    pub max_contact_travel_m: f64,
    /// Most Gauss–Seidel sweeps of the contact solver (default: 100; sweeps stop earlier once converged).
    pub solver_iterations: usize,
    /// The solver's sweeps stop once no contact impulse changed by more than this in a sweep, counted as the
    /// velocity change it makes at its contact, m/s (default: [`MAX_SOLVER_TOLERANCE_MPS`], ours: a tenth of the
    /// stick test's slip speed, far below any velocity that matters to a rock's path). It takes half the sweeps of
    /// 1e-6 on Tschamut and leaves the run-outs as they were within the scatter of seeds (docs/performance.md, "The
    /// solver's tolerance"). The default was 1e-6 until 2026-11-30: a model fitted before then keeps its figures with
    /// `solver_tolerance_mps = 1e-6`.
    pub solver_tolerance_mps: f64,
    /// When restitution coefficients are drawn (default: per rock).
    pub cr_draw: CrDraw,
    /// Horizontal spacing of the path samples that feed rasters and collectors, m (default: 0.5; at least
    /// [`MIN_SAMPLE_SPACING_M`]).
    pub sample_spacing_m: f64,
    /// Also take terrain edges that pass through the rock as contacts (default: false; ours). Only the rock's hull
    /// vertices are tested against the ground otherwise (physics.md §8, as RAMMS), so a ridge, a crest or a spike
    /// narrower than the spacing of a rock's vertices passes through a face unseen (1 t blocks dropped on a ridge
    /// with 60° flanks came to rest with the crest up to 0.9 m inside them). With this on, each terrain edge near
    /// the rock is clipped to the hull; where its deepest point lies more than half `penetration_slop_m` inside,
    /// that point is a contact with the normal of the nearest hull face (or, where it meets a hull edge, the normal
    /// perpendicular to both edges), pointing into the rock; an edge lying along a face, the two ends of the stretch
    /// that deep. They are impacts as vertex contacts are. Off by default: it changes results wherever the ground is
    /// convex under a rock, and on a 5 m DEM proxy (Tschamut) it made the held-out error worse.
    pub terrain_edge_contacts: bool,
    /// Optional effects (default: none).
    pub effects: Effects,
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
            stop_in_place_s: 10.0,
            contact_duration_s: 0.002,
            penetration_slop_m: 0.002,
            impact_substeps: 8,
            max_contact_travel_m: 0.2,
            solver_iterations: 100,
            solver_tolerance_mps: MAX_SOLVER_TOLERANCE_MPS,
            cr_draw: CrDraw::PerRock,
            sample_spacing_m: 0.5,
            terrain_edge_contacts: false,
            effects: Effects::default(),
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
        let at_most = |name: &str, v: f64, max: f64, what: &str, hint: &str| {
            if v > max {
                Err(Error::invalid(format!("{prefix}{name}"), format!("{v} s {what}"), hint))
            } else {
                Ok(())
            }
        };
        pos("dt_s", self.dt_s, "use a step of 0.0005 to 0.002 s")?;
        at_most("dt_s", self.dt_s, 0.01, "is too coarse for contact", "use 0.0005 to 0.002 s")?;
        let at_least = |name: &str, v: f64, min: f64, unit: &str, what: &str, hint: &str| {
            if v < min {
                let got = crate::error::number_text(v);
                Err(Error::invalid(
                    format!("{prefix}{name}"),
                    format!("{got} {unit} is below {what}, {min} {unit}"),
                    hint,
                ))
            } else {
                Ok(())
            }
        };
        let hint = "use 0.0005 to 0.002 s (results converge by 0.00025 s; a finer step only makes a run take hours)";
        at_least("dt_s", self.dt_s, MIN_DT_S, "s", "the smallest step", hint)?;
        pos("max_flight_step_s", self.max_flight_step_s, "use about 0.25 s")?;
        let hint = "use 0.2 m, the default, or less than half the thinnest wall or fin in the terrain";
        pos("max_contact_travel_m", self.max_contact_travel_m, hint)?;
        at_least(
            "max_contact_travel_m",
            self.max_contact_travel_m,
            MIN_CONTACT_TRAVEL_M,
            "m",
            "the shortest travel",
            hint,
        )?;
        pos("contact_duration_s", self.contact_duration_s, "use 0.002 s, the default")?;
        let hint = "use 0.002 s, the default (impacts of rocks on soil last milliseconds)";
        at_most("contact_duration_s", self.contact_duration_s, 0.1, "is longer than a rock's impact lasts", hint)?;
        pos("max_time_s", self.max_time_s, "use for example 120 s")?;
        let hint = "use for example 120 s (a rock still moving after an hour is caught in a hollow, not falling)";
        at_most("max_time_s", self.max_time_s, MAX_TIME_S, "is longer than any rockfall", hint)?;
        pos("stop_speed_mps", self.stop_speed_mps, "use about 0.1 m/s")?;
        pos("stop_spin_radps", self.stop_spin_radps, "use about 0.2 rad/s")?;
        pos("stop_duration_s", self.stop_duration_s, "use about 0.5 s")?;
        pos("stop_in_place_s", self.stop_in_place_s, "use about 10 s")?;
        pos("sample_spacing_m", self.sample_spacing_m, "use half the raster cell size or less")?;
        let hint = format!("use {MIN_SAMPLE_SPACING_M} m or more (half the raster cell size is enough)");
        at_least("sample_spacing_m", self.sample_spacing_m, MIN_SAMPLE_SPACING_M, "m", "the smallest spacing", &hint)?;
        for (name, v) in
            [("bounce_threshold_mps", self.bounce_threshold_mps), ("penetration_slop_m", self.penetration_slop_m)]
        {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(
                    format!("{prefix}{name}"),
                    format!("must be 0 or more, got {v}"),
                    "give a small non-negative number",
                ));
            }
        }
        self.effects.validate(&format!("{prefix}effects."))?;
        if !(1..=MAX_IMPACT_SUBSTEPS).contains(&self.impact_substeps) {
            return Err(Error::invalid(
                format!("{prefix}impact_substeps"),
                format!("must be 1 to {MAX_IMPACT_SUBSTEPS}, got {}", self.impact_substeps),
                "use 1 (none) or 8 (impacts resolved at an eighth of dt_s)",
            ));
        }
        if !(1..=MAX_SOLVER_ITERATIONS).contains(&self.solver_iterations) {
            return Err(Error::invalid(
                format!("{prefix}solver_iterations"),
                format!("must be 1 to {MAX_SOLVER_ITERATIONS}, got {}", self.solver_iterations),
                "use 100, the default (the solver stops earlier once its impulses settle)",
            ));
        }
        if !(self.solver_tolerance_mps > 0.0 && self.solver_tolerance_mps <= MAX_SOLVER_TOLERANCE_MPS) {
            return Err(Error::invalid(
                format!("{prefix}solver_tolerance_mps"),
                format!(
                    "must be above 0 and at most {MAX_SOLVER_TOLERANCE_MPS} m/s, got {}",
                    crate::error::number_text(self.solver_tolerance_mps)
                ),
                "use 1e-4 (the default) or down to 1e-6 for a solver converged further, at about twice the sweeps",
            ));
        }
        Ok(())
    }
}

/// κ of the slippage-dependent friction by default, 1/m (Leine et al. 2014's demonstration set).
pub const SLIP_KAPPA_PER_M: f64 = 0.7;
/// β of the slippage-dependent friction by default, 1/s (Leine et al. 2014's demonstration set).
pub const SLIP_DECAY_PER_S: f64 = 20.0;
/// Reference mass of the mass-dependent restitution by default, kg.
pub const MASS_REFERENCE_KG: f64 = 100.0;

/// Effects the base 3DRB model lacks (physics.md §4), each off by default (`None`). The calibration loop switches
/// them on one at a time when the residuals point at them.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Effects {
    /// Restitution falls with impact speed (Pfeiffer & Bowen 1989, physics.md §3–4): Cr' = Cr / (1 + (v_n/K)²),
    /// with v_n the contact's normal approach speed and K this value, m/s (their K is 9.144 m/s).
    pub speed_restitution_k_mps: Option<f64>,
    /// Restitution depends on the impact angle θ between the incoming velocity and the ground (after Wyllie 2014,
    /// e_n ∝ θ^−1.03): Cr' = min(1, Cr·(max(θ, 5°)/30°)^−a), with a this exponent (ours: the 30° reference).
    pub angle_restitution_exponent: Option<f64>,
    /// Restitution scales with mass (physics.md §8, f_m): Cr' = min(1, Cr·(m/m_ref)^−β), with β this exponent.
    pub mass_restitution_exponent: Option<f64>,
    /// Reference mass of `mass_restitution_exponent`, kg (default [`MASS_REFERENCE_KG`]).
    pub mass_reference_kg: Option<f64>,
    /// Ground roughness felt relative to rock size (PlatRock, physics.md §4): at each impact the contact normal
    /// tilts by U(0, 1)·atan(rough/R) toward a random azimuth, R the equivalent radius; this value is `rough`, m.
    pub roughness_m: Option<f64>,
    /// Rolling resistance μ_r (Azzoni et al. 1995, physics.md §4 and §8): while in contact, the speed along the
    /// ground drops by A·μ_r·g·cos α per second, and the spin by the same fraction (our discretisation), with A the
    /// share of the kinetic energy along the ground in translation: m/(m + I/R²) for a rolling rock as in Azzoni,
    /// 1 for a sliding one (the force μ_r·N then does its work μ_r·N·v on the rock's whole kinetic energy).
    pub rolling_resistance: Option<f64>,
    /// Drag in soft ground: while in contact with one of `soft_materials` (all materials if empty), velocity and
    /// spin decay as exp(−c·t) with c this rate, 1/s (a linear stand-in for RAMMS's scarring drag, ours).
    pub soft_drag_per_s: Option<f64>,
    /// Materials where `soft_drag_per_s` acts (default: all).
    pub soft_materials: Vec<String>,
    /// Linear drag force from low vegetation, F = −c·v while the rock touches the ground, so that velocity and spin
    /// decay as exp(−(c/m)·t) and light rocks slow most (RAMMS's forest drag F_d = −c_d·v, Leine et al. 2014,
    /// physics.md §2, applied in contact: ours, for grass or shrubs lower than the rock); c this value, kg/s. Added
    /// to the soft-ground drag.
    pub vegetation_drag_kg_s: Option<f64>,
    /// RAMMS's slippage-dependent friction (Leine et al. 2014, eqs. 46-47 and 51; physics.md §2): the friction
    /// coefficient grows with the slippage s, the distance the rock's centre travels while touching the ground,
    /// μ(s) = μ_min + (2/π)(μ_max − μ_min)·atan(κ s), and s decays as exp(−β t) in flight, so a rock that rolls or
    /// slides far meets more friction than one that bounces. μ_min is the material's dynamic friction (tan φ_d, as
    /// drawn for the rock); this value is atan(μ_max) in degrees (μ_max below μ_min leaves friction unchanged).
    pub slip_friction_max_deg: Option<f64>,
    /// κ of `slip_friction_max_deg`, 1/m (default [`SLIP_KAPPA_PER_M`]).
    pub slip_friction_kappa_per_m: Option<f64>,
    /// β of `slip_friction_max_deg`, 1/s (default [`SLIP_DECAY_PER_S`]).
    pub slip_friction_decay_per_s: Option<f64>,
    /// Scarring drag in soft soil, quadratic in speed (after Lu et al. 2019's F_d = ½ C_d ρ_Σ A |v|², physics.md
    /// §2): while the rock touches the ground, a force −½ C ρ_Σ π R² |v| v with ρ_Σ = [`SCAR_SOIL_DENSITY_KG_M3`]
    /// and R the equivalent radius, so that velocity and spin fall as v' = v / (1 + k |v| t), k = ½ C ρ_Σ π R² / m.
    /// C is this value: Lu's C_d times the share of the rock's cross-section in the soil (ours: Lu's A(t) and
    /// penetration depth folded into one fitted number). Fast rocks are slowed most; added to the other drags.
    pub scar_drag_coefficient: Option<f64>,
}

/// Density of the scarred soil layer of `scar_drag_coefficient`, kg/m³ (Lu et al. 2019 at Chant Sura,
/// physics.md §2).
pub const SCAR_SOIL_DENSITY_KG_M3: f64 = 1700.0;

impl Effects {
    /// True if no effect is on.
    pub fn is_empty(&self) -> bool {
        self.speed_restitution_k_mps.is_none()
            && self.angle_restitution_exponent.is_none()
            && self.mass_restitution_exponent.is_none()
            && self.roughness_m.is_none()
            && self.rolling_resistance.is_none()
            && self.soft_drag_per_s.is_none()
            && self.vegetation_drag_kg_s.is_none()
            && self.slip_friction_max_deg.is_none()
            && self.scar_drag_coefficient.is_none()
    }

    /// Checks ranges; `prefix` is prepended to field names.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let check = |name: &str, v: Option<f64>, lo: f64, hi: f64| match v {
            Some(v) if !(v.is_finite() && v >= lo && v <= hi) => Err(Error::invalid(
                format!("{prefix}{name}"),
                format!("must be in [{lo}, {hi}], got {v}"),
                "see the effect's documentation in README.md",
            )),
            _ => Ok(()),
        };
        check("speed_restitution_k_mps", self.speed_restitution_k_mps, 0.1, 1000.0)?;
        check("angle_restitution_exponent", self.angle_restitution_exponent, -3.0, 3.0)?;
        check("mass_restitution_exponent", self.mass_restitution_exponent, -2.0, 2.0)?;
        check("mass_reference_kg", self.mass_reference_kg, 1e-3, 1e9)?;
        check("roughness_m", self.roughness_m, 0.0, 100.0)?;
        check("rolling_resistance", self.rolling_resistance, 0.0, 5.0)?;
        check("soft_drag_per_s", self.soft_drag_per_s, 0.0, 1000.0)?;
        check("vegetation_drag_kg_s", self.vegetation_drag_kg_s, 0.0, 1e6)?;
        check("slip_friction_max_deg", self.slip_friction_max_deg, 0.0, 85.0)?;
        check("slip_friction_kappa_per_m", self.slip_friction_kappa_per_m, 1e-3, 1e3)?;
        check("slip_friction_decay_per_s", self.slip_friction_decay_per_s, 0.0, 1e4)?;
        check("scar_drag_coefficient", self.scar_drag_coefficient, 0.0, 100.0)
    }

    /// Writes the defaults of the effects that are on into their unset companions (κ and β of the slippage
    /// friction, the mass restitution's reference mass), so that a run's manifest shows every value it used.
    pub fn fill_defaults(&mut self) {
        if self.slip_friction_max_deg.is_some() {
            self.slip_friction_kappa_per_m.get_or_insert(SLIP_KAPPA_PER_M);
            self.slip_friction_decay_per_s.get_or_insert(SLIP_DECAY_PER_S);
        }
        if self.mass_restitution_exponent.is_some() {
            self.mass_reference_kg.get_or_insert(MASS_REFERENCE_KG);
        }
    }

    /// The friction coefficient after `slip_friction_max_deg` for a rock with dynamic friction coefficient `mu_min`
    /// and slippage `slippage_m` (`mu_min` when off).
    pub fn slip_friction(&self, mu_min: f64, slippage_m: f64) -> f64 {
        match self.slip_friction_max_deg {
            Some(max_deg) => {
                let mu_max = max_deg.to_radians().tan().max(mu_min);
                let kappa = self.slip_friction_kappa_per_m.unwrap_or(SLIP_KAPPA_PER_M);
                mu_min + std::f64::consts::FRAC_2_PI * (mu_max - mu_min) * (kappa * slippage_m).atan()
            }
            None => mu_min,
        }
    }

    /// The factor by which the slippage of `slip_friction_max_deg` decays over `h` seconds in flight.
    pub fn slippage_decay(&self, h: f64) -> f64 {
        (-self.slip_friction_decay_per_s.unwrap_or(SLIP_DECAY_PER_S) * h).exp()
    }

    /// The drag rate of `vegetation_drag_kg_s` on a rock of `mass_kg`, 1/s (0 when off).
    pub fn vegetation_drag_per_s(&self, mass_kg: f64) -> f64 {
        self.vegetation_drag_kg_s.map_or(0.0, |c| c / mass_kg)
    }

    /// The rate k of `scar_drag_coefficient` for a rock of `mass_kg` and equivalent radius `radius_m`, 1/m (0 when
    /// off): in contact the speed falls as dv/dt = −k v².
    pub fn scar_drag_per_m(&self, mass_kg: f64, radius_m: f64) -> f64 {
        self.scar_drag_coefficient
            .map_or(0.0, |c| 0.5 * c * SCAR_SOIL_DENSITY_KG_M3 * std::f64::consts::PI * radius_m * radius_m / mass_kg)
    }

    /// The restitution coefficient after the restitution effects, for a contact approaching at `approach_mps`
    /// with the rock's velocity at `angle_deg` to the ground, for a rock of `mass_kg`.
    pub fn restitution(&self, cr: f64, approach_mps: f64, angle_deg: f64, mass_kg: f64) -> f64 {
        let mut e = cr;
        if let Some(k) = self.speed_restitution_k_mps {
            e /= 1.0 + (approach_mps / k).powi(2);
        }
        if let Some(a) = self.angle_restitution_exponent {
            e *= (angle_deg.max(5.0) / 30.0).powf(-a);
        }
        if let Some(b) = self.mass_restitution_exponent {
            e *= (mass_kg / self.mass_reference_kg.unwrap_or(MASS_REFERENCE_KG)).powf(-b);
        }
        e.clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn impact_substeps_out_of_range_are_refused_by_name() {
        for n in [0, MAX_IMPACT_SUBSTEPS + 1] {
            let e = SimParams { impact_substeps: n, ..SimParams::default() }.validate("simulation.").unwrap_err();
            assert!(e.to_string().contains("simulation.impact_substeps"), "{e}");
        }
        assert!(SimParams { impact_substeps: 8, ..SimParams::default() }.validate("simulation.").is_ok());
    }

    #[test]
    fn solver_tolerances_out_of_range_are_refused_by_name() {
        for v in [0.0, -1e-6, 2.0 * MAX_SOLVER_TOLERANCE_MPS, f64::NAN] {
            let e = SimParams { solver_tolerance_mps: v, ..SimParams::default() }.validate("simulation.").unwrap_err();
            assert!(e.to_string().contains("simulation.solver_tolerance_mps"), "{e}");
        }
        let loosest = SimParams { solver_tolerance_mps: MAX_SOLVER_TOLERANCE_MPS, ..SimParams::default() };
        assert!(loosest.validate("simulation.").is_ok());
    }

    #[test]
    fn slippage_friction_runs_from_the_dynamic_friction_to_its_maximum_and_decays_in_flight() {
        let off = Effects::default();
        assert_eq!(off.slip_friction(0.4, 10.0), 0.4);
        let fx = Effects { slip_friction_max_deg: Some(45.0), ..Effects::default() };
        assert_eq!(fx.slip_friction(0.4, 0.0), 0.4);
        // κ s = 1: half of the way up, (2/π) atan(1) = 1/2.
        assert!((fx.slip_friction(0.4, 1.0 / 0.7) - 0.7).abs() < 1e-12);
        assert!((fx.slip_friction(0.4, 1e9) - 1.0).abs() < 1e-6);
        // A maximum below the rock's dynamic friction leaves it unchanged.
        assert_eq!(fx.slip_friction(1.2, 5.0), 1.2);
        // β = 20 1/s by default: e^−1 after 50 ms.
        assert!((fx.slippage_decay(0.05) - (-1.0f64).exp()).abs() < 1e-12);
        // A manifest shows the defaults it used, and nothing for an effect that is off.
        let mut shown = fx.clone();
        shown.fill_defaults();
        assert_eq!((shown.slip_friction_kappa_per_m, shown.slip_friction_decay_per_s), (Some(0.7), Some(20.0)));
        assert_eq!(shown.mass_reference_kg, None);
        assert_eq!(shown.slip_friction(0.4, 2.0), fx.slip_friction(0.4, 2.0));
        let mut none = Effects::default();
        none.fill_defaults();
        assert_eq!(none, Effects::default());
    }
}
