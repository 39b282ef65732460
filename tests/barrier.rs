//! Barriers in the engine, candidate lines on the terrain, and the `talus barrier` study.

use nalgebra::{UnitQuaternion, Vector3};
use serde_json::json;
use std::path::{Path, PathBuf};
use talus::barrier::design::ModelDesign;
use talus::barrier::{
    candidates::candidates, propose, propose_models, AcrossModels, Assessment, CandidateKind, DesignSpec, Status,
};
use talus::collector::{Collector, CollectorSet, CollectorTrack};
use talus::random::{stream, uniform, TruncNormal};
use talus::rock::{RockBody, RockSize, ShapeKind};
use talus::run::{load_terrain, RunOverrides};
use talus::scenario::{Scenario, ScenarioFile};
use talus::sim::{simulate, Barrier, BarrierHit, Observer, RigidState, Sample, SimParams, StopReason};
use talus::terrain::{Material, Terrain};

fn slope() -> Terrain {
    let m = Material {
        name: "m".into(),
        cr: TruncNormal::fixed(0.35),
        static_friction_deg: 30.0,
        dynamic_friction_deg: 22.0,
        dynamic_friction_sd_deg: 0.0,
        drag_per_s: 0.0,
    };
    // 35° plane falling towards +x.
    let t = 35f64.to_radians().tan();
    Terrain::from_function(200.0, 20, m, move |x, _| (200.0 - x) * t).unwrap()
}

/// Rock `i`: a cube or a smartie of 200–3000 kg released near the top at a random y, moving downslope.
fn release(terrain: &Terrain, i: u64) -> (RockBody, RigidState) {
    let mut rng = stream(99, i);
    let kind = if i.is_multiple_of(2) { ShapeKind::Cube } else { ShapeKind::builtin("smartie").unwrap() };
    let mass = 200.0 * 15f64.powf(uniform(&mut rng));
    let r = RockBody::new(&kind, RockSize::Mass { mass_kg: mass, density_kg_m3: 2650.0 }, "rock").unwrap();
    let (x, y) = (15.0 + 10.0 * uniform(&mut rng), 60.0 + 80.0 * uniform(&mut rng));
    let z = terrain.surface.height(x, y).unwrap() + r.bounding_radius_m + 0.5;
    let q =
        UnitQuaternion::from_euler_angles(uniform(&mut rng) * 3.0, uniform(&mut rng) * 3.0, uniform(&mut rng) * 3.0);
    let v = Vector3::new(4.0 + 6.0 * uniform(&mut rng), 4.0 * (uniform(&mut rng) - 0.5), 0.0);
    (
        r,
        RigidState {
            position_m: Vector3::new(x, y, z),
            velocity_mps: v,
            orientation: q,
            omega_body_radps: Vector3::zeros(),
        },
    )
}

#[derive(Default)]
struct Rec {
    samples: Vec<Sample>,
    hits: Vec<BarrierHit>,
}

impl Observer for Rec {
    fn sample(&mut self, s: &Sample) {
        self.samples.push(*s);
    }
    fn barrier(&mut self, h: &BarrierHit) {
        self.hits.push(*h);
    }
}

const LINE_X: f64 = 110.0;

fn fence(height_m: f64, capacity_j: f64) -> Barrier {
    Barrier { name: "fence".into(), line_m: vec![[LINE_X, -10.0], [LINE_X, 210.0]], height_m, capacity_j }
}

fn params() -> SimParams {
    SimParams { max_time_s: 40.0, ..Default::default() }
}

