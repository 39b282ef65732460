//! `talus run` end to end in temporary folders: outputs, determinism across thread counts, GeoTIFFs read back (and
//! checked with `gdalinfo` where it is installed), and bad input answered with exit code 2 and no output.

use std::path::{Path, PathBuf};
use std::process::Command;

fn talus() -> Command {
    Command::new(env!("CARGO_BIN_EXE_talus"))
}

/// A 40 m × 80 m DEM (2 m cells): a 35° slope falling toward +x onto a flat floor, with one nodata cell.
fn write_dem(dir: &Path) -> PathBuf {
    let (nc, nr, cell) = (40usize, 20usize, 2.0);
    let mut s =
        format!("ncols {nc}\nnrows {nr}\nxllcorner 500000\nyllcorner 5000000\ncellsize {cell}\nNODATA_value -9999\n");
    for r in 0..nr {
        let row: Vec<String> = (0..nc)
            .map(|c| {
                if r == 0 && c == nc - 1 {
                    return "-9999".to_string();
                }
                let x = (c as f64 + 0.5) * cell;
                let z = if x < 40.0 { (40.0 - x) * 35f64.to_radians().tan() } else { 0.0 };
                format!("{:.3}", 100.0 + z)
            })
            .collect();
        s.push_str(&row.join(" "));
        s.push('\n');
    }
    let p = dir.join("slope.asc");
    std::fs::write(&p, s).unwrap();
    p
}

fn scenario(dir: &Path, extra: &str, cr_mean: f64, mass: &str) -> PathBuf {
    write_dem(dir);
    let text = format!(
        r#"
[terrain]
files = ["slope.asc"]
crs_epsg = 2056

[materials.default]
cr_mean = {cr_mean}
cr_sd = 0.05
static_friction_deg = 40.0
dynamic_friction_deg = 32.0

[[sources]]
type = "polyline"
points = [[500004.0, 5000010.0], [500004.0, 5000030.0]]
count = 24
height_m = 0.2

[rocks]
shapes = ["cube", "flat_box", "smartie", "block.xyz"]
mass_kg = {mass}

[simulation]
seed = 3

[output]
cell_size_m = 4.0
{extra}
"#
    );
    let p = dir.join("scenario.toml");
    std::fs::write(&p, text).unwrap();
    // An irregular block as a point file, for hull rocks.
    std::fs::write(
        dir.join("block.xyz"),
        "# x y z\n0 0 0\n1.2 0.1 0\n0.2 0.9 0.1\n0.1 0.2 0.7\n1.0 0.8 0.6\n0.6 0.4 -0.3\n",
    )
    .unwrap();
    p
}

