//! "Bring your own data": the terrain files an engineer arrives with (GeoTIFFs and ESRI ASCII grids exported by
//! GDAL or a GIS, meshes from survey or modelling tools) and the mistakes in them that used to run to the end and
//! write wrong numbers: a DEM in degrees or feet, nodata cells nobody declared, full-precision coordinates read
//! as f32. Each is refused before any work with exit code 2 and no output, or read right. Fixtures are built in
//! temp dirs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use talus::io::geotiff;
use talus::raster::{Crs, GeoKeys, Grid};

fn talus() -> Command {
    Command::new(env!("CARGO_BIN_EXE_talus"))
}

/// A 30 × 20 DEM of 2 m cells in a national grid (large coordinates): a 35° slope falling toward −x onto a floor.
fn slope_grid() -> Grid {
    let (nc, nr, cell) = (30usize, 20usize, 2.0);
    let mut g = Grid::filled(nc, nr, 248_000.0, 352_040.0, cell, 0.0);
    for r in 0..nr {
        for c in 0..nc {
            let x = (c as f64 + 0.5) * cell;
            let z = if x > 20.0 { (x - 20.0) * 35f64.to_radians().tan() } else { 0.0 };
            g.values[r * nc + c] = (1500.0 + z) as f32;
        }
    }
    g
}

/// The grid as an ESRI ASCII grid, with `nodata_line` (e.g. `NODATA_value -9999`, or empty) in its header.
fn ascii_text(g: &Grid, cell_text: &str, nodata_line: &str) -> String {
    let mut s = format!(
        "ncols {}\nnrows {}\nxllcorner {}\nyllcorner {}\ncellsize {cell_text}\n{nodata_line}\n",
        g.ncols,
        g.nrows,
        g.x_min_m,
        g.y_max_m - g.nrows as f64 * g.cell_y_m
    );
    for r in 0..g.nrows {
        let row: Vec<String> = (0..g.ncols).map(|c| format!("{}", g.values[r * g.ncols + c])).collect();
        s.push_str(&row.join(" "));
        s.push('\n');
    }
    s
}

/// A scenario on `terrain` (relative to `dir`) releasing 12 rocks from a point on the slope.
fn scenario(dir: &Path, terrain: &str, release: [f64; 2]) -> PathBuf {
    let text = format!(
        r#"
[terrain]
files = ["{terrain}"]

[materials.default]
preset = "face_all"

[[sources]]
type = "point"
points = [[{}, {}]]
count = 12

[rocks]
shapes = ["cube"]
mass_kg = 200.0

[output]
cell_size_m = 4.0
"#,
        release[0], release[1]
    );
    let p = dir.join("scenario.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn run(scenario: &Path, out: &Path) -> Output {
    talus().arg("run").arg(scenario).arg("--out").arg(out).arg("--threads").arg("1").output().unwrap()
}

/// Asserts that the run was refused with exit code 2, that stderr holds every one of `needles`, and that nothing
/// was written.
fn assert_refused(o: &Output, out: &Path, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "expected exit code 2; stderr: {err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks {n:?}: {err}");
    }
    assert!(err.contains("how to fix"), "{err}");
    let written = std::fs::read_dir(out).map(|d| d.count()).unwrap_or(0);
    assert_eq!(written, 0, "a refused run wrote {written} files");
}

const RELEASE: [f64; 2] = [248_050.0, 352_020.0];

#[test]
fn geotiff_dem_in_degrees_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    // What `gdalwarp -t_srs EPSG:4326` writes: a geographic model; cells of 1/1200 degree.
    let mut g = slope_grid();
    (g.x_min_m, g.y_max_m, g.cell_x_m, g.cell_y_m) = (11.33, 47.05, 1.0 / 1200.0, 1.0 / 1200.0);
    g.crs = Crs {
        epsg: Some(4326),
        geokeys: Some(GeoKeys { directory: vec![1, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326], ..Default::default() }),
        wkt: None,
    };
    geotiff::write_grid(&dir.path().join("dem.tif"), &g).unwrap();
    let sc = scenario(dir.path(), "dem.tif", [11.34, 47.04]);
    let out = dir.path().join("out");
    let o = run(&sc, &out);
    assert_refused(&o, &out, &["dem.tif", "geographic", "EPSG:4326", "gdalwarp -t_srs"]);
}