#[test]
fn a_straight_barrier_across_a_slope_intercepts_every_rock_that_crosses_it() {
    let free = slope();
    let mut fenced = slope();
    fenced.barriers = vec![fence(1000.0, 1e15)];
    let (mut crossing, mut not_crossing) = (0, 0);
    for i in 0..24 {
        let (r, start) = release(&free, i);
        let mut a = Rec::default();
        simulate(&free, &r, start, &params(), &mut stream(5, i), &mut a);
        let crosses = a.samples.iter().any(|s| s.position_m.x > LINE_X);
        let mut b = Rec::default();
        let out = simulate(&fenced, &r, start, &params(), &mut stream(5, i), &mut b);
        if crosses {
            crossing += 1;
            assert_eq!(out.stop_reason, StopReason::Barrier, "rock {i} crossed without the fence but was not caught");
            assert_eq!(b.hits.len(), 1);
            assert!(b.hits[0].caught);
            assert!(
                (out.final_state.position_m.x - LINE_X).abs() < 1e-6,
                "rock {i} stopped at x = {}",
                out.final_state.position_m.x
            );
            assert!(b.samples.iter().all(|s| s.position_m.x <= LINE_X + 1e-6), "rock {i} went past the fence");
        } else {
            not_crossing += 1;
            assert!(b.hits.is_empty());
            assert_eq!(a.samples.len(), b.samples.len(), "rock {i} never reached the fence, so nothing may change");
        }
    }
    assert!(crossing >= 12, "{crossing} of 24 rocks reached the fence; the test needs most of them to");
    eprintln!("{crossing} rocks crossed, {not_crossing} stopped above the fence");
}

