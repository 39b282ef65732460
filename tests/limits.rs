//! Limits and output hygiene: sizes that would exhaust memory or never finish (raster cells, section samples, mesh
//! triangles, rocks, threads, path samples) and output paths that would leave a stray file or overwrite an input
//! are refused with exit code 2 and a message naming the flag or key, before any heavy work and without writing.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// The repository's file `rel`.
fn shipped(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Runs `talus args` in `dir`.
fn talus(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_talus")).args(args).current_dir(dir).output().unwrap()
}

/// Runs `talus args` in `dir`, expecting a quick refusal: exit code 2, every `needles` in the message, a fix
/// suggested, and `dir` holding only what it held before (no output, no temporary file).
fn refused(args: &[&str], dir: &Path, needles: &[&str]) -> String {
    let before = listing(dir);
    let t0 = Instant::now();
    let o = talus(args, dir);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(t0.elapsed() < Duration::from_secs(5), "{args:?} took {:?} to be refused", t0.elapsed());
    for n in needles {
        assert!(err.contains(n), "{args:?}: the message lacks '{n}': {err}");
    }
    assert!(err.contains("how to fix"), "{args:?}: no fix suggested: {err}");
    assert_eq!(listing(dir), before, "{args:?} left files behind");
    err
}

/// The names in `dir`, hidden ones included, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// `examples/bench_stack.toml` in `dir` (its mesh by absolute path) with `from` replaced by `to`.
fn bench_scenario(dir: &Path, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(shipped("examples/bench_stack.toml")).unwrap();
    let mesh = shipped("meshes/bench_stack/bench_stack.obj");
    assert!(text.contains(from), "{from}");
    let text = text
        .replace("../meshes/bench_stack/bench_stack.obj", &mesh.display().to_string().replace('\\', "/"))
        .replace(from, to);
    let p = dir.join("scenario.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// The bench stack terrain copied into `dir`.
fn stack_obj(dir: &Path) -> PathBuf {
    let p = dir.join("stack.obj");
    std::fs::copy(shipped("meshes/bench_stack/bench_stack.obj"), &p).unwrap();
    p
}

#[test]
fn a_raster_cell_size_over_the_cell_limit_is_refused_with_the_smallest_cell_allowed() {
    for cell in ["1e-12", "0.0001"] {
        let dir = tempfile::tempdir().unwrap();
        bench_scenario(dir.path(), "cell_size_m = 1.0", &format!("cell_size_m = {cell}"));
        let err = refused(
            &["run", "scenario.toml", "--out", "out"],
            dir.path(),
            &["output.cell_size_m", "174.3 m × 100.0 m", "raster cells", "100000000", "at least 0.0133 m"],
        );
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn a_section_of_more_than_a_million_samples_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    stack_obj(dir.path());
    for (line, spacing) in [("0,30,1e308,30", "1"), ("0,30,160,30", "1e-9")] {
        let args = ["section", "stack.obj", "--line", line, "--spacing-m", spacing, "--out", "s.csv"];
        refused(&args, dir.path(), &["spacing_m", "more than a million stations", "--spacing-m"]);
    }
}

#[test]
fn a_bench_mesh_over_the_triangle_limit_is_refused_before_it_is_built() {
    let dir = tempfile::tempdir().unwrap();
    for (flag, value) in [("--max-edge-m", "0.001"), ("--lateral-width-m", "9000"), ("--benches", "100000000")] {
        let named = if flag == "--lateral-width-m" { "--max-edge-m" } else { flag };
        let mut args = vec!["mesh", "bench", flag, value, "--out", "m.obj"];
        if flag == "--lateral-width-m" {
            args.extend(["--max-edge-m", "0.2"]);
        }
        refused(&args, dir.path(), &[named, "triangles, more than the limit of 10000000"]);
    }
    // A length past any pit is named itself.
    refused(
        &["mesh", "bench", "--lateral-width-m", "1e12", "--out", "m.obj"],
        dir.path(),
        &["--lateral-width-m", "up to 10000"],
    );
}

/// A negative value after a space is the flag's value, refused by talus's own check (clap took it for a flag:
/// "unexpected argument '-2'").
#[test]
fn a_negative_value_after_a_flag_gets_talus_own_message() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["mesh", "bench", "--bench-height-m", "-20", "--out", "m.obj"];
    refused(&args, dir.path(), &["--bench-height-m", "must be a positive number", "-20"]);
}

#[test]
fn a_bench_study_with_a_mesh_over_the_triangle_limit_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(shipped("examples/benches_quick.toml")).unwrap();
    assert!(text.contains("max_edge_m = 2.5"));
    std::fs::write(dir.path().join("study.toml"), text.replace("max_edge_m = 2.5", "max_edge_m = 0.001")).unwrap();
    refused(
        &["benches", "--config", "study.toml", "--out", "out"],
        dir.path(),
        &["geometry.max_edge_m", "more than the limit of 10000000"],
    );
}

#[test]
fn more_rocks_than_a_run_can_hold_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    bench_scenario(dir.path(), "seed = 1", "seed = 1");
    refused(
        &["run", "scenario.toml", "--rocks", "100000000000", "--out", "out"],
        dir.path(),
        &["sources", "100000000000 rocks", "limit of 10000000", "--rocks"],
    );
    // The same from the sources' counts.
    bench_scenario(dir.path(), "count = 1000", "count = 20000000");
    refused(&["run", "scenario.toml", "--out", "out"], dir.path(), &["20000000 rocks", "limit of 10000000"]);
    // A profile's rocks, a bench study's runs and a calibration's repeats have limits too: a fuzzer's huge counts
    // ran for ever or aborted on a failed allocation (exit 134) before these.
    let profile = shipped("examples/profile_bench.toml");
    let profile = profile.to_str().unwrap();
    refused(
        &["profile", profile, "--rocks", "4294967297", "--out", "out"],
        dir.path(),
        &["rocks", "limit of 10000000"],
    );
    refused(&["benches", "--runs-3drb", "4294967297", "--out", "out"], dir.path(), &["rigid3d.runs", "limit"]);
    refused(&["benches", "--runs-2dlm", "4294967297", "--out", "out"], dir.path(), &["lumped2d.runs", "limit"]);
    // A bench height no pit has is named as such (it overflowed the mesh count, blamed on max_edge_m).
    let tall = ["benches", "--bench-height-m", "1e308", "--runs-3drb", "0", "--out", "out"];
    refused(&tall, dir.path(), &["study: bench_height_m", "up to 10000"]);
    // Named by the study's key, not the generated geometry's (it said geometry.bench_width_m).
    let wide = ["benches", "--bench-widths-m", "8,20000", "--runs-3drb", "0", "--out", "out"];
    refused(&wide, dir.path(), &["study: bench_widths_m[1]", "20000 is not 0 to 10,000 metres"]);
    let campaign = shipped("examples/profile_campaign");
    let profile_csv = campaign.join("profile.csv");
    let (campaign, profile_csv) = (campaign.to_str().unwrap(), profile_csv.to_str().unwrap());
    let calibrate = ["calibrate", campaign, "--terrain", profile_csv, "--model", "2dlm", "--out", "out"];
    refused(&[&calibrate[..], &["--repeats", "10000000"]].concat(), dir.path(), &["repeats", "limit of 10000"]);
    // An --out that is a file: said with a fix, as by the other commands (it said only "File exists").
    std::fs::write(dir.path().join("out"), "").unwrap();
    refused(&calibrate, dir.path(), &["--out", "is a file"]);
}

#[test]
fn more_threads_than_the_limit_are_refused_and_the_limit_is_in_the_help() {
    let dir = tempfile::tempdir().unwrap();
    bench_scenario(dir.path(), "seed = 1", "seed = 1");
    refused(
        &["run", "scenario.toml", "--threads", "100000", "--out", "out"],
        dir.path(),
        &["--threads", "100000 threads", "limit of 1024"],
    );
    bench_scenario(dir.path(), "seed = 1", "seed = 1\nthreads = 100000");
    refused(&["run", "scenario.toml", "--out", "out"], dir.path(), &["simulation.threads", "limit of 1024"]);
    let help = String::from_utf8_lossy(&talus(&["run", "--help"], dir.path()).stdout).into_owned();
    assert!(help.contains("1 to 1024"), "{help}");
}

#[test]
fn a_sample_spacing_below_a_centimetre_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    bench_scenario(dir.path(), "seed = 1", "seed = 1\nsample_spacing_m = 1e-12");
    refused(
        &["run", "scenario.toml", "--paths", "2", "--out", "out"],
        dir.path(),
        &["simulation.sample_spacing_m", "smallest spacing, 0.01 m"],
    );
}

