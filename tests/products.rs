//! A run's products: collectors, GeoJSON, ASCII grids, PNG maps, hazard zones and index.html.

use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use talus::run::{run_scenario, RunOverrides, RunSummary};
use talus::scenario::ScenarioFile;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

const COLLECTOR_X: f64 = 24.0;

/// A small bench-stack run (60 rocks) with a collector across the first bench, a barrier on the second, all paths
/// recorded, ASCII grids on.
fn run(dir: &Path) -> RunSummary {
    let mesh = root().join("meshes/bench_stack/bench_stack.obj");
    let text = format!(
        r#"title = "products"
[terrain]
files = ["{}"]
materials_by = "group"
crs_epsg = 2056
[materials.face]
preset = "face_all"
[materials.floor]
preset = "floor_all"
[[sources]]
type = "scatter"
material = "face"
within = [[10.0, 35.0], [21.6, 35.0], [21.6, 65.0], [10.0, 65.0]]
count = 60
[rocks]
shapes = ["cube", "flat_box", "smartie"]
mass_kg = [100.0, 10000.0]
[output]
cell_size_m = 2.0
paths = 60
ascii_grids = true
[[collectors]]
name = "bench 1"
line = [[{COLLECTOR_X}, 0.0], [{COLLECTOR_X}, 100.0]]
segment_m = 10.0
[[collectors]]
file = "toe.csv"
[[barriers]]
name = "fence"
line = [[45.0, 10.0], [45.0, 90.0]]
height_m = 3.0
capacity_kj = 300.0
"#,
        mesh.display()
    );
    std::fs::write(dir.join("toe.csv"), "x,y\n114.5,0\n114.5,100\n").unwrap();
    let p = dir.join("scenario.toml");
    std::fs::write(&p, text).unwrap();
    let sc = ScenarioFile::read(&p).unwrap().resolve(&p).unwrap();
    run_scenario(&sc, &RunOverrides::default(), &dir.join("out"), &|_, _| {}).unwrap()
}

fn crosses(a: (f64, f64), b: (f64, f64)) -> bool {
    (a.0 - COLLECTOR_X) * (b.0 - COLLECTOR_X) <= 0.0
        && a.0 != b.0
        && (0.0..=100.0).contains(&(a.1 + (COLLECTOR_X - a.0) / (b.0 - a.0) * (b.1 - a.1)))
}