#[test]
fn capacity_stops_exactly_the_rocks_below_it() {
    let free = slope();
    let set = CollectorSet::new(vec![Collector::new("fence line", vec![[LINE_X, -10.0], [LINE_X, 210.0]], 5.0)], None);
    // Energies at the fence with an unbreakable fence, and at the collector on the same line without one.
    let mut unbreakable = slope();
    unbreakable.barriers = vec![fence(1000.0, 1e15)];
    let mut hits = Vec::new();
    for i in 0..24 {
        let (r, start) = release(&free, i);
        let mut rec = Rec::default();
        simulate(&unbreakable, &r, start, &params(), &mut stream(5, i), &mut rec);
        let mut track = CollectorTrack::new(&set, 1.0);
        simulate(&free, &r, start, &params(), &mut stream(5, i), &mut track);
        let crossings = track.into_crossings();
        if let Some(h) = rec.hits.first() {
            let x = crossings.line_first.first().expect("the collector saw the rock cross").1;
            // The collector interpolates between samples at most 0.5 m apart: within a few percent of the energy
            // at the exact crossing.
            assert!(
                (x.kinetic_j / h.kinetic_j - 1.0).abs() < 0.1,
                "rock {i}: collector {} J, barrier {} J",
                x.kinetic_j,
                h.kinetic_j
            );
            hits.push((i, h.kinetic_j));
        }
    }
    assert!(hits.len() >= 12);
    let mut energies: Vec<f64> = hits.iter().map(|h| h.1).collect();
    energies.sort_by(f64::total_cmp);
    let capacity = 0.5 * (energies[energies.len() / 2] + energies[energies.len() / 2 - 1]);
    let mut limited = slope();
    limited.barriers = vec![fence(1000.0, capacity)];
    let (mut caught, mut through) = (0, 0);
    for &(i, e) in &hits {
        let (r, start) = release(&free, i);
        let mut rec = Rec::default();
        let out = simulate(&limited, &r, start, &params(), &mut stream(5, i), &mut rec);
        let h = rec.hits.first().expect("same path up to the fence");
        assert_eq!(h.kinetic_j, e, "rock {i}: the path up to the fence must not change");
        assert_eq!(h.caught, e <= capacity, "rock {i}: {e} J against {capacity} J");
        if h.caught {
            caught += 1;
            assert_eq!(out.stop_reason, StopReason::Barrier);
        } else {
            through += 1;
            assert_ne!(out.stop_reason, StopReason::Barrier);
            assert!(
                rec.samples.iter().any(|s| s.position_m.x > LINE_X + 0.1),
                "rock {i} broke through but did not go on"
            );
        }
    }
    assert!(caught > 0 && through > 0, "caught {caught}, through {through}");
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scenario(path: &Path) -> Scenario {
    ScenarioFile::read(path).unwrap().resolve(path).unwrap()
}

#[test]
fn bench_candidates_lie_on_the_terrain_at_their_level() {
    let sc = scenario(&root().join("examples/bench_stack.toml"));
    let terrain = load_terrain(&sc).unwrap();
    let cands = candidates(&terrain, &DesignSpec::default(), sc.file.output.cell_size_m);
    let oz = terrain.origin.z;
    let mut crests = Vec::new();
    let mut toes = Vec::new();
    for c in &cands {
        let level = match c.kind {
            CandidateKind::BenchCrest { floor_m } => {
                crests.push(floor_m.round() as i64);
                floor_m - 0.25
            }
            CandidateKind::BenchToe { floor_m } => {
                toes.push(floor_m.round() as i64);
                floor_m + 0.25
            }
            _ => continue,
        };
        // Points every 0.25 m along the line are on the contour.
        let mut worst: f64 = 0.0;
        for w in c.line_m.windows(2) {
            let n = ((w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) / 0.25).ceil().max(1.0) as usize;
            for k in 0..=n {
                let f = k as f64 / n as f64;
                let (x, y) = (w[0][0] + f * (w[1][0] - w[0][0]), w[0][1] + f * (w[1][1] - w[0][1]));
                let z = terrain
                    .surface
                    .height(x, y)
                    .unwrap_or_else(|| panic!("{} ({x}, {y}) is not on the terrain", c.name))
                    + oz;
                worst = worst.max((z - level).abs());
            }
        }
        assert!(worst < 0.05, "{}: {worst} m off its level {level}", c.name);
        assert!(
            (talus::barrier::candidates::length(&c.line_m) - 100.0).abs() < 1.5,
            "{} spans the stack's 100 m width",
            c.name
        );
    }
    crests.sort();
    toes.sort();
    assert_eq!(crests, vec![20, 40, 60, 80, 100, 120]);
    assert_eq!(toes, vec![0, 20, 40, 60, 80, 100]);
    assert!(cands.iter().any(|c| matches!(c.kind, CandidateKind::FloorOffset { offset_m } if offset_m == 10.0)));
}

#[test]
fn tyrol_contour_candidates_follow_their_contour() {
    let sc = scenario(&root().join("examples/tyrol.toml"));
    let terrain = load_terrain(&sc).unwrap();
    let cands = candidates(&terrain, &DesignSpec::default(), sc.file.output.cell_size_m);
    let contours: Vec<_> = cands.iter().filter(|c| matches!(c.kind, CandidateKind::Contour { .. })).collect();
    assert!(contours.len() >= 10);
    for c in contours {
        let CandidateKind::Contour { elevation_m } = c.kind else { unreachable!() };
        for p in &c.line_m {
            let z = terrain.surface.height(p[0], p[1]).unwrap() + terrain.origin.z;
            assert!((z - elevation_m).abs() < 0.01, "{}: vertex at {z}", c.name);
            let slope = terrain.surface.at(p[0], p[1]).unwrap().normal.z.acos().to_degrees();
            assert!(slope <= 45.0 + 1e-9, "{}: vertex on a {slope}° slope", c.name);
        }
    }
}

fn small_bench_scenario(dir: &Path, extra: &str) -> PathBuf {
    let mesh = root().join("meshes/bench_stack/bench_stack.obj");
    let text = format!(
        r#"title = "small bench stack"
[terrain]
files = ["{}"]
materials_by = "group"
crs_epsg = 2056
[materials.face]
preset = "face_all"
[materials.floor]
preset = "floor_all"
[[sources]]
type = "scatter"
material = "face"
within = [[10.0, 35.0], [21.6, 35.0], [21.6, 65.0], [10.0, 65.0]]
count = 100
[rocks]
shapes = ["cube", "flat_box", "smartie"]
mass_kg = [100.0, 10000.0]
[output]
cell_size_m = 2.0
{extra}
"#,
        mesh.display()
    );
    let p = dir.join("scenario.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn barrier_study_ranks_sizes_reruns_and_does_not_depend_on_threads() {
    let dir = tempfile::tempdir().unwrap();
    let path = small_bench_scenario(dir.path(), "[barrier_design]\nmin_rocks = 10\nbest = 3\n");
    let sc = scenario(&path);
    let mut outs = Vec::new();
    for threads in [1, 2] {
        let out = dir.path().join(format!("study{threads}"));
        let o = RunOverrides { threads: Some(threads), ..Default::default() };
        let study = propose(&sc, &o, &out, &|_| {}, &|_, _| {}).unwrap();
        outs.push((out, study));
    }
    let (out, study) = &outs[0];
    for f in [
        "index.html",
        "proposals.csv",
        "proposals.md",
        "proposals.geojson",
        "proposals.png",
        "candidates.csv",
        "candidates.geojson",
        "barrier_study.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    for f in [
        "without_barrier/index.html",
        "without_barrier/collectors.csv",
        "with_barrier/index.html",
        "with_barrier/summary.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let a = std::fs::read_to_string(out.join("candidates.csv")).unwrap();
    let b = std::fs::read_to_string(outs[1].0.join("candidates.csv")).unwrap();
    assert_eq!(a, b, "results depend on the thread count");
    let ranked = study.ranked();
    let best = ranked.first().expect("a proposal");
    assert_eq!(best.status, Status::Sized);
    assert!(best.length_m > 0.0 && best.length_m <= best.candidate_length_m + 1e-9);
    assert!(best.fence_height_m >= best.design_height_m && best.fence_height_m - best.design_height_m < 0.5 + 1e-9);
    assert!(best.energy_p95_kj <= best.energy_max_kj);
    if let Some(c) = best.class_kj {
        assert!(best.energy_p95_kj <= c);
    }
    // The re-run keeps the same rocks and puts the proposal in place.
    let m = &study.models[0];
    let r = m.residual.as_ref().expect("re-run");
    assert_eq!(r.reaching_without, best.rocks_reaching);
    assert!(r.reaching_with <= r.reaching_without);
    assert_eq!(r.reaching_with, r.through + r.over + r.around + r.elsewhere);
    let with = m.with.as_ref().unwrap();
    assert_eq!(with.summary.barriers.len(), 1);
    assert_eq!(with.summary.barriers[0].caught, r.caught);
    assert_eq!(with.summary.rocks, m.without.summary.rocks);
    // The hazard zones' areas without and with the barrier are those of the two runs' hazard_zones.tif.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("barrier_study.json")).unwrap()).unwrap();
    for kind in ["without", "with"] {
        let levels = talus::io::geotiff::read_grid(&out.join(format!("{kind}_barrier/hazard_zones.tif"))).unwrap();
        let areas = talus::zones::areas_m2(&levels);
        let got: Vec<f64> =
            json["models"][0]["zone_areas_m2"][kind].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert_eq!(got, areas.to_vec(), "{kind}");
    }
    let md = std::fs::read_to_string(out.join("proposals.md")).unwrap();
    assert!(md.contains("| hazard zone high (red) |"), "{md}");
}

/// `talus barrier --models`: two models of one site (a bouncier bench floor in the second). The proposal holds the
/// target in every model, takes the larger height and energy, and each model's runs are its own `talus barrier`
/// runs; the same model twice sizes exactly as the model alone.
#[test]
fn barrier_against_several_models_holds_in_each_and_takes_the_largest_design() {
    let dir = tempfile::tempdir().unwrap();
    let spec = "[barrier_design]\nmin_rocks = 10\nbest = 3\n";
    let path_a = small_bench_scenario(dir.path(), spec);
    let text = std::fs::read_to_string(&path_a).unwrap();
    let path_b = dir.path().join("bouncy.toml");
    std::fs::write(&path_b, text.replace("preset = \"floor_all\"", "preset = \"floor_all\"\ncr_mean = 0.4")).unwrap();
    let (a, b) = (scenario(&path_a), scenario(&path_b));
    let o = RunOverrides { threads: Some(2), ..Default::default() };
    let run = |models: &[(&str, &Scenario)], out: &str| {
        let models: Vec<(String, Scenario)> = models.iter().map(|(n, s)| (n.to_string(), (*s).clone())).collect();
        propose_models(&models, &o, &dir.path().join(out), false, &|_| {}, &|_, _| {}).unwrap()
    };
    let alone_a = run(&[("a", &a)], "a");
    let alone_b = run(&[("b", &b)], "b");
    let both = run(&[("a", &a), ("b", &b)], "ab");
    let twice = run(&[("a", &a), ("a2", &a)], "aa");

    // The same model twice: every candidate sized as by the model alone.
    let key = |x: &Assessment| {
        (x.rank, x.status, x.from_m, x.to_m, x.share, x.fence_height_m.to_bits(), x.energy_max_kj.to_bits(), x.class_kj)
    };
    for (x, y) in twice.assessments.iter().zip(&alone_a.assessments) {
        assert_eq!(key(x), key(y), "{}", x.name);
    }

    // Each model's runs are its own: the rocks reaching each candidate are those of its study alone.
    for (k, x) in both.assessments.iter().enumerate() {
        if x.status != Status::Sized {
            continue;
        }
        assert_eq!(x.per_model[0].rocks_reaching, alone_a.assessments[k].rocks_reaching, "{}", x.name);
        assert_eq!(x.per_model[1].rocks_reaching, alone_b.assessments[k].rocks_reaching, "{}", x.name);
        let sizing: Vec<_> = x.per_model.iter().filter(|d| d.sizes).collect();
        let max = |f: fn(&ModelDesign) -> f64| sizing.iter().map(|d| f(d)).fold(f64::NAN, f64::max);
        assert_eq!(x.design_height_m, max(|d| d.design_height_m), "{}", x.name);
        assert_eq!(x.energy_p95_kj, max(|d| d.energy_p95_kj), "{}", x.name);
        assert_eq!(x.share, sizing.iter().map(|d| d.share).fold(f64::INFINITY, f64::min), "{}", x.name);
        assert_eq!(
            x.meets_target,
            sizing.iter().all(|d| d.share >= a.file.barrier_design.target_share - 1e-12),
            "{}",
            x.name
        );
        // The run that holds both models is no shorter than either model's own.
        assert!(x.length_m >= alone_a.assessments[k].length_m.min(alone_b.assessments[k].length_m) - 1e-9);
        assert!(["a", "b"].contains(&x.height_from.as_str()) && ["a", "b"].contains(&x.energy_from.as_str()));
    }
    // Pooled: one ensemble of both models' rocks. Its share is of the pooled counts, and each pooled P95 lies
    // between the models' own (a mixture's quantile lies between its components'), to the collectors' bin width
    // (50 bins a decade, 4.7 %).
    let (mut ap, mut bp) = (a.clone(), b.clone());
    ap.file.barrier_design.across_models = AcrossModels::Pooled;
    bp.file.barrier_design.across_models = AcrossModels::Pooled;
    let pooled = run(&[("a", &ap), ("b", &bp)], "pooled");
    let mut checked = 0;
    for x in pooled.assessments.iter().filter(|x| x.status == Status::Sized) {
        let sum = |f: fn(&ModelDesign) -> u64| x.per_model.iter().map(f).sum::<u64>();
        assert_eq!((x.rocks_reaching, x.intercepted), (sum(|d| d.rocks_reaching), sum(|d| d.intercepted)));
        assert_eq!((x.height_from.as_str(), x.energy_from.as_str()), ("pooled", "pooled"));
        let e: Vec<f64> = x.per_model.iter().map(|d| d.energy_p95_kj).filter(|e| e.is_finite()).collect();
        if e.len() == 2 {
            let (lo, hi) = (e[0].min(e[1]), e[0].max(e[1]));
            let e = x.energy_p95_kj;
            assert!(e >= lo / 1.047 && e <= hi * 1.047, "{}: {lo} {e} {hi}", x.name);
            checked += 1;
        }
    }
    assert!(checked > 3, "{checked} candidates crossed in both models");
    // The share of released rocks is of both models' rocks, and the report says so.
    let md = std::fs::read_to_string(dir.path().join("pooled/proposals.md")).unwrap();
    let released = 2 * pooled.models[0].without.summary.rocks;
    assert!(md.contains(&format!("of all {released})")), "{md}");

    let best = both.ranked()[0];
    assert!(best.meets_target, "{}: {}", best.name, best.note);
    // Re-run under each model with the one barrier; each with-run has it and keeps that model's rocks.
    let barrier = both.barrier.as_ref().unwrap();
    assert_eq!(barrier.height_m, best.fence_height_m);
    for (m, d) in both.models.iter().zip(&best.per_model) {
        let r = m.residual.as_ref().unwrap();
        assert_eq!(r.reaching_without, d.rocks_reaching, "{}", m.name);
        assert!(r.reaching_with <= r.reaching_without);
        assert_eq!(m.with.as_ref().unwrap().summary.barriers.len(), 1);
    }
    for f in ["models/a/without_barrier/summary.json", "models/b/with_barrier/summary.json", "index.html"] {
        assert!(dir.path().join("ab").join(f).is_file(), "{f} missing");
    }
    let md = std::fs::read_to_string(dir.path().join("ab/proposals.md")).unwrap();
    assert!(md.contains("## The models") && md.contains("(sets the "), "{md}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("ab/barrier_study.json")).unwrap()).unwrap();
    assert_eq!(json["models"].as_array().unwrap().len(), 2);
    assert_eq!(json["proposals"][0]["per_model"].as_array().unwrap().len(), 2);
}

/// The command line: `--models` files run on the scenario's site; a model without the site's materials is refused
/// with exit 2, naming the model and the materials.
#[test]
fn barrier_models_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let site = small_bench_scenario(dir.path(), "[barrier_design]\nmin_rocks = 10\nbest = 2\n");
    let text = std::fs::read_to_string(&site).unwrap();
    let m1 = dir.path().join("m1.toml");
    let m2 = dir.path().join("m2.toml");
    std::fs::write(&m1, &text).unwrap();
    std::fs::write(&m2, text.replace("preset = \"face_all\"", "preset = \"face_all\"\ncr_mean = 0.25")).unwrap();
    let talus = env!("CARGO_BIN_EXE_talus");
    let out = dir.path().join("study");
    let run = |models: &[&Path]| {
        std::process::Command::new(talus)
            .args(["barrier", site.to_str().unwrap(), "--rocks", "60", "--floor", "--out", out.to_str().unwrap()])
            .arg("--models")
            .args(models)
            .output()
            .unwrap()
    };
    let ok = run(&[&m1, &m2]);
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    let stdout = String::from_utf8_lossy(&ok.stdout);
    assert!(stdout.contains("over 2 models") && stdout.contains("under m2"), "{stdout}");
    let m1_summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("models/m1/without_barrier/summary.json")).unwrap())
            .unwrap();
    assert_eq!(m1_summary["rocks"], 60);
    // --floor: the first model with its seed and the next, sized alike in OUT/floor/.
    let seed = m1_summary["seed"].as_u64().unwrap();
    assert!(stdout.contains("Seeds alone (model m1 with 2 seeds)"), "{stdout}");
    assert!(std::fs::read_to_string(out.join("proposals.md")).unwrap().contains("Seeds alone"));
    let floor_run = |s: u64, kind: &str| {
        let path = out.join(format!("floor/models/seed_{s}/{kind}/summary.json"));
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(&path).unwrap()).unwrap()
    };
    assert!(out.join("floor/index.html").is_file());
    assert_eq!(floor_run(seed, "without_barrier")["runout_m"], m1_summary["runout_m"], "the floor's first is m1's run");
    assert_eq!(floor_run(seed + 1, "with_barrier")["seed"], seed + 1);
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, text.replace("[materials.floor]", "[materials.bench]")).unwrap();
    let err = run(&[&m1, &bad]);
    assert_eq!(err.status.code(), Some(2));
    let e = String::from_utf8_lossy(&err.stderr);
    assert!(e.contains("bad.toml") && e.contains("floor"), "{e}");
}

