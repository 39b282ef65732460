//! GeoTIFF DEMs in, GeoTIFF rasters out, with the `tiff` crate (no GDAL).
//!
//! # Reading
//! The first band of the first image is read and converted to `f32`: sample formats f32, f64, f16 and signed or
//! unsigned integers of 8 to 64 bits, stripped or tiled, with any compression and predictor the `tiff` crate
//! decodes (none, LZW, Deflate, PackBits; horizontal and floating-point predictors). The GDAL_NODATA value and any
//! non-finite value become `NaN`. A colour image (RGB or RGBA) is refused: its bands are not heights. In a sparse
//! file (GDAL's `SPARSE_OK=TRUE`) a strip or tile of 0 bytes is a missing block: nodata, or 0 without a nodata value,
//! as GDAL reads it.
//!
//! Georeferencing comes from ModelPixelScale + ModelTiepoint, or from a ModelTransformation without rotation or
//! shear. With `GTRasterTypeGeoKey = RasterPixelIsPoint` the tie point is a pixel centre, and the grid is shifted
//! by half a cell so that [`Grid::x_min_m`] and [`Grid::y_max_m`] are outer edges (as GDAL does). A south-up file
//! (negative y scale) is flipped to north-up.
//!
//! The three GeoKey tags are kept verbatim in [`Crs::geokeys`]; [`Crs::epsg`] is set from ProjectedCSTypeGeoKey
//! (3072) or GeographicTypeGeoKey (2048) when it holds a real EPSG code.
//!
//! # Writing
//! One float32 band, Deflate, nodata −9999 (tag GDAL_NODATA), PixelIsArea, ModelPixelScale + ModelTiepoint. The
//! CRS is written from [`Crs::geokeys`] verbatim (with the raster type forced to PixelIsArea, since our tie point
//! is a corner), else from [`Crs::epsg`] (GTModelType, GTRasterType, ProjectedCSType or GeographicType, and
//! ProjLinearUnits = metre for projected codes; EPSG 4000–4999 count as geographic), else without any GeoKeys, so
//! that GDAL shows no CRS.

use crate::error::{Error, Result};
use crate::io::grid_check::check_writable;
use crate::io::write_atomic;
use crate::raster::{Crs, GeoKeys, Grid};
use std::fs::File;
use std::io::BufReader;
use std::io::ErrorKind;
use std::path::Path;
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::encoder::{colortype, Compression, DeflateLevel, TiffEncoder};
use tiff::tags::Tag;
use tiff::{ColorType, TiffError};

/// The nodata value written to our GeoTIFFs (and to the GDAL_NODATA tag).
pub const NODATA_VALUE: f32 = -9999.0;

/// How to fix a failed encode (the tiff encoder fails on I/O or on tag values it cannot store).
const ENCODE_HINT: &str = "check free disk space and write permissions for the output folder";

/// The largest decoded image we accept (8 GiB, e.g. 46 000 × 46 000 float32 cells).
const MAX_DECODED_BYTES: u64 = 8 << 30;

/// GeoKey ids used here.
const KEY_MODEL_TYPE: u16 = 1024;
const KEY_RASTER_TYPE: u16 = 1025;
const KEY_GEOGRAPHIC_TYPE: u16 = 2048;
const KEY_PROJECTED_TYPE: u16 = 3072;
const KEY_PROJ_LINEAR_UNITS: u16 = 3076;
/// GTRasterTypeGeoKey values.
const RASTER_PIXEL_IS_AREA: u16 = 1;
const RASTER_PIXEL_IS_POINT: u16 = 2;
/// The EPSG code for the metre (ProjLinearUnitsGeoKey).
const UNIT_METRE: u16 = 9001;
/// GeoKey value meaning "user-defined".
const USER_DEFINED: u16 = 32767;

/// The EPSG codes a GeoTIFF key can hold.
pub const EPSG_CODES: std::ops::Range<u32> = 1..USER_DEFINED as u32;

/// Reads the first band of a GeoTIFF DEM.
///
/// Nodata (GDAL_NODATA) and non-finite values become `NaN`. See the module documentation for what is supported.
pub fn read_grid(path: &Path) -> Result<Grid> {
    read(path, false)
}

/// Reads a GeoTIFF given as a DEM: [`read_grid`], refusing 8-bit samples. Values of 0–255 (or −128–127) in steps
/// of 1 are a picture (a hillshade, a scanned map, a classification), not heights: read as metres they make a
/// terrain a few hundred metres high in 1 m terraces, and the run ends with numbers nobody can use.
pub fn read_dem(path: &Path) -> Result<Grid> {
    read(path, true)
}

