//! GeoJSON out (feature collections of lines, points and polygons, with the CRS) and polylines in (GeoJSON
//! LineStrings or a CSV of vertices).
//!
//! # Writing
//! A `FeatureCollection` with a `name` and, when an EPSG code is known, the `crs` member of the 2008 GeoJSON
//! specification (`{"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::CODE"}}`). RFC 7946 dropped that
//! member and fixed WGS 84, but GDAL and QGIS still read it, and it is the only way to keep projected coordinates
//! (ours: the same choice as GDAL's GeoJSON driver with `RFC7946=NO`, its default). Coordinates are rounded to the
//! millimetre; `NaN` properties become `null`; a vertex without an elevation is written as [x, y].
//!
//! # Reading polylines
//! - GeoJSON: a `LineString` or `MultiLineString` geometry, a `Feature` holding one, or a `FeatureCollection`;
//!   every LineString becomes one polyline, named by the feature's `name` property when it has one. Only x and y
//!   are read.
//! - CSV: one vertex per row. With a header, the columns named `x` and `y` (or `x_m`/`y_m`, `easting`/`northing`,
//!   any case); without one, the first two columns. Blank lines and lines starting with `#` are skipped.

use crate::error::{Error, Result};
use crate::raster::Crs;
use serde_json::{json, Map, Value};
use std::path::Path;

/// A GeoJSON geometry, coordinates (x, y, z) in metres.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    /// A point.
    Point([f64; 3]),
    /// A polyline.
    LineString(Vec<[f64; 3]>),
    /// A polygon: the outer ring (closed or not; it is closed on writing).
    Polygon(Vec<[f64; 3]>),
}

/// A feature: a geometry and its properties.
#[derive(Debug, Clone, PartialEq)]
pub struct Feature {
    /// The geometry.
    pub geometry: Geometry,
    /// Properties (strings, numbers, booleans; `NaN` numbers are written as `null`).
    pub properties: Map<String, Value>,
}

impl Feature {
    /// A feature with no properties yet.
    pub fn new(geometry: Geometry) -> Self {
        Feature { geometry, properties: Map::new() }
    }

    /// Adds a property and returns the feature.
    pub fn with(mut self, key: &str, value: impl Into<Value>) -> Self {
        self.set(key, value);
        self
    }

    /// Sets a property (`NaN` and infinite numbers become `null`).
    pub fn set(&mut self, key: &str, value: impl Into<Value>) {
        self.properties.insert(key.to_string(), value.into());
    }
}

fn round_mm(v: f64) -> Value {
    if v.is_finite() {
        json!((v * 1000.0).round() / 1000.0)
    } else {
        Value::Null
    }
}

/// [x, y, z], or [x, y] when z is unknown (off the terrain): a position never holds `null`.
fn position(p: &[f64; 3]) -> Value {
    let n = if p[2].is_finite() { 3 } else { 2 };
    Value::Array(p[..n].iter().map(|&v| round_mm(v)).collect())
}

fn geometry_value(g: &Geometry) -> Value {
    match g {
        Geometry::Point(p) => json!({"type": "Point", "coordinates": position(p)}),
        Geometry::LineString(pts) => {
            json!({"type": "LineString", "coordinates": pts.iter().map(position).collect::<Vec<_>>()})
        }
        Geometry::Polygon(ring) => {
            let mut r: Vec<Value> = ring.iter().map(position).collect();
            if ring.len() > 1 && ring.first() != ring.last() {
                r.push(position(&ring[0]));
            }
            json!({"type": "Polygon", "coordinates": [r]})
        }
    }
}

/// The `crs` member for `crs`, when its EPSG code is known.
pub fn crs_member(crs: &Crs) -> Option<Value> {
    crs.epsg.map(|code| json!({"type": "name", "properties": {"name": format!("urn:ogc:def:crs:EPSG::{code}")}}))
}