/// The shipped Tschamut barrier site reads, takes the shipped calibrated model (what `--models` does with a fold
/// model) and has candidates, its road's offsets among them.
#[test]
fn the_shipped_tschamut_barrier_site_takes_a_calibrated_model() {
    let site_path = root().join("examples/barrier_tschamut.toml");
    let site = ScenarioFile::read(&site_path).unwrap();
    let model = ScenarioFile::read(&root().join("examples/calibrated_tschamut.toml")).unwrap();
    let sc = talus::envelope::on_site(&site, &model, "calibrated").unwrap().resolve(&site_path).unwrap();
    assert_eq!(sc.file.barrier_design.asset_line.len(), 2);
    let terrain = load_terrain(&sc).unwrap();
    let cands = candidates(&terrain, &sc.file.barrier_design, sc.file.output.cell_size_m);
    let offsets = cands.iter().filter(|c| matches!(c.kind, CandidateKind::AssetOffset { .. })).count();
    assert_eq!(offsets, 3, "{:?}", cands.iter().map(|c| &c.name).collect::<Vec<_>>());
    assert!(cands.len() > 20);
}

/// The shipped Tschamut barrier site's own model (run without `--models`) is the shipped calibrated one, as its
/// header says: a refit copied into `calibrated_tschamut.toml` must be copied into the site too.
#[test]
fn the_shipped_tschamut_barrier_site_runs_the_shipped_calibrated_model() {
    let read = |f: &str| ScenarioFile::read(&root().join("examples").join(f)).unwrap();
    let (site, model) = (read("barrier_tschamut.toml"), read("calibrated_tschamut.toml"));
    let same = |a: serde_json::Value, b: serde_json::Value, table: &str| assert_eq!(a, b, "[{table}]");
    same(json!(site.materials), json!(model.materials), "materials");
    same(json!(site.simulation), json!(model.simulation), "simulation");
    same(json!(site.terrain), json!(model.terrain), "terrain");
}

