//! The benched slope of the paper (a stack of faces and catch benches), as a 2D profile and as a 3D mesh.
//!
//! # Units
//! Lengths in m, angles in degrees. x runs downslope, z up; the profile starts at the crest floor.

use crate::error::{number_text, Error, Result};

/// Most triangles of a bench mesh ([`BenchGeometry::mesh`]). Ours: 10⁷ triangles hold about 0.5 GB as a mesh
/// (vertices, triangles, groups) and several times that once the 3DRB terrain is built from it, and are a
/// 10 cm edge over the default 100 m × 300 m stack: finer than any rock that runs on it needs.
pub const MAX_MESH_TRIANGLES: usize = 10_000_000;
/// Longest length of a bench geometry, m (ours: ten kilometres, past any pit; a huge bench height overflowed the
/// mesh count and was blamed on `max_edge_m`).
pub const MAX_LENGTH_M: f64 = 10_000.0;

/// Geometry of a benched slope. Defaults are the paper's stack: 5 benches of 20 m at 60° with 7 m catch benches.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BenchGeometry {
    /// Vertical height of each face, m (default: 20).
    pub bench_height_m: f64,
    /// Face angle from horizontal, degrees (default: 60).
    pub face_angle_deg: f64,
    /// Horizontal width of each catch bench, m (default: 7).
    pub bench_width_m: f64,
    /// Number of face + catch-bench pairs (default: 5). Below the last catch bench one more face of the same height
    /// drops to the toe floor, so that a rock the last bench does not catch leaves the stack ("bench 0").
    pub n_benches: usize,
    /// Width of the flat floor behind the top crest, m (default: 10).
    pub crest_floor_m: f64,
    /// Width of the flat run-out floor after the last toe, m (default: 60).
    pub toe_floor_m: f64,
    /// Lateral width of the 3D mesh (y extent), m (default: 100).
    pub lateral_width_m: f64,
    /// Largest triangle edge along x and y in the 3D mesh, m (default: 2.5).
    pub max_edge_m: f64,
}

impl Default for BenchGeometry {
    fn default() -> Self {
        BenchGeometry {
            bench_height_m: 20.0,
            face_angle_deg: 60.0,
            bench_width_m: 7.0,
            n_benches: 5,
            crest_floor_m: 10.0,
            toe_floor_m: 60.0,
            lateral_width_m: 100.0,
            max_edge_m: 2.5,
        }
    }
}

/// What a profile segment is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BenchPart {
    /// A bench face.
    Face,
    /// A floor: crest floor, catch bench or toe floor.
    Floor,
}

/// One vertex of a bench profile; `part` is that of the segment that starts here.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileVertex {
    /// Distance along the slope, m.
    pub x_m: f64,
    /// Elevation, m.
    pub z_m: f64,
    /// The segment starting at this vertex.
    pub part: BenchPart,
    /// Which bench this segment belongs to: 0 for the crest floor, k for face k and the bench below it.
    pub bench: usize,
}

