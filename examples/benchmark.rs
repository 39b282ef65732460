//! Throughput and memory of `talus run` (not a test: timings depend on the machine).
//!
//! ```text
//! cargo run --release --example benchmark                  # all cases, 1,000 rocks each
//! cargo run --release --example benchmark -- --memory      # also 100,000 rocks on ~10^6 triangles (minutes)
//! ```
//! Cases: the bench stack (`examples/bench_stack.toml`), the Tyrol crop (`examples/tyrol.toml`), the same Tyrol
//! rocks on the crop refined by bilinear interpolation to about 10^4, 10^5 and 10^6 triangles, and the calibrated
//! Tschamut model (`examples/calibrated_tschamut.toml`: the field releases, the simulations a calibration runs), and
//! the bench stack again with `terrain_edge_contacts = true` (what the opt-in terrain edges cost on a mesh).
//! Each case runs in its own process so that its peak memory (VmHWM) is its own; rocks/s is given for all cores and
//! per core.

use std::path::Path;
use std::time::Instant;
use talus::hazard::{CellTrack, HazardAccumulator, RasterFrame};
use talus::raster::Grid;
use talus::run::{setup, RunOverrides};
use talus::scenario::ScenarioFile;
use talus::terrain::Terrain;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--case") {
        let rocks: usize = args.get(i + 2).and_then(|s| s.parse().ok()).unwrap_or(1000);
        let threads: usize = args.get(i + 3).and_then(|s| s.parse().ok()).unwrap_or(0);
        run_case(&args[i + 1], rocks, threads);
        return;
    }
    let exe = std::env::current_exe().expect("own path");
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    println!(
        "{:<28} {:>10} {:>8} {:>10} {:>12} {:>14} {:>12}",
        "case", "triangles", "rocks", "threads", "rocks/s", "rocks/s/core", "peak MiB"
    );
    let mut cases: Vec<(&str, usize)> = vec![
        ("bench_stack", 1000),
        ("bench_stack_edges", 1000),
        ("tyrol", 1000),
        ("tyrol_x1", 1000),
        ("tyrol_x3", 1000),
        ("tyrol_x9", 1000),
        ("tschamut", 1000),
    ];
    if args.iter().any(|a| a == "--memory") {
        cases.push(("tyrol_x9_run", 100_000));
    }
    for (case, rocks) in cases {
        for threads in [1, cores] {
            if rocks > 1000 && threads == 1 {
                continue;
            }
            let out = std::process::Command::new(&exe)
                .args(["--case", case, &rocks.to_string(), &threads.to_string()])
                .output()
                .expect("run case");
            print!("{}", String::from_utf8_lossy(&out.stdout));
            if !out.status.success() {
                eprintln!("{case} failed: {}", String::from_utf8_lossy(&out.stderr));
            }
        }
    }
}

fn run_case(case: &str, rocks: usize, threads: usize) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    if case == "tyrol_x9_run" {
        return full_run(root, rocks, threads);
    }
    let scenario_path = root.join(match case {
        "bench_stack" | "bench_stack_edges" => "examples/bench_stack.toml",
        "tschamut" => "examples/calibrated_tschamut.toml",
        _ => "examples/tyrol.toml",
    });
    let mut sc = ScenarioFile::read(&scenario_path).and_then(|f| f.resolve(&scenario_path)).expect("scenario");
    sc.file.simulation.params.terrain_edge_contacts = case.ends_with("_edges");
    let overrides = RunOverrides { rocks: Some(rocks), seed: None, threads: Some(threads), paths: None };
    let mut s = setup(&sc, &overrides).expect("setup");
    if let Some(f) = case.strip_prefix("tyrol_x").and_then(|f| f.parse::<usize>().ok()) {
        let grid = talus::io::ascii_grid::read_grid(&root.join("meshes/tyrol/tyrol_crop.asc")).expect("dem");
        let fine = refine(&grid, f);
        let mesh = talus::terrain::build::grid_to_mesh(&fine, "tyrol");
        let t: Terrain = talus::terrain::build::assemble_terrain(
            &[(sc.terrain_files[0].clone(), mesh)],
            grid.crs.clone(),
            &sc.file.terrain,
            &sc.materials,
            &scenario_path,
        )
        .expect("terrain");
        let sources = talus::source::Sources::build(&sc.file.sources, &t, Some(rocks), "sources").expect("sources");
        s = talus::ensemble::Setup::new(&sc, t, sources, sc.file.simulation.seed).expect("setup");
    }
    let frame = RasterFrame::covering(&s.terrain, &sc.file.output, "output").expect("raster frame");
    let mut acc = HazardAccumulator::new(frame);
    let n = s.rock_count();
    let t0 = Instant::now();
    talus::parallel::map_in_order(
        n,
        threads,
        256,
        |i| {
            let mut track = CellTrack::new(&frame);
            s.run_rock(i, &mut track);
            track.into_visits()
        },
        |_, visits| acc.add(&visits),
    );
    let secs = t0.elapsed().as_secs_f64();
    let used = if threads == 0 { std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1) } else { threads };
    println!(
        "{:<28} {:>10} {:>8} {:>10} {:>12.0} {:>14.0} {:>12.0}",
        case,
        s.terrain.stats.triangles,
        n,
        used,
        n as f64 / secs,
        n as f64 / secs / used as f64,
        peak_mib()
    );
}