/// `--models` on a site given by a relative path whose campaign source is relative too (the README's command, run
/// from the repository): the site's paths resolve once, against the site file.
#[test]
fn barrier_models_on_a_relative_site_with_a_campaign_source() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("study");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_talus"))
        .current_dir(root())
        .args(["barrier", "examples/barrier_tschamut.toml", "--rocks", "40", "--no-rerun", "--out"])
        .arg(&out)
        .args(["--models", "examples/calibrated_tschamut.toml", "examples/calibrated_tschamut.toml"])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let runs = std::fs::read_dir(out.join("models")).unwrap().map(|e| e.unwrap().path()).collect::<Vec<_>>();
    assert_eq!(runs.len(), 2, "{runs:?}");
    assert!(runs.iter().all(|r| r.join("without_barrier/summary.json").is_file()), "{runs:?}");
}

#[test]
fn a_barrier_study_reports_the_terrains_warnings_as_a_stage() {
    let dir = tempfile::tempdir().unwrap();
    let extra = "[materials.rockfill]\npreset = \"floor_all\"\n[barrier_design]\nmin_rocks = 10\n";
    let path = small_bench_scenario(dir.path(), extra);
    let said = std::cell::RefCell::new(Vec::new());
    let o = RunOverrides { rocks: Some(20), ..Default::default() };
    propose(&scenario(&path), &o, &dir.path().join("study"), &|s| said.borrow_mut().push(s.to_string()), &|_, _| {})
        .unwrap();
    let said = said.into_inner();
    assert!(said.first().is_some_and(|s| s.starts_with("warning: [materials.rockfill] is defined")), "{said:?}");
}

