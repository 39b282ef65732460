//! A profile cut from a 3D terrain along a polyline (`talus section`).
//!
//! The terrain is any mesh or DEM that [`crate::terrain::build::read_terrain_file`] reads. x of the profile is the
//! horizontal distance along the line from its first point, z the surface elevation (the highest surface over a
//! point, as the 3DRB engine sees it), sampled every `spacing_m` and at every vertex of the line
//! ([`Profile::from_section`]).
//!
//! # Materials (ours, kept simple)
//! - [`SectionMaterials::Single`]: every segment gets one name.
//! - [`SectionMaterials::BySlope`]: a segment is `face` where the ground under its midpoint is steeper than the
//!   threshold and `floor` elsewhere, the names of the bench profiles, so that a scenario written for a bench
//!   stack (Table 1 `face_all`/`floor_all`) runs on the section as it is. The slope is that of the 3D ground (the
//!   triangle's), not the apparent slope along the line, so an oblique section keeps the material of the ground.
//!
//! # Units
//! m and degrees; coordinates in the terrain file's own frame and horizontal axes.

use super::profile::Profile;
use crate::error::{Error, Result};
use crate::io::MeshData;
use crate::terrain::{horizontal_to_local, Surface, UpAxis};
use nalgebra::Vector3;

/// How the segments of a section get their material.
#[derive(Debug, Clone, PartialEq)]
pub enum SectionMaterials {
    /// One material name for every segment.
    Single(String),
    /// `face` where the ground is steeper than `face_slope_deg` (degrees from horizontal), `floor` elsewhere.
    BySlope {
        /// Threshold slope, degrees.
        face_slope_deg: f64,
    },
}

/// Cuts a profile from `mesh` (in its file frame, with `up` its vertical axis) along `line` (horizontal points of
/// the file's frame: (x, y) for z-up files, (x, z) for y-up ones), sampling every `spacing_m`.
///
/// # Errors
/// A mesh without usable triangles or with non-finite vertices, a bad threshold, a material name the profile CSV
/// cannot hold (a comma, a quote or a line break), and the errors of
/// [`Profile::from_section`] (a bad spacing or line, or the surface missing somewhere on the line, located in the
/// file's coordinates).
///
/// # Examples
/// ```
/// use talus::lumped2d::{section_from_mesh, SectionMaterials};
/// use talus::terrain::{BenchGeometry, UpAxis};
/// let g = BenchGeometry::default();
/// let mesh = g.mesh();
/// let p = section_from_mesh(&mesh, UpAxis::Z, &[[0.0, 30.0], [150.0, 30.0]], 1.0,
///                           &SectionMaterials::BySlope { face_slope_deg: 45.0 }).unwrap();
/// assert_eq!(p.material_names(), &["floor".to_string(), "face".to_string()]);
/// assert!((p.z_m()[0] - g.total_height_m()).abs() < 1e-9);
/// ```
pub fn section_from_mesh(
    mesh: &MeshData,
    up: UpAxis,
    line: &[[f64; 2]],
    spacing_m: f64,
    materials: &SectionMaterials,
) -> Result<Profile> {
    if let SectionMaterials::Single(name) = materials {
        check_material_name("section.material", name)?;
    }
    if let SectionMaterials::BySlope { face_slope_deg } = materials {
        if !(face_slope_deg.is_finite() && (0.0..90.0).contains(face_slope_deg)) {
            return Err(Error::invalid(
                "section.face_slope_deg",
                format!("must be in [0, 90) degrees, got {face_slope_deg}"),
                "e.g. 45: steeper ground is `face`, the rest `floor`",
            ));
        }
    }
    let points: Vec<Vector3<f64>> = mesh.vertices.iter().map(|v| up.to_internal(*v)).collect();
    if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(Error::invalid(
            "section.terrain",
            format!("vertex {} has a coordinate that is not finite", i + 1),
            "fix or remove that vertex",
        ));
    }
    // A local origin keeps georeferenced coordinates well conditioned (as the terrain builder does).
    let (ox, oy) = points.iter().fold((f64::INFINITY, f64::INFINITY), |(a, b), p| (a.min(p.x), b.min(p.y)));
    let origin = if ox.is_finite() { Vector3::new(ox.floor(), oy.floor(), 0.0) } else { Vector3::zeros() };
    let local: Vec<Vector3<f64>> = points.iter().map(|p| p - origin).collect();
    crate::terrain::build::check_spread("section.terrain", &local, &mesh.triangles)?;
    let (surface, _, _) = Surface::new(local, &mesh.triangles).ok_or_else(|| {
        Error::invalid(
            "section.terrain",
            "has no usable triangle (all are degenerate or vertical)",
            "check the terrain file and its up axis",
        )
    })?;
    Profile::from_section(line, spacing_m, |x, y| {
        let [lx, ly] = horizontal_to_local(up, &origin, [x, y]);
        let p = surface.at(lx, ly)?;
        let name = match materials {
            SectionMaterials::Single(name) => name.clone(),
            SectionMaterials::BySlope { face_slope_deg } => {
                let slope_deg = p.normal.z.abs().clamp(0.0, 1.0).acos().to_degrees();
                if slope_deg > *face_slope_deg { "face" } else { "floor" }.to_string()
            }
        };
        Some((p.z_m + origin.z, name))
    })
}

/// Refuses a material name (`field` names it in the error) that is empty or that the profile CSV
/// (`x_m,z_m,material`, written without quoting) cannot hold: one with a comma, a double quote or a line break.
fn check_material_name(field: &str, name: &str) -> Result<()> {
    if name.trim().is_empty() {
        return Err(Error::invalid(field, "is empty", "give a non-empty name, e.g. floor"));
    }
    if name.contains([',', '"', '\n', '\r']) {
        return Err(Error::invalid(
            field,
            format!("{name:?} contains a comma, a double quote or a line break, which would break the profile CSV"),
            "give one name of letters, digits, - or _, e.g. floor",
        ));
    }
    Ok(())
}
