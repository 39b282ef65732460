//! Integration tests of the 2D lumped-mass engine: analytic cases, invariants, determinism, the bench study trends,
//! and the scenario/run outputs.

use approx::assert_relative_eq;
use talus::lumped2d::*;
use talus::random::{stream, uniform, TruncNormal};
use talus::terrain::BenchGeometry;

fn fixed(rn: f64, rt: f64, phi_deg: f64) -> Material2d {
    Material2d {
        rn: TruncNormal::fixed(rn),
        rt: TruncNormal::fixed(rt),
        friction: FrictionAngle::Given(TruncNormal::fixed(phi_deg)),
        roughness_sd_deg: 0.0,
    }
}

fn one_material(vertices: &[[f64; 2]], m: Material2d) -> Slope2d {
    let p = Profile::new(vertices, vec![0; vertices.len() - 1], vec!["m".into()], "test").unwrap();
    Slope2d::new(p, vec![m]).unwrap()
}

fn start(x: f64, z: f64, vx: f64, vz: f64) -> RockStart2d {
    RockStart2d { x_m: x, z_m: z, vx_mps: vx, vz_mps: vz, spin_radps: 0.0, mass_kg: 100.0 }
}

fn bench_slope(angle: f64, width: f64) -> (BenchGeometry, Slope2d) {
    let g = BenchGeometry { face_angle_deg: angle, bench_width_m: width, ..Default::default() };
    let face = Material2d::face_all().with_roughness_sd_deg(2.0);
    let floor = Material2d::floor_all().with_roughness_sd_deg(2.0);
    let slope = Slope2d::new(Profile::from_bench(&g).unwrap(), vec![face, floor]).unwrap();
    (g, slope)
}

fn crest_release(g: &BenchGeometry, mass: f64) -> Release2d {
    Release2d::point(0.0, 0.5, mass).with_x_m(g.crest_floor_m, g.crest_floor_m + 0.5).with_vx_mps(1.0, 2.0)
}