impl BenchGeometry {
    /// Checks ranges; `prefix` is prepended to field names in errors.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let field = |name: &str| format!("{prefix}{name}");
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 && v <= MAX_LENGTH_M {
                Ok(())
            } else {
                Err(Error::invalid(
                    field(name),
                    format!("must be a positive number of metres up to {MAX_LENGTH_M}, got {}", number_text(v)),
                    "set a value above 0 and up to 10 km",
                ))
            }
        };
        positive("bench_height_m", self.bench_height_m)?;
        positive("lateral_width_m", self.lateral_width_m)?;
        positive("max_edge_m", self.max_edge_m)?;
        if !(self.face_angle_deg > 1.0 && self.face_angle_deg < 89.9) {
            return Err(Error::invalid(
                field("face_angle_deg"),
                format!("must be between 1 and 89.9 degrees, got {}", self.face_angle_deg),
                "give the face angle from horizontal, e.g. 60",
            ));
        }
        for (name, v) in [
            ("bench_width_m", self.bench_width_m),
            ("crest_floor_m", self.crest_floor_m),
            ("toe_floor_m", self.toe_floor_m),
        ] {
            if !(v.is_finite() && (0.0..=MAX_LENGTH_M).contains(&v)) {
                return Err(Error::invalid(
                    field(name),
                    format!("must be 0 to {MAX_LENGTH_M} metres, got {}", number_text(v)),
                    "set a width from 0 to 10 km",
                ));
            }
        }
        if self.n_benches == 0 {
            return Err(Error::invalid(field("n_benches"), "must be at least 1", "give 1 or more benches"));
        }
        self.check_mesh_size(prefix)
    }

    /// Refuses a geometry whose 3D mesh would have more than [`MAX_MESH_TRIANGLES`] triangles, counted without
    /// building it. The error names the value that, back at its default, lets the mesh fit (finer edges first, then
    /// a wider mesh), else `n_benches`, and says how far that value may go with the others as given.
    fn check_mesh_size(&self, prefix: &str) -> Result<()> {
        let triangles = self.mesh_triangle_count(self.max_edge_m);
        if triangles <= MAX_MESH_TRIANGLES as f64 {
            return Ok(());
        }
        let default = BenchGeometry::default();
        let edges_at_default = BenchGeometry { max_edge_m: default.max_edge_m, ..self.clone() };
        let width_at_default = BenchGeometry { lateral_width_m: default.lateral_width_m, ..self.clone() };
        let most_benches = self.most_benches();
        let edge_hint = |edge_m: f64| {
            format!(
                "give triangle edges of at least {} m (the default is {} m), a narrower lateral width or fewer \
                 benches",
                number_text(edge_m),
                number_text(default.max_edge_m)
            )
        };
        let (key, hint) = match (self.finest_edge_m(), self.widest_lateral_m()) {
            (Some(edge_m), _) if self.max_edge_m < default.max_edge_m && edges_at_default.fits() => {
                ("max_edge_m", edge_hint(edge_m))
            }
            (_, Some(width_m)) if self.lateral_width_m > default.lateral_width_m && width_at_default.fits() => (
                "lateral_width_m",
                format!(
                    "give a lateral width of at most {} m (the default is {} m), longer triangle edges or fewer \
                     benches",
                    number_text(width_m),
                    number_text(default.lateral_width_m)
                ),
            ),
            _ if most_benches >= 1 => (
                "n_benches",
                format!(
                    "give at most {most_benches} benches with these triangle edges and lateral width, or longer \
                     triangle edges or a narrower lateral width for more"
                ),
            ),
            (Some(edge_m), _) => ("max_edge_m", edge_hint(edge_m)),
            (None, _) => ("n_benches", "give fewer benches".to_string()),
        };
        Err(Error::invalid(
            format!("{prefix}{key}"),
            format!(
                "{} benches over a {} m lateral width with {} m triangle edges make {} triangles, more than the \
                 limit of {MAX_MESH_TRIANGLES}",
                self.n_benches,
                number_text(self.lateral_width_m),
                number_text(self.max_edge_m),
                number_text(triangles)
            ),
            hint,
        ))
    }

    /// True if the 3D mesh has at most [`MAX_MESH_TRIANGLES`] triangles.
    fn fits(&self) -> bool {
        self.mesh_triangle_count(self.max_edge_m) <= MAX_MESH_TRIANGLES as f64
    }

    /// The most benches whose mesh fits with the other values as they are (0 if not even 1 does).
    fn most_benches(&self) -> usize {
        let fits = |n: usize| BenchGeometry { n_benches: n, ..self.clone() }.fits();
        let (mut lo, mut hi) = (0, self.n_benches); // fits(lo) or lo = 0; !fits(hi)
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if fits(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        if lo == 0 || fits(lo) {
            lo
        } else {
            0
        }
    }

    /// The shortest triangle edge, to 3 significant digits, whose mesh fits with the other values as they are
    /// (none if no edge up to [`MAX_LENGTH_M`] does). The count never grows with the edge.
    fn finest_edge_m(&self) -> Option<f64> {
        let fits = |edge_m: f64| BenchGeometry { max_edge_m: edge_m, ..self.clone() }.fits();
        if !fits(MAX_LENGTH_M) {
            return None;
        }
        let edge_m = last_fitting(MAX_LENGTH_M, self.max_edge_m, fits);
        let rounded = crate::error::round_up_3_digits(edge_m);
        Some(if fits(rounded) { rounded } else { edge_m })
    }

    /// The widest lateral width, in whole millimetres, whose mesh fits with the other values as they are (none if
    /// not even a millimetre does). The count never falls as the width grows.
    fn widest_lateral_m(&self) -> Option<f64> {
        let fits = |width_m: f64| BenchGeometry { lateral_width_m: width_m, ..self.clone() }.fits();
        let rounded = (last_fitting(0.0, self.lateral_width_m, fits) * 1000.0).floor() / 1000.0;
        (rounded > 0.0 && fits(rounded)).then_some(rounded)
    }

    /// Number of triangles of [`BenchGeometry::mesh`] with edges of at most `max_edge_m`, from the segment
    /// lengths alone (as f64, so that any geometry is counted without overflow or allocation). A segment whose
    /// length is a whole number of edges may get one piece more in the mesh, from rounding.
    pub fn mesh_triangle_count(&self, max_edge_m: f64) -> f64 {
        let pieces = |len_m: f64| (len_m / max_edge_m).ceil().max(1.0);
        let floor = |width_m: f64| if width_m > 0.0 { pieces(width_m) } else { 0.0 };
        let face_m = self.face_run_m().hypot(self.bench_height_m);
        let segments = floor(self.crest_floor_m)
            + self.n_faces() as f64 * pieces(face_m)
            + self.n_benches as f64 * floor(self.bench_width_m)
            + floor(self.toe_floor_m);
        let rows = (self.lateral_width_m / max_edge_m).ceil().max(1.0);
        2.0 * segments * rows
    }

    /// Horizontal run of one face, m.
    pub fn face_run_m(&self) -> f64 {
        self.bench_height_m / self.face_angle_deg.to_radians().tan()
    }

    /// Number of faces: one per bench plus the face below the last bench.
    pub fn n_faces(&self) -> usize {
        self.n_benches + 1
    }

    /// Total height from the crest floor to the toe floor, m.
    pub fn total_height_m(&self) -> f64 {
        self.bench_height_m * self.n_faces() as f64
    }

    /// The profile vertices from the back of the crest floor to the end of the toe floor. The top crest is at
    /// x = `crest_floor_m`, z = total height; the toe floor is at z = 0.
    pub fn profile(&self) -> Vec<ProfileVertex> {
        let run = self.face_run_m();
        let mut z = self.total_height_m();
        let mut x = 0.0;
        let mut out = Vec::new();
        if self.crest_floor_m > 0.0 {
            out.push(ProfileVertex { x_m: x, z_m: z, part: BenchPart::Floor, bench: 0 });
            x += self.crest_floor_m;
        }
        for k in 1..=self.n_faces() {
            let bench = if k > self.n_benches { 0 } else { k };
            out.push(ProfileVertex { x_m: x, z_m: z, part: BenchPart::Face, bench });
            x += run;
            z -= self.bench_height_m;
            let width = if bench == 0 { self.toe_floor_m } else { self.bench_width_m };
            if width > 0.0 {
                out.push(ProfileVertex { x_m: x, z_m: z, part: BenchPart::Floor, bench });
                x += width;
            }
        }
        let last = *out.last().expect("at least one face");
        out.push(ProfileVertex { x_m: x, z_m: z, ..last });
        out
    }

    /// x of the crest of face `k` (1-based) and of its toe.
    pub fn face_span_m(&self, k: usize) -> (f64, f64) {
        let crest = self.crest_floor_m + (k - 1) as f64 * (self.face_run_m() + self.bench_width_m);
        (crest, crest + self.face_run_m())
    }

    /// Which bench a horizontal position x belongs to: k in 1..=n_benches from the middle of face k to the middle
    /// of face k + 1 (the lower half of face k, where a rock rests against the toe of catch bench k, the catch
    /// bench, and the upper half of face k + 1, where a rock hangs on the bench's outer edge), 0 past the last
    /// bench. Positions before the middle of face 1 count as 1 (the bench study counts them as the crest's).
    pub fn bench_at(&self, x_m: f64) -> usize {
        for k in 1..=self.n_benches {
            let (_, toe) = self.face_span_m(k);
            if x_m <= toe + self.bench_width_m + 0.5 * self.face_run_m() {
                return k;
            }
        }
        0
    }
}

