//! Writes a synthetic 3DRB field campaign, made with talus's own rigid-body engine, as the files of a real one: the
//! campaign CSVs, `terrain.obj` and, for boulders, their hull as `boulder.csv`. CASE is any 3DRB case of
//! `calibration_study` (`case_3d`: speed, speed_mixed, size, size_drag, zone, rough, control_a..e, NAME_tracked)
//! with seed SEED (default 1); a tracked case also gets each run's true path as `observed_trajectories.csv`, every
//! height plus Gaussian noise of sd TRACK_POINT_NOISE_M (default 0: exact tracks). The engine takes IMPACT_SUBSTEPS
//! sub-steps at an impact (`[simulation] impact_substeps`; default the engine's, 8; the calibration figures from before
//! 2026-11-27 were written with 1). For trying `talus calibrate --model 3drb` on files whose truth is known.
//!
//! Run: cargo run --release --example write_terrain_campaign -- DIR CASE [TRACK_POINT_NOISE_M [SEED [IMPACT_SUBSTEPS]]]
use talus::calibrate::synthetic::{case_3d, track_noise_arg, write_terrain_campaign};
use talus::sim::SimParams;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(dir), Some(case)) = (args.first(), args.get(1)) else {
        eprintln!("usage: write_terrain_campaign DIR CASE [TRACK_POINT_NOISE_M [SEED [IMPACT_SUBSTEPS]]]");
        std::process::exit(2);
    };
    let noise_m = track_noise_arg(args.get(2).map(String::as_str)).unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2);
    });
    let Ok(seed) = args.get(3).map_or(Ok(1), |s| s.parse::<u64>()) else {
        eprintln!("error: SEED must be a whole number, e.g. 2");
        std::process::exit(2);
    };
    let default = SimParams::default();
    let Ok(impact_substeps) = args.get(4).map_or(Ok(default.impact_substeps), |s| s.parse::<usize>()) else {
        eprintln!("error: IMPACT_SUBSTEPS must be a whole number, e.g. 1 (none) or 8");
        std::process::exit(2);
    };
    let sim = SimParams { impact_substeps, ..default };
    if let Err(e) = sim.validate("") {
        eprintln!("error: IMPACT_SUBSTEPS: {e}");
        std::process::exit(2);
    }
    let Some(spec) = case_3d(case, seed) else {
        eprintln!("error: no 3DRB case `{case}`; try speed, size, zone, control_a or speed_tracked");
        std::process::exit(2);
    };
    if let Err(e) = write_terrain_campaign(&spec, std::path::Path::new(dir), noise_m, &sim) {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
    println!("wrote the `{case}` case into {dir}");
}
