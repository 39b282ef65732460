//! The Tschamut campaign simulated under parameters you give, per block: observed and simulated mean run-out, bias,
//! run-out MAE and coverage (20 repeats per run, all 80 runs). For looking at what a parameter or an effect does to
//! each block without a calibration.
//!
//! Run: cargo run --release --example explore_tschamut -- CR CR_SD STATIC_DEG DYNAMIC_DEG [VEGETATION_DRAG_KG_S]
//! e.g. `-- 0.30 0.06 35.4 20.3` (a W1 k-fold fold's baseline) and `-- 0.30 0.06 35.4 14.0 10` (with vegetation drag)
use std::path::Path;
use talus::calibrate::config::CalibrationConfig;
use talus::calibrate::metrics::metrics;
use talus::calibrate::model::evaluate;
use talus::calibrate::params::Candidate;
use talus::calibrate::synthetic::material_params_3d;
use talus::calibrate::{open_model, ModelKind};

fn main() {
    let args: Vec<f64> = std::env::args().skip(1).map(|a| a.parse().expect("numbers")).collect();
    if !(4..=5).contains(&args.len()) {
        eprintln!("usage: explore_tschamut CR CR_SD STATIC_DEG DYNAMIC_DEG [VEGETATION_DRAG_KG_S]");
        std::process::exit(2);
    }
    let dir = Path::new("meshes/tschamut2014");
    let mut cfg = CalibrationConfig::default();
    cfg.simulation.effects.vegetation_drag_kg_s = args.get(4).copied();
    let model = open_model(dir, &dir.join("terrain_proxy.asc"), ModelKind::Rigid3d, &cfg, "explore_tschamut").unwrap();
    let c =
        Candidate { params: material_params_3d("default", [args[0], args[1], args[2], args[3]]), ..Default::default() };
    let all: Vec<usize> = (0..model.runs().len()).collect();
    let sims = evaluate(model.as_ref(), &c, &all, 20, 1, 0).unwrap();
    println!("block  runs  observed m  simulated m  bias m  MAE m  floor m  coverage");
    for block in ["1", "2", "4"] {
        let s: Vec<_> = sims.iter().filter(|s| model.runs()[s.run].block_id == block).cloned().collect();
        let m = metrics(model.runs(), &s);
        println!(
            "{block:>5}  {:>4}  {:>10.1}  {:>11.1}  {:>+6.1}  {:>5.1}  {:>7.1}  {:>8.2}",
            m.runs,
            m.observed_mean_m,
            m.simulated_mean_m,
            m.runout_bias_m,
            m.runout_mae_m,
            m.scatter_floor_mae_m,
            m.coverage_90
        );
    }
}
