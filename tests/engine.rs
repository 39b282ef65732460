//! Closed forms and invariants of the 3DRB engine.

use approx::assert_relative_eq;
use nalgebra::{UnitQuaternion, Vector3};
use talus::random::{stream, TruncNormal};
use talus::rock::{RockBody, RockSize, ShapeKind};
use talus::sim::{simulate, Impact, Observer, RigidState, Sample, SimParams, StopReason, GRAVITY_MPS2};
use talus::terrain::{Material, Terrain};

fn material(cr: f64, static_deg: f64, dynamic_deg: f64) -> Material {
    Material {
        name: "m".into(),
        cr: TruncNormal::fixed(cr),
        static_friction_deg: static_deg,
        dynamic_friction_deg: dynamic_deg,
        dynamic_friction_sd_deg: 0.0,
        drag_per_s: 0.0,
    }
}

fn rock(kind: ShapeKind, mass_kg: f64) -> RockBody {
    RockBody::new(&kind, RockSize::Mass { mass_kg, density_kg_m3: 2650.0 }, "rock").unwrap()
}

#[derive(Default)]
struct Record {
    samples: Vec<Sample>,
    impacts: Vec<Impact>,
}

impl Observer for Record {
    fn sample(&mut self, s: &Sample) {
        self.samples.push(*s);
    }
    fn impact(&mut self, i: &Impact) {
        self.impacts.push(*i);
    }
}

impl Record {
    /// The first sample in free flight and rising after the first impact: the rebound.
    fn rebound(&self) -> Option<&Sample> {
        let t = self.impacts.first()?.t_s;
        self.samples.iter().find(|s| s.t_s > t && !s.in_contact && s.velocity_mps.z > 0.0)
    }
}

fn at_rest(position: Vector3<f64>, orientation: UnitQuaternion<f64>) -> RigidState {
    RigidState { position_m: position, velocity_mps: Vector3::zeros(), orientation, omega_body_radps: Vector3::zeros() }
}

#[test]
fn free_flight_follows_the_parabola_and_keeps_its_spin() {
    let terrain = Terrain::from_function(400.0, 4, material(0.3, 40.0, 30.0), |_, _| 0.0).unwrap();
    let r = rock(ShapeKind::FlatBox, 500.0);
    let v0 = Vector3::new(12.0, 3.0, 8.0);
    let x0 = Vector3::new(50.0, 50.0, 300.0);
    let start = RigidState {
        position_m: x0,
        velocity_mps: v0,
        orientation: UnitQuaternion::from_euler_angles(0.3, 0.2, 0.1),
        omega_body_radps: Vector3::new(0.3, 4.0, 0.5),
    };
    let mut rec = Record::default();
    let params = SimParams { max_time_s: 5.0, ..Default::default() };
    simulate(&terrain, &r, start, &params, &mut stream(1, 0), &mut rec);
    let e_rot0 = start.rotational_energy_j(&r.inertia_kg_m2);
    let in_flight: Vec<&Sample> = rec.samples.iter().filter(|s| s.t_s > 0.0 && s.t_s <= 5.0).collect();
    assert!(in_flight.len() > 20);
    for s in in_flight {
        let t = s.t_s;
        let want = x0 + v0 * t + Vector3::new(0.0, 0.0, -0.5 * GRAVITY_MPS2 * t * t);
        assert!((s.position_m - want).norm() < 1e-9 * want.norm(), "t={t}: {:?} vs {want:?}", s.position_m);
        let e_rot = s.kinetic_j - s.translational_j;
        assert_relative_eq!(e_rot, e_rot0, max_relative = 1e-9);
    }
}

#[test]
fn a_rock_flying_off_the_terrain_ends_where_it_crossed_the_edge() {
    // Thrown level at 20 m/s from x = 351 m, 300 m above a flat 400 m square: the centre crosses the edge x = 400 m
    // at t = 2.45 s, on the parabola. A flight step lasts up to 0.25 s, so without cutting the flight at the crossing
    // the rock would be found up to 5 m past it.
    let terrain = Terrain::from_function(400.0, 4, material(0.3, 40.0, 30.0), |_, _| 0.0).unwrap();
    let r = rock(ShapeKind::Cube, 500.0);
    let (x0, v0) = (Vector3::new(351.0, 200.0, 300.0), Vector3::new(20.0, 0.0, 0.0));
    let start = RigidState { velocity_mps: v0, ..at_rest(x0, UnitQuaternion::identity()) };
    let out = simulate(&terrain, &r, start, &SimParams::default(), &mut stream(1, 0), &mut ());
    assert_eq!(out.stop_reason, StopReason::LeftTerrain);
    let t = 2.45;
    let want = x0 + v0 * t + Vector3::new(0.0, 0.0, -0.5 * GRAVITY_MPS2 * t * t);
    assert!(
        (out.final_state.position_m - want).norm() < 1e-3,
        "ends at {:?}, crossed at {want:?}",
        out.final_state.position_m
    );
    assert!(out.final_state.position_m.x >= 400.0, "recorded before the edge: {:?}", out.final_state.position_m);
    assert!((out.travel_time_s - t).abs() < 1e-4, "travel time {} s", out.travel_time_s);
}

#[test]
fn cube_dropped_flat_rebounds_with_cr_times_impact_speed_and_no_spin() {
    let cr = 0.5;
    let terrain = Terrain::from_function(40.0, 8, material(cr, 40.0, 30.0), |_, _| 0.0).unwrap();
    let r = rock(ShapeKind::Cube, 2650.0); // 1 m cube
    let drop_m = 2.0;
    let start = at_rest(Vector3::new(20.3, 20.1, 0.5 + drop_m), UnitQuaternion::identity());
    // Also with the impact step divided (`impact_substeps`): the closed form holds as it is resolved; and with the
    // solver converged to 1e-6 m/s. What spin and sideways speed the rebound keeps is the solver's residual: within
    // ten times its tolerance at a contact, 0.5 m from the centre (1e-3 rad/s by default, far below the rest test's
    // 0.2 rad/s).
    for (impact_substeps, solver) in [(1, SimParams::default()), (8, SimParams::default()), (8, fine_solver())] {
        let mut rec = Record::default();
        let params = SimParams { max_time_s: 1.5, impact_substeps, ..solver };
        let tolerance_mps = params.solver_tolerance_mps;
        simulate(&terrain, &r, start, &params, &mut stream(1, 0), &mut rec);
        let first = rec.impacts.first().expect("an impact");
        let v_in = (2.0 * GRAVITY_MPS2 * drop_m).sqrt();
        assert_relative_eq!(first.approach_speed_mps, v_in, max_relative = 0.01);
        // After the impact and before the next one: a free rise whose apex gives the rebound speed.
        let rising = rec.rebound().expect("rising");
        let v_out = (rising.velocity_mps.z.powi(2) + 2.0 * GRAVITY_MPS2 * rising.clearance_m).sqrt();
        let apex_clearance = rising.clearance_m + rising.velocity_mps.z.powi(2) / (2.0 * GRAVITY_MPS2);
        assert_relative_eq!(v_out, cr * v_in, max_relative = 0.01);
        assert_relative_eq!(apex_clearance, cr * cr * drop_m, max_relative = 0.02);
        assert!(rising.spin_radps < 10.0 * tolerance_mps / 0.5, "spin {}", rising.spin_radps);
        let sideways = rising.velocity_mps.x.abs().max(rising.velocity_mps.y.abs());
        assert!(sideways < 10.0 * tolerance_mps, "sideways {sideways} m/s");
    }
}