#[test]
fn out_as_a_folder_is_refused_and_no_temporary_file_is_left() {
    let dir = tempfile::tempdir().unwrap();
    stack_obj(dir.path());
    std::fs::create_dir(dir.path().join("folder")).unwrap();
    let section = ["section", "stack.obj", "--line", "0,30,160,30", "--out", "folder"];
    refused(&section, dir.path(), &["--out", "must be a file path, not a folder"]);
    refused(&["mesh", "bench", "--out", "folder"], dir.path(), &["--out", "must be a file path, not a folder"]);
    assert!(std::fs::read_dir(dir.path().join("folder")).unwrap().next().is_none());
}

/// A folder named like a file a run writes is refused before the rocks run (the run wrote every other file first);
/// the temporary file a killed run left is removed by the next run into its folder.
#[test]
fn a_folder_in_the_way_of_a_run_output_is_refused_and_a_killed_runs_temporary_file_removed() {
    let dir = tempfile::tempdir().unwrap();
    bench_scenario(dir.path(), "[rocks]", "[rocks]");
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("summary.json")).unwrap();
    let run = ["run", "scenario.toml", "--rocks", "20", "--out", "out"];
    refused(&run, dir.path(), &["--out", "summary.json is a folder", "rename"]);
    assert_eq!(listing(&out), vec!["summary.json".to_string()]);
    std::fs::remove_dir(out.join("summary.json")).unwrap();
    std::fs::write(out.join(".endpoints.csv.tmp"), "rock_id,source_id\n0,a\n").unwrap();
    let o = talus(&run, dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let names = listing(&out);
    assert!(names.contains(&"summary.json".to_string()) && names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
}

/// A barrier study whose source lies off the terrain leaves no output folder behind (it left an empty one).
#[test]
fn a_barrier_study_refused_at_its_sources_leaves_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(shipped("examples/bench_stack_barrier.toml")).unwrap();
    let mesh = shipped("meshes/bench_stack/bench_stack.obj").display().to_string().replace('\\', "/");
    let polygon = "[[10.0, 35.0], [21.6, 35.0], [21.6, 65.0], [10.0, 65.0]]";
    assert!(text.contains(polygon));
    let off = "[[1000.0, 35.0], [1021.6, 35.0], [1021.6, 65.0], [1000.0, 65.0]]";
    let text = text.replace("../meshes/bench_stack/bench_stack.obj", &mesh).replace(polygon, off);
    std::fs::write(dir.path().join("scenario.toml"), text).unwrap();
    refused(
        &["barrier", "scenario.toml", "--out", "out"],
        dir.path(),
        &["sources[0]", "`within` overlaps the terrain"],
    );
}