/// [`read_grid`], and with `as_dem` [`read_dem`]'s refusal of 8-bit samples.
fn read(path: &Path, as_dem: bool) -> Result<Grid> {
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let mut dec = Decoder::new(BufReader::new(file)).map_err(|e| tiff_error(path, e))?.with_limits(limits());
    let (width, height) = dec.dimensions().map_err(|e| tiff_error(path, e))?;
    let colortype = dec.colortype().map_err(|e| tiff_error(path, e))?;
    check_colortype(path, colortype)?;
    if as_dem
        && matches!(colortype, ColorType::Gray(8) | ColorType::GrayA(8) | ColorType::Multiband { bit_depth: 8, .. })
    {
        return Err(Error::format(
            path.display().to_string(),
            "the image holds 8-bit values (0 to 255 in steps of 1): a picture such as a hillshade, a scanned map or \
             a classification, not an elevation grid",
            "give the DEM itself; if these really are heights in metres, convert them with \
             `gdal_translate -ot Float32 in.tif dem.tif`",
        ));
    }
    let ncols = width as usize;
    let nrows = height as usize;
    let npix = ncols.checked_mul(nrows).filter(|&n| n > 0).ok_or_else(|| {
        Error::format(
            path.display().to_string(),
            format!("the image is {width} × {height} pixels, which cannot be used as a DEM"),
            "export the DEM again with at least one row and one column",
        )
    })?;

    let scale = find_f64s(&mut dec, path, Tag::ModelPixelScaleTag, "ModelPixelScaleTag")?;
    let tiepoints = find_f64s(&mut dec, path, Tag::ModelTiepointTag, "ModelTiepointTag")?;
    let transform = find_f64s(&mut dec, path, Tag::ModelTransformationTag, "ModelTransformationTag")?;
    let directory = match dec.find_tag(Tag::GeoKeyDirectoryTag).map_err(|e| tiff_error(path, e))? {
        Some(v) => Some(v.into_u16_vec().map_err(|e| tag_error(path, "GeoKeyDirectoryTag", e))?),
        None => None,
    };
    let double_params = find_f64s(&mut dec, path, Tag::GeoDoubleParamsTag, "GeoDoubleParamsTag")?.unwrap_or_default();
    let ascii_params = find_string(&mut dec, path, Tag::GeoAsciiParamsTag, "GeoAsciiParamsTag")?.unwrap_or_default();
    let nodata_text = find_string(&mut dec, path, Tag::GdalNodata, "GDAL_NODATA")?;

    let keys = match &directory {
        Some(dir) => Some(parse_directory(dir).ok_or_else(|| {
            Error::format(
                format!("{}: GeoKeyDirectoryTag", path.display()),
                format!("the GeoKey directory is malformed ({} values do not form a key table)", dir.len()),
                "repair the CRS, e.g. `gdal_translate -a_srs EPSG:<code> in.tif out.tif`",
            )
        })?),
        None => None,
    };
    let pixel_is_point = keys.as_ref().and_then(|k| key_value(k, KEY_RASTER_TYPE)) == Some(RASTER_PIXEL_IS_POINT);
    let epsg = keys.as_deref().and_then(epsg_of);

    let mut geo = georeference(path, scale.as_deref(), tiepoints.as_deref(), transform.as_deref())?;
    if pixel_is_point {
        geo.x0 -= 0.5 * geo.sx;
        geo.y0 += 0.5 * geo.sy;
    }

    let nodata = match nodata_text {
        Some(text) => Some(parse_nodata(&text).ok_or_else(|| {
            Error::format(
                format!("{}: GDAL_NODATA", path.display()),
                format!("the nodata value '{}' is not a number", text.trim()),
                "set a numeric nodata value, e.g. `gdal_edit.py -a_nodata -9999 FILE`",
            )
        })?),
        None => None,
    };

    let mut values = match empty_chunks(&mut dec, path)? {
        Some(chunk_bytes) => read_sparse(&mut dec, path, (ncols, nrows), nodata, &chunk_bytes)?,
        None => {
            let data = dec.read_image().map_err(|e| tiff_error(path, e))?;
            first_band(path, data, npix, nodata)?
        }
    };

    let (y_max_m, cell_y_m) = if geo.sy > 0.0 {
        (geo.y0, geo.sy)
    } else {
        // South-up: row 0 is the southern edge. Flip the rows so that row 0 is north.
        flip_rows(&mut values, ncols);
        (geo.y0 - nrows as f64 * geo.sy, -geo.sy)
    };

    let crs =
        Crs { epsg, geokeys: directory.map(|directory| GeoKeys { directory, double_params, ascii_params }), wkt: None };
    Ok(Grid { ncols, nrows, x_min_m: geo.x0, y_max_m, cell_x_m: geo.sx, cell_y_m, values, crs })
}

