//! File formats end to end: GeoTIFF, ESRI ASCII grid, OBJ, STL and point files, with GDAL cross-checks when
//! `gdalinfo`/`gdal_translate` are on PATH (skipped with a note otherwise). Fixtures are built in temp dirs.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::Command;

use talus::io::{ascii_grid, geotiff, obj, points, stl, MeshData};
use talus::raster::{Crs, Grid};
use tiff::encoder::{colortype, TiffEncoder};
use tiff::tags::Tag;

// ---------------------------------------------------------------------------------------------------------------
// Helpers

/// A 7 × 5 DEM in LV95 with a few NaN cells and distinct values.
fn sample_grid() -> Grid {
    let mut g = Grid::filled(7, 5, 2_600_000.0, 1_200_160.0, 2.0, 0.0);
    for r in 0..g.nrows {
        for c in 0..g.ncols {
            g.values[r * g.ncols + c] = 480.25 + 3.5 * c as f32 + 10.125 * r as f32;
        }
    }
    g.values[3] = f32::NAN;
    g.values[20] = f32::NAN;
    g.crs = Crs::epsg(2056);
    g
}

fn same_values(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x.is_nan() && y.is_nan()) || x == y)
}

/// True if `tool` runs; otherwise prints a note so the skip is visible with `--nocapture`.
fn have(tool: &str) -> bool {
    let ok = Command::new(tool).arg("--version").output().is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!("note: `{tool}` is not on PATH; skipping the GDAL cross-check");
    }
    ok
}

fn run(cmd: &str, args: &[&str]) -> String {
    let out = Command::new(cmd).args(args).output().expect("tool runs");
    assert!(out.status.success(), "{cmd} {args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn p(dir: &Path, name: &str) -> PathBuf {
    dir.join(name)
}

/// GeoKey directory for EPSG:2056, PixelIsArea or PixelIsPoint.
fn lv95_keys(raster_type: u16) -> Vec<u16> {
    vec![1, 1, 0, 4, 1024, 0, 1, 1, 1025, 0, 1, raster_type, 3072, 0, 1, 2056, 3076, 0, 1, 9001]
}

/// Writes a small single-band GeoTIFF fixture with the tiff encoder.
macro_rules! write_fixture {
    ($path:expr, $ct:ty, $w:expr, $h:expr, $data:expr, $scale:expr, $tie:expr, $keys:expr, $nodata:expr) => {{
        let mut file = BufWriter::new(File::create($path).unwrap());
        {
            let mut enc = TiffEncoder::new(&mut file).unwrap();
            let mut img = enc.new_image::<$ct>($w, $h).unwrap();
            let d = img.encoder();
            let scale: Option<[f64; 3]> = $scale;
            if let Some(s) = scale {
                d.write_tag(Tag::ModelPixelScaleTag, &s[..]).unwrap();
            }
            let tie: Option<[f64; 6]> = $tie;
            if let Some(t) = tie {
                d.write_tag(Tag::ModelTiepointTag, &t[..]).unwrap();
            }
            let keys: Option<Vec<u16>> = $keys;
            if let Some(k) = keys {
                d.write_tag(Tag::GeoKeyDirectoryTag, &k[..]).unwrap();
            }
            let nodata: Option<&str> = $nodata;
            if let Some(n) = nodata {
                d.write_tag(Tag::GdalNodata, n).unwrap();
            }
            img.write_data($data).unwrap();
        }
        file.flush().unwrap();
    }};
}

// ---------------------------------------------------------------------------------------------------------------
// GeoTIFF

#[test]
fn geotiff_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = p(dir.path(), "dem.tif");
    let g = sample_grid();
    geotiff::write_grid(&path, &g).unwrap();
    let back = geotiff::read_grid(&path).unwrap();
    assert_eq!((back.ncols, back.nrows), (7, 5));
    assert_eq!((back.x_min_m, back.y_max_m, back.cell_x_m, back.cell_y_m), (2_600_000.0, 1_200_160.0, 2.0, 2.0));
    assert!(same_values(&back.values, &g.values));
    assert_eq!(back.crs.epsg, Some(2056));
    assert!(back.crs.geokeys.is_some());
    // No temporary file is left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names, vec!["dem.tif"]);

    // Damaged image data (the Deflate stream) is called damaged, not a disk or permission problem.
    let mut dec = tiff::decoder::Decoder::new(std::fs::File::open(&path).unwrap()).unwrap();
    let data = dec.get_tag_u64_vec(tiff::tags::Tag::StripOffsets).unwrap()[0] as usize;
    let mut bytes = std::fs::read(&path).unwrap();
    for b in &mut bytes[data..data + 16] {
        *b ^= 0x5a;
    }
    let bad = p(dir.path(), "damaged.tif");
    std::fs::write(&bad, bytes).unwrap();
    let err = geotiff::read_grid(&bad).unwrap_err().to_string();
    assert!(
        err.contains("damaged.tif") && err.contains("cannot be decoded") && err.contains("export it again"),
        "{err}"
    );
    std::fs::remove_file(&bad).unwrap();

    // Passing the read CRS through again gives the same keys.
    let path2 = p(dir.path(), "again.tif");
    geotiff::write_grid(&path2, &back).unwrap();
    assert_eq!(geotiff::read_grid(&path2).unwrap().crs, back.crs);
}