#[test]
fn a_failed_rename_removes_the_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("folder");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), "x").unwrap();
    let e = talus::io::write_bytes_atomic(&target, b"complete").unwrap_err();
    assert!(e.to_string().contains("folder"), "{e}");
    assert_eq!(listing(dir.path()), vec!["folder".to_string()], "the temporary file is left");
}

#[test]
fn out_naming_the_input_terrain_is_refused_and_the_terrain_kept() {
    let dir = tempfile::tempdir().unwrap();
    let obj = stack_obj(dir.path());
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    let before = std::fs::read(&obj).unwrap();
    for out in ["stack.obj", "sub/../stack.obj", obj.to_str().unwrap()] {
        let args = ["section", "stack.obj", "--line", "0,30,160,30", "--out", out];
        refused(&args, dir.path(), &["--out", "input file", "would be overwritten"]);
    }
    assert_eq!(std::fs::read(&obj).unwrap(), before);
}

#[test]
fn an_output_file_extension_that_does_not_match_what_is_written_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    refused(&["mesh", "bench", "--out", "x.stl"], dir.path(), &["--out", "x.stl", ".obj"]);
    refused(&["mesh", "bench", "--2d", "--out", "x.obj"], dir.path(), &["--out", "x.obj", ".csv"]);
    refused(&["mesh", "bench", "--out", "x"], dir.path(), &["--out", ".obj"]);
    stack_obj(dir.path());
    refused(&["section", "stack.obj", "--line", "0,30,160,30", "--out", "s.txt"], dir.path(), &["--out", ".csv"]);
    // The matching extensions are written, in any case.
    for args in [vec!["mesh", "bench", "--out", "x.OBJ"], vec!["mesh", "bench", "--2d", "--out", "x.csv"]] {
        let o = talus(&args, dir.path());
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    }
}

#[test]
fn section_material_names_that_would_break_the_csv_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    stack_obj(dir.path());
    for name in ["a,b", "a\"b", "a\nb", " "] {
        let args = ["section", "stack.obj", "--line", "0,30,160,30", "--material", name, "--out", "s.csv"];
        refused(&args, dir.path(), &["section.material"]);
    }
    let args = ["section", "stack.obj", "--line", "0,30,160,30", "--material", "rock_1", "--out", "s.csv"];
    let o = talus(&args, dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.path().join("s.csv")).unwrap();
    assert!(csv.lines().skip(1).all(|l| l.split(',').count() == 3 && l.ends_with(",rock_1")), "{csv}");
}

