//! Writes a synthetic profile field campaign, made with talus's own 2DLM engine, as the CSV files of a real one:
//! the `2d_zone` case of `calibration_study` (rocks of three masses released from three points on a steep
//! profile, with a soft patch, Rn 0.1, Rt 0.5, 55°, hidden at x 2–9 m, and 0.5 m of measurement noise), seed 1.
//! For trying `talus calibrate --model 2dlm` and `talus profile` on files; `examples/profile_campaign/` was written
//! by it.
//!
//! Run: cargo run --release --example write_profile_campaign -- DIR
use talus::calibrate::synthetic::{case_2d, write_profile_campaign};

fn main() {
    let Some(dir) = std::env::args().nth(1) else {
        eprintln!("usage: write_profile_campaign DIR");
        std::process::exit(2);
    };
    let spec = case_2d("zone", 1).expect("the zone case");
    if let Err(e) = write_profile_campaign(&spec, std::path::Path::new(&dir)) {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
    println!("wrote {dir}/release_points.csv, observed_deposition.csv, block_metadata.csv and profile.csv");
}
