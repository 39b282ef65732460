//! `talus section`.

use anyhow::Context;
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use talus::lumped2d::{section_from_mesh, SectionMaterials};
use talus::terrain::build::read_terrain_file;
use talus::terrain::UpAxis;

/// Cut a 2D profile (x_m,z_m,material) from a 3D terrain along a polyline, for `talus profile`.
///
/// x of the profile is the horizontal distance along the line from its first point and z the surface elevation,
/// sampled every --spacing-m and at every vertex of the line (a kink between samples is cut off: sample finer
/// than the features that matter). Each segment is `face` where the 3D ground under its midpoint is steeper than
/// --face-slope-deg and `floor` elsewhere (the names of the bench profiles), or one --material for all.
///
/// Example:
///   talus section meshes/bench_stack/bench_stack.obj --line 0,30,160,30 --spacing-m 0.5 --out outputs/section.csv
#[derive(Debug, Args)]
pub struct SectionArgs {
    /// Terrain file: .obj, .stl, .tif/.tiff (GeoTIFF DEM) or .asc (ESRI ASCII grid).
    terrain: PathBuf,
    /// The section line as x1,y1,x2,y2[,x3,y3...] in the terrain's coordinates (x,z for a y-up file).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, required = true)]
    line: Vec<f64>,
    /// Sample spacing along the line, m.
    #[arg(long, default_value_t = 1.0)]
    spacing_m: f64,
    /// Output profile CSV.
    #[arg(long)]
    out: PathBuf,
    /// One material name for every segment (instead of face/floor by slope).
    #[arg(long)]
    material: Option<String>,
    /// Ground steeper than this (degrees) is `face`, the rest `floor`.
    #[arg(long, default_value_t = 45.0, conflicts_with = "material")]
    face_slope_deg: f64,
    /// Vertical axis of the terrain file.
    #[arg(long, value_enum, default_value_t = Up::Z)]
    up: Up,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Up {
    Z,
    Y,
}

pub fn run(a: SectionArgs) -> anyhow::Result<()> {
    super::check_out_file("--out", &a.out, Some("csv"), &[&a.terrain])?;
    if a.line.len() < 4 || !a.line.len().is_multiple_of(2) {
        anyhow::bail!(
            "--line: give an even number of coordinates, at least two points (x1,y1,x2,y2), got {} numbers",
            a.line.len()
        );
    }
    let line: Vec<[f64; 2]> = a.line.chunks(2).map(|c| [c[0], c[1]]).collect();
    let materials = match a.material {
        Some(name) => SectionMaterials::Single(name),
        None => SectionMaterials::BySlope { face_slope_deg: a.face_slope_deg },
    };
    let up = match a.up {
        Up::Z => UpAxis::Z,
        Up::Y => UpAxis::Y,
    };
    let (mesh, _) = read_terrain_file(&a.terrain)?;
    let profile = section_from_mesh(&mesh, up, &line, a.spacing_m, &materials)
        .with_context(|| format!("cutting a section from {}", a.terrain.display()))?;
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        talus::io::create_folder(dir)?;
    }
    profile.write_csv(&a.out)?;
    let (x0, x1) = profile.x_range_m();
    let zs = profile.z_m();
    let (zmin, zmax) = zs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &z| (a.min(z), b.max(z)));
    let mut counts = vec![0usize; profile.material_names().len()];
    for &m in profile.segment_materials() {
        counts[m] += 1;
    }
    let mats: Vec<String> =
        profile.material_names().iter().zip(&counts).map(|(n, c)| format!("{n} ({c} segments)")).collect();
    say!(
        "wrote a {:.1} m profile ({} vertices, z {:.1} to {:.1} m; {}) to {}",
        x1 - x0,
        profile.n_vertices(),
        zmin,
        zmax,
        mats.join(", "),
        a.out.display()
    );
    Ok(())
}
