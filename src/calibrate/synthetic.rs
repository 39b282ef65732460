//! Synthetic campaigns made with talus itself: a known model, optionally with an effect switched on that the
//! calibration will not be told about, simulated once per run from streams the calibration never uses, plus
//! measurement noise on the rest points. They test that calibration recovers what it should and that the effects
//! loop names the hidden effect (and nothing when there is none).
//!
//! 3DRB: a 35° slope, a 20° apron and a 5° run-out plain, 160 m × 120 m; four release points across the slope with
//! different drop heights (0.3 to 15 m); three cubic blocks of 20, 150 and 1200 kg. 2DLM: the same profile as a
//! section, three release points, three masses.

use super::effects::EffectKind;
use super::model::{Model, Prepared};
use super::model2d::Model2d;
use super::model3d::Model3d;
use super::params::{Candidate, EffectSpec, Params, Region};
use super::runs::{assign_groups, FieldRun};
use crate::campaign::TrackPoint;
use crate::error::Result;
use crate::lumped2d::{Options2d, Profile};
use crate::random::{standard_normal, stream, uniform, TruncNormal};
use crate::rock::{RockBody, RockSize, ShapeKind};
use crate::sim::SimParams;
use crate::terrain::{Material, Terrain};
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::path::Path;

/// The effect hidden in a synthetic campaign.
#[derive(Debug, Clone, PartialEq)]
pub enum Hidden {
    /// None (a control campaign).
    None,
    /// Restitution falling with impact speed, K in m/s.
    SpeedRestitution(f64),
    /// Roughness felt relative to rock size, in m.
    Roughness(f64),
    /// Restitution scaling with mass, Cr' = Cr (m/150 kg)^−β, with β given.
    MassRestitution(f64),
    /// A soft zone: polygon (x, y) and its material (Cr mean, static °, dynamic °).
    SoftZone(Vec<[f64; 2]>, [f64; 3]),
    /// A zone of soft ground (3DRB): polygon (x, y), its Cr mean (the terrain's friction and Cr spread) and its
    /// drag rate, 1/s.
    DragZone(Vec<[f64; 2]>, [f64; 2]),
    /// A linear drag in contact with the ground everywhere (3DRB), C in kg/s: a rock slows at C/m, so light rocks
    /// are held back most (a size effect through resistance rather than through the bounce).
    VegetationDrag(f64),
    /// RAMMS's slippage-dependent friction (3DRB), μ_max as an angle in degrees (κ and β at their defaults).
    SlipFriction(f64),
    /// A scarring drag quadratic in speed in contact with the ground (3DRB), its coefficient C.
    ScarDrag(f64),
}

impl Hidden {
    /// The effect kind the loop should name (None for a control).
    pub fn kind(&self) -> Option<EffectKind> {
        match self {
            Hidden::None => None,
            Hidden::SpeedRestitution(_) => Some(EffectKind::SpeedRestitution),
            Hidden::Roughness(_) => Some(EffectKind::Roughness),
            Hidden::MassRestitution(_) => Some(EffectKind::MassRestitution),
            Hidden::VegetationDrag(_) => Some(EffectKind::VegetationDrag),
            Hidden::SlipFriction(_) => Some(EffectKind::SlipFriction),
            Hidden::ScarDrag(_) => Some(EffectKind::ScarDrag),
            Hidden::SoftZone(..) | Hidden::DragZone(..) => Some(EffectKind::Zone),
        }
    }

    /// The zone polygon, if any.
    pub fn polygon(&self) -> Option<&[[f64; 2]]> {
        match self {
            Hidden::SoftZone(p, _) | Hidden::DragZone(p, _) => Some(p),
            _ => None,
        }
    }
}

/// Height noise of each tracked point of a tracked synthetic campaign (`CASE_tracked`), sd in m (ours: about what
/// tracking a block's centre from video or an embedded sensor achieves).
pub const TRACK_NOISE_M: f64 = 0.1;

/// Size of a synthetic 3DRB campaign.
#[derive(Debug, Clone, PartialEq)]
pub struct Synthetic3d {
    /// Seed of the data (the calibration uses its own seed).
    pub seed: u64,
    /// Runs per release point and block.
    pub runs_per_group: usize,
    /// Release points used (1 to 4).
    pub release_points: usize,
    /// Blocks used (masses, kg).
    pub masses_kg: Vec<f64>,
    /// The hidden effect.
    pub hidden: Hidden,
    /// Standard deviation of the measurement noise on rest points, m.
    pub noise_m: f64,
    /// Terrain cell size, m.
    pub cell_m: f64,
    /// The slope profile down +x: (horizontal length m, angle °) pieces from x = 0; the last continues.
    pub profile: Vec<(f64, f64)>,
    /// A second profile for the northern half (y ≥ 65 m; blended linearly with `profile` over 55–65 m), if any.
    pub north_profile: Option<Vec<(f64, f64)>>,
    /// Release heights above the ground of the release points, m (cycled over the points).
    pub release_heights_m: Vec<f64>,
    /// Cycle the release heights over the runs of each release point and block instead of over the points, so that
    /// every point sees every height (a speed effect then cannot pass for a place effect).
    pub heights_per_run: bool,
    /// Release x of each release point, m (cycled over the points).
    pub release_x_m: Vec<f64>,
    /// The true material.
    pub material: [f64; 4],
    /// Initial speed down +x, drawn uniformly in [min, max], m/s; cycled with the release heights (a run released
    /// from `release_heights_m[h]` draws from `release_speeds_mps[h % len]`).
    pub release_speeds_mps: Vec<[f64; 2]>,
    /// Block shape: `cube`, `flat_box`, `smartie`, or `boulder` (a rounded 32-vertex hull, see [`boulder`]).
    pub shape: String,
    /// Tracked paths: each run's true path is observed every millisecond with Gaussian height noise of this sd, m
    /// (`observed_tracks`), and the campaign declares it (`track_noise_m`, [`super::rebound`]); `None` for a
    /// campaign of rest points only.
    pub track_noise_m: Option<f64>,
}

/// A rounded boulder: the convex hull of 32 points spread evenly over a sphere (Fibonacci lattice). Its rolling is
/// far less chaotic than a cube's, which keeps the natural scatter of a synthetic campaign small next to the
/// effect hidden in it.
pub fn boulder() -> ShapeKind {
    let n = 32;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let points = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            [r * a.cos(), r * a.sin(), z]
        })
        .collect();
    ShapeKind::Hull { name: "boulder".into(), points }
}