/// Writes `grid` as a float32, Deflate-compressed GeoTIFF with nodata −9999, atomically.
///
/// `NaN` (and any non-finite value) is written as −9999. See the module documentation for how the CRS is written.
pub fn write_grid(path: &Path, grid: &Grid) -> Result<()> {
    check_writable(path, grid)?;
    let width = u32::try_from(grid.ncols).map_err(|_| too_large(path, grid))?;
    let height = u32::try_from(grid.nrows).map_err(|_| too_large(path, grid))?;
    let keys = geokeys_for(path, &grid.crs)?;
    let data: Vec<f32> = grid.values.iter().map(|&v| if v.is_finite() { v } else { NODATA_VALUE }).collect();
    let scale = [grid.cell_x_m, grid.cell_y_m, 0.0];
    let tiepoint = [0.0, 0.0, 0.0, grid.x_min_m, grid.y_max_m, 0.0];
    let nodata = format!("{NODATA_VALUE}");

    write_atomic(path, |w| {
        let err = |e: TiffError| {
            Error::format(path.display().to_string(), format!("cannot encode the TIFF: {e}"), ENCODE_HINT)
        };
        let mut enc = TiffEncoder::new(w).map_err(err)?.with_compression(Compression::Deflate(DeflateLevel::Balanced));
        let mut image = enc.new_image::<colortype::Gray32Float>(width, height).map_err(err)?;
        let dir = image.encoder();
        dir.write_tag(Tag::ModelPixelScaleTag, &scale[..]).map_err(err)?;
        dir.write_tag(Tag::ModelTiepointTag, &tiepoint[..]).map_err(err)?;
        if let Some(keys) = &keys {
            dir.write_tag(Tag::GeoKeyDirectoryTag, &keys.directory[..]).map_err(err)?;
            if !keys.double_params.is_empty() {
                dir.write_tag(Tag::GeoDoubleParamsTag, &keys.double_params[..]).map_err(err)?;
            }
            if !keys.ascii_params.is_empty() {
                dir.write_tag(Tag::GeoAsciiParamsTag, keys.ascii_params.as_str()).map_err(err)?;
            }
        }
        dir.write_tag(Tag::GdalNodata, nodata.as_str()).map_err(err)?;
        image.write_data(&data).map_err(err)?;
        Ok(())
    })
}

/// The affine georeferencing of pixel corners: `x = x0 + col·sx`, `y = y0 − row·sy`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Georef {
    x0: f64,
    y0: f64,
    sx: f64,
    /// Positive for north-up files.
    sy: f64,
}

/// Builds the georeferencing from the model tags.
fn georeference(
    path: &Path,
    scale: Option<&[f64]>,
    tiepoints: Option<&[f64]>,
    transform: Option<&[f64]>,
) -> Result<Georef> {
    let loc = |tag: &str| format!("{}: {tag}", path.display());
    let geo = match (scale, tiepoints, transform) {
        (Some(scale), Some(tie), _) => {
            if scale.len() < 2 {
                return Err(Error::format(
                    loc("ModelPixelScaleTag"),
                    format!("expected 3 values (x, y, z scale), found {}", scale.len()),
                    "repair the georeferencing, e.g. with `gdal_translate -a_ullr ulx uly lrx lry`",
                ));
            }
            if tie.len() < 6 || tie.len() % 6 != 0 {
                return Err(Error::format(
                    loc("ModelTiepointTag"),
                    format!("expected a multiple of 6 values (i, j, k, x, y, z), found {}", tie.len()),
                    "repair the georeferencing, e.g. with `gdal_translate -a_ullr ulx uly lrx lry`",
                ));
            }
            let (i, j, x, y) = (tie[0], tie[1], tie[3], tie[4]);
            Georef { x0: x - i * scale[0], y0: y + j * scale[1], sx: scale[0], sy: scale[1] }
        }
        (_, _, Some(m)) => {
            if m.len() != 16 {
                return Err(Error::format(
                    loc("ModelTransformationTag"),
                    format!("expected 16 values (a 4 × 4 matrix), found {}", m.len()),
                    "repair the georeferencing, e.g. with `gdal_translate -a_ullr ulx uly lrx lry`",
                ));
            }
            let (a, b, d, e, f, h) = (m[0], m[1], m[3], m[4], m[5], m[7]);
            let tol = 1e-12 * (a.abs() + f.abs());
            if b.abs() > tol || e.abs() > tol {
                return Err(Error::format(
                    loc("ModelTransformationTag"),
                    format!("the raster is rotated or sheared (terms {b} and {e}); talus needs a north-up grid"),
                    "warp it to north-up first, e.g. `gdalwarp in.tif out.tif`",
                ));
            }
            Georef { x0: d, y0: h, sx: a, sy: -f }
        }
        (None, Some(tie), None) if tie.len() > 6 => {
            return Err(Error::format(
                loc("ModelTiepointTag"),
                format!("the file has {} ground control points but no pixel scale", tie.len() / 6),
                "rectify it to a north-up grid first, e.g. `gdalwarp in.tif out.tif`",
            ));
        }
        _ => {
            return Err(Error::format(
                path.display().to_string(),
                "the TIFF has no georeferencing (needs ModelPixelScale + ModelTiepoint, or ModelTransformation)",
                "export the DEM as a GeoTIFF, or assign its extent and CRS, e.g. \
                 `gdal_translate -a_ullr ulx uly lrx lry -a_srs EPSG:<code> in.tif out.tif`",
            ));
        }
    };
    let finite = [geo.x0, geo.y0, geo.sx, geo.sy].iter().all(|v| v.is_finite());
    if !finite || geo.sx <= 0.0 || geo.sy == 0.0 {
        return Err(Error::format(
            loc(if transform.is_some() && scale.is_none() { "ModelTransformationTag" } else { "ModelPixelScaleTag" }),
            format!(
                "unusable georeferencing: origin ({}, {}), pixel size ({}, {}); the pixel width must be positive and \
                 the height non-zero",
                geo.x0, geo.y0, geo.sx, geo.sy
            ),
            "repair the georeferencing, e.g. with `gdal_translate -a_ullr ulx uly lrx lry`",
        ));
    }
    Ok(geo)
}