#[test]
fn run_products_are_consistent() {
    let dir = tempfile::tempdir().unwrap();
    let summary = run(dir.path());
    let out = dir.path().join("out");
    for f in &summary.outputs {
        assert!(out.join(f).is_file(), "{f} listed but missing");
    }
    for f in [
        "collectors.csv",
        "collectors.geojson",
        "paths.geojson",
        "hazard_zones.tif",
        "hazard_zones.png",
        "reach_probability.asc",
        "terrain.png",
        "index.html",
    ] {
        assert!(summary.outputs.iter().any(|o| o == f), "{f} not written");
    }

    // collectors.csv agrees with the paths: the rocks whose consecutive samples straddle the line.
    let paths = std::fs::read_to_string(out.join("paths.csv")).unwrap();
    let mut by_rock: BTreeMap<usize, Vec<(f64, f64)>> = BTreeMap::new();
    for line in paths.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        by_rock.entry(f[0].parse().unwrap()).or_default().push((f[2].parse().unwrap(), f[3].parse().unwrap()));
    }
    assert_eq!(by_rock.len(), 60);
    let mut per_stretch = [0u64; 10];
    let mut crossing = 0;
    for pts in by_rock.values() {
        let mut seen = [false; 10];
        let mut any = false;
        for w in pts.windows(2) {
            if crosses(w[0], w[1]) {
                any = true;
                let y = w[0].1 + (COLLECTOR_X - w[0].0) / (w[1].0 - w[0].0) * (w[1].1 - w[0].1);
                seen[((y / 10.0) as usize).min(9)] = true;
            }
        }
        crossing += any as u64;
        for (k, s) in seen.iter().enumerate() {
            per_stretch[k] += *s as u64;
        }
    }
    assert!(crossing > 5, "only {crossing} rocks crossed");
    let csv = std::fs::read_to_string(out.join("collectors.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv.lines().map(|l| l.split(',').map(str::to_string).collect()).collect();
    let col = |name: &str| rows[0].iter().position(|c| c == name).unwrap();
    let bench: Vec<&Vec<String>> = rows.iter().filter(|r| r[0] == "bench 1").collect();
    assert_eq!(bench[0][col("stretch")], "all");
    assert_eq!(bench[0][col("rocks_crossing")].parse::<u64>().unwrap(), crossing);
    assert!((bench[0][col("fraction_crossing")].parse::<f64>().unwrap() - crossing as f64 / 60.0).abs() < 1e-6);
    for k in 0..10 {
        assert_eq!(bench[k + 1][col("rocks_crossing")].parse::<u64>().unwrap(), per_stretch[k], "stretch {k}");
    }
    let p95: f64 = bench[0][col("kinetic_kj_p95")].parse().unwrap();
    let max: f64 = bench[0][col("kinetic_kj_max")].parse().unwrap();
    assert!(p95 > 0.0 && p95 <= max);
    let angle: f64 = bench[0][col("crossing_angle_deg_p50")].parse().unwrap();
    assert!((0.0..=90.0).contains(&angle));
    assert!(rows.iter().any(|r| r[0] == "collector_1"), "the CSV line file names its collector");
    let c = &summary.collectors[0];
    assert_eq!((c.name.as_str(), c.rocks_crossing), ("bench 1", crossing));
    assert_eq!(summary.barriers.len(), 1);

    // GeoJSON parses back, with the CRS and LineStrings of [x, y, z].
    for (file, min_features) in [("collectors.geojson", 2 + 10 + 1), ("paths.geojson", 60)] {
        let v: Value = serde_json::from_str(&std::fs::read_to_string(out.join(file)).unwrap()).unwrap();
        assert_eq!(v["type"], "FeatureCollection", "{file}");
        assert_eq!(v["crs"]["properties"]["name"], "urn:ogc:def:crs:EPSG::2056", "{file}");
        let feats = v["features"].as_array().unwrap();
        assert!(feats.len() >= min_features, "{file}: {} features", feats.len());
        for f in feats {
            assert_eq!(f["type"], "Feature");
            assert_eq!(f["geometry"]["type"], "LineString");
            let coords = f["geometry"]["coordinates"].as_array().unwrap();
            assert!(coords.len() >= 2);
            assert!(
                coords.iter().all(|p| p.as_array().is_some_and(|p| p.len() == 3 && p.iter().all(Value::is_number))),
                "{file}"
            );
            assert!(f["properties"].is_object());
        }
    }

    // ASCII grids: same values as the GeoTIFFs.
    let tif = talus::io::geotiff::read_grid(&out.join("reach_probability.tif")).unwrap();
    let asc = talus::io::ascii_grid::read_grid(&out.join("reach_probability.asc")).unwrap();
    assert_eq!((tif.ncols, tif.nrows), (asc.ncols, asc.nrows));
    assert!(tif
        .values
        .iter()
        .zip(&asc.values)
        .all(|(a, b)| (a.is_nan() && b.is_nan()) || (a - b).abs() <= 1e-6 * a.abs().max(1.0)));

    // PNG size and colour bar range match the raster.
    let style = talus::report::maps::raster_style("reach_probability");
    let again = dir.path().join("again.png");
    let info = talus::report::maps::render(&again, &tif, &style, None, &Default::default()).unwrap();
    let (w, h) = png_size(&again);
    assert_eq!((w, h), (info.width_px, info.height_px));
    let (lo, hi) = tif.values.iter().filter(|v| **v > 0.0).fold((f32::MAX, 0f32), |(a, b), &v| (a.min(v), b.max(v)));
    assert_eq!(info.colorbar_max, hi);
    assert_eq!(info.colorbar_min, lo.max(hi / 1000.0));
    let (w0, h0) = png_size(&out.join("reach_probability.png"));
    assert_eq!((w0, h0), (info.width_px, info.height_px), "the run's map has the raster's geometry");
    let zones = talus::io::geotiff::read_grid(&out.join("hazard_zones.tif")).unwrap();
    assert!(zones.values.iter().all(|v| v.is_nan() || [0.0, 1.0, 2.0, 3.0].contains(v)));
    assert!(
        zones.values.iter().zip(&tif.values).all(|(z, r)| (*z > 0.0) == (*r > 0.0)),
        "zoned exactly where rocks came"
    );

    // index.html links only to files that exist.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for part in html.split("href=\"").skip(1) {
        let link = &part[..part.find('"').unwrap()];
        assert!(out.join(link).is_file(), "index.html links to missing {link}");
    }
    assert!(html.contains("Stop reasons") && html.contains("bench 1") && html.contains("reach_probability.png"));
    chromium_renders(&out.join("index.html"));
}

fn png_size(path: &Path) -> (u32, u32) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let r = dec.read_info().unwrap();
    let i = r.info();
    (i.width, i.height)
}