/// Values that made a run never finish (a step of 10⁻¹² s, a release at 10³⁰ m/s, 4·10⁹ solver sweeps a step), or
/// crawl (a contact travel of 10⁻⁹ m: a thousand sub-steps a step), or
/// end in nonsense (a 10⁻³⁰⁰ kg block left the terrain with NaN end points; a 1 g block gained kilojoules at
/// impacts; a 10⁵ m cube weighed 10¹⁸ kg past the mass limit; a spin of 10¹² rad/s) are refused by name.
#[test]
fn engine_settings_and_releases_that_never_finish_or_end_in_nonsense_are_refused() {
    let cases: [(&str, &str, &[&str]); 12] = [
        ("seed = 1", "seed = 1\ndt_s = 1e-12", &["simulation.dt_s", "below the smallest step, 0.0001 s"]),
        (
            "seed = 1",
            "seed = 1\nmax_contact_travel_m = 1e-9",
            &["simulation.max_contact_travel_m", "below the shortest travel, 0.01 m"],
        ),
        ("seed = 1", "seed = 1\nmax_time_s = 1e9", &["simulation.max_time_s", "longer than any rockfall"]),
        ("seed = 1", "seed = 1\nsolver_iterations = 4000000000", &["simulation.solver_iterations", "1 to 10000"]),
        ("height_m = 0.1", "height_m = 1e30", &["sources[0].height_m", "0 to 1000 m"]),
        ("height_m = 0.1", "height_m = 0.1\nspeed_mps = [1e30, 1e30]", &["sources[0].speed_mps", "1.00e30", "100 m/s"]),
        ("height_m = 0.1", "height_m = 0.1\nvelocity_mps = [0, 0, -1e3]", &["sources[0].velocity_mps", "100 m/s"]),
        ("height_m = 0.1", "height_m = 0.1\nspin_radps = [0, 1e12]", &["sources[0].spin_radps", "200 rad/s"]),
        ("mass_kg = [100.0, 10000.0]", "mass_kg = 1e-300", &["rocks.mass_kg", "1.00e-300 kg", "smallest block"]),
        ("mass_kg = [100.0, 10000.0]", "mass_kg = [0.001, 10.0]", &["rocks.mass_kg", "0.001 kg", "1 kg"]),
        ("mass_kg = [100.0, 10000.0]", "dimensions_m = [1e5, 1e5, 1e5]", &["rocks.dimensions_m", "2.650e18 kg"]),
        ("mass_kg = [100.0, 10000.0]", "dimensions_m = [1.0, 1.0, 0.01]", &["rocks.dimensions_m", "0.05 to 100 m"]),
    ];
    for (from, to, needles) in cases {
        let dir = tempfile::tempdir().unwrap();
        bench_scenario(dir.path(), from, to);
        refused(&["run", "scenario.toml", "--rocks", "5", "--out", "out"], dir.path(), needles);
    }
}

#[test]
fn a_profile_release_far_past_a_rockfall_is_refused() {
    let text = std::fs::read_to_string(shipped("examples/profile_bench.toml")).unwrap();
    for (from, to, needles) in [
        ("height_m = 0.5", "height_m = 1e30", ["release.height_m", "[0, 1000]"]),
        ("vx_mps = [1.0, 2.0]", "vx_mps = 1e30", ["release.vx_mps", "[-100, 100]"]),
    ] {
        let dir = tempfile::tempdir().unwrap();
        assert!(text.contains(from), "{from}");
        std::fs::write(dir.path().join("p.toml"), text.replace(from, to)).unwrap();
        refused(&["profile", "p.toml", "--out", "out"], dir.path(), &needles);
    }
}