/// A plane rising toward −x at `slope_deg`, so that "downslope" is +x.
fn incline(slope_deg: f64, m: Material) -> Terrain {
    let t = slope_deg.to_radians().tan();
    Terrain::from_function(200.0, 20, m, move |x, _| (200.0 - x) * t).unwrap()
}

/// Start pose of a box resting flat on the incline with its long axis downslope.
fn resting_on_incline(r: &RockBody, slope_deg: f64, x: f64, speed_mps: f64) -> RigidState {
    // Body axes of a built-in box: principal axes; find the shortest extent's axis to put it normal to the slope.
    let (mut min_axis, mut max_axis) = (0, 0);
    for a in 0..3 {
        let ext = |a: usize| r.vertices_m.iter().map(|v| v[a].abs()).fold(0.0, f64::max);
        if ext(a) < ext(min_axis) {
            min_axis = a;
        }
        if ext(a) > ext(max_axis) {
            max_axis = a;
        }
    }
    let half_thickness = r.vertices_m.iter().map(|v| v[min_axis].abs()).fold(0.0, f64::max);
    let th = slope_deg.to_radians();
    let normal = Vector3::new(th.sin(), 0.0, th.cos());
    let down = Vector3::new(th.cos(), 0.0, -th.sin());
    let axis = |i: usize| Vector3::ith(i, 1.0);
    // Rotation taking body min_axis to the slope normal and max_axis downslope.
    let third = normal.cross(&down);
    let world = nalgebra::Matrix3::from_columns(&[down, third, normal]);
    let body = nalgebra::Matrix3::from_columns(&[
        axis(max_axis),
        axis(max_axis).cross(&axis(min_axis)) * -1.0,
        axis(min_axis),
    ]);
    let rot = nalgebra::Rotation3::from_matrix_unchecked(world * body.transpose());
    let q = UnitQuaternion::from_rotation_matrix(&rot);
    let ground = (200.0 - x) * th.tan();
    RigidState {
        position_m: Vector3::new(x, 100.0, ground) + normal * half_thickness,
        velocity_mps: down * speed_mps,
        orientation: q,
        omega_body_radps: Vector3::zeros(),
    }
}

/// A 1,000 kg flat box sent down `slope_deg` at 5 m/s on ground of Cr 0 and the friction angles given, until it
/// stops: the distance it slid, m, and its final spin, rad/s.
fn slide(slope_deg: f64, static_deg: f64, dynamic_deg: f64, params: &SimParams) -> (f64, f64) {
    let terrain = incline(slope_deg, material(0.0, static_deg, dynamic_deg));
    let r = rock(ShapeKind::FlatBox, 1000.0);
    let start = resting_on_incline(&r, slope_deg, 60.0, SLIDE_MPS);
    let out = simulate(&terrain, &r, start, params, &mut stream(1, 0), &mut ());
    assert_eq!(out.stop_reason, StopReason::Stopped);
    ((out.final_state.position_m - start.position_m).norm(), out.final_state.omega_body_radps.norm())
}

/// The start speed of [`slide`], m/s.
const SLIDE_MPS: f64 = 5.0;

#[test]
fn block_sliding_down_an_incline_stops_where_the_closed_form_says() {
    let (slope, phi_d) = (10.0f64, 30.0f64);
    let (th, mu) = (slope.to_radians(), phi_d.to_radians().tan());
    let want = SLIDE_MPS * SLIDE_MPS / (2.0 * GRAVITY_MPS2 * (mu * th.cos() - th.sin()));
    // Also with the solver converged further than by default.
    for params in [SimParams::default(), fine_solver()] {
        let (moved, spin) = slide(slope, 32.0, phi_d, &params);
        assert_relative_eq!(moved, want, max_relative = 0.005);
        assert!(spin < 0.2);
    }
}

/// The default engine with the solver's sweeps stopping at 1e-6 m/s (the default until 2026-11-30) rather than at
/// the default, and loosest, tolerance.
fn fine_solver() -> SimParams {
    SimParams { solver_tolerance_mps: 1e-6, ..Default::default() }
}