/// Renders `page` in headless Chromium (Debian's package) when it is installed, and checks the screenshot is a
/// picture, not a blank page.
fn chromium_renders(page: &Path) {
    let chromium = Path::new("/usr/bin/chromium");
    if !chromium.exists() {
        eprintln!("note: /usr/bin/chromium is not installed; index.html was not rendered (apt-get install chromium)");
        return;
    }
    let profile = tempfile::tempdir().unwrap();
    let shot = profile.path().join("shot.png");
    let mut child = std::process::Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            &format!("--user-data-dir={}", profile.path().join("profile").display()),
            &format!("--screenshot={}", shot.display()),
            "--window-size=1400,2400",
            &format!("file://{}", page.display()),
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Give Chromium a minute at most: a hung browser must not hang the test suite.
    let t0 = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > std::time::Duration::from_secs(60) {
            let _ = child.kill();
            panic!("chromium did not finish within 60 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    };
    assert!(status.success(), "chromium failed: {status}");
    assert_eq!(png_size(&shot), (1400, 2400));
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    let px = &buf[..info.buffer_size()];
    let channels = info.color_type.samples();
    let colours: std::collections::HashSet<&[u8]> = px.chunks(channels).step_by(97).collect();
    assert!(colours.len() > 50, "the screenshot has {} colours: a blank page?", colours.len());
}

#[test]
fn new_scenario_tables_are_checked_with_their_field() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = root().join("meshes/bench_stack/bench_stack.obj");
    let base = format!(
        "[terrain]\nfiles = [\"{}\"]\n[materials.default]\npreset = \"face_all\"\n[[sources]]\ntype = \"point\"\npoints = [[15.0, 50.0]]\ncount = 1\n[rocks]\nshapes = [\"cube\"]\nmass_kg = 100.0\n",
        mesh.display()
    );
    for (extra, want) in [
        ("[[collectors]]\nline = [[1.0, 2.0]]\n", "collectors[0].line"),
        ("[[collectors]]\nfile = \"nope.geojson\"\n", "collectors[0].file"),
        ("[[collectors]]\nline = [[1.0, 2.0], [3.0, 4.0]]\nsegment_m = 0.0\n", "collectors[0].segment_m"),
        ("[hazard_zones]\nenergy_kj = [300.0, 30.0]\n", "hazard_zones.energy_kj"),
        ("[barrier_design]\ntarget_share = 1.5\n", "barrier_design.target_share"),
        ("[barrier_design]\nclass_cost_per_m = [1.0]\n", "barrier_design.class_cost_per_m"),
        ("[barrier_design]\nasset_line = [[0.0, 0.0]]\n", "barrier_design.asset_line"),
    ] {
        let p = dir.path().join("s.toml");
        std::fs::write(&p, format!("{base}{extra}")).unwrap();
        let err = ScenarioFile::read(&p).unwrap().resolve(&p).unwrap_err().to_string();
        assert!(err.contains(want) && err.contains("how to fix"), "{extra}: {err}");
    }
    // A material's dynamic friction spread: read, and checked.
    let p = dir.path().join("s.toml");
    let with_spread = |sd: &str| {
        base.replace("preset = \"face_all\"\n", &format!("preset = \"face_all\"\ndynamic_friction_sd_deg = {sd}\n"))
    };
    std::fs::write(&p, with_spread("3.0")).unwrap();
    assert_eq!(ScenarioFile::read(&p).unwrap().resolve(&p).unwrap().materials[0].dynamic_friction_sd_deg, 3.0);
    std::fs::write(&p, with_spread("-2.0")).unwrap();
    let err = ScenarioFile::read(&p).unwrap().resolve(&p).unwrap_err().to_string();
    assert!(err.contains("materials.default.dynamic_friction_sd_deg") && err.contains("-2"), "{err}");
}

#[test]
fn ascii_grids_carry_the_prj_and_geojson_the_epsg_of_a_real_dem() {
    let dir = tempfile::tempdir().unwrap();
    let p = root().join("examples/tyrol.toml");
    let mut sc = ScenarioFile::read(&p).unwrap().resolve(&p).unwrap();
    sc.file.output.ascii_grids = true;
    sc.file.collectors.push(talus::collector::CollectorSpec {
        name: Some("valley".into()),
        line: vec![[248050.0, 352150.0], [248440.0, 352150.0]],
        file: None,
        segment_m: 20.0,
    });
    let o = RunOverrides { rocks: Some(20), ..Default::default() };
    let summary = run_scenario(&sc, &o, dir.path(), &|_, _| {}).unwrap();
    let prj = std::fs::read_to_string(dir.path().join("reach_probability.prj")).unwrap();
    let source = std::fs::read_to_string(root().join("meshes/tyrol/tyrol_crop.prj")).unwrap();
    assert_eq!(prj.trim(), source.trim());
    assert!(summary.outputs.iter().any(|f| f == "hazard_zones.prj"));
    let tif = talus::io::geotiff::read_grid(&dir.path().join("reach_probability.tif")).unwrap();
    assert_eq!(tif.crs.epsg, Some(31287));
    let v: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("collectors.geojson")).unwrap()).unwrap();
    assert_eq!(v["crs"]["properties"]["name"], "urn:ogc:def:crs:EPSG::31287");
    // Map coordinates: the collector's first vertex comes back where it was given, on the ground.
    let first = &v["features"][0]["geometry"]["coordinates"][0];
    assert!(
        (first[0].as_f64().unwrap() - 248050.0).abs() < 1e-3 && (first[1].as_f64().unwrap() - 352150.0).abs() < 1e-3
    );
    assert!((1700.0..2400.0).contains(&first[2].as_f64().unwrap()));
}
