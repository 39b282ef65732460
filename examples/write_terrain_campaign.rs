//! Writes a synthetic 3DRB field campaign, made with talus's own rigid-body engine, as the files of a real one: the
//! campaign CSVs, `terrain.obj` and, for boulders, their hull as `boulder.csv`. CASE is any 3DRB case of
//! `calibration_study` (`case_3d`: speed, speed_mixed, size, size_drag, zone, rough, control_a..e, NAME_tracked)
//! with seed SEED (default 1); a tracked case also gets each run's true path as `observed_trajectories.csv`, every
//! height plus Gaussian noise of sd TRACK_POINT_NOISE_M (default 0: exact tracks). For trying `talus calibrate
//! --model 3drb` on files whose truth is known.
//!
//! Run: cargo run --release --example write_terrain_campaign -- DIR CASE [TRACK_POINT_NOISE_M [SEED]]
use talus::calibrate::synthetic::{case_3d, track_noise_arg, write_terrain_campaign};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(dir), Some(case)) = (args.first(), args.get(1)) else {
        eprintln!("usage: write_terrain_campaign DIR CASE [TRACK_POINT_NOISE_M [SEED]]");
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
    let Some(spec) = case_3d(case, seed) else {
        eprintln!("error: no 3DRB case `{case}`; try speed, size, zone, control_a or speed_tracked");
        std::process::exit(2);
    };
    if let Err(e) = write_terrain_campaign(&spec, std::path::Path::new(dir), noise_m) {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
    println!("wrote the `{case}` case into {dir}");
}
