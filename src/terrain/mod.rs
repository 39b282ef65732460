//! Terrain: the surface rocks move over, its materials, and the generators of synthetic slopes.
//!
//! A [`Terrain`] holds the surface in a local frame (z up, an origin subtracted so that UTM-sized coordinates keep
//! millimetre precision in f64 arithmetic), the material of every triangle, and what is needed to write results
//! back in the terrain's own frame and CRS.

pub mod bench;
pub mod build;
pub mod dem_check;
pub mod frame;
pub mod material;
pub mod split;
pub mod surface;

pub use bench::BenchGeometry;
pub use material::Material;
pub use surface::{Surface, SurfacePoint, SurfaceStats};

use crate::raster::Crs;
use nalgebra::Vector3;

/// Which axis of the input files points up.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    /// z up (GIS, DEMs, most mine surveys).
    #[default]
    Z,
    /// y up (photogrammetry and game-engine exports): file (x, y, z) is talus (x, −z, y).
    Y,
}

impl UpAxis {
    /// File coordinates to talus's z-up axes (before the origin shift).
    pub fn to_internal(self, p: [f64; 3]) -> Vector3<f64> {
        match self {
            UpAxis::Z => Vector3::new(p[0], p[1], p[2]),
            UpAxis::Y => Vector3::new(p[0], -p[2], p[1]),
        }
    }

    /// The point (x, y) of talus's z-up axes as the user gives polygons: (x, y) for z-up files, (x, z) for y-up ones
    /// (the inverse of [`horizontal_to_local`] but for the origin).
    pub fn horizontal_of_internal(self, x: f64, y: f64) -> [f64; 2] {
        match self {
            UpAxis::Z => [x, y],
            UpAxis::Y => [x, -y],
        }
    }

    /// talus z-up axes back to the file's axes.
    pub fn to_file(self, v: &Vector3<f64>) -> [f64; 3] {
        match self {
            UpAxis::Z => [v.x, v.y, v.z],
            UpAxis::Y => [v.x, v.z, -v.y],
        }
    }
}

/// A terrain ready for simulation.
#[derive(Debug, Clone)]
pub struct Terrain {
    /// The surface in the local frame.
    pub surface: Surface,
    /// Material index (into `materials`) of each surface triangle.
    pub triangle_material: Vec<u16>,
    /// tan of the static and dynamic friction angles of each material (cached for the contact loop).
    pub friction: Vec<(f64, f64)>,
    /// Materials.
    pub materials: Vec<Material>,
    /// Local frame origin in talus's z-up axes: a file point p maps to `up.to_internal(p) - origin`.
    pub origin: Vector3<f64>,
    /// Up axis of the input files.
    pub up: UpAxis,
    /// CRS of the input, for outputs.
    pub crs: Crs,
    /// What the surface builder kept and dropped.
    pub stats: SurfaceStats,
    /// Barriers standing on the terrain (none by default).
    pub barriers: Vec<crate::sim::Barrier>,
    /// What the scenario asks that the terrain does not use (a material no triangle has, a renamed group the
    /// files do not hold) and a terrain largely closed over (the other up axis?): warnings for the user, not
    /// errors.
    pub notes: Vec<String>,
    /// West and north cell edges of the first DEM among the terrain files, in the files' frame (`None` for meshes):
    /// where `[output] align_to_dem` puts the raster cells.
    pub grid_anchor_xy: Option<[f64; 2]>,
}

impl Terrain {
    /// Local-frame point back to the file's frame and axes.
    pub fn to_file_frame(&self, local: &Vector3<f64>) -> [f64; 3] {
        self.up.to_file(&(local + self.origin))
    }

    /// A point of the files' frame and axes in the local frame (the inverse of [`Terrain::to_file_frame`]).
    pub fn from_file_frame(&self, p: [f64; 3]) -> Vector3<f64> {
        self.up.to_internal(p) - self.origin
    }

    /// The material of triangle `t`.
    pub fn material_of(&self, t: u32) -> &Material {
        &self.materials[self.triangle_material[t as usize] as usize]
    }