/// Decoding limits: large enough for real DEMs, small enough that a damaged header cannot ask for all memory.
fn limits() -> Limits {
    let mut limits = Limits::default();
    limits.decoding_buffer_size = usize::try_from(MAX_DECODED_BYTES).unwrap_or(usize::MAX);
    limits
}

/// One GeoKey entry: id, tag location (0 = value inline), count, value or offset.
#[derive(Debug, Clone, Copy, PartialEq)]
struct KeyEntry {
    id: u16,
    location: u16,
    count: u16,
    value: u16,
}

/// Splits a GeoKeyDirectory into its entries; `None` if it is too short for the key count in its header.
fn parse_directory(dir: &[u16]) -> Option<Vec<KeyEntry>> {
    let n = usize::from(*dir.get(3)?);
    let body = dir.get(4..4 + 4 * n)?;
    Some(body.chunks_exact(4).map(|c| KeyEntry { id: c[0], location: c[1], count: c[2], value: c[3] }).collect())
}

/// The EPSG code of the CRS the coordinates are in: ProjectedCSType for projected models, GeographicType for
/// geographic ones (for a projected model it is only the base CRS). `None` for user-defined (32767) or undefined (0).
fn epsg_of(keys: &[KeyEntry]) -> Option<u32> {
    let projected = key_value(keys, KEY_PROJECTED_TYPE);
    let geographic = key_value(keys, KEY_GEOGRAPHIC_TYPE);
    let code = match key_value(keys, KEY_MODEL_TYPE) {
        Some(1) => projected,
        Some(2) => geographic,
        _ => projected.or(geographic),
    };
    code.filter(|&c| c != 0 && c != USER_DEFINED).map(u32::from)
}

/// EPSG unit codes named in messages (ProjLinearUnitsGeoKey values).
const UNIT_NAMES: [(u16, &str); 4] =
    [(9001, "metre"), (9002, "international foot"), (9003, "US survey foot"), (9030, "international nautical mile")];

/// Why the horizontal coordinates of a GeoTIFF with this GeoKey directory are not metres, if its keys say so: a
/// geographic model (GTModelType 2: degrees) or a projected one whose ProjLinearUnitsGeoKey is not the metre.
/// `None` when the keys name metres or say nothing about the unit (a bare ProjectedCSType code: its unit would
/// need the EPSG database, which talus does not carry).
pub fn non_metre_units(directory: &[u16]) -> Option<String> {
    let keys = parse_directory(directory)?;
    if key_value(&keys, KEY_MODEL_TYPE) == Some(2) {
        let code = key_value(&keys, KEY_GEOGRAPHIC_TYPE).filter(|&c| c != 0 && c != USER_DEFINED);
        return Some(format!(
            "its CRS is geographic ({}GTModelTypeGeoKey = 2): the coordinates are degrees of latitude and \
             longitude, not metres",
            code.map_or(String::new(), |c| format!("EPSG:{c}, "))
        ));
    }
    match key_value(&keys, KEY_PROJ_LINEAR_UNITS) {
        Some(unit) if unit != UNIT_METRE && unit != 0 && unit != USER_DEFINED => {
            let name = UNIT_NAMES.iter().find(|u| u.0 == unit).map_or("a unit other than the metre", |u| u.1);
            Some(format!("its projected CRS is in {name} (ProjLinearUnitsGeoKey = {unit}), not metres"))
        }
        _ => None,
    }
}