#[test]
fn geotiff_dem_in_us_feet_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = slope_grid();
    // NAD83 / New York Long Island (ftUS), as GDAL writes it: ProjLinearUnitsGeoKey = 9003.
    g.crs = Crs {
        epsg: Some(2263),
        geokeys: Some(GeoKeys {
            directory: vec![1, 1, 0, 3, 1024, 0, 1, 1, 3072, 0, 1, 2263, 3076, 0, 1, 9003],
            ..Default::default()
        }),
        wkt: None,
    };
    geotiff::write_grid(&dir.path().join("dem.tif"), &g).unwrap();
    let sc = scenario(dir.path(), "dem.tif", RELEASE);
    let out = dir.path().join("out");
    let o = run(&sc, &out);
    assert_refused(&o, &out, &["dem.tif", "US survey foot", "9003"]);

    // The same grid in a metre CRS runs.
    g.crs = Crs::epsg(31287);
    geotiff::write_grid(&dir.path().join("dem.tif"), &g).unwrap();
    let o = run(&sc, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn ascii_dem_with_a_geographic_or_foot_prj_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let g = slope_grid();
    std::fs::write(dir.path().join("dem.asc"), ascii_text(&g, "2", "NODATA_value -9999")).unwrap();
    let sc = scenario(dir.path(), "dem.asc", RELEASE);
    let out = dir.path().join("out");
    // What GDAL writes beside an AAIGrid in EPSG:2263 (ESRI WKT, no EPSG code).
    std::fs::write(
        dir.path().join("dem.prj"),
        r#"PROJCS["NAD_1983_StatePlane_New_York_Long_Island_FIPS_3104_Feet",GEOGCS["GCS_North_American_1983",DATUM["D_North_American_1983",SPHEROID["GRS_1980",6378137.0,298.257222101]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]],PROJECTION["Lambert_Conformal_Conic"],PARAMETER["False_Easting",984250.0],UNIT["Foot_US",0.3048006096012192]]"#,
    )
    .unwrap();
    assert_refused(&run(&sc, &out), &out, &["dem.asc", "Foot_US", "not the metre"]);
    std::fs::write(
        dir.path().join("dem.prj"),
        r#"GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,298.257223563]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]]"#,
    )
    .unwrap();
    assert_refused(&run(&sc, &out), &out, &["dem.asc", "geographic"]);
    // The .prj of avaGar (ESRI WKT, metres) is fine.
    std::fs::write(
        dir.path().join("dem.prj"),
        r#"PROJCS["MGI_Austria_Lambert",GEOGCS["GCS_MGI",DATUM["D_MGI",SPHEROID["Bessel_1841",6377397.155,299.1528128]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]],PROJECTION["Lambert_Conformal_Conic"],PARAMETER["False_Easting",400000.0],UNIT["Meter",1.0]]"#,
    )
    .unwrap();
    let o = run(&sc, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn ascii_dem_in_degrees_without_a_crs_is_refused_by_its_slope() {
    let dir = tempfile::tempdir().unwrap();
    let g = slope_grid();
    let mut text = ascii_text(&g, "0.000833333", "NODATA_value -9999");
    text = text.replace("xllcorner 248000", "xllcorner 11.33").replace("yllcorner 352000", "yllcorner 47.03");
    std::fs::write(dir.path().join("dem.asc"), text).unwrap();
    let sc = scenario(dir.path(), "dem.asc", [11.34, 47.04]);
    let out = dir.path().join("out");
    assert_refused(&run(&sc, &out), &out, &["dem.asc", "median slope", "degrees", "gdalwarp"]);
}

#[test]
fn undeclared_nodata_cells_are_refused_not_read_as_a_pit() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = slope_grid();
    // A hole on the floor, below the release.
    for r in 8..12 {
        for c in 2..6 {
            g.values[r * g.ncols + c] = -9999.0;
        }
    }
    let out = dir.path().join("out");
    let sc = scenario(dir.path(), "dem.asc", RELEASE);
    // No NODATA_value line at all.
    std::fs::write(dir.path().join("dem.asc"), ascii_text(&g, "2", "")).unwrap();
    assert_refused(&run(&sc, &out), &out, &["dem.asc", "16 of 600 cells hold -9999", "NODATA_value -9999"]);
    // Another nodata value declared (an Int16 export with -32768) than the one the hole holds.
    std::fs::write(dir.path().join("dem.asc"), ascii_text(&g, "2", "NODATA_value -32768")).unwrap();
    assert_refused(&run(&sc, &out), &out, &["16 of 600 cells hold -9999"]);
    // Declared: the hole is a hole, and the run goes.
    std::fs::write(dir.path().join("dem.asc"), ascii_text(&g, "2", "NODATA_value -9999")).unwrap();
    let o = run(&sc, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn ascii_grid_and_obj_with_a_byte_order_mark_and_crlf_read_as_without() {
    use talus::io::{ascii_grid, obj};
    let dir = tempfile::tempdir().unwrap();
    let g = slope_grid();
    let plain = ascii_text(&g, "2", "NODATA_value -9999");
    std::fs::write(dir.path().join("plain.asc"), &plain).unwrap();
    std::fs::write(dir.path().join("bom.asc"), format!("\u{feff}{}", plain.replace('\n', "\r\n"))).unwrap();
    let a = ascii_grid::read_grid(&dir.path().join("plain.asc")).unwrap();
    let b = ascii_grid::read_grid(&dir.path().join("bom.asc")).unwrap();
    assert_eq!(a, b);
    // An OBJ whose first line is a vertex: the mark used to hide it and shift every face index by one.
    let mesh = "v 0 0 0\nv 10 0 0\nv 10 10 1\nv 0 10 1\nf 1 2 3\nf 1 3 4\n";
    std::fs::write(dir.path().join("plain.obj"), mesh).unwrap();
    std::fs::write(dir.path().join("bom.obj"), format!("\u{feff}{}", mesh.replace('\n', "\r\n"))).unwrap();
    let a = obj::read_obj(&dir.path().join("plain.obj")).unwrap();
    let b = obj::read_obj(&dir.path().join("bom.obj")).unwrap();
    assert_eq!(a, b);
}

#[test]
fn ascii_nodata_matches_at_the_precision_heights_are_kept() {
    // The float32 lowest value, written once by a tool that prints f32 and once in full by another.
    let dir = tempfile::tempdir().unwrap();
    let g = slope_grid();
    let mut text = ascii_text(&g, "2", "NODATA_value -3.4028235e+38");
    let first_value = format!("{}", g.values[0]);
    text = text.replacen(&format!("\n{first_value} "), "\n-3.4028234663852886e+38 ", 1);
    let p = dir.path().join("dem.asc");
    std::fs::write(&p, text).unwrap();
    let read = talus::io::ascii_grid::read_grid(&p).unwrap();
    assert!(read.values[0].is_nan(), "read {}", read.values[0]);
    assert_eq!(read.count_valid(), g.values.len() - 1);
}

#[test]
fn ascii_stl_keeps_full_precision_map_coordinates() {
    // A 0.7 m mesh at a UTM northing of 7.5 million metres, where f32 steps are 0.5 m.
    let dir = tempfile::tempdir().unwrap();
    let (e0, n0, s) = (500_000.37, 7_500_000.41, 0.7);
    let corner = |i: usize, j: usize| [e0 + i as f64 * s, n0 + j as f64 * s, 1000.0 + 0.7 * j as f64 * s];
    let mut text = String::from("solid survey\n");
    for (i, j) in [(0, 0), (1, 0), (0, 1)] {
        let [a, b, c] = [corner(i, j), corner(i + 1, j), corner(i + 1, j + 1)];
        let [d, e, f] = [corner(i, j), corner(i + 1, j + 1), corner(i, j + 1)];
        for t in [[a, b, c], [d, e, f]] {
            text.push_str("facet normal 0 0 1\nouter loop\n");
            for v in t {
                text.push_str(&format!("vertex {:.4} {:.4} {:.4}\n", v[0], v[1], v[2]));
            }
            text.push_str("endloop\nendfacet\n");
        }
    }
    text.push_str("endsolid survey\n");
    let p = dir.path().join("survey.stl");
    std::fs::write(&p, text).unwrap();
    let mesh = talus::io::stl::read_stl(&p).unwrap();
    assert_eq!(mesh.triangles.len(), 6);
    // Three cells in an L share 8 corners.
    assert_eq!(mesh.vertices.len(), 8);
    for v in &mesh.vertices {
        let (i, j) = (((v[0] - e0) / s).round() as usize, ((v[1] - n0) / s).round() as usize);
        let want = corner(i, j);
        for k in 0..3 {
            assert!((v[k] - want[k]).abs() < 1e-6, "vertex {v:?} should be {want:?}");
        }
    }
}

#[test]
fn adjacent_dem_tiles_form_one_surface_without_a_seam() {
    // The slope cut into a west and an east tile along x = 248,030 m (on the slope): the tiles' outer cell centres
    // are 2 m apart, and that strip had no surface, so rocks rolling down "left the terrain" there.
    let dir = tempfile::tempdir().unwrap();
    let g = slope_grid();
    let half = |c0: usize| {
        let mut t = Grid::filled(15, g.nrows, g.x_min_m + c0 as f64 * g.cell_x_m, g.y_max_m, g.cell_x_m, 0.0);
        for r in 0..g.nrows {
            t.values[r * 15..(r + 1) * 15].copy_from_slice(&g.values[r * g.ncols + c0..r * g.ncols + c0 + 15]);
        }
        t
    };
    std::fs::write(dir.path().join("west.asc"), ascii_text(&half(0), "2", "NODATA_value -9999")).unwrap();
    std::fs::write(dir.path().join("east.asc"), ascii_text(&half(15), "2", "NODATA_value -9999")).unwrap();
    let sc = scenario(dir.path(), "west.asc\", \"east.asc", [248_055.0, 352_020.0]);
    let out = dir.path().join("out");
    let o = run(&sc, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let endpoints = std::fs::read_to_string(out.join("endpoints.csv")).unwrap();
    let at_seam: Vec<&str> = endpoints
        .lines()
        .skip(1)
        .filter(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let x: f64 = f[7].parse().unwrap();
            f[10] == "left_terrain" && (x - 248_030.0).abs() < 3.0
        })
        .collect();
    assert!(at_seam.is_empty(), "rocks left the terrain at the seam between the tiles: {at_seam:?}");
    assert_eq!(endpoints.lines().count(), 13);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("not on one grid"));
}

#[test]
fn dem_tiles_that_meet_off_one_grid_are_warned_about() {
    // The east tile on 3 m cells starting 1 m east of the west tile's edge: they cannot be joined, and the run
    // says so (with the GDAL command that puts them on one grid) instead of losing rocks at the seam unexplained.
    let dir = tempfile::tempdir().unwrap();
    let g = slope_grid();
    let mut west = Grid::filled(15, g.nrows, g.x_min_m, g.y_max_m, 2.0, 0.0);
    for r in 0..g.nrows {
        west.values[r * 15..(r + 1) * 15].copy_from_slice(&g.values[r * g.ncols..r * g.ncols + 15]);
    }
    let mut east = Grid::filled(10, 14, g.x_min_m + 31.0, g.y_max_m, 3.0, 0.0);
    for r in 0..14 {
        for c in 0..10 {
            let x = 31.0 + (c as f64 + 0.5) * 3.0;
            east.values[r * 10 + c] = (1500.0 + (x - 20.0) * 35f64.to_radians().tan()) as f32;
        }
    }
    std::fs::write(dir.path().join("west.asc"), ascii_text(&west, "2", "NODATA_value -9999")).unwrap();
    std::fs::write(dir.path().join("east.asc"), ascii_text(&east, "3", "NODATA_value -9999")).unwrap();
    let sc = scenario(dir.path(), "west.asc\", \"east.asc", [248_055.0, 352_020.0]);
    let out = dir.path().join("out");
    let o = run(&sc, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let needle =
        "warning: DEM tiles west.asc (2 × 2 m cells) and east.asc (3 × 3 m cells) meet but are not on one grid";
    assert!(err.contains(needle) && err.contains("gdalwarp -tr 2 2 -tap west.asc east.asc joined.tif"), "{err}");
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("are not on one grid"), "{summary}");
}

#[test]
fn ascii_dem_with_a_prj_says_how_to_georeference_the_geotiffs() {
    let dir = tempfile::tempdir().unwrap();
    let g = slope_grid();
    std::fs::write(dir.path().join("dem.asc"), ascii_text(&g, "2", "NODATA_value -9999")).unwrap();
    std::fs::write(
        dir.path().join("dem.prj"),
        r#"PROJCS["MGI_Austria_Lambert",GEOGCS["GCS_MGI",DATUM["D_MGI",SPHEROID["Bessel_1841",6377397.155,299.1528128]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]],PROJECTION["Lambert_Conformal_Conic"],UNIT["Meter",1.0]]"#,
    )
    .unwrap();
    let sc = scenario(dir.path(), "dem.asc", RELEASE);
    let out = dir.path().join("out");
    let o = run(&sc, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("GeoTIFFs will carry no CRS") && err.contains("dem.prj") && err.contains("crs_epsg"), "{err}");
    assert_eq!(geotiff::read_grid(&out.join("reach_probability.tif")).unwrap().crs.epsg, None);

    // With the code given: no note, and the rasters carry it, over the DEM's extent.
    let text = std::fs::read_to_string(&sc).unwrap().replace("[terrain]\n", "[terrain]\ncrs_epsg = 31287\n");
    std::fs::write(&sc, text).unwrap();
    let o = run(&sc, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("note:"));
    let r = geotiff::read_grid(&out.join("reach_probability.tif")).unwrap();
    assert_eq!(r.crs.epsg, Some(31287));
    let (first_x, first_y) = g.cell_centre(0, 0);
    let (last_x, last_y) = g.cell_centre(g.ncols - 1, g.nrows - 1);
    assert!(r.x_min_m <= first_x && r.x_min_m + r.ncols as f64 * r.cell_x_m >= last_x, "{r:?}");
    assert!(r.y_max_m >= first_y && r.y_max_m - r.nrows as f64 * r.cell_y_m <= last_y);
}