impl BenchGeometry {
    /// The 3D mesh: the profile extruded over `lateral_width_m` in y (from 0), segments cut into pieces no longer
    /// than `max_edge_m`, triangles counter-clockwise seen from above, in groups `face` and `floor`.
    #[allow(clippy::needless_range_loop)] // i indexes the stations and the vertex grid alike
    pub fn mesh(&self) -> crate::io::MeshData {
        let profile = self.profile();
        // Stations along x with their part (of the segment starting there).
        let mut stations: Vec<(f64, f64, BenchPart)> = Vec::new();
        for w in profile.windows(2) {
            let (a, b) = (w[0], w[1]);
            let len = ((b.x_m - a.x_m).powi(2) + (b.z_m - a.z_m).powi(2)).sqrt();
            let pieces = ((len / self.max_edge_m).ceil() as usize).max(1);
            for k in 0..pieces {
                let f = k as f64 / pieces as f64;
                stations.push((a.x_m + f * (b.x_m - a.x_m), a.z_m + f * (b.z_m - a.z_m), a.part));
            }
        }
        let last = profile[profile.len() - 1];
        stations.push((last.x_m, last.z_m, last.part));
        let ny = ((self.lateral_width_m / self.max_edge_m).ceil() as usize).max(1);
        let mut vertices = Vec::with_capacity(stations.len() * (ny + 1));
        for j in 0..=ny {
            let y = self.lateral_width_m * j as f64 / ny as f64;
            for &(x, z, _) in &stations {
                vertices.push([x, y, z]);
            }
        }
        let nx = stations.len();
        let id = |i: usize, j: usize| (j * nx + i) as u32;
        let (mut triangles, mut group) = (Vec::new(), Vec::new());
        for j in 0..ny {
            for (i, station) in stations.iter().enumerate().take(nx - 1) {
                let g = if station.2 == BenchPart::Face { 0 } else { 1 };
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                group.extend([g, g]);
            }
        }
        let n = triangles.len();
        crate::io::MeshData {
            vertices,
            triangles,
            group,
            group_names: vec!["face".into(), "floor".into()],
            material: vec![0; n],
            material_names: vec![String::new()],
        }
    }
}