impl Default for Synthetic3d {
    fn default() -> Self {
        Synthetic3d {
            seed: 1,
            runs_per_group: 4,
            release_points: 4,
            masses_kg: vec![20.0, 150.0, 1200.0],
            hidden: Hidden::None,
            noise_m: 0.5,
            cell_m: 5.0,
            profile: vec![(30.0, 15.0), (1000.0, 0.0)],
            north_profile: None,
            release_heights_m: vec![0.5, 4.0, 10.0, 20.0],
            heights_per_run: false,
            release_x_m: vec![4.0],
            material: TRUE_3D,
            shape: "cube".into(),
            release_speeds_mps: vec![[0.5, 1.5]],
            track_noise_m: None,
        }
    }
}

impl Synthetic3d {
    /// Height of the ground at (x, y), m (80 m at x = 0).
    pub fn height_m(&self, x: f64, y: f64) -> f64 {
        let south = profile_height_m(&self.profile, x);
        match &self.north_profile {
            None => south,
            Some(p) => {
                let w = ((y - 55.0) / 10.0).clamp(0.0, 1.0);
                (1.0 - w) * south + w * profile_height_m(p, x)
            }
        }
    }
}

/// Height at x of a profile of (length, angle °) pieces starting at 80 m, m.
pub fn profile_height_m(profile: &[(f64, f64)], x: f64) -> f64 {
    let mut z = 80.0;
    let mut x0 = 0.0;
    for (k, &(len, deg)) in profile.iter().enumerate() {
        let end = if k + 1 == profile.len() { f64::INFINITY } else { x0 + len };
        z -= (x.clamp(x0, end) - x0) * deg.to_radians().tan();
        x0 = end;
    }
    z
}

/// The true material of the synthetic terrain: Cr 0.35 ± 0.05, friction 40°/32°.
pub const TRUE_3D: [f64; 4] = [0.35, 0.05, 40.0, 32.0];

/// The standard synthetic 3DRB cases (ours, chosen so that the hidden effect moves run-outs by more than the
/// campaign's own scatter, which is what a ≥ 30 % cut of the held-out MAE needs):
/// - `speed` (and `control_a`): rounded boulders; on the southern half they are thrown (3–4 m/s) off 20 m high
///   release points onto a flat plain, on the northern half they start 0.5 m above a 20 m long 20° apron that ends
///   in the plain. Restitution Cr 0.6. `speed` hides Cr' = Cr/(1 + (v_n/6 m/s)²): the thrown blocks hit fast and
///   lose almost everything, the rolling ones hit slowly and keep most. There the fast impacts all land on one
///   patch, so a place effect fits them as well as a speed effect.
/// - `speed_mixed` (and `control_d`): the same terrain, material and effect, but every release point drops half its
///   blocks from 20 m and half from 0.5 m ([`Synthetic3d::heights_per_run`]): fast and slow impacts share the
///   ground, so a place effect cannot explain them (an angle effect still can: the fast drops hit steeply).
/// - `zone` (and `control_c`): rounded boulders start 2 m above a 20 m long 30° slope that ends in an 8° plain, on
///   which they roll off the 160 m terrain; `zone` hides soft ground (Cr 0.1 and drag 20/s, [`standard_zone`]) on
///   the plain below the two southern release points. Until 2026-11-28 the soft ground had the terrain's Cr 0.35:
///   with the impact sub-steps (the default since 2026-11-27) the boulders then hop across it, and 17 of its 36
///   southern runs roll on off the terrain (0 of 36 without the sub-steps), a split no median run-out can fit;
///   soft ground that also absorbs impacts stops them all at 2 ms, with and without the sub-steps
///   (docs/calibration.md, "The zone case and the impact sub-steps"). `rough` hides ground roughness of 0.3 m on
///   the same design: every impact's normal tilts by up to 68° under the 20 kg boulders and 32° under the 1200 kg
///   ones. Without the sub-steps that scattered run-outs more than the model without it could (the spread check
///   fired, p = 0.001); with them it does not fire (p = 0.30, docs/calibration.md, stop 52). On the `size` design
///   the cubes' own tumbling hid it.
/// - `size` (and `control_b`): cubes dropped 0.5 to 20 m onto a 15° apron; `size` hides Cr' = Cr (m/150 kg)^0.4, so
///   the 20 kg blocks bounce less and the 1200 kg ones more.
/// - `size_drag` (and `control_e`): rounded boulders start 2 m above a 20 m long 30° slope that ends in a level
///   plain; `size_drag` hides a drag −C v in contact with the ground (C = 200 kg/s, the `vegetation_drag` effect):
///   a rock slows at C/m, 10/s for the 20 kg blocks and 0.17/s for the 1200 kg ones, so the light ones stop
///   soon after the slope and the heavy ones roll on (a size effect through resistance: physics.md §4, "small
///   rocks over-run in the model because real slopes trap them"). A weaker drag hides in the blocks' scatter:
///   C = 20 or 50 kg/s on this design, or 5 to 40 kg/s on the `size` design, bound the cut at 0 (ratios
///   0.98–1.11, `explore_synthetic`), since a rolling boulder touches the ground only part of the time.
/// - `scar` (with `control_e`): the same design hiding the scarring drag (`scar_drag`, C = 1): in contact a rock
///   slows at k v², k = ½ C ρ π R² / m, from 2.0 /m for the 20 kg boulders to 0.5 /m for the 1200 kg ones, so it
///   acts on the rocks rolling fast down the slope and onto the plain, and lets the slow ones roll on. Tried only
///   when listed in `candidates` (the study's settings must list it).
pub fn case_3d(name: &str, seed: u64) -> Option<Synthetic3d> {
    if let Some(base) = name.strip_suffix("_tracked") {
        return case_3d(base, seed).map(|s| Synthetic3d { track_noise_m: Some(TRACK_NOISE_M), ..s });
    }
    let two_regime = Synthetic3d {
        seed,
        runs_per_group: 6,
        profile: vec![(1000.0, 0.0)],
        north_profile: Some(vec![(20.0, 20.0), (1000.0, 0.0)]),
        release_heights_m: vec![20.0, 20.0, 0.5, 0.5],
        release_speeds_mps: vec![[3.0, 4.0]],
        material: [0.6, 0.02, 40.0, 32.0],
        shape: "boulder".into(),
        ..Default::default()
    };
    let mixed = Synthetic3d { release_heights_m: vec![20.0, 0.5], heights_per_run: true, ..two_regime.clone() };
    let drops = Synthetic3d { seed, runs_per_group: 6, material: [0.35, 0.02, 40.0, 32.0], ..Default::default() };
    let plain = Synthetic3d {
        seed,
        runs_per_group: 6,
        profile: vec![(20.0, 30.0), (1000.0, 8.0)],
        release_heights_m: vec![2.0],
        material: [0.35, 0.02, 40.0, 32.0],
        shape: "boulder".into(),
        ..Default::default()
    };
    let flat = Synthetic3d { profile: vec![(20.0, 30.0), (1000.0, 0.0)], ..plain.clone() };
    Some(match name {
        "speed" => Synthetic3d { hidden: Hidden::SpeedRestitution(6.0), ..two_regime },
        "speed_mixed" => Synthetic3d { hidden: Hidden::SpeedRestitution(6.0), ..mixed },
        "control_d" => mixed,
        "zone" => Synthetic3d { hidden: Hidden::DragZone(standard_zone(), [0.1, 20.0]), ..plain },
        "control_a" => two_regime,
        "rough" => Synthetic3d { hidden: Hidden::Roughness(0.3), ..plain },
        "control_c" => plain,
        "size" => Synthetic3d { hidden: Hidden::MassRestitution(-0.4), ..drops },
        "control_b" => drops,
        "size_drag" => Synthetic3d { hidden: Hidden::VegetationDrag(200.0), ..flat },
        "control_e" => flat,
        "slip" => Synthetic3d { hidden: Hidden::SlipFriction(63.0), ..flat },
        "scar" => Synthetic3d { hidden: Hidden::ScarDrag(1.0), ..flat },
        _ => return None,
    })
}