#[test]
fn run_writes_every_output_and_is_identical_for_1_and_2_threads() {
    let dir = tempfile::tempdir().unwrap();
    let sc = scenario(dir.path(), "", 0.3, "[50.0, 500.0]");
    let mut outs = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("out{threads}"));
        let o = talus()
            .args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap(), "--threads", threads, "--paths", "3"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        outs.push(out);
    }
    let names = [
        "endpoints.csv",
        "endpoint_density.tif",
        "reach_probability.tif",
        "kinetic_energy_p95_kj.tif",
        "kinetic_energy_max_kj.tif",
        "bounce_height_p95_m.tif",
        "bounce_height_max_m.tif",
        "paths.csv",
        "paths.vtk",
    ];
    for n in names {
        let a = std::fs::read(outs[0].join(n)).unwrap_or_else(|_| panic!("{n} missing"));
        let b = std::fs::read(outs[1].join(n)).unwrap();
        assert!(a == b, "{n} differs between 1 and 2 threads");
    }
    // No temporary file is left behind.
    for e in std::fs::read_dir(&outs[0]).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.ends_with(".tmp"), "{name} left behind");
    }
    let csv = std::fs::read_to_string(outs[0].join("endpoints.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "rock_id,source_id,shape,mass_kg,release_x_m,release_y_m,release_z_m,end_x_m,end_y_m,end_z_m,stop_reason,runout_m,travel_time_s,max_kinetic_j,max_bounce_m"
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 24);
    for shape in ["cube", "flat_box", "smartie", "block"] {
        assert!(rows.iter().any(|r| r.split(',').nth(2) == Some(shape)), "no {shape} rock");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(outs[0].join("summary.json")).unwrap()).unwrap();
    for key in
        ["talus_version", "seed", "input_sha256", "parameters", "stop_reasons", "wall_time_s", "rocks_per_second"]
    {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    assert_eq!(summary["rocks"], 24);
    assert_eq!(summary["input_sha256"].as_object().unwrap().len(), 3, "scenario, DEM and hull file");
}

#[test]
fn rasters_read_back_in_the_terrain_frame_with_crs_and_nodata() {
    let dir = tempfile::tempdir().unwrap();
    let sc = scenario(dir.path(), "", 0.3, "300.0");
    let out = dir.path().join("out");
    let o = talus().args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let reach = talus::io::geotiff::read_grid(&out.join("reach_probability.tif")).unwrap();
    assert_eq!(reach.crs.epsg, Some(2056));
    assert_eq!((reach.cell_x_m, reach.cell_y_m), (4.0, 4.0));
    // The DEM's nodes are cell centres from 500001 to 500079 m: the raster frame snaps outward to 4 m.
    assert_eq!(reach.x_min_m, 500000.0);
    assert_eq!(reach.y_max_m, 5000040.0);
    assert_eq!((reach.ncols, reach.nrows), (20, 10));
    let (lo, hi) = reach.min_max().unwrap();
    assert!(lo == 0.0 && hi <= 1.0 && hi > 0.2, "{lo} {hi}");
    let density = talus::io::geotiff::read_grid(&out.join("endpoint_density.tif")).unwrap();
    let total: f64 = density.values.iter().filter(|v| !v.is_nan()).map(|&v| v as f64).sum();
    let stopped =
        std::fs::read_to_string(out.join("endpoints.csv")).unwrap().lines().filter(|l| l.contains(",stopped,")).count();
    assert!(
        (total - stopped as f64 / 24.0).abs() < 0.1,
        "density sums to {total}, stopped fraction {}",
        stopped as f64 / 24.0
    );
    let energy = talus::io::geotiff::read_grid(&out.join("kinetic_energy_max_kj.tif")).unwrap();
    assert!(energy.values.iter().any(|v| v.is_nan()), "cells no rock reached are nodata");
    if Command::new("gdalinfo").arg("--version").output().is_ok_and(|o| o.status.success()) {
        let info = Command::new("gdalinfo").arg(out.join("reach_probability.tif")).output().unwrap();
        let text = String::from_utf8_lossy(&info.stdout);
        assert!(text.contains("ID[\"EPSG\",2056]"), "{text}");
        assert!(text.contains("Origin = (500000.000000000000000,5000040.000000000000000)"), "{text}");
        assert!(text.contains("Pixel Size = (4.000000000000000,-4.000000000000000)"), "{text}");
        assert!(text.contains("NoData Value=-9999"), "{text}");
    } else {
        eprintln!("note: gdalinfo not installed; GDAL check skipped");
    }
}

/// Runs `talus run` on a scenario expected to fail: exit code 2, every `needles` in stderr, nothing written.
fn fails_cleanly(dir: &Path, scenario: &Path, needles: &[&str]) {
    let out = dir.join("out_bad");
    let o = talus().args(["run", scenario.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks '{n}': {err}");
    }
    assert!(err.contains("how to fix"), "no fix suggested: {err}");
    assert!(!out.exists() || std::fs::read_dir(&out).unwrap().next().is_none(), "output written despite the error");
}

fn with_terrain(dir: &Path, file: &str, body: &[u8]) -> PathBuf {
    let sc = scenario(dir, "", 0.3, "300.0");
    std::fs::write(dir.join(file), body).unwrap();
    let text =
        std::fs::read_to_string(&sc).unwrap().replace("files = [\"slope.asc\"]", &format!("files = [\"{file}\"]"));
    std::fs::write(&sc, text).unwrap();
    sc
}

/// The scenario with `key = value` under [terrain].
fn with_terrain_key(dir: &Path, key: &str, value: &str) -> PathBuf {
    let sc = scenario(dir, "", 0.3, "300.0");
    let text =
        std::fs::read_to_string(&sc).unwrap().replace("crs_epsg = 2056", &format!("crs_epsg = 2056\n{key} = {value}"));
    std::fs::write(&sc, text).unwrap();
    sc
}

/// The scenario with `clip` under [terrain].
fn clipped(dir: &Path, clip: &str) -> PathBuf {
    with_terrain_key(dir, "clip", clip)
}

/// Runs `sc` and returns the rows of its `endpoints.csv` and its stderr.
fn endpoint_rows(sc: &Path, out: &Path) -> (Vec<Vec<String>>, String) {
    let o = talus().args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    let csv = std::fs::read_to_string(out.join("endpoints.csv")).unwrap();
    (csv.lines().skip(1).map(|l| l.split(',').map(str::to_string).collect()).collect(), err)
}

#[test]
fn a_clipped_terrain_ends_where_the_clip_polygon_does() {
    // Only the slope (x < 500030 m) is kept: rocks that reach the floor leave the terrain at the clip's edge, and
    // are recorded where they crossed it (a flight is cut at the crossing, a contact step moves a few cm). The
    // triangles the polygon's edge crosses are split along it: 22 rocks end at x = 500030.000–500030.024 m (measured),
    // the other 2 leave the 40 m wide slope sideways. Before the split the clip kept the triangles whose centre was
    // inside, so on these 2 m cells the edge zigzagged between x = 500029 and 500031 m; before flights were cut, a
    // rock could end a flight step (up to 0.25 s) past it: one ended at 500032.2 m. The unclipped floor runs on 50 m.
    let dir = tempfile::tempdir().unwrap();
    let sc = clipped(
        dir.path(),
        "[[500000.0, 5000000.0], [500030.0, 5000000.0], [500030.0, 5000040.0], [500000.0, 5000040.0]]",
    );
    let out = dir.path().join("out");
    let (rows, err) = endpoint_rows(&sc, &out);
    assert_eq!(rows.len(), 24);
    // With nothing past the clip's edge, no rock counts as leaving over a gap.
    assert!(!err.contains("over a gap"), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["left_over_gaps"], 0);
    for r in &rows {
        let x: f64 = r[7].parse().unwrap();
        assert!(x < 500030.05, "rock ends at x = {x}, past the clip's edge: {r:?}");
        assert_eq!(r[10], "left_terrain", "{r:?}");
    }
    let at_edge = rows.iter().filter(|r| r[7].parse::<f64>().unwrap() > 500029.95).count();
    assert!(at_edge >= 20, "{at_edge} of 24 rocks left at the clip's edge");
}

#[test]
fn rocks_leaving_over_a_gap_in_the_terrain_are_counted_and_warned_about() {
    // A strip of nodata across the floor (the column of nodes at x = 45 m, so no triangle between x = 43 and 47 m):
    // rocks reaching it leave the terrain with ground ahead of them, which the run counts and warns about (the clip
    // test checks that a clip's edge, with nothing ahead, counts none).
    let dir = tempfile::tempdir().unwrap();
    let sc = scenario(dir.path(), "", 0.3, "300.0");
    let dem = dir.path().join("slope.asc");
    let text = std::fs::read_to_string(&dem).unwrap();
    let gapped: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(k, l)| {
            if k < 6 {
                return l.to_string();
            }
            let mut v: Vec<&str> = l.split(' ').collect();
            v[22] = "-9999";
            v.join(" ")
        })
        .collect();
    std::fs::write(&dem, gapped.join("\n") + "\n").unwrap();
    let out = dir.path().join("out");
    let (rows, err) = endpoint_rows(&sc, &out);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let gaps = summary["left_over_gaps"].as_u64().unwrap();
    let left = summary["stop_reasons"]["left_terrain"].as_u64().unwrap();
    // The rocks that left at the gap's near side (the others left the 40 m wide terrain sideways, on the slope).
    let at_gap = rows
        .iter()
        .filter(|r| r[10] == "left_terrain" && (r[7].parse::<f64>().unwrap() - 500043.0).abs() < 0.5)
        .count() as u64;
    assert!(
        at_gap >= 3 && gaps == at_gap,
        "{gaps} rocks counted over the gap, {at_gap} left there; {left} left in all"
    );
    assert_eq!(err.matches("rocks left the terrain over a gap inside it").count(), 1, "{err}");
    assert!(summary["warnings"].to_string().contains("over a gap inside it"), "{}", summary["warnings"]);
    // `talus barrier` runs the same rocks (its first run, without a barrier) and says so too.
    let out = dir.path().join("barrier");
    let o = talus().args(["barrier", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(err.matches("rocks left the terrain over a gap inside it").count(), 1, "{err}");
}

#[test]
fn ground_levelled_beyond_a_polygon_continues_at_the_height_of_its_edge() {
    // Only the upper 20 m of the 35° slope are kept as they are; every node past x = 20 m takes the height of the
    // last node inside (x = 19 m: 100 + 21 tan 35° = 114.70 m), so the rocks stop on a level terrace there instead
    // of reaching the floor at 100 m.
    let dir = tempfile::tempdir().unwrap();
    let sc = with_terrain_key(
        dir.path(),
        "level_beyond",
        "[[500000.0, 5000000.0], [500020.0, 5000000.0], [500020.0, 5000040.0], [500000.0, 5000040.0]]",
    );
    let (rows, _) = endpoint_rows(&sc, &dir.path().join("out"));
    assert_eq!(rows.len(), 24);
    let terrace_m = 100.0 + 21.0 * 35f64.to_radians().tan();
    let mut stopped = 0;
    for r in &rows {
        let (x, z): (f64, f64) = (r[7].parse().unwrap(), r[9].parse().unwrap());
        // None reaches the floor (a rock may leave the 40 m wide terrain sideways on the terrace).
        assert!(z > terrace_m - 0.5, "rock ends at z = {z}, below the terrace: {r:?}");
        if r[10] == "stopped" {
            stopped += 1;
            assert!(x > 500019.0 && z < terrace_m + 1.5, "rock stopped off the terrace: {r:?}");
        }
    }
    assert!(stopped >= 18, "{stopped} of 24 rocks stopped");
}

#[test]
fn keys_the_terrain_does_not_use_are_warned_about_and_recorded() {
    // An unused material, a rename of a name the file does not hold and a slope threshold without slope materials
    // change nothing: the run goes on, says so on stderr and records it in summary.json.
    let dir = tempfile::tempdir().unwrap();
    let sc = with_terrain_key(dir.path(), "slope_face_deg", "40.0\nmaterial_names = { scree = \"default\" }");
    let text = std::fs::read_to_string(&sc).unwrap()
        + "\n[materials.rockfill]\ncr_mean = 0.2\nstatic_friction_deg = 40.0\ndynamic_friction_deg = 35.0\n";
    std::fs::write(&sc, text).unwrap();
    let out = dir.path().join("out");
    let o = talus().args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    for needle in [
        "warning: [materials.rockfill] is defined but no triangle of the terrain has it",
        "warning: terrain.slope_face_deg is not used: materials_by is \"single\"",
        "warning: terrain.material_names.scree is not used",
    ] {
        // Once, before the rocks run.
        assert_eq!(err.matches(needle).count(), 1, "stderr lacks '{needle}' or repeats it: {err}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["warnings"].as_array().unwrap().len(), 3, "{}", summary["warnings"]);
    let index = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(index.contains("Warning: [materials.rockfill] is defined"), "index.html lacks the warning");
    // `talus envelope` prints each model's warnings.
    let other = dir.path().join("other");
    std::fs::create_dir_all(&other).unwrap();
    let clean_other = scenario(&other, "", 0.5, "300.0");
    let o = envelope(&[&sc, &clean_other], &dir.path().join("env"), &["--rocks", "4"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(err.matches("warning: model").count(), 3, "{err}");
    assert!(err.contains("[materials.rockfill] is defined"), "{err}");
    // The shipped scenario from the same DEM and nothing unused: no warning.
    let clean = scenario(dir.path(), "", 0.3, "300.0");
    let o = talus().args(["run", clean.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning"), "{}", String::from_utf8_lossy(&o.stderr));
    // A source polygon two thirds off the terrain (y 10-100 m over a DEM of y 0-40 m): its rocks all start from the
    // third over it, which is said.
    let text = std::fs::read_to_string(&clean).unwrap().replace(
        "type = \"polyline\"\npoints = [[500004.0, 5000010.0], [500004.0, 5000030.0]]",
        "type = \"polygon\"\npoints = [[500004.0, 5000010.0], [500030.0, 5000010.0], [500030.0, 5000100.0], \
         [500004.0, 5000100.0]]",
    );
    assert!(text.contains("polygon"));
    std::fs::write(&clean, text).unwrap();
    let o = talus().args(["run", clean.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("warning: ") && err.contains("sources[0].points: 67 % of the polygon lies off"), "{err}");
}

#[test]
fn rasters_follow_the_dems_cells_with_align_to_dem() {
    // The DEM's corner moved off the 4 m multiples (500000.7, 5000000.3; 2 m cells, 40 × 20).
    let dir = tempfile::tempdir().unwrap();
    let sc = scenario(dir.path(), "align_to_dem = true", 0.3, "300.0");
    let dem = dir.path().join("slope.asc");
    let text = std::fs::read_to_string(&dem).unwrap().replace("xllcorner 500000\n", "xllcorner 500000.7\n");
    std::fs::write(&dem, text.replace("yllcorner 5000000\n", "yllcorner 5000000.3\n")).unwrap();
    let corner = |sc: &Path, out: &Path| {
        let o = talus()
            .args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap(), "--rocks", "4"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let g = talus::io::geotiff::read_grid(&out.join("reach_probability.tif")).unwrap();
        (g.x_min_m, g.y_max_m, g.ncols, g.nrows)
    };
    // 4 m cells on the DEM's edges: every second DEM cell edge, the DEM's own corner.
    let (x, y, nc, nr) = corner(&sc, &dir.path().join("aligned"));
    assert!((x - 500000.7).abs() < 1e-6 && (y - 5000040.3).abs() < 1e-6, "corner {x}, {y}");
    assert_eq!((nc, nr), (20, 10));
    // By default the edges are on multiples of the cell size.
    let text = std::fs::read_to_string(&sc).unwrap().replace("align_to_dem = true", "");
    std::fs::write(&sc, text).unwrap();
    let (x, y, _, _) = corner(&sc, &dir.path().join("default"));
    assert_eq!((x, y), (500000.0, 5000040.0));
    // A mesh terrain has no cells to follow.
    let obj = "v 500000 5000000 0\nv 500080 5000000 0\nv 500080 5000040 0\nv 500000 5000040 0\nf 1 2 3\nf 1 3 4\n";
    let mesh = with_terrain(dir.path(), "flat.obj", obj.as_bytes());
    let text = std::fs::read_to_string(&mesh).unwrap() + "align_to_dem = true\n";
    std::fs::write(&mesh, text).unwrap();
    fails_cleanly(dir.path(), &mesh, &["output.align_to_dem", "no DEM file"]);
}

#[test]
fn bad_input_is_answered_with_where_what_and_how() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Truncated binary STL: the header promises 10 triangles.
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&10u32.to_le_bytes());
    stl.extend_from_slice(&[0u8; 120]);
    fails_cleanly(d, &with_terrain(d, "cut.stl", &stl), &["cut.stl"]);
    // OBJ with a NaN vertex.
    fails_cleanly(d, &with_terrain(d, "nan.obj", b"v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n"), &["nan.obj:2"]);
    // Empty mesh.
    fails_cleanly(d, &with_terrain(d, "empty.obj", b"# nothing here\nv 0 0 0\n"), &["empty.obj"]);
    // DEM all nodata.
    fails_cleanly(d, &with_terrain(d, "void.asc", b"ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n-9999 -9999 -9999\n-9999 -9999 -9999\n"), &["void.asc"]);
    // Source polygon outside the terrain.
    let sc = scenario(d, "", 0.3, "300.0");
    let text = std::fs::read_to_string(&sc).unwrap().replace(
        "type = \"polyline\"\npoints = [[500004.0, 5000010.0], [500004.0, 5000030.0]]",
        "type = \"polygon\"\npoints = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]",
    );
    std::fs::write(&sc, text).unwrap();
    fails_cleanly(d, &sc, &["sources[0].points", "does not overlap the terrain"]);
    // A clip polygon of two vertices, and one that misses the terrain.
    fails_cleanly(d, &clipped(d, "[[0.0, 0.0], [1.0, 1.0]]"), &["terrain.clip", "2 vertices"]);
    fails_cleanly(d, &clipped(d, "[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]"), &["terrain.clip", "no triangle"]);
    // The same for the polygon beyond which the ground is levelled.
    let level = |poly: &str| with_terrain_key(d, "level_beyond", poly);
    fails_cleanly(d, &level("[[0.0, 0.0], [1.0, 1.0]]"), &["terrain.level_beyond", "2 vertices"]);
    fails_cleanly(d, &level("[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]"), &["terrain.level_beyond", "no vertex"]);
    // `"field"`, a calibration setting, is not a scenario's: it says what to write instead; so for a number.
    fails_cleanly(d, &level("\"field\""), &["scenario.toml:", "`field` is not a polygon", "`talus calibrate`"]);
    fails_cleanly(d, &level("3"), &["scenario.toml:", "expected a polygon [[x, y], ...]"]);
    // Cr of 1.5.
    fails_cleanly(d, &scenario(d, "", 1.5, "300.0"), &["materials.default.cr", "1.5"]);
    // A negative mass, one no rockfall has, and a word.
    fails_cleanly(d, &scenario(d, "", 0.3, "-5.0"), &["rocks.mass_kg", "-5"]);
    fails_cleanly(d, &scenario(d, "", 0.3, "1e300"), &["rocks.mass_kg", "largest block"]);
    fails_cleanly(d, &scenario(d, "", 0.3, "\"heavy\""), &["scenario.toml:", "a mass in kg (a number) or a range"]);
    // An unknown key.
    fails_cleanly(d, &scenario(d, "colour = \"red\"", 0.3, "300.0"), &["scenario.toml:", "unknown field `colour`"]);
    // An unknown engine key: [simulation]'s keys are listed although serde cannot list flattened ones.
    let sc = scenario(d, "", 0.3, "300.0");
    std::fs::write(&sc, std::fs::read_to_string(&sc).unwrap().replace("seed = 3", "seed = 3\nrockz = 5")).unwrap();
    fails_cleanly(d, &sc, &["unknown field `rockz`", "`rocks`", "`dt_s`"]);
    // A scatter key on a polyline source (it would be ignored).
    let sc = scenario(d, "", 0.3, "300.0");
    std::fs::write(
        &sc,
        std::fs::read_to_string(&sc).unwrap().replace("height_m = 0.2", "height_m = 0.2\nmin_slope_deg = 80.0"),
    )
    .unwrap();
    fails_cleanly(d, &sc, &["sources[0].min_slope_deg", "only applies to scatter sources", "`polyline`"]);
    // A material zone off the terrain.
    let zone = "[[terrain.zones]]\nmaterial = \"default\"\npolygon = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]\n";
    fails_cleanly(d, &scenario(d, zone, 0.3, "300.0"), &["terrain.zones[0].polygon", "covers no part of the terrain"]);
    // A collector line off the terrain (coordinates in another frame), and two collectors of one name.
    let off = "[[collectors]]\nname = \"c\"\nline = [[0.0, 0.0], [10.0, 0.0]]\n";
    fails_cleanly(d, &scenario(d, off, 0.3, "300.0"), &["collectors[0] (c)", "no point of the line"]);
    let on = "[[collectors]]\nname = \"c\"\nline = [[500044.0, 5000000.0], [500044.0, 5000040.0]]\n";
    fails_cleanly(d, &scenario(d, &format!("{on}{on}"), 0.3, "300.0"), &["collectors[1] (c)", "another collector"]);
    // Soft ground on a material the scenario does not define (the drag applied nowhere, without a word).
    let sc = scenario(d, "", 0.3, "300.0");
    let text = std::fs::read_to_string(&sc).unwrap();
    let soft = "seed = 3\n[simulation.effects]\nsoft_drag_per_s = 1.0\nsoft_materials = [\"mud\"]";
    std::fs::write(&sc, text.replace("seed = 3", soft)).unwrap();
    fails_cleanly(d, &sc, &["simulation.effects.soft_materials[0]", "'mud' is not defined", "default"]);
    // A barrier line off the terrain likewise (it ran, catching nothing), its scenario named once.
    let barrier = "[[barriers]]\nname = \"b\"\nline = [[0.0, 0.0], [10.0, 0.0]]\nheight_m = 3.0\ncapacity_kj = 500.0\n";
    let sc = scenario(d, barrier, 0.3, "300.0");
    fails_cleanly(d, &sc, &["barriers[0] (b)", "no point of the line"]);
    let o = talus().args(["run", sc.to_str().unwrap(), "--out", d.join("out_bad").to_str().unwrap()]).output().unwrap();
    assert_eq!(String::from_utf8_lossy(&o.stderr).matches("scenario.toml").count(), 1);
    // An EPSG code no GeoTIFF can hold: refused with the scenario, before a rock runs or a file is written.
    let sc = scenario(d, "", 0.3, "300.0");
    std::fs::write(&sc, std::fs::read_to_string(&sc).unwrap().replace("crs_epsg = 2056", "crs_epsg = 999999")).unwrap();
    fails_cleanly(d, &sc, &["terrain.crs_epsg", "999999"]);
    // A missing scenario file: named once with its operating-system error, and a fix.
    let o = talus()
        .args(["run", d.join("nope.toml").to_str().unwrap(), "--out", d.join("o").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("nope.toml") && err.contains("how to fix"), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
}

/// Runs `talus ARGS`, expected to fail: exit code 2, every `needles` in stderr with a fix, `out` not written.
fn command_fails_cleanly(args: &[&str], out: &Path, needles: &[&str]) {
    let o = talus().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks '{n}': {err}");
    }
    assert!(err.contains("how to fix"), "no fix suggested: {err}");
    assert!(!out.exists(), "{} written despite the error", out.display());
}

/// A folder given as a terrain file is called a folder (it was "does not exist", or "unknown terrain file type
/// '.'"); an output folder that cannot be made is named with a fix (it had none); a bench mesh too large for its
/// benches blames `--benches` with the most allowed (it blamed `--max-edge-m`, which was not given).
#[test]
fn a_terrain_folder_an_output_folder_that_cannot_be_made_and_too_many_benches_are_explained() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("tiles")).unwrap();
    let sc = scenario(d, "", 0.3, "300.0");
    let text = std::fs::read_to_string(&sc).unwrap().replace("files = [\"slope.asc\"]", "files = [\"tiles\"]");
    std::fs::write(&sc, text).unwrap();
    fails_cleanly(d, &sc, &["terrain.files[0]", "tiles is a folder, not a terrain file"]);
    let out = d.join("sec/a.csv");
    let (tiles, out_arg) = (d.join("tiles"), out.to_str().unwrap());
    let section = ["section", tiles.to_str().unwrap(), "--line", "500004,5000020,500070,5000020", "--out", out_arg];
    command_fails_cleanly(&section, &out, &["tiles: is a folder, not a terrain file", "give a terrain file"]);
    // /proc takes no new folder, not even from root.
    if Path::new("/proc/self").is_dir() {
        let slope = d.join("slope.asc");
        let no_folder = Path::new("/proc/talus_no_such_folder");
        let out = no_folder.join("a.csv");
        let section = ["section", slope.to_str().unwrap(), "--line", "500004,5000020,500070,5000020"];
        let args = [&section[..], &["--out", out.to_str().unwrap()]].concat();
        command_fails_cleanly(
            &args,
            &out,
            &["/proc/talus_no_such_folder: cannot create this folder", "how to fix: check the path"],
        );
        let out = no_folder.join("b.obj");
        let args = ["mesh", "bench", "--out", out.to_str().unwrap()];
        command_fails_cleanly(
            &args,
            &out,
            &["/proc/talus_no_such_folder: cannot create this folder", "how to fix: check the path"],
        );
    }
    let out = d.join("mesh/many.obj");
    let args = ["mesh", "bench", "--benches", "100000", "--out", out.to_str().unwrap()];
    command_fails_cleanly(&args, &out, &["--benches: 100000 benches", "give at most 9"]);
}

/// A closed standard output (`talus run ... | head -1`) neither panics nor stops the run short of its files.
#[test]
fn a_closed_standard_output_does_not_stop_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let sc = scenario(dir.path(), "", 0.3, "300.0");
    let out = dir.path().join("out");
    let mut child = talus()
        .args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{:?}: {}", o.status, String::from_utf8_lossy(&o.stderr));
    assert!(out.join("summary.json").is_file() && out.join("index.html").is_file());
}

#[test]
fn every_subcommand_has_help_with_an_example() {
    for args in [vec!["run", "--help"], vec!["mesh", "bench", "--help"], vec!["envelope", "--help"]] {
        let o = talus().args(&args).output().unwrap();
        assert!(o.status.success());
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("Example"), "{args:?}: {text}");
    }
}

#[test]
fn mesh_bench_writes_an_obj_with_face_and_floor_groups() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b.obj");
    let o = talus()
        .args(["mesh", "bench", "--out", out.to_str().unwrap(), "--benches", "2", "--face-angle-deg", "75"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mesh = talus::io::obj::read_obj(&out).unwrap();
    assert_eq!(mesh.group_names, vec!["face".to_string(), "floor".to_string()]);
    let zmax = mesh.vertices.iter().map(|v| v[2]).fold(0.0, f64::max);
    assert!((zmax - 60.0).abs() < 1e-9, "2 benches + the last face of 20 m: {zmax}");
}

/// Runs `talus envelope` on `scenarios` into `out` with `args`.
fn envelope(scenarios: &[&Path], out: &Path, args: &[&str]) -> std::process::Output {
    let mut cmd = talus();
    cmd.arg("envelope").args(scenarios).args(["--out", out.to_str().unwrap()]).args(args);
    cmd.output().unwrap()
}

fn read_grid(path: &Path) -> talus::raster::Grid {
    talus::io::geotiff::read_grid(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn an_envelope_combines_models_run_with_one_seed_and_measures_the_seeds_alone() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    let line = "[[collectors]]\nname = \"toe\"\nline = [[500044.0, 5000000.0], [500044.0, 5000040.0]]\n";
    let sa = scenario(&a, line, 0.3, "[50.0, 500.0]");
    let sb = scenario(&b, line, 0.5, "[50.0, 500.0]");
    // b's own seed differs: the envelope runs both with a's.
    std::fs::write(&sb, std::fs::read_to_string(&sb).unwrap().replace("seed = 3", "seed = 11")).unwrap();
    let out = dir.path().join("env");
    let o = envelope(&[&sa, &sb], &out, &["--floor", "--rocks", "120", "--ascii-grids"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("2 models, 120 rocks each with seed 3") && stdout.contains("seeds alone"), "{stdout}");
    // The floor's own rows, printed as ranges over its seeds and kept in envelope.json.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("envelope.json")).unwrap()).unwrap();
    let p50: Vec<f64> =
        json["floor"]["models"].as_array().unwrap().iter().map(|m| m["runout_m"]["p50"].as_f64().unwrap()).collect();
    assert_eq!(p50.len(), 2);
    let line =
        format!("seeds alone (2 runs of a): run-out median {:.1}-{:.1} m", p50[0].min(p50[1]), p50[0].max(p50[1]));
    assert!(stdout.contains(&line), "{line} not in {stdout}");

    // Each model's run is `talus run` with the common seed, to the byte.
    let alone = dir.path().join("b_alone");
    let o = talus()
        .args(["run", sb.to_str().unwrap(), "--out", alone.to_str().unwrap(), "--rocks", "120", "--seed", "3"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let bytes = |p: PathBuf| std::fs::read(&p).unwrap_or_else(|_| panic!("{} missing", p.display()));
    assert!(bytes(alone.join("endpoints.csv")) == bytes(out.join("models/b/endpoints.csv")));
    // The floor runs the first model with seeds 3 and 4: its seed 3 is model a.
    assert!(bytes(out.join("floor/models/seed_3/endpoints.csv")) == bytes(out.join("models/a/endpoints.csv")));
    assert!(bytes(out.join("floor/models/seed_4/endpoints.csv")) != bytes(out.join("models/a/endpoints.csv")));

    // Each combined raster is the cell-wise min, median and max of the two models' rasters.
    for stem in ["reach_probability", "kinetic_energy_p95_kj", "bounce_height_max_m"] {
        let [ga, gb] = ["a", "b"].map(|m| read_grid(&out.join(format!("models/{m}/{stem}.tif"))));
        let [lo, mid, hi] = ["min", "median", "max"].map(|s| read_grid(&out.join(format!("{stem}_{s}.tif"))));
        let mut both = 0;
        for k in 0..ga.values.len() {
            let (x, y) = (ga.values[k], gb.values[k]);
            match (x.is_nan(), y.is_nan()) {
                (true, true) => assert!(hi.values[k].is_nan() && lo.values[k].is_nan(), "{stem} cell {k}"),
                (false, false) => {
                    both += 1;
                    assert_eq!((lo.values[k], hi.values[k]), (x.min(y), x.max(y)), "{stem} cell {k}");
                    assert!((mid.values[k] - 0.5 * (x + y)).abs() <= 1e-5 * (1.0 + x.abs() + y.abs()));
                }
                _ => {
                    let v = if x.is_nan() { y } else { x };
                    assert_eq!((lo.values[k], mid.values[k], hi.values[k]), (v, v, v), "{stem} cell {k}");
                }
            }
        }
        assert!(both > 10, "{stem}: only {both} cells with both models");
    }
    // --ascii-grids: the combined rasters also as ESRI ASCII grids, the same values (to the digits written).
    let tif = read_grid(&out.join("bounce_height_max_m_max.tif"));
    let asc = talus::io::ascii_grid::read_grid(&out.join("bounce_height_max_m_max.asc")).unwrap();
    assert_eq!((asc.ncols, asc.nrows), (tif.ncols, tif.nrows));
    for (x, y) in tif.values.iter().zip(&asc.values) {
        assert!(x.is_nan() == y.is_nan() && (x.is_nan() || (x - y).abs() <= 1e-4 * (1.0 + x.abs())), "{x} {y}");
    }
    assert!(out.join("models/a/reach_probability.asc").is_file() && out.join("floor/models_reaching.asc").is_file());
    // The zoning: the highest level any model gives each cell, and the cells where the models' levels differ.
    let [za, zb] = ["a", "b"].map(|m| read_grid(&out.join(format!("models/{m}/hazard_zones.tif"))));
    let zmax = read_grid(&out.join("hazard_zones_max.tif"));
    let mut differing = 0;
    for k in 0..za.values.len() {
        let (x, y) = (za.values[k], zb.values[k]);
        if !x.is_nan() {
            assert_eq!(zmax.values[k], x.max(y), "zone cell {k}");
            differing += (x != y) as usize;
        }
    }
    let summary_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("envelope.json")).unwrap()).unwrap();
    assert_eq!(summary_json["zones"]["cells_differing"], differing);
    assert!(summary_json["floor"]["zones"]["cells_zoned"].as_u64().unwrap() > 0);
    let reaching = read_grid(&out.join("models_reaching.tif"));
    assert!(reaching.values.iter().all(|v| v.is_nan() || [0.0, 1.0, 2.0].contains(v)));
    assert!(reaching.values.contains(&2.0));

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("envelope.json")).unwrap()).unwrap();
    let names: Vec<&str> = summary["models"].as_array().unwrap().iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["a", "b"]);
    assert!(summary["models"].as_array().unwrap().iter().all(|m| m["seed"] == 3 && m["rocks"] == 120));
    assert_eq!(summary["rasters"].as_array().unwrap().len(), 6);
    assert_eq!(summary["floor"]["rasters"].as_array().unwrap().len(), 6);
    // The collector line over the two models: the lower and higher of their own summaries' figures.
    let own = |m: &str| -> serde_json::Value {
        let run: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join(format!("models/{m}/summary.json"))).unwrap())
                .unwrap();
        run["collectors"][0].clone()
    };
    let (ca, cb) = (own("a"), own("b"));
    let toe = &summary["collectors"][0];
    assert_eq!(toe["name"], "toe");
    for key in ["fraction_crossing", "passing_height_m_p95", "kinetic_kj_p95"] {
        let (x, y) = (ca[key].as_f64().unwrap(), cb[key].as_f64().unwrap());
        assert_eq!((toe[key]["min"].as_f64(), toe[key]["max"].as_f64()), (Some(x.min(y)), Some(x.max(y))), "{key}");
    }
    assert!(ca["fraction_crossing"].as_f64().unwrap() > 0.0, "no rock reached the toe line");
    assert_eq!(summary["floor"]["collectors"][0]["name"], "toe");
    let md = std::fs::read_to_string(out.join("envelope.md")).unwrap();
    assert!(md.contains("floor P50") && md.contains("| toe |") && md.contains("![runs reaching](models_reaching.png)"));
    for f in summary["outputs"].as_array().unwrap() {
        assert!(out.join(f.as_str().unwrap()).exists(), "{f} listed but missing");
    }
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.ends_with(".tmp"), "{name} left behind");
    }
}

#[test]
fn the_same_model_twice_has_no_spread_and_models_of_two_frames_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    let sa = scenario(&a, "", 0.3, "[50.0, 500.0]");
    let sb = scenario(&b, "", 0.3, "[50.0, 500.0]");
    std::fs::write(&sb, std::fs::read_to_string(&sb).unwrap().replace("seed = 3", "seed = 11")).unwrap();
    let out = dir.path().join("env");
    let o = envelope(&[&sa, &sb], &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for stem in ["endpoint_density", "kinetic_energy_max_kj", "bounce_height_p95_m"] {
        let [lo, hi] = ["min", "max"].map(|s| read_grid(&out.join(format!("{stem}_{s}.tif"))));
        assert!(lo.values.iter().zip(&hi.values).all(|(x, y)| x == y || (x.is_nan() && y.is_nan())), "{stem}");
    }

    // Another cell size: refused before any model runs, naming the second model and the key to align.
    std::fs::write(&sb, std::fs::read_to_string(&sb).unwrap().replace("cell_size_m = 4.0", "cell_size_m = 2.0"))
        .unwrap();
    let bad = dir.path().join("bad");
    let o = envelope(&[&sa, &sb], &bad, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("b: rasters") && err.contains("cell_size_m") && err.contains("how to fix"), "{err}");
    assert!(!bad.join("models").exists(), "a model ran before the refusal");
    // One file given twice is refused (it would read as two models that agree).
    let o = envelope(&[&sa, &sa], &bad, &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("given twice"));
    // One model is not an envelope.
    let o = envelope(&[&sa], &bad, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("at least two models"), "{err}");
}

#[test]
fn an_envelope_of_profile_models_combines_their_envelopes_station_by_station() {
    let dir = tempfile::tempdir().unwrap();
    let text =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/profile_bench.toml")).unwrap();
    let mut paths = Vec::new();
    for (name, roughness) in [("a", "2.0"), ("b", "6.0")] {
        std::fs::create_dir_all(dir.path().join(name)).unwrap();
        let p = dir.path().join(name).join("profile.toml");
        std::fs::write(&p, text.replacen("roughness_sd_deg = 2.0", &format!("roughness_sd_deg = {roughness}"), 1))
            .unwrap();
        paths.push(p);
    }
    let out = dir.path().join("env");
    let o = envelope(&[&paths[0], &paths[1]], &out, &["--floor", "--rocks", "200"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("2 profile models with seed 42") && stdout.contains("first bench catches"), "{stdout}");

    // envelopes.csv: the station keys, then each column's min / median / max over the two models.
    let read = |p: PathBuf| talus::envelope::profile::Table::read(&p).unwrap();
    let (ea, eb, env) = (
        read(out.join("models/a/envelopes.csv")),
        read(out.join("models/b/envelopes.csv")),
        read(out.join("envelopes.csv")),
    );
    assert_eq!(env.header[..5], ["x_m", "ground_z_m", "rocks_min", "rocks_median", "rocks_max"]);
    let col = |t: &talus::envelope::profile::Table, name: &str| t.header.iter().position(|h| h == name).unwrap();
    let (ca, cmax) = (col(&ea, "bounce_p95_m"), col(&env, "bounce_p95_m_max"));
    let mut both = 0;
    for ((ra, rb), re) in ea.rows.iter().zip(&eb.rows).zip(&env.rows) {
        assert_eq!(ra[..2], re[..2]);
        if let (Ok(x), Ok(y)) = (ra[ca].parse::<f64>(), rb[ca].parse::<f64>()) {
            both += 1;
            assert_eq!(re[cmax].parse::<f64>().unwrap(), x.max(y), "station {}", ra[0]);
        }
    }
    assert!(both > 20, "only {both} stations with both models");
    assert!(out.join("collectors.csv").exists() && out.join("floor/envelopes.csv").exists());

    // The share the first bench catches, over the models and over the floor's seeds.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("envelope.json")).unwrap()).unwrap();
    let first: Vec<f64> =
        summary["models"].as_array().unwrap().iter().map(|m| m["bench_fractions"][1].as_f64().unwrap()).collect();
    let spread = &summary["bench_fractions"][1];
    assert_eq!(spread["min"].as_f64().unwrap(), first[0].min(first[1]));
    assert_eq!(spread["max"].as_f64().unwrap(), first[0].max(first[1]));
    assert!(summary["floor"]["bench_fractions"][1]["max"].is_number());
    // The console gives the floor's figures too, as ranges over its seeds.
    let floor_energy: Vec<f64> = (summary["floor"]["models"].as_array().unwrap().iter())
        .map(|m| m["highest_kinetic_p95_kj"].as_f64().unwrap())
        .collect();
    let (lo, hi) = floor_energy.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    let line = stdout.lines().find(|l| l.contains("seeds alone (2 runs of a)")).unwrap_or_else(|| panic!("{stdout}"));
    assert!(line.ends_with(&format!("energy P95 {lo:.1}-{hi:.1} kJ")), "{line}");
    let md = std::fs::read_to_string(out.join("envelope.md")).unwrap();
    assert!(md.contains("seeds alone") && md.contains("(bounce_p95_m.svg)"), "{md}");
    let row = md.lines().find(|l| l.starts_with("| seeds alone (2 runs of a;")).unwrap_or_else(|| panic!("{md}"));
    assert!(row.contains(&format!("| {lo:.1}–{hi:.1} |")), "{row}");
    let svg = std::fs::read_to_string(out.join("bounce_p95_m.svg")).unwrap();
    assert!(svg.contains("models, max") && svg.contains("seeds alone, min"));
    assert!(out.join("floor/bounce_p95_m.svg").exists(), "the floor's envelope.md shows its charts too");

    // Another station spacing: refused before anything runs, naming the model and the key; nothing written.
    std::fs::write(&paths[1], text.replacen("envelope_spacing_m = 1.0", "envelope_spacing_m = 2.0", 1)).unwrap();
    let o = envelope(&[&paths[0], &paths[1]], &dir.path().join("bad"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("b: profile") && err.contains("envelope_spacing_m"), "{err}");
    assert!(!dir.path().join("bad").exists(), "{err}");
}

#[test]
fn models_carried_to_a_site_run_with_the_sites_terrain_rocks_and_seed_and_their_own_materials() {
    let dir = tempfile::tempdir().unwrap();
    let [site, a, b, check] = ["site", "a", "b", "check"].map(|n| dir.path().join(n));
    for d in [&site, &a, &b, &check] {
        std::fs::create_dir_all(d).unwrap();
    }
    let site_file = scenario(&site, "", 0.3, "[50.0, 500.0]");
    // The models' own terrain output, sources and seed differ from the site's; only their materials and engine
    // settings travel.
    let model = |d: &Path, cr: f64| {
        let p = scenario(d, "", cr, "[50.0, 500.0]");
        let text = std::fs::read_to_string(&p).unwrap();
        std::fs::write(&p, text.replace("count = 24", "count = 5").replace("seed = 3", "seed = 8")).unwrap();
        p
    };
    let (ma, mb) = (model(&a, 0.3), model(&b, 0.5));
    let out = dir.path().join("env");
    let o = envelope(&[&ma, &mb], &out, &["--site", site_file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Model b on the site is the site's scenario with b's restitution, to the byte.
    let sc = scenario(&check, "", 0.5, "[50.0, 500.0]");
    let alone = dir.path().join("check_out");
    let o = talus().args(["run", sc.to_str().unwrap(), "--out", alone.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success());
    let bytes = |p: PathBuf| std::fs::read(&p).unwrap_or_else(|_| panic!("{} missing", p.display()));
    assert!(bytes(alone.join("endpoints.csv")) == bytes(out.join("models/b/endpoints.csv")));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("envelope.json")).unwrap()).unwrap();
    assert!(summary["models"].as_array().unwrap().iter().all(|m| m["seed"] == 3 && m["rocks"] == 24));

    // A model without the site's material: refused, naming the model and the materials.
    std::fs::write(&mb, std::fs::read_to_string(&mb).unwrap().replace("[materials.default]", "[materials.rock]"))
        .unwrap();
    let o = envelope(&[&ma, &mb], &dir.path().join("bad"), &["--site", site_file.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("b/scenario.toml: materials") && err.contains("default") && err.contains("rock"), "{err}");

    // The shipped site takes the shipped Tschamut model.
    let examples = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples");
    let read = |n: &str| talus::scenario::ScenarioFile::read(&examples.join(n)).unwrap();
    let model = read("calibrated_tschamut.toml");
    let carried = talus::envelope::on_site(&read("tyrol_site.toml"), &model, "m").unwrap();
    let sc = carried.resolve(&examples.join("tyrol_site.toml")).unwrap();
    assert_eq!(sc.materials.len(), 1);
    let (drag, fitted) =
        (sc.file.simulation.params.effects.vegetation_drag_kg_s, model.simulation.params.effects.vegetation_drag_kg_s);
    assert!(fitted.is_some() && drag == fitted, "the model's effects travel: {drag:?}, fitted {fitted:?}");
}

/// A bad later model of `talus envelope` is refused with exit 2 before any model runs (its output folder holds no
/// run), and the message names the file that holds the bad value: the model's, also when its values are carried
/// onto a `--site`.
#[test]
fn a_bad_envelope_model_is_named_by_its_file_and_refused_before_any_run() {
    let dir = tempfile::tempdir().unwrap();
    let [site, a, b] = ["site", "a", "b"].map(|n| dir.path().join(n));
    for d in [&site, &a, &b] {
        std::fs::create_dir_all(d).unwrap();
    }
    let (ss, sa, sb) =
        (scenario(&site, "", 0.3, "100.0"), scenario(&a, "", 0.3, "100.0"), scenario(&b, "", 0.3, "100.0"));
    let text = std::fs::read_to_string(&sb).unwrap();
    let refused = |args: &[&str], out: &Path, needle: &str| {
        let o = envelope(&[&sa, &sb], out, args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle) && err.contains("how to fix") && !err.contains("panicked"), "{needle}: {err}");
        assert!(!out.join("models").exists(), "a model ran before the refusal: {err}");
    };
    // A source off the terrain, found only with the terrain loaded: model a must not run first.
    std::fs::write(
        &sb,
        text.replace(
            "[[500004.0, 5000010.0], [500004.0, 5000030.0]]",
            "[[600004.0, 5000010.0], [600004.0, 5000030.0]]",
        ),
    )
    .unwrap();
    refused(&["--rocks", "4"], &dir.path().join("off"), &format!("{}: sources[0]", sb.display()));
    // A bad engine setting of a model carried onto a site: named in the model's file, not the site's.
    std::fs::write(&sb, text.replace("seed = 3", "seed = 3\ndt_s = -1.0")).unwrap();
    let site_args = ["--rocks", "4", "--site", ss.to_str().unwrap()];
    refused(&site_args, &dir.path().join("dt"), &format!("{}: simulation.dt_s", sb.display()));
    let soft = "seed = 3\n[simulation.effects]\nsoft_materials = [\"nosuch\"]";
    std::fs::write(&sb, text.replace("seed = 3", soft)).unwrap();
    refused(&site_args, &dir.path().join("soft"), &format!("{}: simulation.effects.soft_materials[0]", sb.display()));
}

/// A bad 2DLM profile model of `talus envelope` is named by its file (its own checks name only the field), with
/// exit 2 and nothing written.
#[test]
fn a_bad_profile_envelope_model_is_named_by_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let text =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/profile_bench.toml")).unwrap();
    let (pa, pb) = (dir.path().join("a.toml"), dir.path().join("b.toml"));
    std::fs::write(&pa, &text).unwrap();
    for (from, to, field) in [
        ("collectors_x_m = [21.547, 28.5]", "collectors_x_m = [1000.0]", "collectors_x_m[0]"),
        ("roughness_sd_deg = 2.0", "roughness_sd_deg = -2.0", "materials.face.roughness_sd_deg"),
    ] {
        std::fs::write(&pb, text.replacen(from, to, 1)).unwrap();
        let out = dir.path().join("out");
        let o = envelope(&[&pa, &pb], &out, &["--rocks", "20"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(&format!("{}: {field}", pb.display())) && err.contains("how to fix"), "{err}");
        assert!(!out.exists(), "{field}: output written despite the error");
    }
}

/// A profile scenario given to a 3D command, or a 3D scenario to `talus profile`, is refused by its kind (exit 2,
/// naming the command to use), not by its first unknown key.
#[test]
fn a_scenario_of_the_other_kind_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let root = env!("CARGO_MANIFEST_DIR");
    let (profile, rigid) = (format!("{root}/examples/profile_bench.toml"), format!("{root}/examples/bench_stack.toml"));
    for (args, needle) in [
        (vec!["run", &profile], "talus profile"),
        (vec!["barrier", &profile], "talus profile"),
        (vec!["envelope", &rigid, &profile], "talus profile"),
        (vec!["profile", &rigid], "talus run"),
    ] {
        let o = talus().args(&args).arg("--out").arg(&out).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(needle) && err.contains("how to fix") && !err.contains("unknown field"),
            "{args:?}: {err}"
        );
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}

/// A run into the folder of an earlier one removes the earlier run's files it does not write again (paths, ASCII
/// grids), and nothing that run did not list.
#[test]
fn a_run_into_an_earlier_runs_folder_leaves_one_run_there() {
    let dir = tempfile::tempdir().unwrap();
    let sc = scenario(dir.path(), "", 0.3, "300.0");
    let out = dir.path().join("out");
    let run = |extra: &[&str]| {
        let o =
            talus().args(["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]).args(extra).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run(&["--paths", "3", "--ascii-grids"]);
    assert!(out.join("paths.csv").is_file() && out.join("reach_probability.asc").is_file());
    std::fs::write(out.join("my_notes.txt"), "mine").unwrap();
    run(&["--seed", "9"]);
    assert!(!out.join("paths.csv").exists() && !out.join("reach_probability.asc").exists());
    assert!(out.join("my_notes.txt").is_file() && out.join("reach_probability.tif").is_file());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let listed: Vec<&str> = summary["outputs"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(name == "my_notes.txt" || listed.contains(&name.as_str()), "{name} is not this run's");
    }
}