#[test]
fn geotiff_int16_f64_pixel_is_point_and_errors() {
    let dir = tempfile::tempdir().unwrap();

    // int16 with nodata -32768, PixelIsArea.
    let path = p(dir.path(), "i16.tif");
    let data: Vec<i16> = vec![100, 200, -32768, 400, 500, 600];
    write_fixture!(
        &path,
        colortype::GrayI16,
        3,
        2,
        &data,
        Some([5.0, 5.0, 0.0]),
        Some([0.0, 0.0, 0.0, 1000.0, 2000.0, 0.0]),
        Some(lv95_keys(1)),
        Some("-32768")
    );
    let g = geotiff::read_grid(&path).unwrap();
    assert!(same_values(&g.values, &[100.0, 200.0, f32::NAN, 400.0, 500.0, 600.0]));
    assert_eq!((g.x_min_m, g.y_max_m, g.cell_x_m), (1000.0, 2000.0, 5.0));
    assert_eq!(g.crs.epsg, Some(2056));

    // f64, no nodata tag, NaN stays NaN; geographic CRS.
    let path = p(dir.path(), "f64.tif");
    let data: Vec<f64> = vec![1.5, f64::NAN, 3.25, 4.0];
    let keys = vec![1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326];
    write_fixture!(
        &path,
        colortype::Gray64Float,
        2,
        2,
        &data,
        Some([0.5, 0.25, 0.0]),
        Some([0.0, 0.0, 0.0, 7.0, 46.0, 0.0]),
        Some(keys),
        None
    );
    let g = geotiff::read_grid(&path).unwrap();
    assert!(same_values(&g.values, &[1.5, f32::NAN, 3.25, 4.0]));
    assert_eq!((g.cell_x_m, g.cell_y_m, g.y_max_m), (0.5, 0.25, 46.0));
    assert_eq!(g.crs.epsg, Some(4326));

    // PixelIsPoint: the tie point is the centre of pixel (0, 0).
    let path = p(dir.path(), "point.tif");
    let data: Vec<f32> = vec![1.0; 4 * 3];
    write_fixture!(
        &path,
        colortype::Gray32Float,
        4,
        3,
        &data,
        Some([2.0, 2.0, 0.0]),
        Some([0.0, 0.0, 0.0, 101.0, 199.0, 0.0]),
        Some(lv95_keys(2)),
        None
    );
    let g = geotiff::read_grid(&path).unwrap();
    assert_eq!((g.x_min_m, g.y_max_m), (100.0, 200.0));
    if have("gdalinfo") {
        let info = run("gdalinfo", &[path.to_str().unwrap()]);
        assert!(info.contains("Origin = (100.000000000000000,200.000000000000000)"), "{info}");
    }
    // Writing it back is PixelIsArea with the corner origin, so GDAL agrees too.
    let out = p(dir.path(), "point_out.tif");
    geotiff::write_grid(&out, &g).unwrap();
    let again = geotiff::read_grid(&out).unwrap();
    assert_eq!((again.x_min_m, again.y_max_m), (100.0, 200.0));
    if have("gdalinfo") {
        let info = run("gdalinfo", &[out.to_str().unwrap()]);
        assert!(info.contains("Origin = (100.000000000000000,200.000000000000000)"), "{info}");
        assert!(info.contains("AREA_OR_POINT=Area"), "{info}");
    }

    // No georeferencing: a clear error naming the file.
    let path = p(dir.path(), "plain.tif");
    write_fixture!(&path, colortype::Gray32Float, 2, 2, &[0.0f32; 4], None, None, None, None);
    let err = geotiff::read_grid(&path).unwrap_err().to_string();
    assert!(err.contains("plain.tif") && err.contains("no georeferencing") && err.contains("how to fix"), "{err}");

    // A colour image (an orthophoto, a scanned map) is not read as heights.
    let path = p(dir.path(), "rgb.tif");
    let scale = Some([5.0, 5.0, 0.0]);
    let tie = Some([0.0, 0.0, 0.0, 1000.0, 2000.0, 0.0]);
    write_fixture!(&path, colortype::RGB8, 2, 2, &[90u8; 12], scale, tie, Some(lv95_keys(1)), None);
    let err = geotiff::read_grid(&path).unwrap_err().to_string();
    assert!(err.contains("rgb.tif") && err.contains("colour image") && err.contains("gdal_translate -b 1"), "{err}");

    // An 8-bit grey image (a hillshade) is a picture: refused as a DEM, though it reads as a grid; 16-bit heights
    // are read.
    let path = p(dir.path(), "hillshade.tif");
    write_fixture!(&path, colortype::Gray8, 2, 2, &[0u8, 90, 180, 255], scale, tie, Some(lv95_keys(1)), None);
    assert!(geotiff::read_grid(&path).is_ok());
    let err = geotiff::read_dem(&path).unwrap_err().to_string();
    assert!(err.contains("hillshade.tif") && err.contains("8-bit") && err.contains("-ot Float32"), "{err}");
    let path = p(dir.path(), "dem16.tif");
    write_fixture!(&path, colortype::Gray16, 2, 2, &[410u16, 412, 415, 420], scale, tie, Some(lv95_keys(1)), None);
    assert_eq!(geotiff::read_dem(&path).unwrap().get(1, 1), Some(420.0));

    // Not a TIFF at all.
    let path = p(dir.path(), "junk.tif");
    std::fs::write(&path, b"not a tiff").unwrap();
    let err = geotiff::read_grid(&path).unwrap_err().to_string();
    assert!(err.contains("junk.tif"), "{err}");
}