/// A `FeatureCollection` named `name` holding `features`, with the CRS member when known.
pub fn feature_collection(name: &str, crs: &Crs, features: &[Feature]) -> Value {
    let mut fc = Map::new();
    fc.insert("type".into(), json!("FeatureCollection"));
    fc.insert("name".into(), json!(name));
    if let Some(c) = crs_member(crs) {
        fc.insert("crs".into(), c);
    }
    let feats: Vec<Value> = features
        .iter()
        .map(|f| {
            let props: Map<String, Value> = f
                .properties
                .iter()
                .map(|(k, v)| {
                    let v = match v.as_f64() {
                        Some(x) if !x.is_finite() => Value::Null,
                        _ => v.clone(),
                    };
                    (k.clone(), v)
                })
                .collect();
            json!({"type": "Feature", "properties": props, "geometry": geometry_value(&f.geometry)})
        })
        .collect();
    fc.insert("features".into(), Value::Array(feats));
    Value::Object(fc)
}

/// Writes a feature collection to `path`, atomically.
pub fn write(path: &Path, name: &str, crs: &Crs, features: &[Feature]) -> Result<()> {
    let v = feature_collection(name, crs, features);
    let text = serde_json::to_string(&v)
        .map_err(|e| Error::invalid(path.display().to_string(), e.to_string(), "report this as a bug"))?;
    crate::io::write_bytes_atomic(path, text.as_bytes())
}

/// A polyline read from a file: its name (if the file gives one) and its (x, y) vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedLine {
    /// The feature's `name` property, if any.
    pub name: Option<String>,
    /// Vertices (x, y).
    pub xy: Vec<[f64; 2]>,
}

/// Reads polylines from a GeoJSON (`.geojson`, `.json`) or CSV (anything else) file.
pub fn read_lines(path: &Path) -> Result<Vec<NamedLine>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase()).unwrap_or_default();
    let lines = if ext == "geojson" || ext == "json" {
        lines_from_geojson(path, &text)?
    } else {
        vec![line_from_csv(path, &text)?]
    };
    if lines.is_empty() {
        return Err(Error::format(
            path.display().to_string(),
            "holds no LineString",
            "give a GeoJSON LineString (or a Feature / FeatureCollection of them) or a CSV with x,y columns",
        ));
    }
    for l in &lines {
        if l.xy.len() < 2 {
            return Err(Error::format(
                path.display().to_string(),
                format!("a line has {} vertices", l.xy.len()),
                "give at least 2 vertices per line",
            ));
        }
    }
    Ok(lines)
}

fn lines_from_geojson(path: &Path, text: &str) -> Result<Vec<NamedLine>> {
    let loc = path.display().to_string();
    let v: Value = serde_json::from_str(text).map_err(|e| {
        Error::format(
            format!("{loc}:{}", e.line()),
            format!("not valid JSON: {e}"),
            "check the file with a JSON validator",
        )
    })?;
    let mut out = Vec::new();
    collect_lines(&loc, &v, None, &mut out)?;
    Ok(out)
}

fn collect_lines(loc: &str, v: &Value, name: Option<String>, out: &mut Vec<NamedLine>) -> Result<()> {
    let kind = v.get("type").and_then(Value::as_str).unwrap_or("");
    let bad =
        |what: &str| Error::format(loc, what.to_string(), "coordinates must be arrays of [x, y] or [x, y, z] numbers");
    let read_ring = |c: &Value| -> Result<Vec<[f64; 2]>> {
        let arr = c.as_array().ok_or_else(|| bad("LineString coordinates are not an array"))?;
        arr.iter()
            .map(|p| {
                let x = p.get(0).and_then(Value::as_f64);
                let y = p.get(1).and_then(Value::as_f64);
                match (x, y) {
                    (Some(x), Some(y)) if x.is_finite() && y.is_finite() => Ok([x, y]),
                    _ => Err(bad(&format!("vertex {p} is not an [x, y] pair of numbers"))),
                }
            })
            .collect()
    };
    match kind {
        "FeatureCollection" => {
            let feats =
                v.get("features").and_then(Value::as_array).ok_or_else(|| bad("FeatureCollection without features"))?;
            for f in feats {
                collect_lines(loc, f, None, out)?;
            }
        }
        "Feature" => {
            let name = v.pointer("/properties/name").and_then(Value::as_str).map(str::to_string);
            if let Some(g) = v.get("geometry") {
                collect_lines(loc, g, name, out)?;
            }
        }
        "LineString" => {
            let c = v.get("coordinates").ok_or_else(|| bad("LineString without coordinates"))?;
            out.push(NamedLine { name, xy: read_ring(c)? });
        }
        "MultiLineString" => {
            let parts = v
                .get("coordinates")
                .and_then(Value::as_array)
                .ok_or_else(|| bad("MultiLineString without coordinates"))?;
            for (k, c) in parts.iter().enumerate() {
                let n = name.as_ref().map(|n| format!("{n}_{k}"));
                out.push(NamedLine { name: n, xy: read_ring(c)? });
            }
        }
        _ => {}
    }
    Ok(())
}

