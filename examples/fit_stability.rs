//! How much the Tschamut population fit depends on its random numbers: fits the calibration settings' free
//! parameters on all 80 runs once per seed (the seed sets the common random numbers of the searches, nothing else
//! here; with `search_starts > 1` in the settings, each fit is the best of several searches), then simulates every fitted candidate under one independent seed (1000) with 20 repeats per run and prints
//! its parameters, its objective there, and per block the bias and run-out MAE. If the fit were stable the rows
//! would agree to within the evaluation's own noise; where they do not, the fit, not the model, limits any
//! comparison of settings made with it.
//!
//! Run: cargo run --release --example fit_stability -- SETTINGS SEED [SEED ...]
//! e.g. `-- examples/tschamut_combined_level.toml 1 2 3` (about 9.5 min per seed on 2 cores).
use std::path::Path;
use std::time::Instant;
use talus::calibrate::config::CalibrationConfig;
use talus::calibrate::fit::{fit_population, Context};
use talus::calibrate::metrics::metrics;
use talus::calibrate::model::evaluate;
use talus::calibrate::objective::objective;
use talus::calibrate::{base_candidate, open_model, ModelKind};

/// Simulations per run in the common evaluation.
const REPEATS: usize = 20;
/// The evaluation's seed: none of the fits uses it.
const EVALUATION_SEED: u64 = 1000;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seeds: Vec<u64> = args.iter().skip(1).map(|a| a.parse().expect("seeds are whole numbers")).collect();
    if seeds.is_empty() {
        eprintln!("usage: fit_stability SETTINGS SEED [SEED ...]");
        std::process::exit(2);
    }
    let cfg = CalibrationConfig::read(Path::new(&args[0])).unwrap_or_else(|e| panic!("{e}"));
    let dir = Path::new("meshes/tschamut2014");
    let model = open_model(dir, &dir.join("terrain_proxy.asc"), ModelKind::Rigid3d, &cfg, &args[0]).unwrap();
    let runs = model.runs();
    let all: Vec<usize> = (0..runs.len()).collect();
    let quiet = |_: &str| {};
    for &seed in &seeds {
        let mut cfg = cfg.clone();
        cfg.seed = seed;
        let ctx = Context::new(model.as_ref(), &cfg, &quiet);
        let (start, free) = base_candidate(model.as_ref(), &cfg);
        let t = Instant::now();
        let (c, search, _) = fit_population(&ctx, &start, &free, &all, "population fit");
        let sims = evaluate(model.as_ref(), &c, &all, REPEATS, EVALUATION_SEED, cfg.threads).unwrap();
        let params: Vec<String> =
            free.iter().map(|p| format!("{}={:.3}", p.name, c.params.get_or(&p.name, 0.0))).collect();
        let mut line = format!(
            "seed {seed}: fit {:.0} s, {} evaluations (last improvement at {}), objective at fit {:.2} m, at \
             evaluation {:.2} m",
            t.elapsed().as_secs_f64(),
            search.evaluations,
            search.history.iter().position(|&v| v == search.f).map_or(0, |i| i + 1),
            search.f,
            objective(cfg.objective, runs, &sims)
        );
        for block in ["1", "2", "4"] {
            let s: Vec<_> = sims.iter().filter(|s| runs[s.run].block_id == block).cloned().collect();
            let m = metrics(runs, &s);
            line += &format!("; block {block} bias {:+.1} MAE {:.1}", m.runout_bias_m, m.runout_mae_m);
        }
        let m = metrics(runs, &sims);
        line += &format!(
            "; all bias {:+.1} MAE {:.1} W1 {:.1}\n    {}",
            m.runout_bias_m,
            m.runout_mae_m,
            m.runout_w1_m,
            params.join(" ")
        );
        println!("{line}");
    }
}