#[test]
fn an_asset_line_or_polygon_off_the_terrain_is_refused_before_any_run() {
    // The bench stack spans about 0-160 m by 0-100 m: a line given in another frame lies far off it.
    let dir = tempfile::tempdir().unwrap();
    for (key, value) in [
        ("asset_line", "[[150000.0, 0.0], [150000.0, 100.0]]"),
        ("asset_polygon", "[[150000.0, 0.0], [150100.0, 0.0], [150100.0, 100.0]]"),
    ] {
        let path = small_bench_scenario(dir.path(), &format!("[barrier_design]\n{key} = {value}\n"));
        let out = dir.path().join("study");
        let e = propose(&scenario(&path), &RunOverrides::default(), &out, &|_| {}, &|_, _| {}).unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains(&format!("barrier_design.{key}")) && e.contains("no part of it lies over the terrain"),
            "{e}"
        );
        assert!(!out.exists(), "{key}: output written despite the error");
    }
    // A polygon around the whole terrain protects all of it: accepted.
    let around = "[[-1000.0, -1000.0], [1000.0, -1000.0], [1000.0, 1000.0], [-1000.0, 1000.0]]";
    let path =
        small_bench_scenario(dir.path(), &format!("[barrier_design]\nasset_polygon = {around}\nmin_rocks = 10\n"));
    let o = RunOverrides { rocks: Some(20), ..Default::default() };
    propose(&scenario(&path), &o, &dir.path().join("around"), &|_| {}, &|_, _| {}).unwrap();
}

