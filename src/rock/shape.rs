//! Rock shapes as convex polyhedra, and their exact mass properties.
//!
//! Shapes are built at unit size, then scaled to a mass (through the density) or to given dimensions. Mass, centre
//! of mass and principal inertia are those of the polyhedron itself (parry's exact convex-polyhedron integrals),
//! and the body frame is the principal frame with the centre of mass at its origin.
//!
//! # Default proportions (our choice, documented)
//! - `cube`: 1 : 1 : 1.
//! - `flat_box`: 1 : 0.6 : 0.3. In Zingg's (1935) shape classes, b/a = 0.6 < 2/3 and c/b = 0.5 < 2/3 make it
//!   *bladed*: elongated **and** flat, the "elongated flat box" of the seed paper's design study.
//! - `smartie`: an oblate lens with thickness/diameter 0.45 (a confectionery smartie is about 6 mm by 14 mm),
//!   30 vertices: a 10-vertex equator and two 7- and 3-vertex rings on each cap, each ring twisted against the
//!   one below so that the facets are irregular. Angular, like a real lens-shaped block, not a smooth ellipsoid.

use crate::error::{Error, Result};
use nalgebra::{Point3, Vector3};
use parry3d_f64::mass_properties::MassProperties;

/// Density of rock used when only a mass is given, kg/m³ (default for granite-like rock, as in the seed paper).
pub const DEFAULT_DENSITY_KG_M3: f64 = 2650.0;

/// A named shape family; the polyhedron is built at unit scale by [`ShapeKind::unit_points`].
#[derive(Debug, Clone, PartialEq)]
pub enum ShapeKind {
    /// Cube.
    Cube,
    /// Bladed box 1 : 0.6 : 0.3.
    FlatBox,
    /// Oblate angular lens, 30 vertices.
    Smartie,
    /// The convex hull of user points (read from an OBJ, STL or point file); `name` is what the user called it.
    Hull {
        /// Name shown in outputs (the file stem).
        name: String,
        /// The points, any frame and scale.
        points: Vec<[f64; 3]>,
    },
}

impl ShapeKind {
    /// The name written to outputs.
    pub fn name(&self) -> &str {
        match self {
            ShapeKind::Cube => "cube",
            ShapeKind::FlatBox => "flat_box",
            ShapeKind::Smartie => "smartie",
            ShapeKind::Hull { name, .. } => name,
        }
    }

    /// Parses a built-in shape name.
    pub fn builtin(name: &str) -> Option<ShapeKind> {
        match name {
            "cube" => Some(ShapeKind::Cube),
            "flat_box" => Some(ShapeKind::FlatBox),
            "smartie" => Some(ShapeKind::Smartie),
            _ => None,
        }
    }

    /// Points of the shape at unit scale (longest dimension about 1 m).
    pub fn unit_points(&self) -> Vec<Point3<f64>> {
        match self {
            ShapeKind::Cube => box_points(1.0, 1.0, 1.0),
            ShapeKind::FlatBox => box_points(1.0, 0.6, 0.3),
            ShapeKind::Smartie => smartie_points(0.5, 0.225),
            ShapeKind::Hull { points, .. } => points.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect(),
        }
    }
}

fn box_points(a: f64, b: f64, c: f64) -> Vec<Point3<f64>> {
    let mut out = Vec::with_capacity(8);
    for sx in [-0.5, 0.5] {
        for sy in [-0.5, 0.5] {
            for sz in [-0.5, 0.5] {
                out.push(Point3::new(sx * a, sy * b, sz * c));
            }
        }
    }
    out
}

/// Oblate lens: equator of 10 vertices, rings of 7 at 45° and 3 at 75° latitude on each cap (latitudes on the
/// ellipsoid x²/r² + y²/r² + z²/h² = 1), rings twisted by half a step.
fn smartie_points(radius: f64, half_thickness: f64) -> Vec<Point3<f64>> {
    let mut out = Vec::with_capacity(30);
    let rings: [(f64, usize, f64); 5] =
        [(0.0, 10, 0.0), (45.0, 7, 0.5), (-45.0, 7, 0.25), (75.0, 3, 0.0), (-75.0, 3, 0.5)];
    for (lat_deg, n, twist) in rings {
        let lat = lat_deg.to_radians();
        for k in 0..n {
            let lon = std::f64::consts::TAU * (k as f64 + twist) / n as f64;
            out.push(Point3::new(
                radius * lat.cos() * lon.cos(),
                radius * lat.cos() * lon.sin(),
                half_thickness * lat.sin(),
            ));
        }
    }
    out
}