#[test]
fn flight_lands_where_the_parabola_says() {
    // A slope z = −0.5 x cut into segments of uneven length; the rock lands on a later segment.
    let xs = [0.0, 0.7, 3.1, 4.0, 9.5, 13.0, 40.0];
    let v: Vec<[f64; 2]> = xs.iter().map(|&x| [x, -0.5 * x]).collect();
    let slope = one_material(&v, fixed(0.0, 0.0, 0.0));
    let (x0, z0, vx, vz) = (0.3, 10.0, 5.0, 3.0);
    let mut rec = PathRecorder::default();
    simulate_rock(&slope, &start(x0, z0, vx, vz), &Options2d::default(), &mut stream(1, 0), &mut rec);
    let PathPiece::Flight(f) = rec.pieces[0] else { panic!("{:?}", rec.pieces[0]) };
    // z0 + vz t − g t²/2 = −0.5 (x0 + vx t)
    let (a, b, c) = (0.5 * G_MPS2, -(vz + 0.5 * vx), -(z0 + 0.5 * x0));
    let t = (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    assert_relative_eq!(f.duration_s, t, max_relative = 1e-9);
    let p = f.end_position();
    assert_relative_eq!(p[0], x0 + vx * t, max_relative = 1e-9);
    assert_relative_eq!(p[1], -0.5 * (x0 + vx * t), max_relative = 1e-9);
    let PathPiece::Impact(i) = rec.pieces[1] else { panic!("{:?}", rec.pieces[1]) };
    assert_eq!(i.segment, 4);
}

#[test]
fn sliding_block_stops_where_the_closed_form_says() {
    let theta = 10f64.to_radians();
    let phi = 30f64.to_radians();
    let slope = one_material(&[[0.0, 0.0], [200.0, -200.0 * theta.tan()]], fixed(0.3, 0.8, 30.0));
    let v0 = 5.0;
    let r = simulate_rock(
        &slope,
        &start(1.0, -theta.tan(), v0 * theta.cos(), -v0 * theta.sin()),
        &Options2d::default(),
        &mut stream(1, 0),
        &mut (),
    );
    assert_eq!(r.stop_reason, StopReason::Stopped);
    let s_expected = v0 * v0 / (2.0 * G_MPS2 * (theta.cos() * phi.tan() - theta.sin()));
    let s = (r.end_x_m - 1.0) / theta.cos();
    assert_relative_eq!(s, s_expected, max_relative = 1e-9);
    assert_relative_eq!(r.travel_time_s, 2.0 * s_expected / v0, max_relative = 1e-9);
    assert_eq!(r.impacts, 0);
}

#[test]
fn pfeiffer_bowen_halves_rn_at_9_144_mps() {
    let slope = one_material(&[[0.0, 0.0], [20.0, 0.0]], fixed(0.5, 1.0, 30.0));
    let h = PFEIFFER_BOWEN_MPS * PFEIFFER_BOWEN_MPS / (2.0 * G_MPS2);
    for (scale, rn) in [(true, 0.25), (false, 0.5)] {
        let opt = Options2d { scale_rn_by_velocity: scale, ..Default::default() };
        let mut rec = PathRecorder::default();
        simulate_rock(&slope, &start(10.0, h, 0.0, 0.0), &opt, &mut stream(1, 0), &mut rec);
        let PathPiece::Impact(i) = rec.pieces[1] else { panic!("{:?}", rec.pieces[1]) };
        assert_relative_eq!(i.velocity_in_mps[1], -PFEIFFER_BOWEN_MPS, max_relative = 1e-12);
        assert_relative_eq!(i.rn, rn, max_relative = 1e-12);
        assert_relative_eq!(i.velocity_out_mps[1], rn * PFEIFFER_BOWEN_MPS, max_relative = 1e-12);
    }
}

#[test]
fn rn_scales_with_a_chosen_k_and_with_mass() {
    // A drop at 4 m/s with K = 4 m/s halves Rn; the mass rule multiplies it by (m/m_ref)^-beta; both together
    // multiply. The first rebound speed is Rn_eff × 4 m/s (a bounce of height Rn_eff² × the drop).
    let slope = one_material(&[[0.0, 0.0], [20.0, 0.0]], fixed(0.5, 1.0, 30.0));
    let h = 16.0 / (2.0 * G_MPS2);
    let cases =
        [(true, 0.0, 100.0, 0.25), (false, -0.5, 400.0, 1.0), (false, 0.5, 400.0, 0.25), (true, 0.5, 400.0, 0.125)];
    for (scale, beta, mass_kg, rn) in cases {
        let opt = Options2d {
            scale_rn_by_velocity: scale,
            rn_velocity_scale_mps: 4.0,
            rn_mass_exponent: beta,
            rn_reference_mass_kg: 100.0,
            ..Default::default()
        };
        let mut rec = PathRecorder::default();
        let s = RockStart2d { mass_kg, ..start(10.0, h, 0.0, 0.0) };
        simulate_rock(&slope, &s, &opt, &mut stream(1, 0), &mut rec);
        let PathPiece::Impact(i) = rec.pieces[1] else { panic!("{:?}", rec.pieces[1]) };
        assert_relative_eq!(i.rn, rn, max_relative = 1e-12);
        assert_relative_eq!(i.velocity_out_mps[1], rn * 4.0, max_relative = 1e-12);
    }
}

/// The lowest ground at `x`: at the x of a vertical step the whole step is ground, so a point on it is not below
/// the profile.
fn ground_low(profile: &Profile, x: f64) -> f64 {
    profile
        .segments_at(x)
        .map(|i| {
            let (a, b) = (profile.vertex(i), profile.vertex(i + 1));
            if b[0] > a[0] {
                a[1] + (b[1] - a[1]) * ((x - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0)
            } else {
                a[1].min(b[1])
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Checks every impact (energy, outgoing direction) and samples every flight against the ground.
struct Checker<'a> {
    profile: &'a Profile,
    radius: f64,
    rotation: Rotation,
    impacts: usize,
}

impl PathObserver for Checker<'_> {
    fn flight(&mut self, f: &FlightPiece) {
        for k in 0..=16 {
            let p = f.position_at(f.duration_s * k as f64 / 16.0);
            let ground = ground_low(self.profile, p[0]);
            assert!(p[1] >= ground - 1e-7, "flight below ground at x = {}: {} < {ground}", p[0], p[1]);
        }
    }
    fn impact(&mut self, e: &ImpactEvent) {
        self.impacts += 1;
        let spin_e =
            |w: f64| if self.rotation == Rotation::Off { 0.0 } else { 0.4 * self.radius * self.radius * w * w };
        let e_in = e.velocity_in_mps[0].powi(2) + e.velocity_in_mps[1].powi(2) + spin_e(e.spin_radps[0]);
        let e_out = e.velocity_out_mps[0].powi(2) + e.velocity_out_mps[1].powi(2) + spin_e(e.spin_radps[1]);
        assert!(e_out <= e_in * (1.0 + 1e-12), "impact adds energy: {e:?}");
        assert!(e.angle_offset_deg.abs() <= 9.0 + 1e-12); // 3 sd of the roughest material
    }
}

/// A rough profile with vertical steps, for invariants.
fn rough_profile(seed: u64) -> Slope2d {
    let mut rng = stream(seed, 0);
    let (mut x, mut z) = (0.0, 100.0);
    let mut v = vec![[x, z]];
    for i in 0..120 {
        if i % 17 == 5 {
            z -= 3.0 * uniform(&mut rng); // vertical drop
        } else {
            x += 0.2 + 2.0 * uniform(&mut rng);
            z += (uniform(&mut rng) - 0.8) * 3.0;
        }
        v.push([x, z]);
    }
    let mats = (0..v.len() - 1).map(|i| i % 2).collect();
    let p = Profile::new(&v, mats, vec!["a".into(), "b".into()], "rough").unwrap();
    let a = Material2d::face_all().with_roughness_sd_deg(3.0);
    let b = Material2d::floor_all().with_roughness_sd_deg(2.0).with_friction(FrictionAngle::FromRt);
    Slope2d::new(p, vec![a, b]).unwrap()
}

#[test]
fn impacts_never_add_energy_and_rocks_stay_above_ground() {
    let mut total = 0;
    for (k, rotation) in [Rotation::Off, Rotation::Rocfall, Rotation::Crsp].into_iter().enumerate() {
        for scale in [false, true] {
            let opt = Options2d { rotation, scale_rn_by_velocity: scale, ..Default::default() };
            let slopes = [rough_profile(k as u64), bench_slope(60.0, 7.0).1, bench_slope(45.0, 4.0).1];
            for slope in &slopes {
                let release = Release2d {
                    x_m: ValueRange::new(0.0, 10.0),
                    height_m: ValueRange::new(0.0, 3.0),
                    vx_mps: ValueRange::new(-1.0, 4.0),
                    vz_mps: ValueRange::new(-1.0, 2.0),
                    spin_radps: ValueRange::new(-3.0, 3.0),
                    mass_kg: 500.0,
                };
                for i in 0..100 {
                    let mut c = Checker { profile: slope.profile(), radius: opt.radius_m(500.0), rotation, impacts: 0 };
                    let r = simulate_ensemble_rock(slope, &release, &opt, 3, i, &mut c);
                    let ground = ground_low(slope.profile(), r.end_x_m);
                    assert!(r.end_z_m >= ground - 1e-9, "end point below the profile: {r:?}");
                    assert!(r.max_bounce_m >= 0.0 && r.travel_time_s >= 0.0);
                    assert_eq!(c.impacts, r.impacts as usize);
                    total += c.impacts;
                }
            }
        }
    }
    assert!(total > 1000, "{total}");
}

#[cfg(feature = "parallel")]
#[test]
fn same_results_for_1_and_2_threads() {
    let (g, slope) = bench_slope(60.0, 7.0);
    let release = crest_release(&g, 1000.0);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| simulate_rocks(&slope, &release, &Options2d::default(), 600, 99).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a, b);
    assert_ne!(a, simulate_rocks(&slope, &release, &Options2d::default(), 600, 100).unwrap());

    // The written outputs too (every file but summary.json, which holds the wall time).
    let scenario =
        ProfileScenario::from_toml_str(include_str!("../examples/profile_bench.toml"), "profile_bench.toml").unwrap();
    let files = |threads: usize| {
        let dir = tempfile::tempdir().unwrap();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| run_profile(&scenario, dir.path()).unwrap());
        ["endpoints.csv", "envelopes.csv", "collectors.csv", "profile.csv"]
            .map(|f| std::fs::read(dir.path().join(f)).unwrap())
    };
    assert_eq!(files(1), files(2));
}

#[test]
fn first_bench_capture_grows_with_width_and_face_angle() {
    let capture = |angle: f64, width: f64| {
        let (g, _) = bench_slope(angle, width);
        let face = Material2d::face_all().with_roughness_sd_deg(2.0);
        let floor = Material2d::floor_all().with_roughness_sd_deg(2.0);
        let run =
            simulate_bench(&g, &face, &floor, &crest_release(&g, 1000.0), &Options2d::default(), 300, 2016).unwrap();
        assert_eq!(run.capture.per_bench.iter().sum::<usize>(), 300);
        run.capture.fraction(1)
    };
    for angle in [45.0, 60.0, 75.0] {
        let c: Vec<f64> = (4..=10).map(|w| capture(angle, w as f64)).collect();
        assert!(c.windows(2).all(|w| w[1] >= w[0] - 0.02), "{angle}°: {c:?}");
        if angle > 45.0 {
            assert!(c[6] > c[0] + 0.05, "{angle}°: {c:?}");
        }
    }
    for width in [4.0, 7.0, 10.0] {
        let (shallow, steep) = (capture(45.0, width), capture(75.0, width));
        assert!(steep > shallow, "width {width}: 45° {shallow}, 75° {steep}");
    }
}

#[test]
fn profile_csv_errors_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.csv");
    std::fs::write(&path, "x_m,z_m,material\n0,10,rock\n5,8,rock\n4.5,6,rock\n").unwrap();
    let e = Profile::from_csv_path(&path).unwrap_err().to_string();
    assert!(e.contains(&format!("{}:4", path.display())), "{e}");
    std::fs::write(&path, "x_m,z_m,material\n0,10,rock\n5,8,rock\n6,NaN,rock\n").unwrap();
    let e = Profile::from_csv_path(&path).unwrap_err().to_string();
    assert!(e.contains(&format!("{}:4", path.display())) && e.contains("z_m"), "{e}");
}

#[test]
fn scenario_errors_name_the_field() {
    let text = include_str!("../examples/profile_bench.toml");
    let bad = text.replace("rn = { mean = 0.300, sd = 0.058 }", "rn = 1.5");
    let e = ProfileScenario::from_toml_str(&bad, "s.toml").unwrap().resolve().unwrap_err().to_string();
    assert!(e.contains("materials.floor.rn") && e.contains("1.5"), "{e}");
    let bad = text.replace("[release]", "[release]\nheigth_m = 2");
    let e = ProfileScenario::from_toml_str(&bad, "s.toml").unwrap_err().to_string();
    assert!(e.contains("heigth_m") && e.contains("s.toml:"), "{e}");
}

#[test]
fn run_profile_writes_consistent_outputs() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("slope.csv"),
        "x_m,z_m,material\n0,30,rock\n5,30,rock\n15,10,rock\n20,9,soil\n60,8,soil\n",
    )
    .unwrap();
    let scenario_path = dir.path().join("s.toml");
    std::fs::write(
        &scenario_path,
        r#"
        rocks = 500
        mass_kg = 200.0
        seed = 5
        envelope_spacing_m = 2.0
        collectors_x_m = [18.0, 30.0]
        profile = { csv = "slope.csv" }
        [materials.rock]
        preset = "face_sandstone"
        roughness_sd_deg = 3.0
        [materials.soil]
        preset = "floor_weathered"
        [release]
        x_m = [4.0, 5.0]
        height_m = [0.0, 1.0]
        vx_mps = [0.5, 2.0]
        "#,
    )
    .unwrap();
    let scenario = ProfileScenario::load(&scenario_path).unwrap();
    let out = dir.path().join("out");
    let summary = run_profile(&scenario, &out).unwrap();
    assert_eq!(summary.rocks, 500);
    let s = summary.stop_reasons;
    assert_eq!(s.stopped + s.left_profile + s.max_events + s.max_time, 500);
    assert!(summary.rocks_per_second > 0.0);

    let endpoints = std::fs::read_to_string(out.join("endpoints.csv")).unwrap();
    let mut lines = endpoints.lines();
    assert_eq!(
        lines.next().unwrap(),
        "rock_id,end_x_m,end_z_m,stop_reason,runout_m,travel_time_s,max_kinetic_j,max_bounce_m,impacts"
    );
    let ends: Vec<f64> = lines.map(|l| l.split(',').nth(1).unwrap().parse().unwrap()).collect();
    assert_eq!(ends.len(), 500);

    // Rocks only move downslope here, so the rocks passing a station are those that ended beyond it.
    let env = std::fs::read_to_string(out.join("envelopes.csv")).unwrap();
    let header: Vec<&str> = env.lines().next().unwrap().split(',').collect();
    assert_eq!(header[..4], ["x_m", "ground_z_m", "rocks", "fraction"]);
    assert!(header.contains(&"kinetic_p95_j") && header.contains(&"bounce_max_m"));
    for line in env.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let x: f64 = f[0].parse().unwrap();
        let rocks: usize = f[2].parse().unwrap();
        if x > 5.0 {
            assert_eq!(rocks, ends.iter().filter(|&&e| e >= x).count(), "station {x}");
        }
        if rocks > 0 {
            let p50: f64 = f[8].parse().unwrap();
            let p95: f64 = f[10].parse().unwrap();
            let max: f64 = f[11].parse().unwrap();
            assert!(p50 <= p95 && p95 <= max, "{line}");
        }
    }
    let col = std::fs::read_to_string(out.join("collectors.csv")).unwrap();
    assert_eq!(col.lines().count(), 3);
    let first: Vec<&str> = col.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(first[1].parse::<f64>().unwrap(), 18.0);
    assert_eq!(first[3].parse::<usize>().unwrap(), ends.iter().filter(|&&e| e >= 18.0).count());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["seed"], 5);
    assert_eq!(json["materials"]["rock"]["roughness_sd_deg"], 3.0);
    assert!(json["stop_reasons"]["stopped"].as_u64().unwrap() > 0);
    let p = Profile::from_csv_path(&out.join("profile.csv")).unwrap();
    assert_eq!(p.n_vertices(), 5);
}

/// Golden hash of a small ensemble's results (the bits of every number). It pins the engine's behaviour and, as CI
/// runs the tests with and without the `parallel` feature, the serial/parallel parity. Libm may round
/// transcendental functions differently on other platforms, so it is checked on x86_64 Linux only. Re-mint it only
/// together with a CHANGELOG note that says why the results changed.
#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
#[test]
fn golden_ensemble_hash() {
    let (g, slope) = bench_slope(60.0, 7.0);
    let release = crest_release(&g, 1000.0);
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325; // FNV-1a
    let mut eat = |v: u64| {
        for b in v.to_le_bytes() {
            hash = (hash ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for opt in
        [Options2d::default(), Options2d { rotation: Rotation::Crsp, scale_rn_by_velocity: true, ..Default::default() }]
    {
        for r in simulate_rocks(&slope, &release, &opt, 200, 2016).unwrap() {
            for v in [r.end_x_m, r.end_z_m, r.travel_time_s, r.max_bounce_m, r.max_speed_mps] {
                eat(v.to_bits());
            }
            eat(r.impacts as u64);
            eat(r.stop_reason as u64);
        }
    }
    assert_eq!(hash, 0xd2e5_4561_bbb0_2b25, "golden hash changed: {hash:#018x}");
}