/// A stretch of 10⁻⁹ m asked for 10¹¹ stretches and aborted the run out of memory (so would a line 10⁶ m long at
/// 0.5 m); an empty `within` scattered over the whole terrain.
#[test]
fn a_stretch_below_half_a_metre_and_an_empty_scatter_polygon_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let collector = "[[collectors]]\nline = [[40.0, 10.0], [40.0, 90.0]]\nsegment_m = 1e-9\n\n[simulation]";
    bench_scenario(dir.path(), "[simulation]", collector);
    refused(&["run", "scenario.toml", "--out", "out"], dir.path(), &["collectors[0].segment_m", "at least 0.5 m"]);
    let collector = "[[collectors]]\nline = [[40.0, 10.0], [40.0, 1e6]]\nsegment_m = 5\n\n[simulation]";
    bench_scenario(dir.path(), "[simulation]", collector);
    refused(&["run", "scenario.toml", "--out", "out"], dir.path(), &["collectors[0].segment_m", "199998 stretches"]);
    let design = "[barrier_design]\nsegment_m = 1e-9\n\n[simulation]";
    bench_scenario(dir.path(), "[simulation]", design);
    refused(&["barrier", "scenario.toml", "--out", "out"], dir.path(), &["barrier_design.segment_m", "0.5 m"]);
    bench_scenario(dir.path(), "within = [[10.0, 35.0], [21.6, 35.0], [21.6, 65.0], [10.0, 65.0]]", "within = []");
    refused(&["run", "scenario.toml", "--out", "out"], dir.path(), &["sources[0].within", "has 0 vertices"]);
}

/// A 12,000 × 12,000 DEM aborted out of memory while it was triangulated; two terrain files 300 km apart (one in
/// another CRS) asked for 10¹⁰ index bins.
#[test]
fn a_dem_too_large_to_triangulate_and_terrain_triangles_far_apart_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = |files: &str| {
        let text = format!(
            "[terrain]\nfiles = [{files}]\n[materials.default]\npreset = \"face_all\"\n[[sources]]\ntype = \"point\"\n\
             points = [[20.0, 50.0]]\ncount = 5\n[rocks]\nshapes = [\"cube\"]\nmass_kg = 100.0\n"
        );
        std::fs::write(dir.path().join("scenario.toml"), text).unwrap();
    };
    let n = 4001;
    let mut dem = talus::raster::Grid::filled(n, n, 0.0, n as f64, 1.0, 0.0);
    for (k, z) in dem.values.iter_mut().enumerate() {
        *z = 0.5 * (k % n) as f32;
    }
    talus::io::geotiff::write_grid(&dir.path().join("big.tif"), &dem).unwrap();
    scenario("\"big.tif\"");
    refused(
        &["run", "scenario.toml", "--out", "out"],
        dir.path(),
        &["big.tif", "4001 × 4001 = 16008001 cells", "16000000", "coarser cell"],
    );
    std::fs::remove_file(dir.path().join("big.tif")).unwrap();
    let mesh = shipped("meshes/bench_stack/bench_stack.obj");
    // The stack's mesh with each vertex moved by `f`.
    let moved = |f: fn([f64; 3]) -> [f64; 3]| -> String {
        let text = std::fs::read_to_string(&mesh).unwrap();
        text.lines()
            .map(|l| match l.strip_prefix("v ") {
                Some(v) => {
                    let c: Vec<f64> = v.split_whitespace().map(|x| x.parse().unwrap()).collect();
                    let [x, y, z] = f([c[0], c[1], c[2]]);
                    format!("v {x} {y} {z}\n")
                }
                None => format!("{l}\n"),
            })
            .collect()
    };
    // The stack's mesh and a copy of it moved 300 km east and 300 km north.
    std::fs::write(dir.path().join("far.obj"), moved(|[x, y, z]| [x + 3e5, y + 3e5, z])).unwrap();
    scenario(&format!("\"{}\", \"far.obj\"", mesh.display().to_string().replace('\\', "/")));
    refused(&["run", "scenario.toml", "--out", "out"], dir.path(), &["terrain.files", "lie far apart", "same CRS"]);
    // The stack's mesh exported y-up and read z-up: on its side, its triangles seen edge-on; the error names `up`.
    let y_up = moved(|[x, y, z]| [x, z, -y]);
    std::fs::write(dir.path().join("y_up.obj"), y_up).unwrap();
    scenario("\"y_up.obj\"");
    refused(
        &["run", "scenario.toml", "--out", "out"],
        dir.path(),
        &["terrain.files", "lie far apart", "`up` in [terrain]"],
    );
    // One file with a stray triangle 300 km away: `talus section` asked for 24 GB and more.
    let stray = std::fs::read_to_string(&mesh).unwrap() + "v 3e5 3e5 0\nv 300010 3e5 0\nv 3e5 300010 0\nf -3 -2 -1\n";
    std::fs::write(dir.path().join("stray.obj"), stray).unwrap();
    let args = ["section", "stray.obj", "--line", "0,30,160,30", "--out", "s.csv"];
    refused(&args, dir.path(), &["section.terrain", "lie far apart", "3.000e5 × 3.000e5 m"]);
}
