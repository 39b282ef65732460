//! Command-line arguments (clap) and their dispatch. The library never sees clap types.

mod barrier;
mod benches;
mod calibrate;
mod mesh;
mod profile;
mod progress;
mod run;
mod section;

use clap::{Parser, Subcommand};

/// talus: open-source rockfall hazard mapping (3D rigid bodies over real terrain, 2D lumped masses on profiles).
#[derive(Debug, Parser)]
#[command(name = "talus", version, about, long_about = None, arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Run(run::RunArgs),
    Profile(profile::ProfileArgs),
    Benches(benches::BenchesArgs),
    Section(section::SectionArgs),
    Mesh(mesh::MeshArgs),
    Barrier(barrier::BarrierArgs),
    Calibrate(calibrate::CalibrateArgs),
}

/// Parses the command line and runs the command.
pub fn main() -> anyhow::Result<()> {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // Help and version go to stdout with exit 0; usage errors exit 2 with clap's message.
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            std::process::exit(code);
        }
    };
    match cli.command {
        Command::Run(a) => run::run(a),
        Command::Profile(a) => profile::run(a),
        Command::Benches(a) => benches::run(a),
        Command::Section(a) => section::run(a),
        Command::Mesh(a) => mesh::run(a),
        Command::Barrier(a) => barrier::run(a),
        Command::Calibrate(a) => calibrate::run(a),
    }
}