/// How big a rock is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RockSize {
    /// A mass: the shape is scaled so that its volume times the density gives it.
    Mass {
        /// Mass, kg.
        mass_kg: f64,
        /// Density, kg/m³.
        density_kg_m3: f64,
    },
    /// Bounding dimensions along the shape's own x, y, z (longest first for built-ins), and a density.
    Dimensions {
        /// Dimensions, m.
        size_m: [f64; 3],
        /// Density, kg/m³.
        density_kg_m3: f64,
    },
    /// Bounding dimensions, with the density chosen so that the polyhedron has exactly this mass.
    DimensionsAndMass {
        /// Dimensions, m.
        size_m: [f64; 3],
        /// Mass, kg.
        mass_kg: f64,
    },
}

/// A rigid rock ready for the engine: a convex polyhedron in its principal frame.
#[derive(Debug, Clone, PartialEq)]
pub struct RockBody {
    /// Shape name for outputs.
    pub shape: String,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Principal moments of inertia about the centre of mass, kg·m².
    pub inertia_kg_m2: Vector3<f64>,
    /// Hull vertices in the body frame (principal axes, centre of mass at the origin), m.
    pub vertices_m: Vec<Vector3<f64>>,
    /// Outward face planes of the hull in the body frame: (unit normal, offset) with n·x ≤ offset inside.
    pub faces: Vec<(Vector3<f64>, f64)>,
    /// Largest distance from the centre of mass to a vertex, m.
    pub bounding_radius_m: f64,
    /// Volume, m³.
    pub volume_m3: f64,
    /// Bounding box dimensions in the body frame, sorted longest first, m.
    pub extents_m: [f64; 3],
}