/// The whole `talus run` pipeline (all rasters, end points, manifest) on the Tyrol crop refined ×9 (about 10^6
/// triangles), written to `outputs/benchmark/`.
fn full_run(root: &Path, rocks: usize, threads: usize) {
    let dir = root.join("outputs/benchmark");
    std::fs::create_dir_all(&dir).expect("output folder");
    let grid = talus::io::ascii_grid::read_grid(&root.join("meshes/tyrol/tyrol_crop.asc")).expect("dem");
    let dem = dir.join("tyrol_x9.asc");
    talus::io::ascii_grid::write_grid(&dem, &refine(&grid, 9)).expect("write dem");
    let text = std::fs::read_to_string(root.join("examples/tyrol.toml"))
        .expect("scenario")
        .replace("../meshes/tyrol/tyrol_crop.asc", "tyrol_x9.asc");
    let scenario_path = dir.join("tyrol_x9.toml");
    std::fs::write(&scenario_path, text).expect("write scenario");
    let sc = ScenarioFile::read(&scenario_path).and_then(|f| f.resolve(&scenario_path)).expect("scenario");
    let overrides = RunOverrides { rocks: Some(rocks), seed: None, threads: Some(threads), paths: None };
    let summary = talus::run::run_scenario(&sc, &overrides, &dir.join("tyrol_x9_run"), &|_, _| {}).expect("run");
    let used = if threads == 0 { std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1) } else { threads };
    println!(
        "{:<28} {:>10} {:>8} {:>10} {:>12.0} {:>14.0} {:>12.0}",
        "tyrol_x9 (talus run)",
        summary.terrain.triangles,
        summary.rocks,
        used,
        summary.rocks_per_second,
        summary.rocks_per_second / used as f64,
        peak_mib()
    );
}

/// Bilinear refinement of a DEM by an integer factor (node spacing / f).
fn refine(g: &Grid, f: usize) -> Grid {
    if f == 1 {
        return g.clone();
    }
    let (nc, nr) = ((g.ncols - 1) * f + 1, (g.nrows - 1) * f + 1);
    let cell = g.cell_x_m / f as f64;
    // Node (c, r) of the fine grid sits at the coarse node position (c / f, r / f).
    let x_min = g.x_min_m + 0.5 * g.cell_x_m - 0.5 * cell;
    let y_max = g.y_max_m - 0.5 * g.cell_y_m + 0.5 * cell;
    let mut out = Grid::filled(nc, nr, x_min, y_max, cell, f32::NAN);
    for r in 0..nr {
        for c in 0..nc {
            let (fc, fr) = (c as f64 / f as f64, r as f64 / f as f64);
            let (c0, r0) = ((fc.floor() as usize).min(g.ncols - 2), (fr.floor() as usize).min(g.nrows - 2));
            let (u, v) = (fc - c0 as f64, fr - r0 as f64);
            let z = |c: usize, r: usize| g.get(c, r).map(|z| z as f64);
            if let (Some(a), Some(b), Some(d), Some(e)) = (z(c0, r0), z(c0 + 1, r0), z(c0, r0 + 1), z(c0 + 1, r0 + 1)) {
                out.values[r * nc + c] =
                    ((1.0 - u) * (1.0 - v) * a + u * (1.0 - v) * b + (1.0 - u) * v * d + u * v * e) as f32;
            }
        }
    }
    out
}

/// Peak resident memory of this process, MiB (Linux VmHWM; 0 elsewhere).
fn peak_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<f64>().ok())
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(0.0)
}