/// Parses a GDAL_NODATA string; `nan` in any case or sign is NaN (no value matches it, so NaN cells stay NaN).
fn parse_nodata(text: &str) -> Option<f64> {
    let t = text.trim();
    if t.trim_start_matches(['-', '+']).eq_ignore_ascii_case("nan") {
        return Some(f64::NAN);
    }
    t.parse::<f64>().ok()
}

/// The inline (SHORT) value of key `id`, if present.
fn key_value(keys: &[KeyEntry], id: u16) -> Option<u16> {
    keys.iter().find(|k| k.id == id && k.location == 0 && k.count == 1).map(|k| k.value)
}

/// The GeoKeys to write for `crs`: verbatim, from the EPSG code, or none when the CRS is unknown.
fn geokeys_for(path: &Path, crs: &Crs) -> Result<Option<GeoKeys>> {
    if let Some(keys) = &crs.geokeys {
        if let Some(entries) = parse_directory(&keys.directory) {
            if keys.ascii_params.is_ascii() && !keys.ascii_params.contains('\0') {
                let mut out = keys.clone();
                // Our tie point is a pixel corner: force PixelIsArea, or GDAL would shift the grid by half a cell.
                for (i, k) in entries.iter().enumerate() {
                    if k.id == KEY_RASTER_TYPE && k.location == 0 {
                        out.directory[4 + 4 * i + 3] = RASTER_PIXEL_IS_AREA;
                    }
                }
                return Ok(Some(out));
            }
        }
    }
    let mut keys: Vec<[u16; 4]> = Vec::new();
    match crs.epsg {
        Some(code) => {
            let code16 = u16::try_from(code).ok().filter(|&c| c > 0 && c < USER_DEFINED).ok_or_else(|| {
                Error::invalid(
                    format!("{}: crs.epsg", path.display()),
                    format!("EPSG code {code} cannot be stored in a GeoTIFF key (1 to 32766)"),
                    "use an EPSG code of a projected or geographic CRS, e.g. 2056",
                )
            })?;
            let geographic = (4000..5000).contains(&code);
            keys.push([KEY_MODEL_TYPE, 0, 1, if geographic { 2 } else { 1 }]);
            keys.push([KEY_RASTER_TYPE, 0, 1, RASTER_PIXEL_IS_AREA]);
            if geographic {
                keys.push([KEY_GEOGRAPHIC_TYPE, 0, 1, code16]);
            } else {
                keys.push([KEY_PROJECTED_TYPE, 0, 1, code16]);
                keys.push([KEY_PROJ_LINEAR_UNITS, 0, 1, UNIT_METRE]);
            }
        }
        // No CRS: no GeoKeys at all, as GDAL writes it (PixelIsArea is the default). A directory with only
        // GTRasterType would make GDAL show an unnamed engineering CRS.
        None => return Ok(None),
    }
    keys.sort_by_key(|k| k[0]);
    let mut directory = vec![1, 1, 0, keys.len() as u16];
    directory.extend(keys.iter().flatten());
    Ok(Some(GeoKeys { directory, double_params: Vec::new(), ascii_params: String::new() }))
}

/// Accepts grey and multi-band images (the first band is read); refuses colour images, whose bands are not heights.
fn check_colortype(path: &Path, colortype: ColorType) -> Result<()> {
    let bits = match colortype {
        ColorType::Gray(b) | ColorType::GrayA(b) => b,
        ColorType::RGB(_) | ColorType::RGBA(_) => {
            return Err(Error::format(
                path.display().to_string(),
                format!("the image is {colortype:?}, a colour image (an orthophoto or a map), not an elevation grid"),
                "give the DEM itself; if band 1 of this file holds the heights, extract it with \
                 `gdal_translate -b 1 -ot Float32 in.tif dem.tif`",
            ))
        }
        ColorType::Multiband { bit_depth, .. } => bit_depth,
        other => {
            return Err(Error::format(
                path.display().to_string(),
                format!("the image is {other:?}, not a single-band elevation grid"),
                "convert it to one float32 band, e.g. `gdal_translate -b 1 -ot Float32 in.tif dem.tif`",
            ))
        }
    };
    if !matches!(bits, 8 | 16 | 32 | 64) {
        return Err(Error::format(
            path.display().to_string(),
            format!("samples of {bits} bits are not supported (8, 16, 32 or 64)"),
            "convert it to float32, e.g. `gdal_translate -ot Float32 in.tif dem.tif`",
        ));
    }
    Ok(())
}