/// A little-endian float32 TIFF of `width` × `height` pixels, cut into `chunk_w` × `chunk_h` tiles (or strips of
/// `chunk_h` rows when `tiled` is false) as GDAL writes a sparse file (`SPARSE_OK=TRUE`): a chunk for which `value`
/// gives `None` at its top-left pixel is not written (offset 0, 0 bytes); the others hold `value` (padded with 0).
fn sparse_tiff(
    width: u32,
    height: u32,
    tiled: bool,
    (chunk_w, chunk_h): (u32, u32),
    nodata: Option<&str>,
    value: impl Fn(u32, u32) -> Option<f32>,
) -> Vec<u8> {
    let chunk_w = if tiled { chunk_w } else { width };
    let (across, down) = (width.div_ceil(chunk_w), height.div_ceil(chunk_h));
    let mut bytes = b"II*\0\0\0\0\0".to_vec();
    let (mut offsets, mut counts) = (Vec::new(), Vec::new());
    for chunk in 0..across * down {
        let (x0, y0) = ((chunk % across) * chunk_w, (chunk / across) * chunk_h);
        if value(x0, y0).is_none() {
            offsets.push(0u32);
            counts.push(0u32);
            continue;
        }
        // A tile is padded to its full size; a strip (the last one may be short) is not.
        let rows = if tiled { chunk_h } else { chunk_h.min(height - y0) };
        offsets.push(bytes.len() as u32);
        counts.push(rows * chunk_w * 4);
        for y in y0..y0 + rows {
            for x in x0..x0 + chunk_w {
                let v = if x < width && y < height { value(x, y).unwrap_or(0.0) } else { 0.0 };
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    // Tag entries: (tag, type, count, value bytes); types 2 ASCII, 3 SHORT, 4 LONG, 12 DOUBLE.
    let short = |v: u16| (3u16, 1u32, v.to_le_bytes().to_vec());
    let long = |v: u32| (4u16, 1u32, v.to_le_bytes().to_vec());
    let longs = |v: &[u32]| (4u16, v.len() as u32, v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>());
    let doubles = |v: &[f64]| (12u16, v.len() as u32, v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>());
    let mut tags = vec![
        (256u16, long(width)),
        (257, long(height)),
        (258, short(32)),
        (259, short(1)),
        (262, short(1)),
        (277, short(1)),
        (284, short(1)),
        (339, short(3)),
        (33550, doubles(&[2.0, 2.0, 0.0])),
        (33922, doubles(&[0.0, 0.0, 0.0, 1000.0, 2000.0, 0.0])),
    ];
    if tiled {
        tags.extend([(322, long(chunk_w)), (323, long(chunk_h)), (324, longs(&offsets)), (325, longs(&counts))]);
    } else {
        tags.extend([(273, longs(&offsets)), (278, long(chunk_h)), (279, longs(&counts))]);
    }
    if let Some(text) = nodata {
        let mut ascii = text.as_bytes().to_vec();
        ascii.push(0);
        tags.push((42113, (2, ascii.len() as u32, ascii)));
    }
    tags.sort_by_key(|t| t.0);
    // Values longer than 4 bytes go before the directory.
    let mut entries = Vec::new();
    for (tag, (kind, count, mut data)) in tags {
        if data.len() > 4 {
            if bytes.len() % 2 == 1 {
                bytes.push(0);
            }
            let at = bytes.len() as u32;
            bytes.extend_from_slice(&data);
            data = at.to_le_bytes().to_vec();
        }
        data.resize(4, 0);
        entries.push((tag, kind, count, data));
    }
    if bytes.len() % 2 == 1 {
        bytes.push(0);
    }
    let ifd = bytes.len() as u32;
    bytes[4..8].copy_from_slice(&ifd.to_le_bytes());
    bytes.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    for (tag, kind, count, data) in entries {
        bytes.extend_from_slice(&tag.to_le_bytes());
        bytes.extend_from_slice(&kind.to_le_bytes());
        bytes.extend_from_slice(&count.to_le_bytes());
        bytes.extend_from_slice(&data);
    }
    bytes.extend_from_slice(&0u32.to_le_bytes());
    bytes
}

/// A valid sparse GeoTIFF (GDAL's `SPARSE_OK=TRUE`: blocks never written have offset 0 and 0 bytes) reads its
/// missing blocks as nodata, or as 0 without a nodata value, as GDAL does; it was called truncated.
#[test]
fn a_sparse_geotiff_reads_its_missing_blocks_as_nodata_or_0() {
    let dir = tempfile::tempdir().unwrap();
    let height = |x: u32, y: u32| 100.0 + x as f32 + 0.5 * y as f32;
    // 20 × 20 pixels in 16 × 16 tiles: the top-left and the bottom-right (partial) tiles are written, the others not.
    let diagonal = |x: u32, y: u32| ((x < 16) == (y < 16)).then(|| height(x, y));
    for (nodata, missing) in [(Some("-9999"), f32::NAN), (None, 0.0)] {
        let path = p(dir.path(), "sparse_tiles.tif");
        std::fs::write(&path, sparse_tiff(20, 20, true, (16, 16), nodata, diagonal)).unwrap();
        let g = geotiff::read_dem(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((g.ncols, g.nrows, g.x_min_m, g.y_max_m), (20, 20, 1000.0, 2000.0));
        let want: Vec<f32> = (0..400).map(|i| diagonal(i % 20, i / 20).unwrap_or(missing)).collect();
        assert!(same_values(&g.values, &want), "tiles, nodata {nodata:?}: {:?}", g.values);
    }
    // 5 × 7 pixels in strips of 3 rows: the middle strip is missing, the last one (1 row) is written.
    let middle = |x: u32, y: u32| (!(3..6).contains(&y)).then(|| height(x, y));
    let path = p(dir.path(), "sparse_strips.tif");
    std::fs::write(&path, sparse_tiff(5, 7, false, (5, 3), Some("-9999"), middle)).unwrap();
    let g = geotiff::read_dem(&path).unwrap_or_else(|e| panic!("{e}"));
    let want: Vec<f32> = (0..35).map(|i| middle(i % 5, i / 5).unwrap_or(f32::NAN)).collect();
    assert!(same_values(&g.values, &want), "strips: {:?}", g.values);
    // A file with every block written reads as before.
    let full = p(dir.path(), "full.tif");
    std::fs::write(&full, sparse_tiff(20, 20, true, (16, 16), None, |x, y| Some(height(x, y)))).unwrap();
    let g = geotiff::read_dem(&full).unwrap();
    assert!(same_values(&g.values, &(0..400).map(|i| height(i % 20, i / 20)).collect::<Vec<_>>()));
}

#[test]
fn geotiff_checked_by_gdalinfo() {
    if !have("gdalinfo") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let path = p(dir.path(), "dem.tif");
    let g = sample_grid();
    geotiff::write_grid(&path, &g).unwrap();
    let info = run("gdalinfo", &["-stats", path.to_str().unwrap()]);
    assert!(info.contains("Origin = (2600000.000000000000000,1200160.000000000000000)"), "{info}");
    assert!(info.contains("Pixel Size = (2.000000000000000,-2.000000000000000)"), "{info}");
    assert!(info.contains("NoData Value=-9999"), "{info}");
    assert!(info.contains("ID[\"EPSG\",2056]"), "{info}");
    assert!(info.contains("AREA_OR_POINT=Area"), "{info}");
    let (lo, hi) = g.min_max().unwrap();
    assert!(info.contains(&format!("Minimum={lo:.3}, Maximum={hi:.3}")), "{lo} {hi}\n{info}");

    // No CRS at all: GDAL shows none.
    let mut bare = g.clone();
    bare.crs = Crs::default();
    let path = p(dir.path(), "bare.tif");
    geotiff::write_grid(&path, &bare).unwrap();
    let info = run("gdalinfo", &[path.to_str().unwrap()]);
    assert!(!info.contains("Coordinate System is:"), "{info}");
    assert!(info.contains("Origin = (2600000.000000000000000,1200160.000000000000000)"), "{info}");

    // A geographic EPSG code.
    let mut geo = g.clone();
    geo.crs = Crs::epsg(4326);
    geo.x_min_m = 7.0;
    geo.y_max_m = 46.0;
    geo.cell_x_m = 0.001;
    geo.cell_y_m = 0.001;
    let path = p(dir.path(), "wgs84.tif");
    geotiff::write_grid(&path, &geo).unwrap();
    let info = run("gdalinfo", &[path.to_str().unwrap()]);
    assert!(info.contains("ID[\"EPSG\",4326]"), "{info}");
}

#[test]
fn geotiff_written_by_gdal() {
    if !have("gdal_translate") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // 40 × 30 cells, so 16 × 16 tiles include partial ones at the edges.
    let mut g = Grid::filled(40, 30, 2_600_000.0, 1_200_060.0, 2.0, 0.0);
    for (i, v) in g.values.iter_mut().enumerate() {
        *v = 500.0 + (i % 40) as f32 * 0.75 - (i / 40) as f32 * 1.5;
    }
    g.values[41] = f32::NAN;
    g.values[1199] = f32::NAN;
    let asc = p(dir.path(), "src.asc");
    ascii_grid::write_grid(&asc, &g).unwrap();
    let ours = ascii_grid::read_grid(&asc).unwrap();

    let variants: [(&str, &[&str]); 3] = [
        (
            "tiled_deflate_p3.tif",
            &[
                "-ot",
                "Float32",
                "-co",
                "TILED=YES",
                "-co",
                "BLOCKXSIZE=16",
                "-co",
                "BLOCKYSIZE=16",
                "-co",
                "COMPRESS=DEFLATE",
                "-co",
                "PREDICTOR=3",
            ],
        ),
        ("lzw.tif", &["-ot", "Float32", "-co", "COMPRESS=LZW"]),
        ("lzw_int32_p2.tif", &["-ot", "Int32", "-co", "COMPRESS=LZW", "-co", "PREDICTOR=2"]),
    ];
    for (name, opts) in variants {
        let tif = p(dir.path(), name);
        let mut args: Vec<&str> = vec!["-q", "-of", "GTiff", "-a_srs", "EPSG:2056"];
        args.extend_from_slice(opts);
        args.push(asc.to_str().unwrap());
        args.push(tif.to_str().unwrap());
        run("gdal_translate", &args);
        let back = geotiff::read_grid(&tif).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((back.ncols, back.nrows), (ours.ncols, ours.nrows), "{name}");
        assert_eq!((back.x_min_m, back.y_max_m, back.cell_x_m, back.cell_y_m), (2_600_000.0, 1_200_060.0, 2.0, 2.0));
        assert_eq!(back.crs.epsg, Some(2056), "{name}");
        // GDAL's GeoKeys (with citation keys into GeoAsciiParams) pass through our writer intact.
        if name.starts_with("tiled") {
            let keys = back.crs.geokeys.as_ref().expect("GDAL wrote GeoKeys");
            assert!(!keys.ascii_params.is_empty(), "GDAL writes citations");
            let out = p(dir.path(), "passthrough.tif");
            geotiff::write_grid(&out, &back).unwrap();
            assert_eq!(geotiff::read_grid(&out).unwrap().crs, back.crs);
            let info = run("gdalinfo", &[out.to_str().unwrap()]);
            assert!(info.contains("ID[\"EPSG\",2056]"), "{info}");
        }
        if name.contains("int32") {
            // GDAL rounded to integers.
            let close =
                back.values.iter().zip(&ours.values).all(|(a, b)| (a.is_nan() && b.is_nan()) || (a - b).abs() <= 0.5);
            assert!(close, "{name}: values differ");
        } else {
            assert!(same_values(&back.values, &ours.values), "{name}: values differ");
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// ESRI ASCII grid

#[test]
fn ascii_grid_round_trip_with_prj() {
    let dir = tempfile::tempdir().unwrap();
    let path = p(dir.path(), "dem.asc");
    let mut g = sample_grid();
    g.crs = Crs { wkt: Some("PROJCS[\"CH1903+ / LV95\"]".into()), ..Default::default() };
    g.values[5] = 0.1; // needs the shortest exact representation
    ascii_grid::write_grid(&path, &g).unwrap();
    assert!(p(dir.path(), "dem.prj").exists());
    let back = ascii_grid::read_grid(&path).unwrap();
    assert_eq!(Grid { values: Vec::new(), ..back.clone() }, Grid { values: Vec::new(), ..g.clone() });
    assert!(same_values(&back.values, &g.values));

    // Rectangular cells cannot be written.
    let mut rect = g.clone();
    rect.cell_y_m = 3.0;
    let err = ascii_grid::write_grid(&p(dir.path(), "rect.asc"), &rect).unwrap_err().to_string();
    assert!(err.contains("rect.asc") && err.contains("square"), "{err}");
}

#[test]
fn ascii_grid_xllcenter() {
    let dir = tempfile::tempdir().unwrap();
    let path = p(dir.path(), "c.asc");
    std::fs::write(&path, "ncols 2\nnrows 2\nxllcenter 1001\nyllcenter 2001\ncellsize 2\n1 2\n3 4\n").unwrap();
    let g = ascii_grid::read_grid(&path).unwrap();
    assert_eq!((g.x_min_m, g.y_max_m), (1000.0, 2004.0));
    assert_eq!(g.cell_centre(0, 1), (1001.0, 2001.0));
}

#[test]
fn ascii_grid_bad_token_names_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = p(dir.path(), "bad.asc");
    std::fs::write(
        &path,
        "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n1 2 3\n4 5,5 6\n",
    )
    .unwrap();
    let err = ascii_grid::read_grid(&path).unwrap_err().to_string();
    assert!(err.contains("bad.asc:8") && err.contains("'5,5'"), "{err}");
    // nan, inf and values no float32 holds are refused at their line too (nan was read as nodata without a word,
    // 1e308 became inf and was blamed on a vertex).
    for (token, header) in [("nan", "-9999"), ("1e308", "-9999"), ("-1e308", "-9999"), ("inf", "-9999")] {
        let text = format!(
            "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value {header}\n1 2 3\n4 {token} 6\n"
        );
        std::fs::write(&path, text).unwrap();
        let err = ascii_grid::read_grid(&path).unwrap_err().to_string();
        assert!(
            err.contains("bad.asc:8") && err.contains(&format!("'{token}'")) && err.contains("row 2, column 2"),
            "{err}"
        );
    }
}

// ---------------------------------------------------------------------------------------------------------------
// OBJ

const TWO_GROUPS: &str = "\
# two groups, two materials, the .mtl is missing
mtllib missing.mtl
v 0 0 0
v 10 0 0
v 10 10 0
v 0 10 0
v 2600000.123456789 1200000.987654321 512.000000001
g face
usemtl rock
f 1 2 3
f 1 3 4
g scree
usemtl talus_scree
f 2 5 3
g face
usemtl rock
f 4 3 5 1
";

#[test]
fn obj_groups_and_materials_without_mtl() {
    let dir = tempfile::tempdir().unwrap();
    let path = p(dir.path(), "slope.obj");
    std::fs::write(&path, TWO_GROUPS).unwrap();
    let m = obj::read_obj(&path).unwrap();
    assert_eq!(m.vertices.len(), 5);
    assert_eq!(m.vertices[4], [2600000.123456789, 1200000.987654321, 512.000000001]);
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2], [3, 2, 4], [3, 4, 0]]);
    assert_eq!(m.group_names, vec!["face", "scree"]);
    assert_eq!(m.group, vec![0, 0, 1, 0, 0]);
    assert_eq!(m.material_names, vec!["rock", "talus_scree"]);
    assert_eq!(m.material, vec![0, 0, 1, 0, 0]);
}

#[test]
fn obj_write_read_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let src = p(dir.path(), "slope.obj");
    std::fs::write(&src, TWO_GROUPS).unwrap();
    let m = obj::read_obj(&src).unwrap();
    let out = p(dir.path(), "out.obj");
    obj::write_obj(&out, &m).unwrap();
    let back = obj::read_obj(&out).unwrap();
    assert_eq!(back.vertices, m.vertices);
    assert_eq!(back.group_names, m.group_names);
    // Faces are written group by group, so compare (triangle, group, material) as sets.
    let key = |m: &MeshData| {
        let mut k: Vec<_> = (0..m.triangles.len())
            .map(|t| {
                let g = &m.group_names[m.group[t] as usize];
                (m.triangles[t], g.clone(), m.material_names[m.material[t] as usize].clone())
            })
            .collect();
        k.sort();
        k
    };
    assert_eq!(key(&back), key(&m));

    // A mesh without groups or materials.
    let plain = MeshData {
        vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.1]],
        triangles: vec![[0, 1, 2]],
        ..Default::default()
    };
    obj::write_obj(&out, &plain).unwrap();
    let back = obj::read_obj(&out).unwrap();
    assert_eq!(back.triangles, plain.triangles);
    assert_eq!(back.group_names, vec!["default"]);
    assert_eq!(back.material_names, vec![""]);
}