/// Writes the bench profile as a CSV profile (`x_m,z_m,material`, materials `face` and `floor`).
pub fn write_profile_csv(g: &BenchGeometry, path: &std::path::Path) -> Result<()> {
    use std::io::Write;
    crate::io::write_atomic(path, |w| {
        let err = |e| Error::io(path, e);
        writeln!(w, "x_m,z_m,material").map_err(err)?;
        for v in g.profile() {
            let m = if v.part == BenchPart::Face { "face" } else { "floor" };
            writeln!(w, "{},{},{m}", v.x_m, v.z_m).map_err(err)?;
        }
        Ok(())
    })
}

/// The value nearest `bad` that still fits, between `good` (fits) and `bad` (does not), to the last bit: 100
/// bisections.
fn last_fitting(mut good: f64, mut bad: f64, fits: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..100 {
        let mid = 0.5 * (good + bad);
        if fits(mid) {
            good = mid;
        } else {
            bad = mid;
        }
    }
    good
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_stack_profile() {
        let g = BenchGeometry::default();
        let p = g.profile();
        assert!((p.last().unwrap().z_m).abs() < 1e-12);
        let run = 20.0 / 60f64.to_radians().tan();
        assert_eq!(p.first().unwrap().z_m, 120.0);
        let expected_len = 10.0 + 6.0 * run + 5.0 * 7.0 + 60.0;
        assert!((p.last().unwrap().x_m - expected_len).abs() < 1e-9);
        assert_eq!(p.iter().filter(|v| v.part == BenchPart::Face).count(), 6);
        assert_eq!(g.bench_at(g.face_span_m(1).1 + 1.0), 1);
        assert_eq!(g.bench_at(g.face_span_m(2).1 + 1.0), 2);
        // The upper half of face k + 1 belongs with bench k (a rock hanging on its outer edge), the lower half with
        // bench k + 1.
        let (crest2, toe2) = g.face_span_m(2);
        assert_eq!(g.bench_at(crest2 + 0.4 * (toe2 - crest2)), 1);
        assert_eq!(g.bench_at(crest2 + 0.6 * (toe2 - crest2)), 2);
        assert_eq!(g.bench_at(g.face_span_m(5).1 + 7.1), 5);
        assert_eq!(g.bench_at(g.face_span_m(5).1 + 7.0 + 0.6 * run), 0);
    }

    #[test]
    fn mesh_is_the_extruded_profile() {
        let g = BenchGeometry::default();
        let m = g.mesh();
        assert_eq!(m.triangles.len(), m.group.len());
        let xmax = m.vertices.iter().map(|v| v[0]).fold(0.0, f64::max);
        assert!((xmax - g.profile().last().unwrap().x_m).abs() < 1e-9);
        // Every triangle is counter-clockwise from above (or vertical) and no longer than max_edge in x and y.
        for t in &m.triangles {
            let [a, b, c] = t.map(|k| m.vertices[k as usize]);
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
            assert!(det > 0.0);
        }
        assert!(m.group.contains(&0) && m.group.contains(&1));
    }

    #[test]
    fn triangles_are_counted_before_the_mesh_is_built() {
        for g in [
            BenchGeometry::default(),
            BenchGeometry { max_edge_m: 1.3, n_benches: 2, lateral_width_m: 33.0, ..Default::default() },
        ] {
            let (counted, built) = (g.mesh_triangle_count(g.max_edge_m), g.mesh().triangles.len() as f64);
            // Within one piece per segment (4 segments a bench at most) of every row.
            let rows = (g.lateral_width_m / g.max_edge_m).ceil();
            assert!((counted - built).abs() <= 2.0 * rows * (g.n_benches as f64 * 2.0 + 4.0), "{counted} vs {built}");
        }
        let fine = BenchGeometry { max_edge_m: 0.001, ..Default::default() };
        let e = fine.validate("geometry.").unwrap_err().to_string();
        assert!(e.contains("geometry.max_edge_m") && e.contains("more than the limit"), "{e}");
        let many = BenchGeometry { n_benches: 100_000_000, ..Default::default() };
        assert!(many.validate("").unwrap_err().to_string().starts_with("n_benches"));
    }

    /// Too many triangles are blamed on the value that was changed, with the most it may be: more benches (it
    /// blamed the default triangle edges), a wider mesh, or finer edges.
    #[test]
    fn a_mesh_too_large_names_the_value_changed_and_how_far_it_may_go() {
        let many = BenchGeometry { n_benches: 100_000, ..Default::default() };
        let e = many.validate("").unwrap_err().to_string();
        let most = many.most_benches();
        assert!(e.starts_with("n_benches:") && e.contains(&format!("give at most {most} benches")), "{e}");
        assert!(BenchGeometry { n_benches: most, ..many.clone() }.fits());
        assert!(!BenchGeometry { n_benches: most + 1, ..many }.fits());
        let wide = BenchGeometry { lateral_width_m: 10_000.0, bench_height_m: 10_000.0, ..Default::default() };
        let e = wide.validate("").unwrap_err().to_string();
        assert!(e.starts_with("lateral_width_m:") && e.contains("a lateral width of at most"), "{e}");
        let width = wide.widest_lateral_m().unwrap();
        assert!(BenchGeometry { lateral_width_m: width, ..wide.clone() }.fits());
        assert!(!BenchGeometry { lateral_width_m: width + 0.01, ..wide }.fits());
        let fine = BenchGeometry { max_edge_m: 0.01, ..Default::default() };
        let e = fine.validate("").unwrap_err().to_string();
        let edge = fine.finest_edge_m().unwrap();
        assert!(e.starts_with("max_edge_m:") && e.contains(&format!("edges of at least {}", number_text(edge))), "{e}");
        assert!(BenchGeometry { max_edge_m: edge, ..fine }.fits());
    }
}
