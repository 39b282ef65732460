//! `talus mesh`: generated terrains.

use clap::{Args, Subcommand};
use std::path::PathBuf;
use talus::terrain::BenchGeometry;

/// Write generated terrains.
///
/// Example:
///   talus mesh bench --out outputs/bench_stack.obj
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct MeshArgs {
    #[command(subcommand)]
    kind: MeshKind,
}

#[derive(Debug, Subcommand)]
enum MeshKind {
    /// The seed paper's benched slope, as an OBJ with `face` and `floor` groups (or a 2D profile CSV with --2d).
    ///
    /// Example:
    ///   talus mesh bench --out outputs/bench_stack.obj
    ///   talus mesh bench --face-angle-deg 75 --bench-width-m 9 --2d --out outputs/bench75.csv
    #[command(verbatim_doc_comment)]
    Bench(BenchArgs),
}

#[derive(Debug, Args)]
struct BenchArgs {
    /// Output file: .obj, or .csv with --2d (other extensions are refused).
    #[arg(long)]
    out: PathBuf,
    /// Write the 2D profile (x_m,z_m,material) instead of the 3D mesh.
    #[arg(long = "2d")]
    two_d: bool,
    /// Vertical height of each face, m.
    #[arg(long, default_value_t = 20.0)]
    bench_height_m: f64,
    /// Face angle from horizontal, degrees.
    #[arg(long, default_value_t = 60.0)]
    face_angle_deg: f64,
    /// Catch-bench width, m.
    #[arg(long, default_value_t = 7.0)]
    bench_width_m: f64,
    /// Number of face + catch-bench pairs (one more face drops to the toe floor).
    #[arg(long, default_value_t = 5)]
    benches: usize,
    /// Lateral width of the 3D mesh, m.
    #[arg(long, default_value_t = 100.0)]
    lateral_width_m: f64,
    /// Flat floor behind the top crest, m.
    #[arg(long, default_value_t = 10.0)]
    crest_floor_m: f64,
    /// Run-out floor beyond the last toe, m.
    #[arg(long, default_value_t = 60.0)]
    toe_floor_m: f64,
    /// Largest triangle edge, m.
    #[arg(long, default_value_t = 2.5)]
    max_edge_m: f64,
}

pub fn run(a: MeshArgs) -> anyhow::Result<()> {
    match a.kind {
        MeshKind::Bench(b) => {
            let g = BenchGeometry {
                bench_height_m: b.bench_height_m,
                face_angle_deg: b.face_angle_deg,
                bench_width_m: b.bench_width_m,
                n_benches: b.benches,
                crest_floor_m: b.crest_floor_m,
                toe_floor_m: b.toe_floor_m,
                lateral_width_m: b.lateral_width_m,
                max_edge_m: b.max_edge_m,
            };
            super::check_out_file("--out", &b.out, Some(if b.two_d { "csv" } else { "obj" }), &[])?;
            g.validate("").map_err(as_flags)?;
            if let Some(dir) = b.out.parent().filter(|d| !d.as_os_str().is_empty()) {
                talus::io::create_folder(dir)?;
            }
            if b.two_d {
                talus::terrain::bench::write_profile_csv(&g, &b.out)?;
                say!("wrote the 2D profile of {} benches to {}", g.n_benches, b.out.display());
            } else {
                let mesh = g.mesh();
                talus::io::obj::write_obj(&b.out, &mesh)?;
                say!("wrote {} triangles ({} benches) to {}", mesh.triangles.len(), g.n_benches, b.out.display());
            }
            Ok(())
        }
    }
}

/// A [`BenchGeometry::validate`] error with its key (e.g. `max_edge_m`) named as the flag (`--max-edge-m`).
fn as_flags(e: talus::error::Error) -> talus::error::Error {
    match e {
        talus::error::Error::Invalid { field, message, hint } => {
            let flag = match field.as_str() {
                "n_benches" => "--benches".to_string(),
                key => format!("--{}", key.replace('_', "-")),
            };
            talus::error::Error::invalid(flag, message, hint)
        }
        other => other,
    }
}