#[test]
fn with_slippage_dependent_friction_a_sliding_block_stops_where_the_closed_form_says() {
    // RAMMS's μ(s) = μ_min + (2/π)(μ_max − μ_min) atan(κ s) (Leine et al. 2014, physics.md §2), s the distance slid:
    // v dv/ds = −g (μ(s) cos θ − sin θ), so v0²/2 = g (cos θ M(D) − D sin θ) with
    // M(D) = ∫0^D μ = μ_min D + (2/π)(μ_max − μ_min)(D atan(κD) − ln(1 + κ²D²)/(2κ)). Solved for D by bisection.
    let (slope, phi_d, max_deg, kappa) = (10.0f64, 25.0f64, 45.0f64, 0.7f64);
    let terrain = incline(slope, material(0.0, 27.0, phi_d));
    let r = rock(ShapeKind::FlatBox, 1000.0);
    let v0 = 5.0;
    let start = resting_on_incline(&r, slope, 60.0, v0);
    let mut params = SimParams::default();
    params.effects.slip_friction_max_deg = Some(max_deg);
    params.effects.slip_friction_kappa_per_m = Some(kappa);
    let out = simulate(&terrain, &r, start, &params, &mut stream(1, 0), &mut ());
    assert_eq!(out.stop_reason, StopReason::Stopped);
    let (th, mu_min, mu_max) = (slope.to_radians(), phi_d.to_radians().tan(), max_deg.to_radians().tan());
    let m = |d: f64| {
        mu_min * d
            + std::f64::consts::FRAC_2_PI
                * (mu_max - mu_min)
                * (d * (kappa * d).atan() - (kappa * kappa * d * d).ln_1p() / (2.0 * kappa))
    };
    let work = |d: f64| GRAVITY_MPS2 * (th.cos() * m(d) - d * th.sin()) - 0.5 * v0 * v0;
    let (mut lo, mut hi) = (0.0, 100.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if work(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let moved = (out.final_state.position_m - start.position_m).norm();
    assert_relative_eq!(moved, lo, max_relative = 0.01);
    // Without the effect the block slides farther (μ_min alone: 4.46 m; with it 2.53 m, the closed form 2.525 m).
    let plain = v0 * v0 / (2.0 * GRAVITY_MPS2 * (mu_min * th.cos() - th.sin()));
    assert!(moved < 0.7 * plain, "{moved} against {plain}");
}

#[test]
fn with_scarring_drag_a_sliding_block_stops_where_the_closed_form_says() {
    // A drag quadratic in speed (after Lu et al. 2019, physics.md §2) on a block sliding down θ with friction μ:
    // v dv/ds = −a − k v², a = g (μ cos θ − sin θ), so v² + a/k falls as exp(−2 k s) and the block stops after
    // D = ln(1 + k v0² / a) / (2 k), with k = ½ C ρ π R² / m.
    let (slope, phi_d, coefficient) = (10.0f64, 25.0f64, 0.5f64);
    let terrain = incline(slope, material(0.0, 27.0, phi_d));
    let r = rock(ShapeKind::FlatBox, 1000.0);
    let v0 = 5.0;
    let start = resting_on_incline(&r, slope, 60.0, v0);
    let mut params = SimParams::default();
    params.effects.scar_drag_coefficient = Some(coefficient);
    let radius_m = (3.0 * r.volume_m3 / (4.0 * std::f64::consts::PI)).cbrt();
    let k = params.effects.scar_drag_per_m(r.mass_kg, r.equivalent_radius_m());
    assert_relative_eq!(k, 0.5 * coefficient * 1700.0 * std::f64::consts::PI * radius_m * radius_m / r.mass_kg);
    let out = simulate(&terrain, &r, start, &params, &mut stream(1, 0), &mut ());
    assert_eq!(out.stop_reason, StopReason::Stopped);
    let th = slope.to_radians();
    let a = GRAVITY_MPS2 * (phi_d.to_radians().tan() * th.cos() - th.sin());
    let want = (k * v0 * v0 / a).ln_1p() / (2.0 * k);
    let moved = (out.final_state.position_m - start.position_m).norm();
    assert_relative_eq!(moved, want, max_relative = 0.01);
    // Without the drag the block slides almost twice as far (v0² / 2a = 4.46 m; with it 2.29 m, the closed form
    // 2.28 m).
    assert!(moved < 0.6 * v0 * v0 / (2.0 * a), "{moved}");
}

#[test]
fn a_dynamic_friction_spread_gives_each_rock_its_own_angle_with_the_set_mean_and_sd() {
    // Each rock draws φ_d once, so each stops where the closed form says for its own angle: inverting that form,
    // tan φ = (v0²/(2 g s) + sin θ)/cos θ, recovers the drawn angles, whose mean and sd must be the material's
    // (30° ± 3°; 200 rocks: standard errors 0.2° on the mean, 0.15° on the sd).
    let (slope, phi_d, sd) = (10.0f64, 30.0f64, 3.0f64);
    let terrain = incline(slope, Material { dynamic_friction_sd_deg: sd, ..material(0.0, 45.0, phi_d) });
    let r = rock(ShapeKind::FlatBox, 1000.0);
    let v0 = 5.0;
    let start = resting_on_incline(&r, slope, 60.0, v0);
    let th = slope.to_radians();
    let angles: Vec<f64> = (0..200)
        .map(|i| {
            let out = simulate(&terrain, &r, start, &SimParams::default(), &mut stream(7, i), &mut ());
            assert_eq!(out.stop_reason, StopReason::Stopped);
            let s = (out.final_state.position_m - start.position_m).norm();
            ((v0 * v0 / (2.0 * GRAVITY_MPS2 * s) + th.sin()) / th.cos()).atan().to_degrees()
        })
        .collect();
    let n = angles.len() as f64;
    let mean = angles.iter().sum::<f64>() / n;
    let sample_sd = (angles.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    assert!((mean - phi_d).abs() < 0.6, "mean {mean}");
    assert!((sample_sd - sd).abs() < 0.5, "sd {sample_sd}");
    assert!(angles.iter().all(|a| (phi_d - 3.0 * sd - 0.3..=phi_d + 3.0 * sd + 0.3).contains(a)), "{angles:?}");
}

#[test]
fn drag_on_soft_ground_stops_a_frictionless_block_after_v0_over_c() {
    // On a flat frictionless plane with drag c, v(t) = v0 e^(−ct): the block glides v0/c (less the last
    // < 0.1 m/s it spends below the rest speed, under 3 % here).
    let c = 2.0;
    let terrain = incline(0.0, Material { drag_per_s: c, ..material(0.0, 0.0, 0.0) });
    let r = rock(ShapeKind::FlatBox, 1000.0);
    let v0 = 4.0;
    let start = resting_on_incline(&r, 0.0, 60.0, v0);
    let out = simulate(&terrain, &r, start, &SimParams::default(), &mut stream(1, 0), &mut ());
    assert_eq!(out.stop_reason, StopReason::Stopped);
    let moved = (out.final_state.position_m - start.position_m).norm();
    assert_relative_eq!(moved, v0 / c, max_relative = 0.03);
}

#[test]
fn on_soft_ground_steeper_than_its_dynamic_friction_a_block_creeps_at_the_terminal_speed_and_never_stops() {
    // Sliding down θ with dynamic friction μ below tan θ and drag c: dv/dt = a − c v with a = g (sin θ − μ cos θ),
    // so v → a/c. Stepped (drag as exp(−c h) after each step of h) the steady speed is a h e^(−ch)/(1 − e^(−ch))
    // ≈ a/c − a h/2. At 15°, 8° and 10 /s that is 0.12 m/s, above the 0.1 m/s rest speed: the block creeps on
    // until the time limit, however high its static friction. This is why a calibration's zone arm, whose soft
    // ground tries drags of 3 and 10 /s, can run rocks to `max_time_s` (docs/calibration.md).
    let (slope, phi_d, c) = (15.0f64, 8.0f64, 10.0);
    let terrain = incline(slope, Material { drag_per_s: c, ..material(0.0, 45.0, phi_d) });
    let r = rock(ShapeKind::FlatBox, 1000.0);
    let params = SimParams { max_time_s: 20.0, ..SimParams::default() };
    let out = simulate(&terrain, &r, resting_on_incline(&r, slope, 60.0, 1.0), &params, &mut stream(1, 0), &mut ());
    assert_eq!(out.stop_reason, StopReason::MaxTime);
    let th = slope.to_radians();
    let a = GRAVITY_MPS2 * (th.sin() - phi_d.to_radians().tan() * th.cos());
    let decay = (-c * params.dt_s).exp();
    let stepped = a * params.dt_s * decay / (1.0 - decay);
    assert_relative_eq!(out.final_state.velocity_mps.norm(), stepped, max_relative = 1e-3);
    assert_relative_eq!(stepped, a / c, max_relative = 0.02);
    assert!(stepped > params.stop_speed_mps);
}

#[test]
fn vegetation_drag_stops_a_frictionless_block_after_v0_m_over_c() {
    // The force −C·v decelerates a rock of mass m at rate C/m: it glides v0·m/C, so a block of half the mass stops
    // in half the distance.
    let terrain = incline(0.0, material(0.0, 0.0, 0.0));
    let c_kg_s = 2000.0;
    let params = SimParams {
        effects: talus::sim::Effects { vegetation_drag_kg_s: Some(c_kg_s), ..Default::default() },
        ..Default::default()
    };
    let v0 = 4.0;
    for mass_kg in [1000.0, 500.0] {
        let r = rock(ShapeKind::FlatBox, mass_kg);
        let start = resting_on_incline(&r, 0.0, 60.0, v0);
        let out = simulate(&terrain, &r, start, &params, &mut stream(1, 0), &mut ());
        assert_eq!(out.stop_reason, StopReason::Stopped);
        let moved = (out.final_state.position_m - start.position_m).norm();
        assert_relative_eq!(moved, v0 * r.mass_kg / c_kg_s, max_relative = 0.03);
    }
}

#[test]
fn roughness_tilts_each_impact_normal_by_a_uniform_share_of_atan_rough_over_r() {
    // PlatRock's size-relative roughness (physics.md §4): the normal of a new contact tilts by U(0,1)·atan(rough/R)
    // toward a uniform azimuth. Cubes dropped corner-down on level ground, so that one vertex lands first, below the
    // centre: the first impact's normal leans by at most atan(rough/R), half of that on average, the lean and its
    // direction are uniform, the rebound picks up a horizontal speed (without roughness the impulse is vertical
    // through the centre), and no impact adds energy.
    let terrain = Terrain::from_function(40.0, 8, material(0.5, 40.0, 30.0), |_, _| 0.0).unwrap();
    let r = rock(ShapeKind::Cube, 2650.0);
    let rough_m = 0.2;
    let bound = (rough_m / r.equivalent_radius_m()).atan();
    let params = SimParams {
        max_time_s: 0.8,
        effects: talus::sim::Effects { roughness_m: Some(rough_m), ..Default::default() },
        ..Default::default()
    };
    let corner = UnitQuaternion::rotation_between(&Vector3::new(1.0, 1.0, 1.0), &-Vector3::z()).unwrap();
    let corner_down = at_rest(Vector3::new(20.3, 20.1, 0.5 * 3f64.sqrt() + 2.0), corner);
    let (mut tilts, mut east, mut moved) = (Vec::new(), 0u64, 0u64);
    let drops = 300;
    for i in 0..drops {
        let mut rec = Record::default();
        simulate(&terrain, &r, corner_down, &params, &mut stream(7, i), &mut rec);
        let first = rec.impacts.first().expect("an impact");
        tilts.push(first.normal.z.clamp(-1.0, 1.0).acos());
        east += u64::from(first.normal.x > 0.0);
        for imp in &rec.impacts {
            assert!(imp.kinetic_after_j <= imp.kinetic_before_j * (1.0 + 1e-9), "drop {i}: an impact added energy");
        }
        moved += u64::from(rec.rebound().is_some_and(|s| s.velocity_mps.xy().norm() > 1e-3));
    }
    let mut smooth = Record::default();
    let no_roughness = SimParams { max_time_s: 0.8, ..Default::default() };
    simulate(&terrain, &r, corner_down, &no_roughness, &mut stream(7, 0), &mut smooth);
    assert!(
        smooth.rebound().expect("a rebound").velocity_mps.xy().norm() < 1e-6,
        "without roughness the rebound is vertical"
    );
    let max = tilts.iter().cloned().fold(0.0, f64::max);
    let mean = tilts.iter().sum::<f64>() / drops as f64;
    let below_half = tilts.iter().filter(|&&t| t < 0.5 * bound).count() as f64 / drops as f64;
    assert!(max <= bound + 1e-9 && max > 0.9 * bound, "largest tilt {max} against the bound {bound}");
    // U(0, b): mean b/2 with a standard error of b/√(12 n) ≈ 0.017 b here; half the tilts below b/2 (± 0.029).
    assert_relative_eq!(mean, 0.5 * bound, max_relative = 0.08);
    assert!((below_half - 0.5).abs() < 0.1, "share below half the bound {below_half}");
    assert!((east as f64 / drops as f64 - 0.5).abs() < 0.1, "share of normals leaning toward +x {east}/{drops}");
    assert!(moved > drops * 9 / 10, "only {moved} of {drops} rebounds move sideways");
}

#[test]
fn with_rolling_resistance_a_sliding_block_stops_where_the_closed_form_says() {
    // A block sliding without rotation has all its kinetic energy in translation (A = 1 in Azzoni et al. 1995,
    // physics.md §4): the resistance adds μ_r·g·cos θ to the friction's deceleration, so the block stops after
    // v0² / (2 g ((μ + μ_r) cos θ − sin θ)).
    let (slope, phi_d, mu_r) = (10.0f64, 25.0f64, 0.1f64);
    let params = SimParams {
        effects: talus::sim::Effects { rolling_resistance: Some(mu_r), ..Default::default() },
        ..Default::default()
    };
    let (moved, _) = slide(slope, 27.0, phi_d, &params);
    let th = slope.to_radians();
    let want = SLIDE_MPS * SLIDE_MPS / (2.0 * GRAVITY_MPS2 * ((phi_d.to_radians().tan() + mu_r) * th.cos() - th.sin()));
    assert_relative_eq!(moved, want, max_relative = 0.01);
}

#[test]
fn with_rolling_resistance_a_rolling_ball_slows_as_azzoni_says() {
    // A ball rolling without slip down θ accelerates at A·g·cos θ·(tan θ − μ_r), A = m/(m + I/R²) (Azzoni et al.
    // 1995, physics.md §4 and §8): the resistance takes A·μ_r·g·cos θ off its acceleration, not μ_r·g·cos θ (1.4
    // times more for a ball, enough to stop it here where tan θ > μ_r says it rolls on). A hull of 600 points on a
    // sphere released at rest on 20° (tan 0.36) with friction high enough to roll, with and without μ_r = 0.25:
    // the distances after 1 s give the deceleration the resistance added, 2 (s₀ − s₁) / t². Measured 7 % below
    // A·μ_r·g·cos θ, at time steps of 2, 1 and 0.5 ms alike: the polyhedron rolls over its vertices, not as a ball.
    let ball = ball(20_000.0);
    let radius_m = ball.vertices_m.iter().map(|v| v.norm()).sum::<f64>() / ball.vertices_m.len() as f64;
    let a_share = 1.0 / (1.0 + ball.inertia_kg_m2.mean() / (ball.mass_kg * radius_m * radius_m));
    let (slope, mu_r, t_s) = (20.0f64, 0.25, 1.0);
    let th = slope.to_radians();
    let terrain = incline(slope, material(0.0, 70.0, 65.0));
    let normal = Vector3::new(th.sin(), 0.0, th.cos());
    let start = at_rest(Vector3::new(60.0, 100.0, 140.0 * th.tan()) + normal * radius_m, UnitQuaternion::identity());
    let moved = |mu_r: Option<f64>| {
        let effects = talus::sim::Effects { rolling_resistance: mu_r, ..Default::default() };
        let params = SimParams { max_time_s: t_s, effects, ..Default::default() };
        let out = simulate(&terrain, &ball, start, &params, &mut stream(1, 0), &mut ());
        assert_eq!(out.stop_reason, StopReason::MaxTime);
        (out.final_state.position_m - start.position_m).norm()
    };
    let (free, resisted) = (moved(None), moved(Some(mu_r)));
    assert_relative_eq!(free, 0.5 * a_share * GRAVITY_MPS2 * th.sin() * t_s * t_s, max_relative = 0.03);
    let braking = 2.0 * (free - resisted) / (t_s * t_s);
    assert_relative_eq!(braking, a_share * mu_r * GRAVITY_MPS2 * th.cos(), max_relative = 0.1);
}

#[test]
fn with_rolling_resistance_rocks_dropped_onto_a_slope_they_rest_on_stop() {
    // 25° under a static angle of 35°: a block dropped 10 cm comes to rest (a lens landing on its rim may roll
    // away); none runs to the time limit. With the resistance applied after the contact solve, a resting rock
    // lifted off every few dozen steps and never counted as stopped: 12 of 100 such drops ran to the time limit at
    // μ_r = 1 (4 at 0.3).
    let slope_deg = 25.0f64;
    let terrain = incline(slope_deg, material(0.3, 35.0, 30.0));
    let th = slope_deg.to_radians();
    let mut stopped = 0;
    for (i, kind) in [ShapeKind::Cube, ShapeKind::FlatBox, ShapeKind::Smartie].into_iter().cycle().take(60).enumerate()
    {
        let r = rock(kind, 10.0 + 30.0 * i as f64);
        let mut rng = stream(3, i as u64);
        let u = [0; 3].map(|_| talus::random::uniform(&mut rng));
        let q = UnitQuaternion::from_euler_angles(u[0] * 6.3, u[1] * 6.3, u[2] * 6.3);
        let x = 100.0;
        let start = at_rest(Vector3::new(x, 100.0, (200.0 - x) * th.tan() + r.bounding_radius_m / th.cos() + 0.1), q);
        for mu_r in [0.3, 1.0] {
            let effects = talus::sim::Effects { rolling_resistance: Some(mu_r), ..Default::default() };
            let params = SimParams { max_time_s: 30.0, effects, ..Default::default() };
            let out = simulate(&terrain, &r, start, &params, &mut stream(1, i as u64), &mut ());
            assert_ne!(out.stop_reason, StopReason::MaxTime, "rock {i} ({}) at μ_r = {mu_r}: {out:?}", r.shape);
            stopped += usize::from(out.stop_reason == StopReason::Stopped);
        }
    }
    assert!(stopped >= 100, "{stopped} of 120 stopped");
}

#[test]
fn with_terrain_edge_contacts_blocks_dropped_on_a_knife_ridge_stay_on_top_of_it() {
    // A ridge of 60° flanks whose crest has a vertex every 10 m, under blocks of about 1 t (0.7–1.3 m): between its
    // vertices the crest passes through a face unseen by the hull vertices, and blocks came to rest with it deep
    // inside them. With `terrain_edge_contacts`, no block's centre goes below the ground, and no block gains
    // mechanical energy.
    let (crest_m, tan) = (30.0, 60f64.to_radians().tan());
    let ground = move |x: f64| crest_m - (x - 20.0).abs() * tan;
    let terrain = Terrain::from_function(40.0, 4, material(0.3, 35.0, 30.0), move |x, _| ground(x)).unwrap();
    let deepest = |edges: bool| {
        let params = SimParams { max_time_s: 5.0, terrain_edge_contacts: edges, ..Default::default() };
        let mut deepest = 0.0f64;
        for (i, kind) in
            [ShapeKind::Cube, ShapeKind::FlatBox, ShapeKind::Smartie].into_iter().cycle().take(30).enumerate()
        {
            let r = rock(kind, 1000.0);
            let mut rng = stream(5, i as u64);
            let u = [0; 3].map(|_| talus::random::uniform(&mut rng));
            let q = UnitQuaternion::from_euler_angles(u[0] * 6.3, u[1] * 6.3, u[2] * 6.3);
            let mut start = at_rest(Vector3::new(20.0 + 0.2 * u[0], 15.0 + 10.0 * u[1], 0.0), q);
            talus::source::place_above_ground(&terrain, &r, &mut start, 0.3, edges);
            let mut rec = Record::default();
            simulate(&terrain, &r, start, &params, &mut stream(1, i as u64), &mut rec);
            let energy = |s: &Sample| s.kinetic_j + r.mass_kg * GRAVITY_MPS2 * s.position_m.z;
            let e0 = energy(&rec.samples[0]);
            for s in &rec.samples {
                if (2.0..38.0).contains(&s.position_m.x) {
                    deepest = deepest.max(ground(s.position_m.x) - s.position_m.z);
                }
                assert!(energy(s) <= e0 + 1e-6 * e0.abs() + 1.0, "block {i} gained energy at {} s", s.t_s);
            }
        }
        deepest
    };
    // 1 cm: the engine leaves penetrations of up to `penetration_slop_m` (2 mm) uncorrected.
    assert!(deepest(true) < 0.01, "a centre went {} m below the ground", deepest(true));
    assert!(deepest(false) > 0.3, "the hull vertices alone kept the crest out: {} m", deepest(false));
}

/// A ball: the convex hull of 600 points spread evenly over a sphere (a Fibonacci lattice).
#[test]
fn with_terrain_edge_contacts_a_cube_dropped_flat_on_a_knife_ridge_rebounds_with_cr_and_no_spin() {
    // A 1 m cube dropped flat from 2 m onto a crest of 60° flanks under the middle of its bottom face, the crest
    // along y: no hull vertex touches, the crest meets the face along a line. The impact is the edge's, reported as
    // one, and the rebound is Cr times the impact speed with no spin, as on flat ground.
    let cr = 0.5;
    let tan = 60f64.to_radians().tan();
    let terrain =
        Terrain::from_function(40.0, 4, material(cr, 40.0, 30.0), move |x, _| 30.0 - (x - 20.0).abs() * tan).unwrap();
    let r = rock(ShapeKind::Cube, 2650.0);
    let drop_m = 2.0;
    let start = at_rest(Vector3::new(20.0, 15.3, 30.5 + drop_m), UnitQuaternion::identity());
    let params = SimParams { max_time_s: 1.5, terrain_edge_contacts: true, ..SimParams::default() };
    let mut rec = Record::default();
    simulate(&terrain, &r, start, &params, &mut stream(1, 0), &mut rec);
    let first = rec.impacts.first().expect("an impact");
    let v_in = (2.0 * GRAVITY_MPS2 * drop_m).sqrt();
    assert_relative_eq!(first.approach_speed_mps, v_in, max_relative = 0.01);
    assert!((first.point_m.x - 20.0).abs() < 1e-3 && (first.point_m.z - 30.0).abs() < 0.01, "{:?}", first.point_m);
    let rising = rec.rebound().expect("rising");
    let v_out = (rising.velocity_mps.z.powi(2) + 2.0 * GRAVITY_MPS2 * rising.clearance_m).sqrt();
    assert_relative_eq!(v_out, cr * v_in, max_relative = 0.02);
    assert!(rising.spin_radps < 0.01, "spin {}", rising.spin_radps);
}

#[test]
fn with_terrain_edge_contacts_blocks_tipping_over_a_crest_gain_no_energy() {
    // A flat top ending in a 60° face, in 5 m cells, under boxes of 20–60 t released at rest across its crest: they
    // tip over it on their own edges. The contact normal of a terrain edge met by a hull edge is perpendicular to
    // both; with a face's normal instead, the box moved into the crest along the other face unresisted, and the
    // depth projected out every step lifted it (gains of up to 0.6 MJ on the bench stack).
    let tan = 60f64.to_radians().tan();
    let ground = move |x: f64| if x < 20.0 { 60.0 } else { 60.0 - (x - 20.0) * tan };
    let terrain = Terrain::from_function(40.0, 8, material(0.3, 35.0, 30.0), move |x, _| ground(x)).unwrap();
    let params = SimParams { max_time_s: 3.0, terrain_edge_contacts: true, ..Default::default() };
    let mut gains = Vec::new();
    for i in 0..60u64 {
        let r = rock(ShapeKind::FlatBox, 20_000.0 + 40_000.0 * (i as f64 / 59.0));
        let mut rng = stream(7, i);
        let u = [0; 3].map(|_| talus::random::uniform(&mut rng));
        let q = UnitQuaternion::from_euler_angles(u[0] * 6.3, u[1] * 6.3, u[2] * 6.3);
        let mut start = at_rest(Vector3::new(18.0 + 2.0 * u[0], 15.0 + 10.0 * u[1], 0.0), q);
        talus::source::place_above_ground(&terrain, &r, &mut start, 0.1, true);
        let mut rec = Record::default();
        simulate(&terrain, &r, start, &params, &mut stream(1, i), &mut rec);
        let energy = |s: &Sample| s.kinetic_j + r.mass_kg * GRAVITY_MPS2 * s.position_m.z;
        let e0 = energy(&rec.samples[0]);
        let gain = rec.samples.iter().map(|s| energy(s) - e0).fold(0.0, f64::max);
        // 1 kJ: a tenth of what a 20 t block releases falling 5 cm.
        if gain > 1000.0 {
            gains.push((i, gain));
        }
    }
    assert!(gains.is_empty(), "blocks gained energy (block, J): {gains:?}");
}

#[test]
fn with_terrain_edge_contacts_a_slab_lying_on_terrain_edges_alone_comes_to_rest() {
    // A 17 m square slab 0.86 m thick (660 t) laid on a 10 m wide flat top of 5 m cells, between the terrain's own
    // edge and a 45° face: its corners hang over both, so only the terrain edges under it hold it. Every slab must
    // count as at rest. (Met at the slop itself, the edges were pushed clear every few steps, the slab fell a step,
    // and 2 of these 20 ran to the time limit, as one slab of an audit did.)
    let terrain =
        Terrain::from_function(60.0, 12, material(0.3, 35.0, 30.0), |x, _| if x < 10.0 { 30.0 } else { 40.0 - x })
            .unwrap();
    let size = RockSize::Dimensions { size_m: [17.1, 17.1, 0.86], density_kg_m3: 2650.0 };
    let slab = RockBody::new(&ShapeKind::FlatBox, size, "slab").unwrap();
    let params = SimParams { max_time_s: 20.0, terrain_edge_contacts: true, ..Default::default() };
    for k in 0..20u64 {
        let kf = k as f64;
        let position = Vector3::new(4.0 + 0.1 * (kf % 7.0), 30.0 + 0.13 * (kf % 5.0), 30.53);
        let tilt = UnitQuaternion::from_euler_angles(0.002 * (kf % 3.0 - 1.0), 0.0015 * (kf % 4.0 - 1.5), 0.3 * kf);
        let out = simulate(&terrain, &slab, at_rest(position, tilt), &params, &mut stream(1, k), &mut ());
        assert_eq!(out.stop_reason, StopReason::Stopped, "slab {k} ended at {:?}", out.final_state.position_m);
        assert!((out.final_state.position_m.z - 30.43).abs() < 0.005, "slab {k} rests at {:?}", out.final_state);
    }
}

fn ball(mass_kg: f64) -> RockBody {
    ball_of(mass_kg, 600)
}

/// A ball as the hull of `n` points spread evenly over a sphere (a Fibonacci lattice).
fn ball_of(mass_kg: f64, n: usize) -> RockBody {
    let points: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            let phi = i as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
            let rho = (1.0 - z * z).sqrt();
            [rho * phi.cos(), rho * phi.sin(), z]
        })
        .collect();
    let size = RockSize::Mass { mass_kg, density_kg_m3: 2650.0 };
    RockBody::new(&ShapeKind::Hull { name: "ball".into(), points }, size, "ball").unwrap()
}

#[test]
fn a_drag_acts_for_the_contacts_duration_whatever_the_time_step() {
    // The solver resolves an impact in one step; a drag in contact then acts for `contact_duration_s` (2 ms) after
    // the last step in contact, not for one step: a cube dropped flat with Cr 0.5 onto soft ground of drag c leaves
    // with Cr·v·exp(−c·2 ms) at steps of 2, 1, 0.5 and 0.25 ms alike, and rises to Cr²·h·exp(−2c·2 ms) (a drag per
    // step would give exp(−c·dt)).
    let (cr, c, drop_m) = (0.5, 50.0, 2.0);
    let terrain =
        Terrain::from_function(40.0, 8, Material { drag_per_s: c, ..material(cr, 40.0, 30.0) }, |_, _| 0.0).unwrap();
    let r = rock(ShapeKind::Cube, 2650.0); // 1 m cube
    let start = at_rest(Vector3::new(20.3, 20.1, 0.5 + drop_m), UnitQuaternion::identity());
    let duration_s = SimParams::default().contact_duration_s;
    let want = cr * cr * drop_m * (-2.0 * c * duration_s).exp();
    let apex = |dt_s, impact_substeps| {
        let mut rec = Record::default();
        let params = SimParams { dt_s, impact_substeps, max_time_s: 1.5, ..Default::default() };
        simulate(&terrain, &r, start, &params, &mut stream(1, 0), &mut rec);
        let rising = rec.rebound().expect("rising");
        rising.clearance_m + rising.velocity_mps.z.powi(2) / (2.0 * GRAVITY_MPS2)
    };
    for dt_s in [0.002, 0.001, 0.0005, 0.00025] {
        assert_relative_eq!(apex(dt_s, 1), want, max_relative = 0.02);
    }
    // With the impact step in 8 sub-steps of 0.25 ms the cube is still below the ground for a second sub-step
    // after its impact here (as at a plain step of 0.25 ms with another phase of the crossing), and the drag acts
    // from there: 2 ms and one sub-step, no more.
    let (a, sub_s) = (apex(0.002, 8), 0.002 / 8.0);
    assert!(a <= want * 1.001 && a >= want * (-2.0 * c * sub_s).exp() * 0.999, "{a} against {want}");
}

#[test]
fn block_on_an_incline_below_its_static_friction_angle_stays_put() {
    let terrain = incline(25.0, material(0.0, 30.0, 20.0));
    let r = rock(ShapeKind::FlatBox, 1000.0);
    let start = resting_on_incline(&r, 25.0, 60.0, 0.0);
    for params in [SimParams::default(), fine_solver()] {
        let out = simulate(&terrain, &r, start, &params, &mut stream(1, 0), &mut ());
        assert_eq!(out.stop_reason, StopReason::Stopped);
        assert!((out.final_state.position_m - start.position_m).norm() < 0.01);
    }
}

#[test]
fn the_default_solver_tolerance_takes_fewer_sweeps_than_a_fine_one() {
    // A cube tumbling down a bumpy slope (the closed forms above hold at both tolerances).
    let terrain = rough_slope(material(0.4, 35.0, 30.0));
    let r = rock(ShapeKind::Cube, 2650.0);
    let z = terrain.surface.height(20.0, 100.0).unwrap() + r.bounding_radius_m + 0.5;
    let start = at_rest(Vector3::new(20.0, 100.0, z), UnitQuaternion::from_euler_angles(0.3, 0.5, 0.2));
    let sweeps = |params: &SimParams| {
        let out = simulate(&terrain, &r, start, params, &mut stream(1, 0), &mut ());
        assert!(out.contact_steps > 100, "{} contact steps", out.contact_steps);
        out.solver_sweeps as f64 / out.contact_steps as f64
    };
    let (fine, coarse) = (sweeps(&fine_solver()), sweeps(&SimParams::default()));
    assert!(coarse < 0.8 * fine, "{coarse:.1} sweeps a step at the default tolerance, {fine:.1} at 1e-6");
}

/// A rough slope: 35° mean with bumps, falling toward +x.
fn rough_slope(m: Material) -> Terrain {
    Terrain::from_function(200.0, 80, m, |x, y| {
        (200.0 - x) * 35f64.to_radians().tan()
            + 1.5 * (0.31 * x).sin() * (0.23 * y).cos()
            + 0.7 * (1.1 * x + 0.4 * y).sin()
    })
    .unwrap()
}

struct EnergyCheck {
    impacts: usize,
    worst_gain: f64,
}

impl Observer for EnergyCheck {
    fn impact(&mut self, i: &Impact) {
        self.impacts += 1;
        self.worst_gain = self.worst_gain.max((i.kinetic_after_j - i.kinetic_before_j) / i.kinetic_before_j.max(1e-9));
    }
}

#[test]
fn no_impact_adds_energy_and_no_rock_ends_below_the_surface() {
    let m = Material {
        name: "m".into(),
        cr: TruncNormal { mean: 0.6, sd: 0.3, min: 0.0, max: 1.0 },
        static_friction_deg: 35.0,
        dynamic_friction_deg: 30.0,
        dynamic_friction_sd_deg: 0.0,
        drag_per_s: 0.0,
    };
    let terrain = rough_slope(m);
    let shapes = [ShapeKind::Cube, ShapeKind::FlatBox, ShapeKind::Smartie];
    let mut total_impacts = 0;
    for (i, impact_substeps) in (0..12u64).flat_map(|i| [(i, 1), (i, 8)]) {
        let params = SimParams {
            cr_draw: talus::sim::CrDraw::PerImpact,
            max_time_s: 30.0,
            impact_substeps,
            ..Default::default()
        };
        let mut rng = stream(5, i);
        let r = rock(shapes[i as usize % 3].clone(), [50.0, 800.0, 5000.0][(i as usize / 3) % 3]);
        let q = talus::rock::random_orientation(&mut rng);
        let x = 20.0 + 3.0 * i as f64;
        let z = terrain.surface.height(x, 100.0).unwrap() + r.bounding_radius_m + 0.5;
        let start = RigidState {
            position_m: Vector3::new(x, 100.0, z),
            velocity_mps: Vector3::new(2.0, 0.0, 0.0),
            orientation: q,
            omega_body_radps: Vector3::zeros(),
        };
        let mut check = EnergyCheck { impacts: 0, worst_gain: 0.0 };
        let out = simulate(&terrain, &r, start, &params, &mut rng, &mut check);
        assert!(check.worst_gain <= 1e-9, "rock {i}: an impact added {:.3e} of the energy", check.worst_gain);
        total_impacts += check.impacts;
        let p = out.final_state.position_m;
        if let Some(ground) = terrain.surface.height(p.x, p.y) {
            assert!(p.z > ground, "rock {i} ends with its centre below the ground: {} < {ground}", p.z);
            let rot = out.final_state.orientation.to_rotation_matrix();
            for v in &r.vertices_m {
                let q = p + rot * v;
                if let Some(g) = terrain.surface.height(q.x, q.y) {
                    assert!(q.z > g - 0.05, "rock {i}: a vertex ends {} m below the ground", g - q.z);
                }
            }
        }
    }
    assert!(total_impacts > 50, "only {total_impacts} impacts: the test is not exercising impacts");
}

/// A flat floor 60 m long with a wall `thickness_m` thick and 3 m high across it, from x = 30 m.
fn floor_with_wall(thickness_m: f64) -> Terrain {
    let m = material(0.3, 40.0, 30.0);
    let mut v = Vec::new();
    let xs = [0.0, 29.9, 29.9001, 29.9001 + thickness_m, 29.9002 + thickness_m, 60.0];
    let zs = [0.0, 0.0, 3.0, 3.0, 0.0, 0.0];
    for y in [0.0, 20.0] {
        for (x, z) in xs.iter().zip(zs) {
            v.push(Vector3::new(*x, y, z));
        }
    }
    let n = xs.len() as u32;
    let mut t = Vec::new();
    for i in 0..n - 1 {
        t.push([i, i + 1, n + i + 1]);
        t.push([i, n + i + 1, n + i]);
    }
    Terrain::from_local(v, &t, &vec![0; t.len()], vec![m]).unwrap()
}

#[test]
fn no_tunnelling_through_a_thin_wall_at_40_mps() {
    let terrain = floor_with_wall(0.2);
    for shape in [ShapeKind::Cube, ShapeKind::Smartie] {
        let r = rock(shape, 100.0);
        let start = RigidState {
            position_m: Vector3::new(10.0, 10.0, 1.5),
            velocity_mps: Vector3::new(40.0, 0.0, 0.0),
            orientation: UnitQuaternion::from_euler_angles(0.4, 0.1, 0.7),
            omega_body_radps: Vector3::new(0.0, 10.0, 0.0),
        };
        let out = simulate(
            &terrain,
            &r,
            start,
            &SimParams { max_time_s: 10.0, ..Default::default() },
            &mut stream(1, 0),
            &mut (),
        );
        assert!(
            out.final_state.position_m.x < 29.9,
            "{} went through the wall: {:?}",
            r.shape,
            out.final_state.position_m
        );
    }
}

#[test]
fn at_the_coarsest_step_a_rock_at_100_mps_neither_enters_nor_passes_a_half_metre_wall() {
    // dt_s = 0.01 without impact sub-steps moves a rock at 100 m/s a metre a step, twice the wall's thickness: a
    // hull vertex met past the wall's midline was pushed on through it. `max_contact_travel_m` cuts such steps so
    // no vertex moves more than 0.2 m in one; with it out of the way (10 m) rocks pass, which the test asserts too.
    let terrain = floor_with_wall(0.5);
    let outcomes = |travel_m: f64| {
        let params = SimParams { dt_s: 0.01, impact_substeps: 1, max_contact_travel_m: travel_m, ..Default::default() };
        (0..30u64)
            .map(|k| {
                let shape = [ShapeKind::Cube, ShapeKind::FlatBox, ShapeKind::Smartie][k as usize % 3].clone();
                let r = rock(shape, [1.0, 30.0, 1000.0][k as usize / 3 % 3]);
                let start = RigidState {
                    position_m: Vector3::new(10.0, 10.0, 0.3 + r.bounding_radius_m),
                    velocity_mps: Vector3::new(100.0, 0.0, 0.0),
                    orientation: UnitQuaternion::from_euler_angles(0.3 * k as f64, 0.7 * k as f64, 1.1 * k as f64),
                    omega_body_radps: Vector3::new(0.0, 20.0 * (k % 10) as f64, 0.0),
                };
                simulate(&terrain, &r, start, &params, &mut stream(k, 0), &mut ()).final_state.position_m
            })
            .collect::<Vec<_>>()
    };
    for x in outcomes(SimParams::default().max_contact_travel_m) {
        assert!(x.x < 29.9 || x.z > 3.0, "a rock ended in or past the wall, at {x:?}");
    }
    let through = outcomes(10.0).iter().filter(|x| x.x > 29.9 && x.z < 3.0).count();
    assert!(through > 0, "no rock went into or through the wall without the travel limit: the test tests nothing");
}

#[test]
fn impact_substeps_change_nothing_without_an_impact() {
    // A box set sliding on an incline touches the ground with every step but never newly meets it faster than the
    // bounce threshold: no step is divided, and the path is the same to the bit.
    let params = |n| SimParams { impact_substeps: n, ..SimParams::default() };
    assert_eq!(slide(30.0, 40.0, 35.0, &params(1)), slide(30.0, 40.0, 35.0, &params(8)));
}

#[test]
fn a_zone_leaves_a_rock_that_keeps_clear_of_it_as_it_was_and_stops_one_that_crosses_it() {
    // A bumpy 30° slope in 10 m cells; the zone (Cr 0, soft ground) is a pentagon whose edges cross its triangles.
    // The calibration's zone arm reuses the simulations that keep clear of a candidate zone: they must be the ones
    // the zoned terrain gives, bit for bit.
    let z = |x: f64, y: f64| (200.0 - x) * 30f64.to_radians().tan() + 1.5 * (y / 9.0).sin() * (x / 13.0).cos();
    let plain = Terrain::from_function(200.0, 20, material(0.6, 25.0, 20.0), z).unwrap();
    let mut zoned = plain.clone();
    let soft = Material { name: "soft".into(), drag_per_s: 20.0, ..material(0.0, 35.0, 30.0) };
    zoned.friction.push((soft.mu_static(), soft.mu_dynamic()));
    zoned.materials.push(soft);
    let poly = [[33.0, 107.0], [187.0, 111.0], [183.0, 173.0], [71.0, 181.0], [28.0, 152.0]];
    assert!(zoned.paint_zone(&poly, 1).unwrap() > 0);
    assert!(zoned.surface.triangles().len() > plain.surface.triangles().len(), "the zone's edges split triangles");
    let r = rock(ShapeKind::Cube, 500.0);
    let end = |terrain: &Terrain, y: f64, k: u64| {
        let start = at_rest(Vector3::new(10.0, y, z(10.0, y) + 5.0), UnitQuaternion::identity());
        let out = simulate(terrain, &r, start, &SimParams::default(), &mut stream(7, k), &mut ());
        (out.final_state.position_m, out.stop_reason)
    };
    // Down the slope along y = 20-56 m, 47 m and more from the zone.
    for k in 0..10 {
        let y = 20.0 + 4.0 * k as f64;
        let (p, q) = (end(&plain, y, k), end(&zoned, y, k));
        assert!(p.0.x > 180.0 && (p.0.y - y).abs() < 40.0, "the rock runs down the slope: {p:?}");
        assert_eq!(p.0.map(f64::to_bits), q.0.map(f64::to_bits), "{p:?} against {q:?}");
        assert_eq!(p.1, q.1);
    }
    // Down the slope along y = 140 m, through the zone: it stops in it.
    let (p, q) = (end(&plain, 140.0, 0), end(&zoned, 140.0, 0));
    assert!(p.0.x > 180.0 && q.0.x < 180.0 && q.1 == StopReason::Stopped, "{p:?} against {q:?}");
    assert!(talus::terrain::point_in_polygon(q.0.x, q.0.y, &poly), "{q:?}");
}

/// A cube balanced on one corner, its body diagonal vertical, spinning about it at 60 rad/s (above the 39 rad/s a
/// sleeping top of its shape needs to stay up; at 20 rad/s it topples after 12 s): the corner is on the
/// axis, so its point contact feels no slip and no friction, and the top sleeps (the engine has no drilling
/// friction over a contact patch). It stops as at rest after `stop_in_place_s` in place instead of running to the
/// time limit; without that test it spins until `max_time_s`.
#[test]
fn a_cube_spinning_in_place_on_a_corner_stops_after_stop_in_place_s() {
    let terrain = Terrain::from_function(40.0, 8, material(0.3, 40.0, 30.0), |_, _| 0.0).unwrap();
    let r = rock(ShapeKind::Cube, 1000.0);
    let corner = r.vertices_m.iter().min_by(|a, b| a.sum().total_cmp(&b.sum())).unwrap();
    let q = UnitQuaternion::rotation_between(corner, &-Vector3::z()).unwrap();
    let start = RigidState {
        position_m: Vector3::new(20.0, 20.0, corner.norm() + 1e-4),
        velocity_mps: Vector3::zeros(),
        orientation: q,
        omega_body_radps: -corner.normalize() * 60.0,
    };
    for (in_place_s, want) in [(10.0, StopReason::Stopped), (1000.0, StopReason::MaxTime)] {
        let params = SimParams { max_time_s: 30.0, stop_in_place_s: in_place_s, ..Default::default() };
        let out = simulate(&terrain, &r, start, &params, &mut stream(1, 0), &mut Record::default());
        assert_eq!(out.stop_reason, want, "stop_in_place_s {in_place_s}");
        assert_eq!(out.stopped_in_place, want == StopReason::Stopped);
        let moved = (out.final_state.position_m - start.position_m).norm();
        assert!(moved < 0.01, "the top sleeps in place: it moved {moved} m");
        assert!(out.final_state.omega_body_radps.norm() > 59.0, "and spins on: {}", out.final_state.omega_body_radps);
        if want == StopReason::Stopped {
            assert!((out.travel_time_s - in_place_s).abs() < 0.1, "stopped at {} s", out.travel_time_s);
        }
    }
}

/// Balls released at rest on a 10° incline roll without slipping (friction 30°, far above the (2/7)·tan θ = 0.05
/// rolling needs): their spin keeps pace with their speed, ω = v/R, and their centres run towards a solid sphere's
/// ½·(5/7)·g·sin θ·t², not a frictionless slide's ½·g·sin θ·t², 1.4 times farther. A hull rolls from face to face,
/// and each new face meets the ground with Cr 0 here and takes a little energy, as the spokes of a rimless wheel do:
/// over 4 s the hulls of 600, 2,400 and 9,600 points run 85, 92 and 96 % of the sphere's distance, the shortfall
/// shrinking with the angle between faces.
#[test]
fn balls_roll_down_an_incline_towards_five_sevenths_of_g_sin_theta() {
    let slope_deg: f64 = 10.0;
    let th = slope_deg.to_radians();
    let terrain = incline(slope_deg, material(0.0, 40.0, 30.0));
    let normal = Vector3::new(th.sin(), 0.0, th.cos());
    let x0 = 20.0;
    let params = SimParams { max_time_s: 4.0, ..Default::default() };
    let mut shortfall = Vec::new();
    for n in [600, 2400, 9600] {
        let b = ball_of(1000.0, n);
        let radius = b.vertices_m.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let on_slope = Vector3::new(x0, 100.0, (200.0 - x0) * th.tan()) + normal * (radius + 1e-4);
        let start = at_rest(on_slope, UnitQuaternion::identity());
        let mut rec = Record::default();
        simulate(&terrain, &b, start, &params, &mut stream(1, 0), &mut rec);
        let last = rec.samples.last().unwrap();
        let travelled = (last.position_m - start.position_m).norm();
        let rolling = 0.5 * (5.0 / 7.0) * GRAVITY_MPS2 * th.sin() * last.t_s * last.t_s;
        assert_relative_eq!(last.spin_radps, last.velocity_mps.norm() / radius, max_relative = 0.01);
        assert!(travelled < rolling, "{n} points: {travelled} m, a sphere rolls {rolling} m");
        shortfall.push(1.0 - travelled / rolling);
    }
    assert!(shortfall[2] < 0.05, "9,600 points run within 5 % of the sphere: {shortfall:?}");
    assert!(shortfall[1] < 0.7 * shortfall[0] && shortfall[2] < 0.7 * shortfall[1], "{shortfall:?}");
}