#[test]
fn obj_errors_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let nan = p(dir.path(), "nan.obj");
    std::fs::write(&nan, "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n").unwrap();
    let err = obj::read_obj(&nan).unwrap_err().to_string();
    assert!(err.contains("nan.obj:3") && err.contains("not finite"), "{err}");
    // A coordinate no terrain has (it was read, then every triangle read as degenerate, naming no file).
    std::fs::write(&nan, "v 0 0 0\nv 1 0 0\nv -1e308 1 0\nf 1 2 3\n").unwrap();
    let err = obj::read_obj(&nan).unwrap_err().to_string();
    assert!(err.contains("nan.obj:3") && err.contains("beyond ±1e9 m") && err.contains("-1e308"), "{err}");

    let empty = p(dir.path(), "empty.obj");
    std::fs::write(&empty, "# nothing\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    let err = obj::read_obj(&empty).unwrap_err().to_string();
    assert!(err.contains("empty.obj") && err.contains("no faces"), "{err}");

    let range = p(dir.path(), "range.obj");
    std::fs::write(&range, "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n").unwrap();
    let err = obj::read_obj(&range).unwrap_err().to_string();
    assert!(err.contains("range.obj:5") && err.contains("out of range"), "{err}");
}

// ---------------------------------------------------------------------------------------------------------------
// STL