/// The first band of the decoded image as `f32`, with nodata and non-finite values as `NaN`.
fn first_band(path: &Path, data: DecodingResult, npix: usize, nodata: Option<f64>) -> Result<Vec<f32>> {
    fn convert<T: Copy>(
        src: &[T],
        stride: usize,
        is_nodata: impl Fn(T) -> bool,
        to_f32: impl Fn(T) -> f32,
    ) -> Vec<f32> {
        src.iter()
            .step_by(stride)
            .map(|&v| {
                let x = to_f32(v);
                if is_nodata(v) || !x.is_finite() {
                    f32::NAN
                } else {
                    x
                }
            })
            .collect()
    }
    let len = match &data {
        DecodingResult::U8(v) => v.len(),
        DecodingResult::U16(v) => v.len(),
        DecodingResult::U32(v) => v.len(),
        DecodingResult::U64(v) => v.len(),
        DecodingResult::F16(v) => v.len(),
        DecodingResult::F32(v) => v.len(),
        DecodingResult::F64(v) => v.len(),
        DecodingResult::I8(v) => v.len(),
        DecodingResult::I16(v) => v.len(),
        DecodingResult::I32(v) => v.len(),
        DecodingResult::I64(v) => v.len(),
    };
    if len < npix || len % npix != 0 {
        return Err(Error::format(
            path.display().to_string(),
            format!("decoded {len} samples for {npix} pixels"),
            "the file may be damaged; check it with `gdalinfo -checksum FILE`",
        ));
    }
    let stride = len / npix;
    let nd = nodata.unwrap_or(f64::NAN);
    let nd32 = nd as f32;
    let int_nd = move |v: f64| v == nd;
    Ok(match data {
        DecodingResult::U8(v) => convert(&v, stride, |x| int_nd(f64::from(x)), f32::from),
        DecodingResult::U16(v) => convert(&v, stride, |x| int_nd(f64::from(x)), f32::from),
        DecodingResult::U32(v) => convert(&v, stride, |x| int_nd(f64::from(x)), |x| x as f32),
        DecodingResult::U64(v) => convert(&v, stride, |x| int_nd(x as f64), |x| x as f32),
        DecodingResult::I8(v) => convert(&v, stride, |x| int_nd(f64::from(x)), f32::from),
        DecodingResult::I16(v) => convert(&v, stride, |x| int_nd(f64::from(x)), f32::from),
        DecodingResult::I32(v) => convert(&v, stride, |x| int_nd(f64::from(x)), |x| x as f32),
        DecodingResult::I64(v) => convert(&v, stride, |x| int_nd(x as f64), |x| x as f32),
        DecodingResult::F16(v) => convert(&v, stride, |x| x.to_f32() == nd32, |x| x.to_f32()),
        DecodingResult::F32(v) => convert(&v, stride, |x| x == nd32, |x| x),
        DecodingResult::F64(v) => convert(&v, stride, |x| x == nd, |x| x as f32),
    })
}

/// The byte counts of the image's strips or tiles if one of them is 0 (a sparse file, GDAL's `SPARSE_OK=TRUE`: a
/// block never written has offset 0 and 0 bytes), else `None`.
fn empty_chunks(dec: &mut Decoder<BufReader<File>>, path: &Path) -> Result<Option<Vec<u64>>> {
    let (tag, name) = match dec.get_chunk_type() {
        tiff::decoder::ChunkType::Tile => (Tag::TileByteCounts, "TileByteCounts"),
        tiff::decoder::ChunkType::Strip => (Tag::StripByteCounts, "StripByteCounts"),
    };
    let counts = match dec.find_tag(tag).map_err(|e| tiff_error(path, e))? {
        Some(v) => v.into_u64_vec().map_err(|e| tag_error(path, name, e))?,
        None => return Ok(None),
    };
    Ok(counts.contains(&0).then_some(counts))
}