/// `--models`: a bad value in a model file is named in that file, not in the site scenario's, with exit 2 and no
/// run left in the output folder.
#[test]
fn a_bad_value_in_a_models_file_is_named_in_that_file() {
    let dir = tempfile::tempdir().unwrap();
    let site = small_bench_scenario(dir.path(), "[barrier_design]\nmin_rocks = 10\n");
    let text = std::fs::read_to_string(&site).unwrap();
    let (good, bad) = (dir.path().join("good.toml"), dir.path().join("bad.toml"));
    std::fs::write(&good, &text).unwrap();
    for (value, field) in [
        ("[simulation]\ndt_s = -1.0", "simulation.dt_s"),
        ("[simulation.effects]\nsoft_materials = [\"nosuch\"]", "simulation.effects.soft_materials[0]"),
        ("[materials.floor]\npreset = \"floor_all\"\ncr_mean = -0.5", "materials.floor"),
    ] {
        let model = if value.starts_with("[materials.floor]") {
            text.replace("[materials.floor]\npreset = \"floor_all\"", value)
        } else {
            text.replace("[output]", &format!("{value}\n[output]"))
        };
        std::fs::write(&bad, model).unwrap();
        let out = dir.path().join("study");
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_talus"))
            .args(["barrier", site.to_str().unwrap(), "--rocks", "10", "--out", out.to_str().unwrap(), "--models"])
            .args([&good, &bad])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(&format!("{}: {field}", bad.display())) && err.contains("how to fix"), "{field}: {err}");
        assert!(!out.join("models").exists(), "{field}: a model ran before the refusal");
    }
}

