//! A slope profile: a polyline in the vertical (x, z) plane with a material per segment.
//!
//! # Units
//! x (horizontal distance along the profile) and z (elevation) in m.
//!
//! # CSV form
//! ```text
//! x_m,z_m,material
//! 0,120,floor
//! 10,120,face
//! 21.547,100,floor
//! ```
//! One vertex per row, in order of increasing x; `material` is that of the segment starting at the vertex (the
//! last row's material is ignored and may be empty). Vertical segments (two rows with the same x) are allowed,
//! overhangs (x decreasing) are not. Extra columns are ignored.

use crate::error::{Error, Result};
use crate::io::csv_text::Table;
use crate::terrain::bench::{BenchGeometry, BenchPart};
use std::io::Write;
use std::path::Path;

/// Most stations along a profile: the samples of a section ([`Profile::from_section`]) and the envelope stations
/// of a profile run (`envelope_spacing_m`). Ours: a million is a 1 mm spacing over a kilometre, finer than any
/// terrain model, and keeps a profile's vectors within tens of MB.
pub const MAX_STATIONS: usize = 1_000_000;

/// Refuses a `spacing_m` (named `field` in the error) that puts more than [`MAX_STATIONS`] stations on `length_m`
/// of profile; `fix` ends the hint (e.g. `, or a shorter line`).
pub(crate) fn check_station_count(field: &str, spacing_m: f64, length_m: f64, fix: &str) -> Result<()> {
    if length_m / spacing_m <= MAX_STATIONS as f64 {
        return Ok(());
    }
    let text = crate::error::number_text;
    Err(Error::invalid(
        field,
        format!("{} m gives more than a million stations on a {} m profile", text(spacing_m), text(length_m)),
        format!(
            "use a wider spacing, at least {} m{fix}",
            text(crate::error::round_up_3_digits(length_m / MAX_STATIONS as f64))
        ),
    ))
}

/// A slope profile: vertices (x_m, z_m) with x non-decreasing, a material index per segment and the material names.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    x_m: Vec<f64>,
    z_m: Vec<f64>,
    segment_material: Vec<usize>,
    material_names: Vec<String>,
}

impl Profile {
    /// A profile from vertices `[x_m, z_m]`, the material index of each segment (one fewer than vertices) and the
    /// material names. `source` names where the data came from, for errors.
    ///
    /// # Errors
    /// Fewer than 2 vertices, values that are not finite, x decreasing, zero-length segments, a vertical run that
    /// folds back on itself, or a material index out of range.
    pub fn new(
        vertices: &[[f64; 2]],
        segment_material: Vec<usize>,
        material_names: Vec<String>,
        source: &str,
    ) -> Result<Profile> {
        let locate = |i: usize| format!("{source}: vertex {}", i + 1);
        if vertices.len() < 2 {
            return Err(Error::format(
                source,
                format!("a profile needs at least 2 vertices, got {}", vertices.len()),
                "give the profile as at least two (x_m, z_m) points",
            ));
        }
        if segment_material.len() != vertices.len() - 1 {
            return Err(Error::format(
                source,
                format!("{} segment materials for {} vertices", segment_material.len(), vertices.len()),
                "give one material per segment (one fewer than vertices)",
            ));
        }
        for (i, v) in vertices.iter().enumerate() {
            if !(v[0].is_finite() && v[1].is_finite()) {
                return Err(Error::format(locate(i), "x_m or z_m is not a finite number", "give plain numbers"));
            }
            if i == 0 {
                continue;
            }
            let p = vertices[i - 1];
            if v[0] < p[0] {
                return Err(Error::format(
                    locate(i),
                    format!("x_m {} is less than the previous vertex's {}", v[0], p[0]),
                    "order vertices by increasing x; vertical steps (equal x) are allowed, overhangs are not",
                ));
            }
            if v[0] == p[0] && v[1] == p[1] {
                return Err(Error::format(
                    locate(i),
                    format!("repeats the previous vertex ({}, {})", v[0], v[1]),
                    "remove the duplicate row",
                ));
            }
            if i >= 2 && v[0] == p[0] && p[0] == vertices[i - 2][0] && (v[1] - p[1]) * (p[1] - vertices[i - 2][1]) < 0.0
            {
                return Err(Error::format(
                    locate(i),
                    "a vertical run turns back on itself (down then up, or up then down, at the same x)",
                    "remove the vertex that makes the spike",
                ));
            }
        }
        if let Some((i, &m)) = segment_material.iter().enumerate().find(|(_, &m)| m >= material_names.len()) {
            return Err(Error::format(
                locate(i),
                format!("material index {m} but only {} material names", material_names.len()),
                "give a name for every material index",
            ));
        }
        Ok(Profile {
            x_m: vertices.iter().map(|v| v[0]).collect(),
            z_m: vertices.iter().map(|v| v[1]).collect(),
            segment_material,
            material_names,
        })
    }