/// The soft-ground polygon of the standard zone case: 40 m of the plain below the two southern release points.
pub fn standard_zone() -> Vec<[f64; 2]> {
    vec![[20.0, 0.0], [60.0, 0.0], [60.0, 57.0], [20.0, 57.0]]
}

/// Builds the synthetic 3DRB campaign: the model (with the terrain's declared material only) and the runs'
/// observed rest points made with the hidden effect on.
pub fn synthetic_3d(spec: &Synthetic3d, sim: SimParams) -> Result<Model3d> {
    let mat = |name: &str, v: [f64; 4]| Material {
        name: name.into(),
        cr: TruncNormal::three_sigma(v[0], v[1], 0.0, 1.0),
        static_friction_deg: v[2],
        dynamic_friction_deg: v[3],
        dynamic_friction_sd_deg: 0.0,
        drag_per_s: 0.0,
    };
    let n = (160.0 / spec.cell_m).round() as usize;
    let terrain = Terrain::from_function(160.0, n, mat("default", spec.material), |x, y| spec.height_m(x, y))?;
    let release_y = [20.0, 45.0, 70.0, 95.0];
    let release_h = &spec.release_heights_m;
    let mut bodies = BTreeMap::new();
    for (k, &m) in spec.masses_kg.iter().enumerate() {
        let shape = if spec.shape == "boulder" {
            boulder()
        } else {
            ShapeKind::builtin(&spec.shape).unwrap_or(ShapeKind::Cube)
        };
        bodies.insert(
            format!("b{}", k + 1),
            RockBody::new(&shape, RockSize::Mass { mass_kg: m, density_kg_m3: 2650.0 }, "synthetic block")?,
        );
    }
    let mut rng = stream(spec.seed, 7);
    let mut runs = Vec::new();
    for (p, release_y) in release_y.iter().enumerate().take(spec.release_points.clamp(1, 4)) {
        for (b, body) in &bodies {
            for i in 0..spec.runs_per_group {
                let (x, y) = (
                    spec.release_x_m[p % spec.release_x_m.len()] + 2.0 * (uniform(&mut rng) - 0.5),
                    release_y + 2.0 * (uniform(&mut rng) - 0.5),
                );
                let h = if spec.heights_per_run { i } else { p };
                let z = spec.height_m(x, y) + release_h[h % release_h.len()] + body.bounding_radius_m;
                let [lo, hi] = spec.release_speeds_mps[h % spec.release_speeds_mps.len()];
                let speed = lo + (hi - lo) * uniform(&mut rng);
                runs.push(FieldRun {
                    id: format!("s{:03}", runs.len() + 1),
                    index: runs.len(),
                    block_id: b.clone(),
                    mass_kg: body.mass_kg,
                    size_m: body.extents_m,
                    release_m: [x, y, z],
                    velocity_mps: [speed, 0.0, 0.0],
                    ..Default::default()
                });
            }
        }
    }
    let groups = assign_groups(&mut runs, 10.0);
    let truth_runs = runs.clone();
    let truth = truth_3d(spec);
    let truth_model =
        Model3d::from_parts(truth_runs, groups.clone(), terrain.clone(), bodies.clone(), sim.clone(), None)?;
    observe(&truth_model, &truth, &mut runs, spec.seed, spec.noise_m)?;
    let model = Model3d::from_parts(runs, groups, terrain, bodies, sim, None)?;
    let tracks = campaign_tracks(model.runs(), spec.track_noise_m, spec.seed, || {
        truth_model.tracks(&truth, 0, data_seed(spec.seed))
    })?;
    model.with_tracks(&tracks, spec.track_noise_m)
}

/// The true model of a synthetic 3DRB campaign: the terrain's material, plus the hidden effect.
pub fn truth_3d(spec: &Synthetic3d) -> Candidate {
    let mut truth = Candidate { params: material_params_3d("default", spec.material), ..Default::default() };
    match &spec.hidden {
        Hidden::None => {}
        Hidden::SpeedRestitution(k) => {
            truth.params.set("hidden.k_mps", *k);
            truth.effects.push(hidden_effect(EffectKind::SpeedRestitution));
        }
        Hidden::Roughness(r) => {
            truth.params.set("hidden.rough_m", *r);
            truth.effects.push(hidden_effect(EffectKind::Roughness));
        }
        Hidden::MassRestitution(b) => {
            truth.params.set("hidden.exponent", *b);
            truth.params.set("hidden.reference_kg", 150.0);
            truth.effects.push(hidden_effect(EffectKind::MassRestitution));
        }
        Hidden::VegetationDrag(c) => {
            truth.params.set("hidden.c_kg_s", *c);
            truth.effects.push(hidden_effect(EffectKind::VegetationDrag));
        }
        Hidden::SlipFriction(max_deg) => {
            truth.params.set("hidden.max_deg", *max_deg);
            truth.effects.push(hidden_effect(EffectKind::SlipFriction));
        }
        Hidden::ScarDrag(c) => {
            truth.params.set("hidden.coefficient", *c);
            truth.effects.push(hidden_effect(EffectKind::ScarDrag));
        }
        Hidden::SoftZone(poly, [cr, s, d]) => add_zone_3d(&mut truth, poly, [*cr, 0.02, *s, *d], 0.0),
        Hidden::DragZone(poly, [cr, rate]) => {
            let [_, cr_sd, s, d] = spec.material;
            add_zone_3d(&mut truth, poly, [*cr, cr_sd, s, d], *rate)
        }
    }
    truth
}