/// Several models: every one is checked before the first runs, so that a model its run would refuse (here a source
/// off the terrain, found only with the terrain loaded) leaves no run of the others behind.
#[test]
fn every_model_of_a_barrier_study_is_checked_before_the_first_runs() {
    let dir = tempfile::tempdir().unwrap();
    let path = small_bench_scenario(dir.path(), "[barrier_design]\nmin_rocks = 10\n");
    let good = scenario(&path);
    let text = std::fs::read_to_string(&path).unwrap();
    let within = "within = [[10.0, 35.0], [21.6, 35.0], [21.6, 65.0], [10.0, 65.0]]";
    let off = text.replace(within, "within = [[9010.0, 35.0], [9021.6, 35.0], [9021.6, 65.0], [9010.0, 65.0]]");
    let bad_path = dir.path().join("off.toml");
    std::fs::write(&bad_path, off).unwrap();
    let models = [("good".to_string(), good), ("off".to_string(), scenario(&bad_path))];
    let out = dir.path().join("study");
    let o = RunOverrides { rocks: Some(10), ..Default::default() };
    let e = propose_models(&models, &o, &out, false, &|_| {}, &|_, _| {}).unwrap_err().to_string();
    assert!(e.contains("off.toml: sources[0]"), "{e}");
    assert!(!out.join("models").exists(), "a model ran before the refusal: {e}");
}