    /// Reads a profile CSV (`x_m,z_m,material`, see the module docs).
    ///
    /// # Errors
    /// I/O errors, and format errors that name the file and line.
    pub fn from_csv_path(path: &Path) -> Result<Profile> {
        let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        Profile::from_csv_reader(file, &path.display().to_string())
    }

    /// Reads a profile CSV from any reader; `source` (a file name) is used in error messages.
    ///
    /// # Errors
    /// Format errors that name `source` and the line.
    pub fn from_csv_reader<R: std::io::Read>(mut reader: R, source: &str) -> Result<Profile> {
        let mut text = Vec::new();
        reader.read_to_end(&mut text).map_err(|e| Error::io(source, e))?;
        let t = Table::parse(&with_last_material(text), source, false)?;
        let hint = "start the file with the line `x_m,z_m,material`";
        let (ix, iz, imat) = (t.need("x_m", hint)?, t.need("z_m", hint)?, t.col("material"));
        let mut vertices = Vec::new();
        let mut mats: Vec<String> = Vec::new();
        let mut lines = Vec::new();
        for row in &t.rows {
            vertices.push([t.number(row, ix, "x_m")?, t.number(row, iz, "z_m")?]);
            mats.push(t.field(row, imat).to_string());
            lines.push(row.line);
        }
        if vertices.len() < 2 {
            return Err(Error::format(
                source,
                format!("a profile needs at least 2 vertices, found {}", vertices.len()),
                "give at least two rows of x_m,z_m,material",
            ));
        }
        let mut names: Vec<String> = Vec::new();
        let mut seg_mat = Vec::with_capacity(vertices.len() - 1);
        for (k, name) in mats.iter().take(vertices.len() - 1).enumerate() {
            let name = if imat.is_none() { "default" } else { name.as_str() };
            if name.is_empty() {
                return Err(Error::at_line(
                    source,
                    lines[k],
                    "the material is empty (only the last row may leave it out)",
                    "name the material of the segment that starts at this vertex",
                ));
            }
            let idx = match names.iter().position(|n| n == name) {
                Some(i) => i,
                None => {
                    names.push(name.to_string());
                    names.len() - 1
                }
            };
            seg_mat.push(idx);
        }
        // Re-run the geometric checks with line numbers in the messages.
        for i in 1..vertices.len() {
            let start = i.saturating_sub(2);
            let sub = &vertices[start..=i];
            let mats = vec![0; sub.len() - 1];
            if let Err(Error::Format { message, hint, .. }) = Profile::new(sub, mats, vec![String::new()], source) {
                return Err(Error::at_line(source, lines[i], message, hint));
            }
        }
        Profile::new(&vertices, seg_mat, names, source)
    }

    /// The profile of a benched slope. Segments get material 0 (`"face"`) or 1 (`"floor"`).
    ///
    /// # Errors
    /// When the geometry is out of range (see [`BenchGeometry::validate`]).
    pub fn from_bench(geometry: &BenchGeometry) -> Result<Profile> {
        geometry.validate("bench.")?;
        let verts = geometry.profile();
        let xz: Vec<[f64; 2]> = verts.iter().map(|v| [v.x_m, v.z_m]).collect();
        let mats = verts[..verts.len() - 1]
            .iter()
            .map(|v| match v.part {
                BenchPart::Face => 0,
                BenchPart::Floor => 1,
            })
            .collect();
        Profile::new(&xz, mats, vec!["face".into(), "floor".into()], "bench profile")
    }