/// The hidden effect `kind` as the truth carries it (its parameters under `hidden.`).
fn hidden_effect(kind: EffectKind) -> EffectSpec {
    EffectSpec { kind, label: "hidden".into(), material: None, region: None }
}

/// The hidden zone over `region` (its material under `zonetrue.`).
fn hidden_zone(region: Region) -> EffectSpec {
    EffectSpec { kind: EffectKind::Zone, label: "zonetrue".into(), material: None, region: Some(region) }
}

/// Adds a hidden 3DRB zone over `poly` with `material` and, when positive, soft-ground drag to `truth`.
fn add_zone_3d(truth: &mut Candidate, poly: &[[f64; 2]], material: [f64; 4], drag_per_s: f64) {
    for (k, v) in material_params_3d("zonetrue", material).0 {
        truth.params.set(k, v);
    }
    if drag_per_s > 0.0 {
        truth.params.set("zonetrue.drag_per_s", drag_per_s);
    }
    truth.effects.push(hidden_zone(Region::Polygon(poly.to_vec())));
}

/// A profile campaign with long run-outs (ours): a 35° slope 40 m long, a 10° apron 30 m long and a flat floor;
/// releases 0.5, 5 and 15 m above the slope at x = 4, 12 and 20 m. Run-outs of 20 to 50 m, so that an effect moves
/// them by more than the 0.5 m measurement noise.
pub fn steep_2d() -> Synthetic2d {
    Synthetic2d {
        profile: vec![(40.0, 35.0), (30.0, 10.0), (1000.0, 0.0)],
        releases: vec![(4.0, 0.5), (12.0, 5.0), (20.0, 15.0)],
        ..Default::default()
    }
}

/// A profile campaign where restitution decides the run-out (ours, for the speed case): an endless 25° slope with
/// a bouncy material (Rn 0.6, Rt 0.8, friction 40°), releases 0.5, 2, 5, 10, 20 and 40 m above it, three runs per
/// release point and mass. Impact speeds range from 3 to 28 m/s, so a restitution that falls with speed
/// compresses the long drops' run-outs, which no single Rn can mimic.
pub fn bouncy_2d() -> Synthetic2d {
    Synthetic2d {
        runs_per_group: 3,
        profile: vec![(1000.0, 25.0)],
        releases: vec![(4.0, 0.5), (8.0, 2.0), (12.0, 5.0), (16.0, 10.0), (20.0, 20.0), (24.0, 40.0)],
        material: [0.6, 0.04, 0.8, 0.04, 40.0, 3.0],
        ..Default::default()
    }
}

/// The standard synthetic 2DLM cases (ours): `speed` hides Rn/(1 + (v_n/10 m/s)²) on [`bouncy_2d`]; `size` hides
/// Rn (m/500 kg)^0.3 and `zone` a soft patch at x 2–9 m (Rn 0.1, Rt 0.5, friction 55°) on [`steep_2d`];
/// `control_a` and `control_b` are the two designs with nothing hidden.
pub fn case_2d(name: &str, seed: u64) -> Option<Synthetic2d> {
    if let Some(base) = name.strip_suffix("_tracked") {
        return case_2d(base, seed).map(|s| Synthetic2d { track_noise_m: Some(TRACK_NOISE_M), ..s });
    }
    let (design, hidden) = match name {
        "speed" => (bouncy_2d(), Hidden::SpeedRestitution(10.0)),
        "size" => (steep_2d(), Hidden::MassRestitution(-0.3)),
        "zone" => (steep_2d(), Hidden::SoftZone(vec![[2.0, 0.0], [9.0, 0.0]], [0.1, 0.5, 55.0])),
        "control_a" => (bouncy_2d(), Hidden::None),
        "control_b" => (steep_2d(), Hidden::None),
        _ => return None,
    };
    Some(Synthetic2d { seed, hidden, ..design })
}

/// The true model of a synthetic 2DLM campaign: the profile's material, plus the hidden effect.
pub fn truth_2d(spec: &Synthetic2d) -> Candidate {
    let mut truth = Candidate { params: material_params_2d("ground", spec.material), effects: Vec::new() };
    match &spec.hidden {
        Hidden::None
        | Hidden::Roughness(_)
        | Hidden::DragZone(..)
        | Hidden::VegetationDrag(_)
        | Hidden::SlipFriction(_)
        | Hidden::ScarDrag(_) => {}
        Hidden::SpeedRestitution(k) => {
            truth.effects.push(hidden_effect(EffectKind::SpeedRestitution));
            truth.params.set("hidden.k_mps", *k);
        }
        Hidden::MassRestitution(b) => {
            truth.effects.push(hidden_effect(EffectKind::MassRestitution));
            truth.params.set("hidden.exponent", *b);
            truth.params.set("hidden.reference_kg", 500.0);
        }
        Hidden::SoftZone(iv, [rn, rt, f]) => {
            for (k, v) in material_params_2d("zonetrue", [*rn, 0.02, *rt, 0.02, *f, 3.0]).0 {
                truth.params.set(k, v);
            }
            truth.effects.push(hidden_zone(Region::Interval([iv[0][0], iv[1][0]])));
        }
    }
    truth
}

/// The parameters of a 3DRB material `[cr_mean, cr_sd, static °, dynamic °]` under `name`.
pub fn material_params_3d(name: &str, v: [f64; 4]) -> Params {
    let mut p = Params::default();
    for (k, x) in ["cr_mean", "cr_sd", "static_friction_deg", "dynamic_friction_deg"].iter().zip(v) {
        p.set(format!("{name}.{k}"), x);
    }
    p
}

/// Simulates each run once under `truth` from data streams ([`data_seed`], never used by calibration), adds noise,
/// and stores the rest points (noise `noise_m`) and run-outs in `runs`.
fn observe(model: &dyn Model, truth: &Candidate, runs: &mut [FieldRun], seed: u64, noise_m: f64) -> Result<()> {
    let prepared: Box<dyn Prepared + '_> = model.prepare(truth)?;
    let sims =
        crate::parallel::collect_in_order(runs.len(), 0, |i| prepared.simulate(&model.runs()[i], 0, data_seed(seed)));
    let mut rng = stream(seed, 11);
    let profile = model.kind() == super::config::ModelKind::Lumped2d;
    for (r, s) in runs.iter_mut().zip(sims) {
        let dx = noise_m * standard_normal(&mut rng);
        let dy = if profile { 0.0 } else { noise_m * standard_normal(&mut rng) };
        r.rest_m = [s.rest_m[0] + dx, s.rest_m[1] + dy, s.rest_m[2]];
        r.runout_m = (r.rest_m[0] - r.release_m[0]).hypot(r.rest_m[1] - r.release_m[1]);
    }
    Ok(())
}