/// Reads the first band of a sparse image (`ncols` × `nrows`) strip by strip or tile by tile, as GDAL does: a
/// strip or tile of 0 bytes (`chunk_bytes`) is a missing block, filled with nodata (`NaN`), or with 0 when the
/// file has no nodata value.
fn read_sparse(
    dec: &mut Decoder<BufReader<File>>,
    path: &Path,
    (ncols, nrows): (usize, usize),
    nodata: Option<f64>,
    chunk_bytes: &[u64],
) -> Result<Vec<f32>> {
    let npix = ncols * nrows;
    if npix as u64 * 4 > MAX_DECODED_BYTES {
        return Err(tiff_error(path, TiffError::LimitsExceeded));
    }
    let (chunk_w, chunk_h) = dec.chunk_dimensions();
    let (chunk_w, chunk_h) = (chunk_w as usize, chunk_h as usize);
    if chunk_w == 0 || chunk_h == 0 {
        return Err(Error::format(
            path.display().to_string(),
            format!("the image's strips or tiles are {chunk_w} × {chunk_h} pixels"),
            "re-save it with `gdal_translate in.tif out.tif`",
        ));
    }
    let across = ncols.div_ceil(chunk_w);
    let mut values = vec![if nodata.is_some() { f32::NAN } else { 0.0 }; npix];
    // The first band's chunks come first, also in a planar (band by band) file.
    for chunk in 0..across * nrows.div_ceil(chunk_h) {
        if chunk_bytes.get(chunk).is_none_or(|&n| n == 0) {
            continue;
        }
        let data = dec.read_chunk(chunk as u32).map_err(|e| tiff_error(path, e))?;
        let (w, h) = dec.chunk_data_dimensions(chunk as u32);
        let (w, h) = (w as usize, h as usize);
        let band = first_band(path, data, w * h, nodata)?;
        let (x0, y0) = ((chunk % across) * chunk_w, (chunk / across) * chunk_h);
        let width = w.min(ncols - x0);
        for r in 0..h.min(nrows - y0) {
            values[(y0 + r) * ncols + x0..][..width].copy_from_slice(&band[r * w..][..width]);
        }
    }
    Ok(values)
}

/// Reverses the row order of a row-major grid.
fn flip_rows(values: &mut [f32], ncols: usize) {
    let nrows = values.len() / ncols;
    for r in 0..nrows / 2 {
        let (top, bottom) = values.split_at_mut((nrows - 1 - r) * ncols);
        top[r * ncols..(r + 1) * ncols].swap_with_slice(&mut bottom[..ncols]);
    }
}

/// Reads an optional tag as `f64`s.
fn find_f64s(dec: &mut Decoder<BufReader<File>>, path: &Path, tag: Tag, name: &str) -> Result<Option<Vec<f64>>> {
    match dec.find_tag(tag).map_err(|e| tiff_error(path, e))? {
        Some(v) => Ok(Some(v.into_f64_vec().map_err(|e| tag_error(path, name, e))?)),
        None => Ok(None),
    }
}

/// Reads an optional ASCII tag.
fn find_string(dec: &mut Decoder<BufReader<File>>, path: &Path, tag: Tag, name: &str) -> Result<Option<String>> {
    match dec.find_tag(tag).map_err(|e| tiff_error(path, e))? {
        Some(v) => Ok(Some(v.into_string().map_err(|e| tag_error(path, name, e))?)),
        None => Ok(None),
    }
}

fn too_large(path: &Path, grid: &Grid) -> Error {
    Error::invalid(
        format!("{}: grid", path.display()),
        format!("{} × {} cells is too large for a TIFF", grid.ncols, grid.nrows),
        "use a coarser cell size",
    )
}

fn tag_error(path: &Path, tag: &str, e: TiffError) -> Error {
    Error::format(
        format!("{}: {tag}", path.display()),
        format!("the tag has an unexpected type or value ({e})"),
        "repair the file, e.g. by re-saving it with `gdal_translate in.tif out.tif`",
    )
}