    /// A profile along a section line through a 3D surface.
    ///
    /// x is the horizontal distance along `polyline_xy` (map coordinates, m). The surface is sampled every
    /// `spacing_m` along the line and at each of its vertices; `surface(x, y)` returns the elevation (m) and the
    /// material name there, or `None` off the surface. A segment's material is sampled at its midpoint.
    ///
    /// # Errors
    /// Fewer than 2 distinct points, a spacing that is not positive or that gives more than [`MAX_STATIONS`]
    /// samples, or the surface missing somewhere on the line.
    pub fn from_section(
        polyline_xy: &[[f64; 2]],
        spacing_m: f64,
        surface: impl Fn(f64, f64) -> Option<(f64, String)>,
    ) -> Result<Profile> {
        if !(spacing_m.is_finite() && spacing_m > 0.0) {
            return Err(Error::invalid(
                "section.spacing_m",
                format!("must be a positive number of metres, got {spacing_m}"),
                "sample every 1 m or so",
            ));
        }
        if polyline_xy.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::invalid("section.line", "has a coordinate that is not finite", "give plain numbers"));
        }
        // Distances along the line: every spacing, plus every polyline vertex.
        let mut legs = Vec::new(); // (start s, start point, unit direction, length)
        let mut total = 0.0;
        for w in polyline_xy.windows(2) {
            let (dx, dy) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
            let len = dx.hypot(dy);
            if len > 0.0 {
                legs.push((total, w[0], [dx / len, dy / len], len));
                total += len;
            }
        }
        if legs.is_empty() {
            return Err(Error::invalid(
                "section.line",
                "needs at least two distinct points",
                "give the section as a polyline of two or more (x, y) points",
            ));
        }
        check_station_count("section.spacing_m", spacing_m, total, " (--spacing-m), or a shorter --line")?;
        let mut s_list: Vec<f64> = Vec::new();
        let n_steps = (total / spacing_m).floor() as usize;
        s_list.extend((0..=n_steps).map(|k| k as f64 * spacing_m));
        s_list.extend(legs.iter().map(|l| l.0));
        s_list.push(total);
        s_list.sort_by(f64::total_cmp);
        let tol = 1e-9 * total.max(1.0);
        s_list.dedup_by(|b, a| (*b - *a).abs() <= tol);
        let point_at = |s: f64| {
            let leg = legs.iter().rev().find(|l| l.0 <= s).unwrap_or(&legs[0]);
            let d = (s - leg.0).min(leg.3);
            [leg.1[0] + leg.2[0] * d, leg.1[1] + leg.2[1] * d]
        };
        let sample = |s: f64| {
            let p = point_at(s);
            surface(p[0], p[1]).filter(|(z, _)| z.is_finite()).ok_or_else(|| {
                Error::invalid(
                    "section.line",
                    format!(
                        "the surface is missing at {s:.3} m along the line, at (x, y) = ({:.3}, {:.3})",
                        p[0], p[1]
                    ),
                    "keep the section line inside the surface, or fill the gap in the surface",
                )
            })
        };
        let mut vertices = Vec::with_capacity(s_list.len());
        for &s in &s_list {
            vertices.push([s, sample(s)?.0]);
        }
        let mut names: Vec<String> = Vec::new();
        let mut seg_mat = Vec::with_capacity(s_list.len() - 1);
        for w in s_list.windows(2) {
            let name = sample(0.5 * (w[0] + w[1]))?.1;
            let idx = names.iter().position(|n| *n == name).unwrap_or_else(|| {
                names.push(name);
                names.len() - 1
            });
            seg_mat.push(idx);
        }
        Profile::new(&vertices, seg_mat, names, "section")
    }

    /// Writes the profile as CSV (`x_m,z_m,material`; the last row repeats the last segment's material).
    ///
    /// # Errors
    /// I/O errors.
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        crate::io::write_atomic(path, |w| self.write_csv_to(w).map_err(|e| Error::io(path, e)))
    }

    /// Writes the CSV form to any writer.
    ///
    /// # Errors
    /// I/O errors of the writer.
    pub fn write_csv_to<W: Write>(&self, w: &mut W) -> std::io::Result<()> {
        writeln!(w, "x_m,z_m,material")?;
        for i in 0..self.n_vertices() {
            let m = self.segment_material[i.min(self.n_segments() - 1)];
            writeln!(w, "{},{},{}", self.x_m[i], self.z_m[i], self.material_names[m])?;
        }
        Ok(())
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.x_m.len()
    }

    /// Number of segments (vertices − 1).
    pub fn n_segments(&self) -> usize {
        self.x_m.len() - 1
    }

    /// Vertex x coordinates, m (non-decreasing).
    pub fn x_m(&self) -> &[f64] {
        &self.x_m
    }

    /// Vertex elevations, m.
    pub fn z_m(&self) -> &[f64] {
        &self.z_m
    }

    /// Vertex `i` as `[x_m, z_m]`.
    pub fn vertex(&self, i: usize) -> [f64; 2] {
        [self.x_m[i], self.z_m[i]]
    }

    /// Material index of each segment (into [`Profile::material_names`]).
    pub fn segment_materials(&self) -> &[usize] {
        &self.segment_material
    }

    /// Material names, in order of first appearance.
    pub fn material_names(&self) -> &[String] {
        &self.material_names
    }

    /// The x range `(first, last)` of the profile, m.
    pub fn x_range_m(&self) -> (f64, f64) {
        (self.x_m[0], self.x_m[self.x_m.len() - 1])
    }

    /// The segments whose x range contains `x_m`, as an index range (empty outside the profile). A position on a
    /// vertex belongs to both segments that meet there, and a vertical segment at that x too.
    pub fn segments_at(&self, x_m: f64) -> std::ops::Range<usize> {
        let a = self.x_m.partition_point(|&v| v < x_m);
        let b = self.x_m.partition_point(|&v| v <= x_m);
        let first = a.max(1) - 1;
        let end = b.min(self.n_segments());
        first..end.max(first)
    }

    /// Elevation of the ground surface at `x_m`, m: the highest point of the profile at that x (the top of a
    /// vertical step). `None` outside the profile.
    pub fn z_at(&self, x_m: f64) -> Option<f64> {
        let mut best: Option<f64> = None;
        for i in self.segments_at(x_m) {
            let (x0, x1, z0, z1) = (self.x_m[i], self.x_m[i + 1], self.z_m[i], self.z_m[i + 1]);
            let z = if x1 > x0 { z0 + (z1 - z0) * ((x_m - x0) / (x1 - x0)).clamp(0.0, 1.0) } else { z0.max(z1) };
            best = Some(best.map_or(z, |b: f64| b.max(z)));
        }
        best
    }
}