/// Size of a synthetic 2DLM campaign.
#[derive(Debug, Clone, PartialEq)]
pub struct Synthetic2d {
    /// Seed of the data.
    pub seed: u64,
    /// Runs per release point and mass.
    pub runs_per_group: usize,
    /// Masses, kg.
    pub masses_kg: Vec<f64>,
    /// Hidden effect: `None`, `SpeedRestitution` (Pfeiffer–Bowen on), or `SoftZone` with an interval
    /// `[[x0, 0], [x1, 0]]` and its (Rn, Rt, friction °).
    pub hidden: Hidden,
    /// Noise on rest x, m.
    pub noise_m: f64,
    /// The profile: (horizontal length m, angle °) pieces from x = 0 (80 m high), to x = 200 m.
    pub profile: Vec<(f64, f64)>,
    /// Release points: (x, height above the profile), m.
    pub releases: Vec<(f64, f64)>,
    /// The true material `[rn, rn_sd, rt, rt_sd, friction °, roughness °]` (default [`TRUE_2D`]).
    pub material: [f64; 6],
    /// Tracked paths, observed and declared as in [`Synthetic3d::track_noise_m`]; `None` for rest points only.
    pub track_noise_m: Option<f64>,
}

impl Default for Synthetic2d {
    fn default() -> Self {
        Synthetic2d {
            seed: 1,
            runs_per_group: 6,
            masses_kg: vec![50.0, 500.0, 5000.0],
            hidden: Hidden::None,
            noise_m: 0.5,
            profile: vec![(30.0, 15.0), (1000.0, 0.0)],
            releases: vec![(3.0, 0.5), (6.0, 5.0), (9.0, 15.0)],
            material: TRUE_2D,
            track_noise_m: None,
        }
    }
}

/// The true 2DLM material: Rn 0.35 ± 0.04, Rt 0.80 ± 0.04, friction 32°, roughness 3°.
pub const TRUE_2D: [f64; 6] = [0.35, 0.04, 0.80, 0.04, 32.0, 3.0];

/// The parameters of a 2DLM material `[rn, rn_sd, rt, rt_sd, friction °, roughness °]` under `name`.
pub fn material_params_2d(name: &str, v: [f64; 6]) -> Params {
    let mut p = Params::default();
    for (k, x) in ["rn_mean", "rn_sd", "rt_mean", "rt_sd", "friction_angle_deg", "roughness_sd_deg"].iter().zip(v) {
        p.set(format!("{name}.{k}"), x);
    }
    p
}

/// A synthetic profile of (length, angle °) pieces (one material, `ground`), 0 to 200 m.
pub fn synthetic_profile(pieces: &[(f64, f64)]) -> Result<Profile> {
    let mut xs = vec![0.0];
    for (len, _) in pieces {
        let next = xs.last().copied().unwrap_or(0.0) + len;
        if next >= 200.0 {
            break;
        }
        xs.push(next);
    }
    xs.push(200.0);
    let v: Vec<[f64; 2]> = xs.iter().map(|&x| [x, profile_height_m(pieces, x)]).collect();
    Profile::new(&v, vec![0; v.len() - 1], vec!["ground".into()], "synthetic profile")
}

/// Builds the synthetic 2DLM campaign.
pub fn synthetic_2d(spec: &Synthetic2d, options: Options2d) -> Result<Model2d> {
    let profile = synthetic_profile(&spec.profile)?;
    let mut rng = stream(spec.seed, 7);
    let mut runs = Vec::new();
    for &(x0, h) in &spec.releases {
        for (k, &m) in spec.masses_kg.iter().enumerate() {
            for _ in 0..spec.runs_per_group {
                let x = x0 + (uniform(&mut rng) - 0.5);
                let z = profile_height_m(&spec.profile, x) + h;
                let size = (m / 2650.0).cbrt();
                runs.push(FieldRun {
                    id: format!("p{:03}", runs.len() + 1),
                    index: runs.len(),
                    block_id: format!("m{}", k + 1),
                    mass_kg: m,
                    size_m: [size; 3],
                    release_m: [x, 0.0, z],
                    velocity_mps: [0.5 + uniform(&mut rng), 0.0, 0.0],
                    ..Default::default()
                });
            }
        }
    }
    let groups = assign_groups(&mut runs, 2.0);
    let truth = truth_2d(spec);
    let truth_model = Model2d::from_parts(runs.clone(), groups.clone(), profile.clone(), options.clone())?;
    observe(&truth_model, &truth, &mut runs, spec.seed, spec.noise_m)?;
    let model = Model2d::from_parts(runs, groups, profile, options)?;
    let tracks = campaign_tracks(model.runs(), spec.track_noise_m, spec.seed, || {
        truth_model.tracks(&truth, 0, data_seed(spec.seed))
    })?;
    model.with_tracks(&tracks, spec.track_noise_m)
}

/// The tracks' height noise as given to the campaign writers (`write_profile_campaign`, `write_terrain_campaign`
/// examples): none is 0 (exact tracks); otherwise a non-negative number of metres.
///
/// # Errors
/// The text is not a finite non-negative number.
pub fn track_noise_arg(text: Option<&str>) -> std::result::Result<f64, String> {
    match text.map(str::parse::<f64>) {
        None => Ok(0.0),
        Some(Ok(v)) if v.is_finite() && v >= 0.0 => Ok(v),
        Some(_) => Err("TRACK_POINT_NOISE_M must be a non-negative number of metres, e.g. 0.1".into()),
    }
}