const TETRA: [[[f32; 3]; 3]; 4] = [
    [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
    [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
];

fn tetra_binary() -> Vec<u8> {
    let tris: Vec<stl_io::Triangle> = TETRA
        .iter()
        .map(|t| stl_io::Triangle {
            normal: stl_io::Normal::new([0.0, 0.0, 0.0]),
            vertices: t.map(stl_io::Vertex::new),
        })
        .collect();
    let mut buf = Vec::new();
    stl_io::write_stl(&mut buf, tris.iter()).unwrap();
    buf
}

#[test]
fn stl_ascii_and_binary() {
    let dir = tempfile::tempdir().unwrap();
    let bin = p(dir.path(), "rock.stl");
    std::fs::write(&bin, tetra_binary()).unwrap();
    let mut ascii = String::from("solid rock\n");
    for t in TETRA {
        ascii.push_str("  facet normal 0 0 0\n    outer loop\n");
        for v in t {
            ascii.push_str(&format!("      vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        ascii.push_str("    endloop\n  endfacet\n");
    }
    ascii.push_str("endsolid rock\n");
    let asc = p(dir.path(), "rock_ascii.stl");
    std::fs::write(&asc, &ascii).unwrap();

    for (path, stem) in [(&bin, "rock"), (&asc, "rock_ascii")] {
        let m = stl::read_stl(path).unwrap();
        assert_eq!((m.vertices.len(), m.triangles.len()), (4, 4));
        assert_eq!(m.group_names, vec![stem]);
        assert_eq!(m.material_names, vec![""]);
        assert_eq!(m.group, vec![0; 4]);
        for (t, tri) in m.triangles.iter().enumerate() {
            for k in 0..3 {
                assert_eq!(m.vertices[tri[k] as usize], TETRA[t][k].map(f64::from));
            }
        }
    }
    assert_eq!(points::read_hull_points(&bin).unwrap().len(), 4);
}

#[test]
fn stl_truncated_binary_names_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let path = p(dir.path(), "cut.stl");
    let mut b = tetra_binary();
    b.truncate(b.len() - 7);
    std::fs::write(&path, &b).unwrap();
    let err = stl::read_stl(&path).unwrap_err().to_string();
    assert!(err.contains("cut.stl") && err.contains("4 triangles") && err.contains("284 bytes"), "{err}");
    assert!(err.contains("277 bytes"), "{err}");
    // The same with a header starting with `solid`, as CAD exporters write: still a truncated binary file (it was
    // read as ASCII, "no facets").
    b[..11].copy_from_slice(b"solid part ");
    std::fs::write(&path, &b).unwrap();
    let err = stl::read_stl(&path).unwrap_err().to_string();
    assert!(err.contains("4 triangles") && err.contains("277 bytes"), "{err}");
}

// ---------------------------------------------------------------------------------------------------------------
// Points

#[test]
fn hull_points_by_extension() {
    let dir = tempfile::tempdir().unwrap();
    let xyz = p(dir.path(), "block.xyz");
    std::fs::write(&xyz, "x y z\n0 0 0\n2 0 0\n0 1 0\n0 0 0.5\n").unwrap();
    assert_eq!(points::read_hull_points(&xyz).unwrap()[3], [0.0, 0.0, 0.5]);
    let objp = p(dir.path(), "slope.obj");
    std::fs::write(&objp, TWO_GROUPS).unwrap();
    assert_eq!(points::read_hull_points(&objp).unwrap().len(), 5);
    let bad = p(dir.path(), "bad.csv");
    std::fs::write(&bad, "x,y,z\n0,0,0\n1,0\n").unwrap();
    let err = points::read_hull_points(&bad).unwrap_err().to_string();
    assert!(err.contains("bad.csv:3"), "{err}");
}