impl RockBody {
    /// Builds a rock of `kind` and `size`. `field` names the rock settings in errors.
    pub fn new(kind: &ShapeKind, size: RockSize, field: &str) -> Result<RockBody> {
        let unit = kind.unit_points();
        if unit.len() < 4 || unit.iter().any(|p| !p.coords.iter().all(|c| c.is_finite())) {
            return Err(Error::invalid(
                field,
                format!("shape '{}' needs at least 4 finite points, got {}", kind.name(), unit.len()),
                "give a hull file with at least 4 points that are not all in one plane",
            ));
        }
        // Scale the shape to the requested bounding dimensions first (if any), at unit density.
        let (lo, hi) = bbox(&unit);
        let ext = hi - lo;
        let points: Vec<Point3<f64>> = match size {
            RockSize::Dimensions { size_m, .. } | RockSize::DimensionsAndMass { size_m, .. } => {
                check_positive(field, "size_m", &size_m)?;
                // Match the sorted extents of the shape to the sorted requested sizes.
                let order = sorted_axes(&ext);
                let mut target = size_m;
                target.sort_by(|a, b| b.total_cmp(a));
                let mut scale = Vector3::zeros();
                for (rank, &axis) in order.iter().enumerate() {
                    scale[axis] = if ext[axis] > 0.0 { target[rank] / ext[axis] } else { 0.0 };
                }
                unit.iter().map(|p| Point3::from(p.coords.component_mul(&scale))).collect()
            }
            RockSize::Mass { .. } => unit,
        };
        let (hull_pts, hull_tris) = parry3d_f64::transformation::try_convex_hull(&points).map_err(|_| {
            Error::invalid(
                field,
                format!(
                    "the points of shape '{}' have no convex hull: they coincide, lie on a line or in one plane",
                    kind.name()
                ),
                "give at least 4 distinct points that span a volume (the corners of the block, say)",
            )
        })?;
        let mp = MassProperties::from_convex_polyhedron(1.0, &hull_pts, &hull_tris);
        let unit_volume = mp.mass();
        if !(unit_volume.is_finite() && unit_volume > 1e-12) {
            return Err(Error::invalid(
                field,
                format!("shape '{}' has no volume (its points are flat or collinear)", kind.name()),
                "give points that span a volume",
            ));
        }
        let (scale, density) = match size {
            RockSize::Mass { mass_kg, density_kg_m3 } => {
                check_positive(field, "mass_kg", &[mass_kg])?;
                check_positive(field, "density_kg_m3", &[density_kg_m3])?;
                ((mass_kg / density_kg_m3 / unit_volume).cbrt(), density_kg_m3)
            }
            RockSize::Dimensions { density_kg_m3, .. } => {
                check_positive(field, "density_kg_m3", &[density_kg_m3])?;
                (1.0, density_kg_m3)
            }
            RockSize::DimensionsAndMass { mass_kg, .. } => {
                check_positive(field, "mass_kg", &[mass_kg])?;
                (1.0, mass_kg / unit_volume)
            }
        };
        let volume = unit_volume * scale.powi(3);
        let mass = volume * density;
        // Principal inertia at unit density scales with scale^5 and density.
        let inertia = mp.principal_inertia() * density * scale.powi(5);
        let frame = mp.principal_inertia_local_frame;
        let com = mp.local_com;
        let to_body = |p: &Point3<f64>| frame.inverse_transform_vector(&((p - com) * scale));
        let vertices: Vec<Vector3<f64>> = hull_pts.iter().map(to_body).collect();
        let mut faces = Vec::with_capacity(hull_tris.len());
        for t in &hull_tris {
            let (a, b, c) = (vertices[t[0] as usize], vertices[t[1] as usize], vertices[t[2] as usize]);
            let n = (b - a).cross(&(c - a));
            if n.norm() > 1e-14 {
                let n = n.normalize();
                faces.push((n, n.dot(&a)));
            }
        }
        let bounding_radius_m = vertices.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let (blo, bhi) = bbox(&vertices.iter().map(|v| Point3::from(*v)).collect::<Vec<_>>());
        let mut extents_m = [bhi.x - blo.x, bhi.y - blo.y, bhi.z - blo.z];
        extents_m.sort_by(|a, b| b.total_cmp(a));
        Ok(RockBody {
            shape: kind.name().to_string(),
            mass_kg: mass,
            inertia_kg_m2: inertia,
            vertices_m: vertices,
            faces,
            bounding_radius_m,
            volume_m3: volume,
            extents_m,
        })
    }

    /// Radius of the sphere of equal volume, m.
    pub fn equivalent_radius_m(&self) -> f64 {
        (3.0 * self.volume_m3 / (4.0 * std::f64::consts::PI)).cbrt()
    }

    /// Height of the lowest hull vertex relative to the centre of mass in the orientation `rot`, m (negative).
    pub fn lowest_dz_m(&self, rot: &nalgebra::Rotation3<f64>) -> f64 {
        self.vertices_m.iter().map(|b| (rot * b).z).fold(f64::INFINITY, f64::min)
    }
}

fn bbox(points: &[Point3<f64>]) -> (Vector3<f64>, Vector3<f64>) {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(&p.coords);
        hi = hi.sup(&p.coords);
    }
    (lo, hi)
}

/// Axis indices sorted by decreasing extent (stable for ties).
fn sorted_axes(ext: &Vector3<f64>) -> [usize; 3] {
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| ext[b].total_cmp(&ext[a]));
    order
}

fn check_positive(field: &str, name: &str, values: &[f64]) -> Result<()> {
    for &v in values {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::invalid(
                format!("{field}.{name}"),
                format!("must be positive, got {v}"),
                "give a value above 0",
            ));
        }
    }
    Ok(())
}