/// Writes the synthetic 2DLM campaign of `spec` into the folder `dir` as a user's field campaign would be: the
/// campaign CSVs (`release_points.csv`, `observed_deposition.csv`, `block_metadata.csv`) and the profile as
/// `profile.csv`, ready for `talus calibrate DIR --terrain DIR/profile.csv --model 2dlm`. A tracked case also gets
/// `observed_trajectories.csv`: each run's true path ([`Model2d::tracks`]) every millisecond to 1 mm, every height
/// plus Gaussian noise of sd `track_point_noise_m` (0 for exact tracks; the campaign in memory adds noise of sd
/// `track_noise_m` to each height). A rest point its survey noise puts past an end of the profile (a rock that ran
/// off the end) is written at that end, as a surveyor measuring along the profile would record it: `talus calibrate`
/// refuses rest points off the profile.
///
/// # Errors
/// The campaign cannot be simulated, or a file cannot be written.
pub fn write_profile_campaign(spec: &Synthetic2d, dir: &Path, track_point_noise_m: f64) -> Result<()> {
    let model = synthetic_2d(spec, Options2d::default())?;
    let profile = synthetic_profile(&spec.profile)?;
    let (x0, x1) = profile.x_range_m();
    let mut release = String::from("trajectory_id,x_m,z_m,vx_mps,vz_mps,wy_radps,block_id\n");
    let mut rest = String::from("trajectory_id,x_m,z_m,block_id\n");
    let mut blocks = BTreeMap::new();
    for r in model.runs() {
        let [vx, _, vz] = r.velocity_mps;
        let state = [r.release_m[0], r.release_m[2], vx, vz, r.spin_radps[1]].map(|v| v.to_string()).join(",");
        release += &format!("{},{state},{}\n", r.id, r.block_id);
        rest += &format!("{},{},{},{}\n", r.id, r.rest_m[0].clamp(x0, x1), r.rest_m[2], r.block_id);
        blocks.insert(r.block_id.clone(), (r.mass_kg, r.size_m));
    }
    let mut block_csv = String::from("block_id,mass_kg,size_x_m,size_y_m,size_z_m\n");
    for (id, (mass_kg, size_m)) in blocks {
        block_csv += &format!("{id},{mass_kg},{}\n", size_m.map(|v| v.to_string()).join(","));
    }
    crate::io::create_folder(dir)?;
    for (name, text) in
        [("release_points.csv", release), ("observed_deposition.csv", rest), ("block_metadata.csv", block_csv)]
    {
        crate::io::write_bytes_atomic(&dir.join(name), text.as_bytes())?;
    }
    if spec.track_noise_m.is_some() {
        let tracks = observed_tracks(
            model.runs(),
            model.tracks(&truth_2d(spec), 0, data_seed(spec.seed))?,
            track_point_noise_m,
            spec.seed,
        );
        let csv =
            tracks_csv("trajectory_id,time_s,x_m,z_m", model.runs(), &tracks, |p| format!("{:.3},{:.3}", p[0], p[2]));
        crate::io::write_bytes_atomic(&dir.join("observed_trajectories.csv"), csv.as_bytes())?;
    }
    profile.write_csv(&dir.join("profile.csv"))
}

/// Writes the synthetic 3DRB campaign of `spec` into the folder `dir` as a user's field campaign would be: the
/// campaign CSVs, the terrain as `terrain.obj` (the synthetic terrain's own triangles), and for boulders their hull
/// as `boulder.csv`; ready for `talus calibrate DIR --terrain DIR/terrain.obj --model 3drb`. A tracked case also
/// gets `observed_trajectories.csv`: each run's true path (a point every millisecond, [`Model3d::tracks`]) to 1 mm
/// and 1 ms, every height plus Gaussian noise of sd `track_point_noise_m` (0 for exact tracks; with the case's own
/// `track_noise_m`, the very tracks of the campaign in memory). The files read back give the same runs; the
/// terrain read from OBJ lies in another local frame, so simulations agree in distribution, not to the bit. A rest
/// point off the terrain (a rock that left it, or one its survey noise puts past an edge) is written at the edge,
/// its run-out measured to there: `talus calibrate` refuses rest points off the terrain.
///
/// The campaign is simulated with the engine settings `sim`.
///
/// # Errors
/// The campaign cannot be simulated, or a file cannot be written.
pub fn write_terrain_campaign(spec: &Synthetic3d, dir: &Path, track_point_noise_m: f64, sim: &SimParams) -> Result<()> {
    let model = synthetic_3d(spec, sim.clone())?;
    crate::io::create_folder(dir)?;
    // The terrain's horizontal extent in the campaign's frame, a millimetre inside its edges.
    let t = model.terrain();
    let (x0, y0, x1, y1) = t.surface.bounds_xy();
    let [a, b] = [[x0, y0], [x1, y1]].map(|[x, y]| t.to_file_frame(&nalgebra::Vector3::new(x, y, 0.0)));
    let inside = |v: f64, k: usize| v.clamp(a[k].min(b[k]) + 1e-3, a[k].max(b[k]) - 1e-3);
    let mut release = String::from("trajectory_id,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,block_id\n");
    let mut rest = String::from("trajectory_id,x_m,y_m,z_m,observed_runout_m,block_id\n");
    let mut blocks = BTreeMap::new();
    for r in model.runs() {
        let state: Vec<String> = r.release_m.iter().chain(&r.velocity_mps).map(|v| v.to_string()).collect();
        release += &format!("{},{},{}\n", r.id, state.join(","), r.block_id);
        let ([x, y, z], [x_r, y_r, _]) = (r.rest_m, r.release_m);
        let (x, y) = (inside(x, 0), inside(y, 1));
        let runout_m = if [x, y] == [r.rest_m[0], r.rest_m[1]] { r.runout_m } else { (x - x_r).hypot(y - y_r) };
        rest += &format!("{},{x},{y},{z},{runout_m},{}\n", r.id, r.block_id);
        blocks.insert(r.block_id.clone(), (r.mass_kg, r.size_m));
    }
    let shape = if spec.shape == "boulder" { "boulder.csv" } else { spec.shape.as_str() };
    let mut block_csv = String::from("block_id,mass_kg,size_x_m,size_y_m,size_z_m,shape\n");
    for (id, (mass_kg, size_m)) in blocks {
        block_csv += &format!("{id},{mass_kg},{},{shape}\n", size_m.map(|v| v.to_string()).join(","));
    }
    let mut files =
        vec![("release_points.csv", release), ("observed_deposition.csv", rest), ("block_metadata.csv", block_csv)];
    if let (true, ShapeKind::Hull { points, .. }) = (spec.shape == "boulder", boulder()) {
        let rows: Vec<String> = points.iter().map(|p| p.map(|v| v.to_string()).join(",")).collect();
        files.push(("boulder.csv", format!("x,y,z\n{}\n", rows.join("\n"))));
    }
    if spec.track_noise_m.is_some() {
        let paths = model.tracks(&truth_3d(spec), 0, data_seed(spec.seed))?;
        let tracks = observed_tracks(model.runs(), paths, track_point_noise_m, spec.seed);
        let csv = tracks_csv("trajectory_id,time_s,x_m,y_m,z_m", model.runs(), &tracks, |[x, y, z]| {
            format!("{x:.3},{y:.3},{z:.3}")
        });
        files.push(("observed_trajectories.csv", csv));
    }
    for (name, text) in files {
        crate::io::write_bytes_atomic(&dir.join(name), text.as_bytes())?;
    }
    let n = (160.0 / spec.cell_m).round() as usize;
    let (vertices, triangles) = crate::terrain::grid_mesh(160.0, n, |x, y| spec.height_m(x, y));
    let t = triangles.len();
    let mesh = crate::io::MeshData {
        vertices: vertices.iter().map(|v| [v.x, v.y, v.z]).collect(),
        triangles,
        group: vec![0; t],
        group_names: vec!["terrain".into()],
        material: vec![0; t],
        material_names: vec![String::new()],
    };
    crate::io::obj::write_obj(&dir.join("terrain.obj"), &mesh)
}