fn tiff_error(path: &Path, e: TiffError) -> Error {
    match e {
        // The decompressor reports damaged image data as an I/O error: not the disk's or the path's fault.
        TiffError::IoError(source)
            if matches!(source.kind(), ErrorKind::InvalidData | ErrorKind::InvalidInput | ErrorKind::Other) =>
        {
            Error::format(
                path.display().to_string(),
                format!("the image data cannot be decoded ({source}): the file is damaged"),
                "copy or export it again; if `gdalinfo -checksum FILE` reads it, re-save it with \
                 `gdal_translate in.tif out.tif`",
            )
        }
        TiffError::IoError(source) => Error::io(path, source),
        TiffError::LimitsExceeded => Error::format(
            path.display().to_string(),
            format!("the image is larger than talus reads at once ({} GiB decoded)", MAX_DECODED_BYTES >> 30),
            "crop the DEM to the study area, e.g. `gdal_translate -projwin ulx uly lrx lry in.tif out.tif`",
        ),
        TiffError::UnsupportedError(_) => Error::format(
            path.display().to_string(),
            format!("cannot decode the TIFF: {e}"),
            "re-save it in a supported encoding, e.g. \
             `gdal_translate -ot Float32 -co COMPRESS=DEFLATE in.tif out.tif`",
        ),
        _ => Error::format(
            path.display().to_string(),
            format!("cannot read the TIFF: {e}"),
            "check that this is a GeoTIFF (`gdalinfo FILE`); re-save it with `gdal_translate in.tif out.tif`",
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directory_parsing_and_values() {
        let dir = [1u16, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 2, 3072, 0, 1, 2056];
        let keys = parse_directory(&dir).unwrap();
        assert_eq!(keys.len(), 3);
        assert_eq!(key_value(&keys, KEY_RASTER_TYPE), Some(2));
        assert_eq!(key_value(&keys, KEY_PROJECTED_TYPE), Some(2056));
        assert_eq!(key_value(&keys, KEY_GEOGRAPHIC_TYPE), None);
        assert!(parse_directory(&[1, 1, 0, 2, 1024, 0, 1, 1]).is_none());
        assert!(parse_directory(&[1, 1]).is_none());
    }

    #[test]
    fn epsg_follows_the_model_type() {
        let keys = |v: &[u16]| parse_directory(v).unwrap();
        // Projected, user-defined projection on WGS 84: not EPSG:4326.
        assert_eq!(epsg_of(&keys(&[1, 1, 0, 3, 1024, 0, 1, 1, 2048, 0, 1, 4326, 3072, 0, 1, 32767])), None);
        assert_eq!(epsg_of(&keys(&[1, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326])), Some(4326));
        assert_eq!(epsg_of(&keys(&[1, 1, 0, 1, 3072, 0, 1, 2056])), Some(2056));
        assert_eq!(epsg_of(&keys(&[1, 1, 0, 1, 3072, 0, 1, 0])), None);
    }

    #[test]
    fn nodata_strings() {
        assert_eq!(parse_nodata(" -9999 "), Some(-9999.0));
        assert_eq!(parse_nodata("-3.4028234663852886e+38"), Some(f64::from(f32::MIN)));
        assert!(parse_nodata("-nan").unwrap().is_nan());
        assert!(parse_nodata("NaN").unwrap().is_nan());
        assert_eq!(parse_nodata("none"), None);
    }

    #[test]
    fn geokeys_from_epsg_are_sorted() {
        let p = Path::new("x.tif");
        let k = geokeys_for(p, &Crs::epsg(2056)).unwrap().unwrap();
        assert_eq!(k.directory, vec![1, 1, 0, 4, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 2056, 3076, 0, 1, 9001]);
        let k = geokeys_for(p, &Crs::epsg(4326)).unwrap().unwrap();
        assert_eq!(k.directory, vec![1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326]);
        assert_eq!(geokeys_for(p, &Crs::default()).unwrap(), None);
        let err = geokeys_for(p, &Crs::epsg(102_100)).unwrap_err().to_string();
        assert!(err.contains("crs.epsg") && err.contains("102100"), "{err}");
    }

    #[test]
    fn passthrough_forces_pixel_is_area() {
        let crs = Crs {
            epsg: Some(2056),
            geokeys: Some(GeoKeys {
                directory: vec![1, 1, 0, 2, 1025, 0, 1, 2, 1026, 34737, 7, 0],
                double_params: vec![],
                ascii_params: "LV95 x|".into(),
            }),
            wkt: None,
        };
        let k = geokeys_for(Path::new("x.tif"), &crs).unwrap().unwrap();
        assert_eq!(k.directory, vec![1, 1, 0, 2, 1025, 0, 1, 1, 1026, 34737, 7, 0]);
        assert_eq!(k.ascii_params, "LV95 x|");
    }

    #[test]
    fn georeference_variants() {
        let p = Path::new("d.tif");
        let g = georeference(p, Some(&[2.0, 3.0, 0.0]), Some(&[1.0, 2.0, 0.0, 100.0, 200.0, 0.0]), None).unwrap();
        assert_eq!(g, Georef { x0: 98.0, y0: 206.0, sx: 2.0, sy: 3.0 });
        let m = [2.0, 0.0, 0.0, 10.0, 0.0, -2.0, 0.0, 50.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let g = georeference(p, None, None, Some(&m)).unwrap();
        assert_eq!(g, Georef { x0: 10.0, y0: 50.0, sx: 2.0, sy: 2.0 });
        let mut rot = m;
        rot[1] = 0.5;
        let err = georeference(p, None, None, Some(&rot)).unwrap_err().to_string();
        assert!(err.contains("ModelTransformationTag") && err.contains("rotated"), "{err}");
        let err = georeference(p, None, None, None).unwrap_err().to_string();
        assert!(err.contains("no georeferencing") && err.contains("how to fix"), "{err}");
    }

    #[test]
    fn flip_rows_reverses_order() {
        let mut v = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        flip_rows(&mut v, 2);
        assert_eq!(v, vec![5.0, 6.0, 3.0, 4.0, 1.0, 2.0]);
    }
}
