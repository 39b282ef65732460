//! Writes a synthetic profile field campaign, made with talus's own 2DLM engine, as the CSV files of a real one:
//! by default the `2d_zone` case of `calibration_study` (rocks of three masses released from three points on a
//! steep profile, with a soft patch, Rn 0.1, Rt 0.5, 55°, hidden at x 2–9 m, and 0.5 m of measurement noise), seed
//! 1; or another 2DLM case of `case_2d` (`speed_tracked` adds each run's tracked path, every height plus Gaussian
//! noise of sd TRACK_POINT_NOISE_M, default 0: exact tracks). For trying `talus calibrate --model 2dlm` and `talus
//! profile` on files; `examples/profile_campaign/` (zone) and `examples/profile_campaign_tracked/` (speed_tracked)
//! were written by it.
//!
//! Run: cargo run --release --example write_profile_campaign -- DIR [CASE [TRACK_POINT_NOISE_M]]
use talus::calibrate::synthetic::{case_2d, track_noise_arg, write_profile_campaign};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(dir), case) = (args.first(), args.get(1).map_or("zone", String::as_str)) else {
        eprintln!("usage: write_profile_campaign DIR [CASE [TRACK_POINT_NOISE_M]]");
        std::process::exit(2);
    };
    let noise_m = track_noise_arg(args.get(2).map(String::as_str)).unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2);
    });
    let Some(spec) = case_2d(case, 1) else {
        eprintln!("error: no 2DLM case `{case}`; try zone, speed, size, speed_tracked or control_a");
        std::process::exit(2);
    };
    if let Err(e) = write_profile_campaign(&spec, std::path::Path::new(dir), noise_m) {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
    println!("wrote the `{case}` case into {dir}");
}