/// The tracks of `runs` as a tracking system records the true `paths` (each run's recorded path, in order; 3DRB a
/// point every millisecond): times rounded to the millisecond (a point closer in time to the last one kept is left out),
/// every height plus Gaussian noise of sd `noise_m` from the data's own stream (none when 0), by run id.
fn observed_tracks(
    runs: &[FieldRun],
    paths: Vec<Vec<TrackPoint>>,
    noise_m: f64,
    seed: u64,
) -> BTreeMap<String, Vec<TrackPoint>> {
    let mut rng = stream(seed, 13);
    let mut tracks = BTreeMap::new();
    for (r, path) in runs.iter().zip(paths) {
        let mut track: Vec<TrackPoint> = Vec::new();
        for p in path {
            let ms = (p.time_s * 1000.0).round();
            if track.last().is_none_or(|q| ms > (q.time_s * 1000.0).round()) {
                let [x, y, z] = p.position_m;
                let z = z + noise_m * standard_normal(&mut rng);
                track.push(TrackPoint { time_s: ms / 1000.0, position_m: [x, y, z] });
            }
        }
        tracks.insert(r.id.clone(), track);
    }
    tracks
}

/// The observed tracks of a synthetic campaign's `runs`: on a tracked campaign (`track_noise_m` given) the true
/// `paths` as [`observed_tracks`] records them with that noise, on an untracked one none (`paths` not simulated).
fn campaign_tracks(
    runs: &[FieldRun],
    track_noise_m: Option<f64>,
    seed: u64,
    paths: impl FnOnce() -> Result<Vec<Vec<TrackPoint>>>,
) -> Result<BTreeMap<String, Vec<TrackPoint>>> {
    match track_noise_m {
        None => Ok(BTreeMap::new()),
        Some(sd) => Ok(observed_tracks(runs, paths()?, sd, seed)),
    }
}

/// The `observed_trajectories.csv` text of the `tracks` of `runs` under `header`, each position written by
/// `coords`.
fn tracks_csv(
    header: &str,
    runs: &[FieldRun],
    tracks: &BTreeMap<String, Vec<TrackPoint>>,
    coords: impl Fn([f64; 3]) -> String,
) -> String {
    let mut csv = format!("{header}\n");
    for r in runs {
        for p in &tracks[&r.id] {
            csv += &format!("{},{:.3},{}\n", r.id, p.time_s, coords(p.position_m));
        }
    }
    csv
}

/// Seed of the true simulations of a synthetic campaign of seed `seed` (apart from the calibration's own seeds).
fn data_seed(seed: u64) -> u64 {
    seed.wrapping_add(1000)
}