impl RockBody {
    /// The same shape and density scaled to `mass_kg`.
    pub fn with_mass(&self, mass_kg: f64) -> RockBody {
        let s = (mass_kg / self.mass_kg).cbrt();
        RockBody {
            shape: self.shape.clone(),
            mass_kg,
            inertia_kg_m2: self.inertia_kg_m2 * s.powi(5),
            vertices_m: self.vertices_m.iter().map(|v| v * s).collect(),
            faces: self.faces.iter().map(|(n, d)| (*n, d * s)).collect(),
            bounding_radius_m: self.bounding_radius_m * s,
            volume_m3: self.volume_m3 * s.powi(3),
            extents_m: self.extents_m.map(|e| e * s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn cube_mass_properties_are_exact() {
        let r =
            RockBody::new(&ShapeKind::Cube, RockSize::Mass { mass_kg: 2650.0, density_kg_m3: 2650.0 }, "rock").unwrap();
        assert_relative_eq!(r.mass_kg, 2650.0, max_relative = 1e-12);
        assert_relative_eq!(r.volume_m3, 1.0, max_relative = 1e-12);
        for i in 0..3 {
            assert_relative_eq!(r.inertia_kg_m2[i], 2650.0 / 6.0, max_relative = 1e-9);
        }
        assert_eq!(r.vertices_m.len(), 8);
        assert_relative_eq!(r.bounding_radius_m, 3f64.sqrt() / 2.0, max_relative = 1e-9);
    }

    #[test]
    fn flat_box_dimensions_and_inertia() {
        let size = RockSize::Dimensions { size_m: [0.3, 1.0, 0.6], density_kg_m3: 1000.0 };
        let r = RockBody::new(&ShapeKind::FlatBox, size, "rock").unwrap();
        assert_relative_eq!(r.mass_kg, 180.0, max_relative = 1e-9);
        let mut got: Vec<f64> = r.inertia_kg_m2.iter().copied().collect();
        got.sort_by(f64::total_cmp);
        let m = 180.0;
        let mut want = [m * (0.36 + 0.09) / 12.0, m * (1.0 + 0.09) / 12.0, m * (1.0 + 0.36) / 12.0];
        want.sort_by(f64::total_cmp);
        for i in 0..3 {
            assert_relative_eq!(got[i], want[i], max_relative = 1e-9);
        }
        assert_relative_eq!(r.extents_m[0], 1.0, max_relative = 1e-9);
        assert_relative_eq!(r.extents_m[2], 0.3, max_relative = 1e-9);
    }

    #[test]
    fn smartie_is_an_oblate_lens_with_few_dozen_vertices() {
        let r = RockBody::new(&ShapeKind::Smartie, RockSize::Mass { mass_kg: 1000.0, density_kg_m3: 2650.0 }, "rock")
            .unwrap();
        assert_eq!(r.vertices_m.len(), 30);
        assert_relative_eq!(r.mass_kg, 1000.0, max_relative = 1e-9);
        // Oblate: one large principal moment (about the symmetry axis), two nearly equal smaller ones.
        let mut i: Vec<f64> = r.inertia_kg_m2.iter().copied().collect();
        i.sort_by(f64::total_cmp);
        assert!(i[2] > 1.3 * i[1], "{i:?}");
        assert!((i[1] - i[0]) / i[1] < 0.05, "{i:?}");
        assert_relative_eq!(r.extents_m[2] / r.extents_m[0], 0.45, max_relative = 0.05);
        // The centre of mass is the origin: the vertex mean of a symmetric hull is near 0.
        let c: Vector3<f64> = r.vertices_m.iter().sum::<Vector3<f64>>() / 30.0;
        assert!(c.norm() < 0.05 * r.bounding_radius_m);
        // Every vertex is inside or on every face plane.
        for v in &r.vertices_m {
            for (n, d) in &r.faces {
                assert!(n.dot(v) <= d + 1e-9);
            }
        }
    }

    #[test]
    fn bad_sizes_are_errors() {
        let e = RockBody::new(&ShapeKind::Cube, RockSize::Mass { mass_kg: -5.0, density_kg_m3: 2650.0 }, "rocks")
            .unwrap_err();
        assert!(e.to_string().contains("rocks.mass_kg"), "{e}");
        let flat = ShapeKind::Hull {
            name: "flat".into(),
            points: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
        };
        assert!(RockBody::new(&flat, RockSize::Mass { mass_kg: 1.0, density_kg_m3: 2650.0 }, "rocks").is_err());
    }
}
