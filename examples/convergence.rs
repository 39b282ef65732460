//! Time-step convergence of the 3DRB engine.
//!
//! 1. The default example: the median run-out of `examples/bench_stack.toml` at the default step and at half of it
//!    (same rocks, same seed).
//! 2. Hopping over uneven ground: blocks of Tschamut's block 1 (69 kg, 0.37 × 0.32 × 0.37 m) launched at 10 m/s
//!    down a 20° slope with bumps of ±8 cm every 1.3–1.5 m (a real surface of 0.25 m cells, no roughness effect;
//!    Cr 0.26 ± 0.04, static 30.9°, dynamic 23.2°), at steps of 2 to 0.25 ms and at 2 ms with `impact_substeps`.
//!
//! ```text
//! cargo run --release --example convergence                # 4,000 rocks, 300 blocks
//! cargo run --release --example convergence -- 10000 1000  # more
//! ```

use nalgebra::Vector3;
use std::path::Path;
use talus::random::{stream, TruncNormal};
use talus::rock::{random_orientation, RockBody, RockSize, ShapeKind};
use talus::run::{quantile_sorted, setup, RunOverrides};
use talus::scenario::ScenarioFile;
use talus::sim::{simulate, RigidState, SimParams, StopReason};
use talus::terrain::{Material, Terrain};

fn main() {
    let arg = |i: usize, default: usize| std::env::args().nth(i).and_then(|s| s.parse().ok()).unwrap_or(default);
    bench_stack(arg(1, 4000));
    bumpy_slope(arg(2, 300));
}

fn bench_stack(rocks: usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/bench_stack.toml");
    let sc = ScenarioFile::read(&path).and_then(|f| f.resolve(&path)).expect("scenario");
    let base = setup(&sc, &RunOverrides { rocks: Some(rocks), ..Default::default() }).expect("setup");
    let dt = base.params.dt_s;
    println!("{rocks} rocks on the bench stack");
    println!("{:>10} {:>16} {:>16} {:>16}", "dt_s", "median runout_m", "p90 runout_m", "stopped");
    let mut medians = Vec::new();
    for step in [dt, dt / 2.0] {
        let mut s = base.clone();
        s.params.dt_s = step;
        let records = talus::parallel::collect_in_order(rocks, 0, |i| s.run_rock(i, &mut ()));
        let mut runout: Vec<f64> = records.iter().map(|r| r.runout_m).collect();
        runout.sort_by(f64::total_cmp);
        let stopped = records.iter().filter(|r| r.outcome.stop_reason == StopReason::Stopped).count();
        let median = quantile_sorted(&runout, 0.5);
        println!("{:>10} {:>16.3} {:>16.3} {:>16}", step, median, quantile_sorted(&runout, 0.9), stopped);
        medians.push(median);
    }
    println!(
        "halving the step moves the median run-out by {:.2} %\n",
        100.0 * (medians[1] - medians[0]).abs() / medians[0]
    );
}

fn bumpy_slope(blocks: usize) {
    let (size_m, slope) = (200.0, 20f64.to_radians());
    let material = Material {
        name: "slope".into(),
        cr: TruncNormal::three_sigma(0.26, 0.04, 0.0, 1.0),
        static_friction_deg: 30.9,
        dynamic_friction_deg: 23.2,
        dynamic_friction_sd_deg: 0.0,
        drag_per_s: 0.0,
    };
    let bumps_m = 0.08;
    let ground = move |x: f64, y: f64| {
        (size_m - x) * slope.tan()
            + bumps_m * (std::f64::consts::TAU * x / 1.5).sin() * (std::f64::consts::TAU * y / 1.3).sin()
    };
    let terrain = Terrain::from_function(size_m, 800, material, ground).expect("terrain");
    let size = RockSize::DimensionsAndMass { size_m: [0.37, 0.32, 0.37], mass_kg: 69.0 };
    let rock = RockBody::new(&ShapeKind::Cube, size, "block").expect("rock");
    println!("{blocks} blocks launched at 10 m/s down a bumpy 20° slope ({size_m} m long)");
    println!(
        "{:>10} {:>16} {:>16} {:>16} {:>10}",
        "dt_s", "impact_substeps", "mean distance_m", "left the slope", "seconds"
    );
    for (dt_s, impact_substeps) in [(0.002, 1), (0.001, 1), (0.0005, 1), (0.00025, 1), (0.002, 8)] {
        let params = SimParams { dt_s, impact_substeps, ..SimParams::default() };
        let clock = std::time::Instant::now();
        let runs = talus::parallel::collect_in_order(blocks, 0, |i| {
            let mut rng = stream(7, i as u64);
            let x0 = 15.0;
            let start = RigidState {
                position_m: Vector3::new(x0, size_m / 2.0 + 0.37 * i as f64 / blocks as f64, ground(x0, 0.0) + 0.5),
                velocity_mps: Vector3::new(10.0 * slope.cos(), 0.0, -10.0 * slope.sin()),
                orientation: random_orientation(&mut rng),
                omega_body_radps: Vector3::zeros(),
            };
            let out = simulate(&terrain, &rock, start, &params, &mut rng, &mut ());
            (out.final_state.position_m.x - x0, out.stop_reason != StopReason::Stopped)
        });
        let mean = runs.iter().map(|r| r.0).sum::<f64>() / blocks as f64;
        let left = runs.iter().filter(|r| r.1).count();
        let secs = clock.elapsed().as_secs_f64();
        println!("{dt_s:>10} {impact_substeps:>16} {mean:>16.1} {left:>16} {secs:>10.1}");
    }
}