/// The last vertex's material is ignored (it starts no segment), so a last row may leave it out: such a row gets an
/// empty field, since the CSV reader refuses rows shorter than the header.
fn with_last_material(text: Vec<u8>) -> Vec<u8> {
    let Ok(s) = std::str::from_utf8(&text) else { return text };
    let lines: Vec<&str> = s.lines().collect();
    let (Some(header), Some(k)) = (lines.first(), lines.iter().rposition(|l| !l.trim().is_empty())) else {
        return text;
    };
    let ends_in_material = header.rsplit(',').next().is_some_and(|c| c.trim() == "material");
    if k == 0 || !ends_in_material || lines[k].split(',').count() + 1 != header.split(',').count() {
        return text;
    }
    let mut out = lines[..k].join("\n");
    out.push_str(&format!("\n{},\n", lines[k].trim_end()));
    out.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csv(text: &str) -> Result<Profile> {
        Profile::from_csv_reader(text.as_bytes(), "p.csv")
    }

    #[test]
    fn the_last_row_may_leave_out_its_material_but_no_other_row() {
        let p = csv("x_m,z_m,material\n0,10,rock\n10,0\n").unwrap();
        assert_eq!(p.n_segments(), 1);
        let e = csv("x_m,z_m,material\n0,10\n10,0,rock\n").unwrap_err().to_string();
        assert!(e.contains("p.csv:2"), "{e}");
    }

    #[test]
    fn reads_csv_with_materials_and_vertical_steps() {
        let p = csv("x_m,z_m,material\n0,10,rock\n5,10,rock\n5,0,soil\n20,-1,rock\n30,-1,\n").unwrap();
        assert_eq!(p.n_segments(), 4);
        assert_eq!(p.material_names(), &["rock".to_string(), "soil".to_string()]);
        assert_eq!(p.segment_materials(), &[0, 0, 1, 0]);
        assert_eq!(p.z_at(5.0), Some(10.0));
        assert_eq!(p.z_at(12.5), Some(-0.5));
        assert_eq!(p.z_at(31.0), None);
        assert_eq!(p.segments_at(5.0), 0..3);
        assert_eq!(p.segments_at(0.0), 0..1);
        assert_eq!(p.segments_at(30.0), 3..4);
        assert_eq!(p.segments_at(-1.0).len(), 0);
    }

    #[test]
    fn csv_errors_name_the_line() {
        let e = csv("x_m,z_m,material\n0,10,a\n5,9,a\n4,8,a\n").unwrap_err().to_string();
        assert!(e.contains("p.csv:4") && e.contains("less than"), "{e}");
        let e = csv("x_m,z_m,material\n0,10,a\nfive,9,a\n").unwrap_err().to_string();
        assert!(e.contains("p.csv:3") && e.contains("five"), "{e}");
        let e = csv("x_m,z_m,material\n0,10,a\n1,9,\n2,8,a\n").unwrap_err().to_string();
        assert!(e.contains("p.csv:3") && e.contains("empty"), "{e}");
        let e = csv("x,z\n0,1\n").unwrap_err().to_string();
        assert!(e.contains("p.csv:1"), "{e}");
        let e = csv("x_m,z_m,material\n0,10,a\n0,5,a\n0,8,a\n").unwrap_err().to_string();
        assert!(e.contains("p.csv:4") && e.contains("turns back"), "{e}");
    }

    #[test]
    fn csv_round_trip() {
        let p = csv("x_m,z_m,material\n0,10,rock\n5,10,rock\n5,0,soil\n20,-1.25,rock\n").unwrap();
        let mut buf = Vec::new();
        p.write_csv_to(&mut buf).unwrap();
        let q = Profile::from_csv_reader(buf.as_slice(), "q").unwrap();
        assert_eq!(p, q);
    }

    #[test]
    fn bench_profile_has_face_and_floor() {
        let p = Profile::from_bench(&BenchGeometry::default()).unwrap();
        assert_eq!(p.material_names(), &["face".to_string(), "floor".to_string()]);
        assert_eq!(p.segment_materials()[0], 1);
        assert_eq!(p.segment_materials()[1], 0);
    }

    #[test]
    fn section_samples_every_spacing_and_at_vertices() {
        let p = Profile::from_section(&[[0.0, 0.0], [3.0, 4.0], [3.0, 6.5]], 2.0, |x, y| {
            Some((100.0 - x - y, if x < 2.0 { "a".to_string() } else { "b".to_string() }))
        })
        .unwrap();
        assert_eq!(p.x_m(), &[0.0, 2.0, 4.0, 5.0, 6.0, 7.5]);
        assert!((p.z_m()[3] - 93.0).abs() < 1e-12);
        assert_eq!(p.material_names(), &["a".to_string(), "b".to_string()]);
        let e = Profile::from_section(&[[0.0, 0.0], [10.0, 0.0]], 1.0, |x, _| (x < 5.5).then(|| (0.0, "a".into())))
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing at 6.000 m"), "{e}");
    }
}