/// Share of `polygon`'s area that lies inside `truth` (estimated on a 40 × 40 lattice over the polygon's bounding
/// box), and whether the polygon's centroid lies inside `truth`.
pub fn zone_overlap(polygon: &[[f64; 2]], truth: &[[f64; 2]]) -> (f64, bool) {
    let r = Region::Polygon(polygon.to_vec());
    let [x0, y0, x1, y1] = r.bbox();
    let (mut inside, mut both) = (0usize, 0usize);
    let (mut cx, mut cy) = (0.0, 0.0);
    for a in 0..40 {
        for b in 0..40 {
            let x = x0 + (a as f64 + 0.5) / 40.0 * (x1 - x0);
            let y = y0 + (b as f64 + 0.5) / 40.0 * (y1 - y0);
            if r.contains(x, y) {
                inside += 1;
                cx += x;
                cy += y;
                if crate::terrain::point_in_polygon(x, y, truth) {
                    both += 1;
                }
            }
        }
    }
    if inside == 0 {
        return (0.0, false);
    }
    let c = Vector3::new(cx / inside as f64, cy / inside as f64, 0.0);
    (both as f64 / inside as f64, crate::terrain::point_in_polygon(c.x, c.y, truth))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_tracks_give_back_the_rebounds_of_the_true_paths() {
        // The tracked paths `write_profile_campaign` writes, read back as a user's file, rebound as the true model's
        // simulations of the same runs did (to the millimetres the file keeps).
        let spec = Synthetic2d { runs_per_group: 2, ..case_2d("speed_tracked", 1).unwrap() };
        let dir = tempfile::tempdir().unwrap();
        write_profile_campaign(&spec, dir.path(), 0.0).unwrap();
        let campaign = crate::campaign::Campaign::read(dir.path()).unwrap();
        assert_eq!(campaign.tracks.len(), campaign.releases.len());
        let (runs, groups) = super::super::runs::field_runs(&campaign, 2.0, crate::terrain::UpAxis::Z).unwrap();
        let cfg = super::super::config::CalibrationConfig::default();
        let read = Model2d::new(&campaign, runs, groups, &dir.path().join("profile.csv"), &cfg).unwrap();
        // The campaign read from the files simulates (and measures the rebounds of) the true paths again.
        let prepared = read.prepare(&truth_2d(&spec)).unwrap();
        let mut bounced = 0;
        for run in read.runs() {
            let simulated = prepared.simulate(run, 0, data_seed(spec.seed)).summary.rebound_height_m;
            let observed = run.rebound_height_m.unwrap();
            assert!((observed - simulated).abs() < 0.005, "{}: {observed:.3} against {simulated:.3} m", run.id);
            bounced += usize::from(simulated > 0.5);
        }
        assert!(bounced > 5, "only {bounced} runs rebound more than 0.5 m");
    }

    #[test]
    fn a_written_terrain_campaign_reads_back_as_the_same_runs_and_paths() {
        // The `speed_tracked` design (boulders, the hull in boulder.csv) with 2 runs per group and exact tracks,
        // written and read back as a user's files: the same runs to the digit, the same blocks, and the tracks give
        // back the rebounds of the campaign in memory and of the true paths simulated again (read at the track's
        // times) to the millimetres the file keeps; the true model from the files runs out as it does in memory
        // (the OBJ terrain lies in another local frame, so the simulations agree in distribution, not to the bit).
        let spec = Synthetic3d { runs_per_group: 2, track_noise_m: Some(0.0), ..case_3d("speed_tracked", 1).unwrap() };
        let dir = tempfile::tempdir().unwrap();
        write_terrain_campaign(&spec, dir.path(), 0.0, &SimParams::default()).unwrap();
        let campaign = crate::campaign::Campaign::read(dir.path()).unwrap();
        assert_eq!(campaign.tracks.len(), campaign.releases.len());
        let (runs, groups) = super::super::runs::field_runs(&campaign, 10.0, crate::terrain::UpAxis::Z).unwrap();
        let cfg = super::super::config::CalibrationConfig::default();
        let read = Model3d::new(&campaign, runs, groups, &dir.path().join("terrain.obj"), &cfg, "test").unwrap();
        let memory = synthetic_3d(&spec, SimParams::default()).unwrap();
        // Only the model read from files takes `[terrain] level_beyond` from the settings (a warning suggests it).
        assert!(read.levelled_by_settings() && !memory.levelled_by_settings());
        assert_eq!(read.runs().len(), memory.runs().len());
        for (a, b) in read.runs().iter().zip(memory.runs()) {
            assert_eq!(
                (&a.id, &a.block_id, a.release_m, a.rest_m, a.runout_m),
                (&b.id, &b.block_id, b.release_m, b.rest_m, b.runout_m)
            );
            assert!((a.mass_kg - b.mass_kg).abs() < 1e-9 * b.mass_kg);
        }
        let truth = truth_3d(&spec);
        let prepared = memory.prepare(&truth).unwrap();
        let mut bounced = 0;
        for (run, mem) in read.runs().iter().zip(memory.runs()) {
            let simulated = prepared.simulate(mem, 0, data_seed(spec.seed)).summary.rebound_height_m;
            let (observed, in_memory) = (run.rebound_height_m.unwrap(), mem.rebound_height_m.unwrap());
            for other in [simulated, in_memory] {
                assert!((observed - other).abs() < 0.005, "{}: {observed:.3} against {other:.3} m", run.id);
            }
            bounced += usize::from(simulated > 0.5);
        }
        assert!(bounced > 3, "only {bounced} runs rebound more than 0.5 m");
        let all: Vec<usize> = (0..read.runs().len()).collect();
        let mean_runout = |m: &Model3d| {
            let sims = super::super::model::evaluate(m, &truth, &all, 8, 5, 0).unwrap();
            let r = sims.iter().flat_map(|s| s.runouts()).collect::<Vec<f64>>();
            r.iter().sum::<f64>() / r.len() as f64
        };
        let (from_files, from_memory) = (mean_runout(&read), mean_runout(&memory));
        assert!((from_files / from_memory - 1.0).abs() < 0.05, "{from_files:.1} against {from_memory:.1} m");
    }

    #[test]
    fn simulated_rebounds_on_level_ground_stay_below_the_drop_and_near_cr_squared() {
        // Boulders dropped 5 and 10 m onto level ground, Cr 0.35 ± 0.05: an impact never adds energy, so no path's
        // rebound (the centre's rise above its lowest point, `rebound.rs`) exceeds the fall; a sphere would rebound
        // Cr² × the fall (0.12 of it), a 32-vertex hull striking off-centre less, as part of the speed goes to
        // spin (median 0.088 of it here, its flights read every millisecond; 0.08 when read at the engine's
        // samples, which cut the apex).
        let spec = Synthetic3d {
            runs_per_group: 3,
            release_points: 2,
            masses_kg: vec![150.0],
            profile: vec![(1000.0, 0.0)],
            release_heights_m: vec![5.0, 10.0],
            release_speeds_mps: vec![[0.0, 0.0]],
            shape: "boulder".into(),
            track_noise_m: Some(0.0),
            ..Synthetic3d::default()
        };
        let model = synthetic_3d(&spec, SimParams::default()).unwrap();
        let prepared = model.prepare(&truth_3d(&spec)).unwrap();
        let size = RockSize::Mass { mass_kg: 150.0, density_kg_m3: 2650.0 };
        let r = RockBody::new(&boulder(), size, "").unwrap().bounding_radius_m;
        let mut ratios = Vec::new();
        for run in model.runs() {
            let [x, y, z] = run.release_m;
            let fall_m = z - spec.height_m(x, y) - r;
            assert!(run.rebound_height_m.is_some(), "a tracked synthetic run has an observed rebound");
            for repeat in 0..8 {
                let h = prepared.simulate(run, repeat, 5).summary.rebound_height_m;
                assert!((0.0..=fall_m + 0.2 * r).contains(&h), "rebound {h:.2} m after a fall of {fall_m:.1} m");
                ratios.push(h / fall_m);
            }
        }
        ratios.sort_by(f64::total_cmp);
        let median = ratios[ratios.len() / 2];
        assert!((0.04..=0.15).contains(&median), "median rebound / fall {median:.3} (a sphere: 0.12)");
    }

    #[test]
    fn heights_per_run_drops_every_height_from_every_release_point() {
        let heights = |name: &str| -> Vec<(usize, f64)> {
            let spec = Synthetic3d { runs_per_group: 2, masses_kg: vec![150.0], ..case_3d(name, 1).unwrap() };
            let model = synthetic_3d(&spec, SimParams::default()).unwrap();
            let size = RockSize::Mass { mass_kg: 150.0, density_kg_m3: 2650.0 };
            let r = RockBody::new(&boulder(), size, "").unwrap().bounding_radius_m;
            let mut out: Vec<(usize, f64)> = model
                .runs()
                .iter()
                .map(|run| {
                    let [x, y, z] = run.release_m;
                    let point = ((y - 20.0) / 25.0).round() as usize;
                    (point, ((z - spec.height_m(x, y) - r) * 10.0).round() / 10.0)
                })
                .collect();
            out.sort_by(|a, b| a.partial_cmp(b).unwrap());
            out
        };
        // `speed`: the two southern points drop 20 m, the northern 0.5 m; `speed_mixed`: each point both.
        assert_eq!(
            heights("speed"),
            vec![(0, 20.0), (0, 20.0), (1, 20.0), (1, 20.0), (2, 0.5), (2, 0.5), (3, 0.5), (3, 0.5)]
        );
        assert_eq!(
            heights("speed_mixed"),
            vec![(0, 0.5), (0, 20.0), (1, 0.5), (1, 20.0), (2, 0.5), (2, 20.0), (3, 0.5), (3, 20.0)]
        );
    }
}
