//! Throughput of the 2D lumped-mass engine on the seed paper's bench design study: 63 configurations (face angles
//! 45°, 60°, 75° × bench widths 4–10 m × rocks of 100, 1,000 and 10,000 kg) × 300 rocks = 18,900 rocks on 20 m
//! bench stacks, Table 1 "all data" parameters, roughness 2°.
//!
//! Run with `cargo run --release --example profile_speed`. Prints rocks/s and the share of rocks caught on the
//! first bench per configuration, then the throughput of a full `run_profile` (envelopes, collectors and CSV
//! outputs) of `examples/profile_bench.toml` with 18,900 rocks.

use std::time::Instant;
use talus::lumped2d::{run_profile, simulate_bench, Material2d, Options2d, ProfileScenario, Release2d};
use talus::terrain::BenchGeometry;

fn main() -> Result<(), talus::Error> {
    let face = Material2d::face_all().with_roughness_sd_deg(2.0);
    let floor = Material2d::floor_all().with_roughness_sd_deg(2.0);
    let options = Options2d::default();
    let angles = [45.0, 60.0, 75.0];
    let widths = [4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0];
    let masses = [100.0, 1000.0, 10000.0];
    let per_config = 300;
    let mut table = Vec::new();
    let t0 = Instant::now();
    let mut rocks = 0;
    for &angle in &angles {
        for &width in &widths {
            for &mass in &masses {
                let g = BenchGeometry { face_angle_deg: angle, bench_width_m: width, ..Default::default() };
                // Rocks leave the top crest with 1–2 m/s, 0.5 m above the top of the face.
                let release = Release2d::point(0.0, 0.5, mass)
                    .with_x_m(g.crest_floor_m, g.crest_floor_m + 0.5)
                    .with_vx_mps(1.0, 2.0);
                let run = simulate_bench(&g, &face, &floor, &release, &options, per_config, 2016)?;
                rocks += run.rocks.len();
                table.push((angle, width, mass, run.capture.fraction(1)));
            }
        }
    }
    let secs = t0.elapsed().as_secs_f64();
    println!("{rocks} rocks in {secs:.3} s: {:.0} rocks/s ({} threads)", rocks as f64 / secs, threads());
    println!("first-bench capture (%), rows: face angle and mass; columns: bench width 4..10 m");
    for &angle in &angles {
        for &mass in &masses {
            let row: Vec<String> =
                table.iter().filter(|r| r.0 == angle && r.2 == mass).map(|r| format!("{:5.1}", 100.0 * r.3)).collect();
            println!("{angle:>4}° {mass:>6} kg: {}", row.join(" "));
        }
    }

    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/profile_bench.toml");
    let mut scenario = ProfileScenario::load(&path)?;
    scenario.rocks = Some(rocks);
    let out = std::env::temp_dir().join(format!("talus-profile-speed-{}", std::process::id()));
    let summary = run_profile(&scenario, &out)?;
    println!(
        "run_profile with outputs ({} stations, {} collectors): {} rocks in {:.3} s: {:.0} rocks/s",
        (summary.profile.x_range_m[1] - summary.profile.x_range_m[0]).floor() as usize + 1,
        summary.collectors_x_m.len(),
        summary.rocks,
        summary.wall_time_s,
        summary.rocks_per_second
    );
    std::fs::remove_dir_all(&out).map_err(|e| talus::Error::io(&out, e))?;
    Ok(())
}

fn threads() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}