    /// Triangles of each material, in the order of `materials`.
    pub fn triangles_per_material(&self) -> Vec<usize> {
        let mut n = vec![0; self.materials.len()];
        for &m in &self.triangle_material {
            n[m as usize] += 1;
        }
        n
    }

    /// Index of the material named `name`.
    pub fn material_index(&self, name: &str) -> Option<usize> {
        self.materials.iter().position(|m| m.name == name)
    }
}

impl Terrain {
    /// A terrain from local-frame vertices (z up, no origin shift) and triangles, with the material index of each
    /// input triangle. Degenerate and vertical triangles are dropped (see [`Terrain::stats`]).
    pub fn from_local(
        vertices: Vec<Vector3<f64>>,
        triangles: &[[u32; 3]],
        triangle_material: &[u16],
        materials: Vec<Material>,
    ) -> crate::Result<Terrain> {
        let (surface, kept, stats) = Surface::new(vertices, triangles).ok_or_else(|| {
            crate::Error::invalid(
                "terrain",
                "no usable triangle (all are degenerate or vertical)",
                "check the terrain files",
            )
        })?;
        let triangle_material = kept.iter().map(|&i| triangle_material[i]).collect();
        let friction = materials.iter().map(|m| (m.mu_static(), m.mu_dynamic())).collect();
        Ok(Terrain {
            surface,
            triangle_material,
            friction,
            materials,
            origin: Vector3::zeros(),
            up: UpAxis::Z,
            crs: Crs::default(),
            stats,
            barriers: Vec::new(),
            notes: Vec::new(),
            grid_anchor_xy: None,
        })
    }

    /// A square grid terrain over [0, size]² with `n` × `n` cells and heights `z(x, y)`, one material. For tests,
    /// examples and synthetic studies.
    pub fn from_function(
        size_m: f64,
        n: usize,
        material: Material,
        z: impl Fn(f64, f64) -> f64,
    ) -> crate::Result<Terrain> {
        let (v, t) = grid_mesh(size_m, n, z);
        let mats = vec![0u16; t.len()];
        Terrain::from_local(v, &t, &mats, vec![material])
    }
}

/// The mesh of [`Terrain::from_function`]: nodes over [0, size]² every size/n, two triangles per cell.
pub fn grid_mesh(size_m: f64, n: usize, z: impl Fn(f64, f64) -> f64) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
    let mut v = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (size_m * i as f64 / n as f64, size_m * j as f64 / n as f64);
            v.push(Vector3::new(x, y, z(x, y)));
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut t = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (v, t)
}

/// A horizontal point as the user gives it ((x, y) for z-up files, (x, z) for y-up ones) in the local frame.
pub fn horizontal_to_local(up: UpAxis, origin: &Vector3<f64>, p: [f64; 2]) -> [f64; 2] {
    let v = match up {
        UpAxis::Z => Vector3::new(p[0], p[1], 0.0),
        UpAxis::Y => Vector3::new(p[0], -p[1], 0.0),
    };
    [v.x - origin.x, v.y - origin.y]
}

/// Horizontal bounding box `[x_min, y_min, x_max, y_max]` of points whose first two coordinates are x and y
/// (polygon vertices `[x, y]` or positions `[x, y, z]`); infinite (min > max) for no points.
pub fn bbox_xy<const N: usize>(points: impl IntoIterator<Item = [f64; N]>) -> [f64; 4] {
    points.into_iter().fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, p| {
        [b[0].min(p[0]), b[1].min(p[1]), b[2].max(p[0]), b[3].max(p[1])]
    })
}

/// Even–odd point-in-polygon test.
pub fn point_in_polygon(x: f64, y: f64, poly: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = poly.len();
    let mut j = n - 1;
    for i in 0..n {
        let (xi, yi, xj, yj) = (poly[i][0], poly[i][1], poly[j][0], poly[j][1]);
        if (yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi {
            inside = !inside;
        }
        j = i;
    }
    inside
}