fn line_from_csv(path: &Path, text: &str) -> Result<NamedLine> {
    let mut cols: Option<(usize, usize)> = None;
    let mut xy = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split([',', ';', '\t']).map(str::trim).collect();
        let numeric = fields.iter().take(2).all(|f| f.parse::<f64>().is_ok());
        if cols.is_none() && !numeric {
            let find = |names: &[&str]| fields.iter().position(|f| names.contains(&f.to_lowercase().as_str()));
            match (find(&["x", "x_m", "easting", "east"]), find(&["y", "y_m", "northing", "north"])) {
                (Some(cx), Some(cy)) => cols = Some((cx, cy)),
                _ => {
                    return Err(Error::at_line(
                        path,
                        i + 1,
                        format!("header '{line}' has no x and y columns"),
                        "name the columns x,y (or x_m,y_m / easting,northing), or leave the header out",
                    ))
                }
            }
            continue;
        }
        let (cx, cy) = *cols.get_or_insert((0, 1));
        let get = |c: usize| -> Result<f64> {
            let f = fields.get(c).copied().unwrap_or("");
            f.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                Error::at_line(path, i + 1, format!("'{f}' (column {}) is not a number", c + 1), "give x,y in metres")
            })
        };
        xy.push([get(cx)?, get(cy)?]);
    }
    Ok(NamedLine { name: None, xy })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_crs_and_nulls_and_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.geojson");
        let f = Feature::new(Geometry::LineString(vec![[1.0, 2.0, 3.0], [4.0, 5.0004, 6.0]]))
            .with("name", "fence")
            .with("e", f64::NAN);
        write(&p, "test", &Crs::epsg(2056), &[f]).unwrap();
        let v: Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        assert_eq!(v["crs"]["properties"]["name"], "urn:ogc:def:crs:EPSG::2056");
        assert_eq!(v["features"][0]["properties"]["e"], Value::Null);
        assert_eq!(v["features"][0]["geometry"]["coordinates"][1][1], 5.0);
        assert_eq!(position(&[1.0, 2.0, f64::NAN]), json!([1.0, 2.0]));
        let lines = read_lines(&p).unwrap();
        assert_eq!(lines, vec![NamedLine { name: Some("fence".into()), xy: vec![[1.0, 2.0], [4.0, 5.0]] }]);
    }

    #[test]
    fn csv_with_and_without_header_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("l.csv");
        std::fs::write(&p, "# fence\nid,Y,X\n1,10,0\n2,20,5\n").unwrap();
        assert_eq!(read_lines(&p).unwrap()[0].xy, vec![[0.0, 10.0], [5.0, 20.0]]);
        std::fs::write(&p, "0,1\n2,3\n").unwrap();
        assert_eq!(read_lines(&p).unwrap()[0].xy, vec![[0.0, 1.0], [2.0, 3.0]]);
        std::fs::write(&p, "x,y\n0,1\n2,oops\n").unwrap();
        let e = read_lines(&p).unwrap_err().to_string();
        assert!(e.contains("l.csv:3") && e.contains("oops"), "{e}");
        std::fs::write(&p, "x,y\n0,1\n").unwrap();
        assert!(read_lines(&p).unwrap_err().to_string().contains("1 vertices"));
    }
}
