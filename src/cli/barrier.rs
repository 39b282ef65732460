//! `talus barrier`.

use super::progress;
use anyhow::Context;
use clap::Args;
use std::path::PathBuf;
use talus::barrier::{propose, Status};
use talus::scenario::ScenarioFile;

/// Propose rockfall barrier positions: candidate lines (contours, bench crests and toes, offsets of a toe or asset
/// line) are sized from one run (length to intercept the target share of rocks, fence height, energy class, cost)
/// and ranked; the scenario is run again with the best one in place to show what still passes. Settings:
/// [barrier_design] in the scenario (see docs/barrier.md).
///
/// Example:
///   talus barrier examples/bench_stack.toml --out outputs/bench_barrier
///   talus barrier examples/tyrol.toml --out outputs/tyrol_barrier --target-share 0.95
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct BarrierArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Output folder (created if missing): index.html, proposals.*, candidates.*, without_barrier/, with_barrier/.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    control: super::RunControl,
    /// Share of the rocks reaching the protected zone a barrier must intercept (overrides barrier_design.target_share).
    #[arg(long)]
    target_share: Option<f64>,
    /// Number of proposals written (overrides barrier_design.best).
    #[arg(long)]
    best: Option<usize>,
    /// Do not run again with the best proposal in place.
    #[arg(long)]
    no_rerun: bool,
    /// Also write every raster as an ESRI ASCII grid.
    #[arg(long)]
    ascii_grids: bool,
}

pub fn run(a: BarrierArgs) -> anyhow::Result<()> {
    a.control.check()?;
    let mut file = ScenarioFile::read(&a.scenario)?;
    if let Some(t) = a.target_share {
        file.barrier_design.target_share = t;
    }
    if let Some(b) = a.best {
        file.barrier_design.best = b;
    }
    file.barrier_design.rerun &= !a.no_rerun;
    file.output.ascii_grids |= a.ascii_grids;
    let sc = file
        .resolve(&a.scenario)
        .map_err(|e| anyhow::anyhow!("{e}\n  (command-line values are checked as barrier_design.* keys)"))?;
    let overrides = a.control.overrides(None);
    let pb = progress::bar(0, "rocks");
    let stage = |s: &str| {
        if pb.is_hidden() {
            eprintln!("talus barrier: {s}");
        } else {
            pb.println(format!("talus barrier: {s}"));
        }
    };
    let progress = |done: usize, total: usize| {
        if done == 1 {
            pb.reset();
            pb.set_length(total as u64);
        }
        pb.set_position(done as u64);
    };
    let study = propose(&sc, &overrides, &a.out, &stage, &progress)
        .with_context(|| format!("talus barrier {}", a.scenario.display()))?;
    pb.finish_and_clear();
    let ranked = study.ranked();
    let sized = study.assessments.iter().filter(|x| x.status == Status::Sized).count();
    println!("{} candidate lines, {} sized; best proposals:", study.candidates.len(), sized);
    println!(
        "{:>3}  {:<34} {:>8} {:>9} {:>10} {:>10}  {:<16} {:>8} {:>8}",
        "#", "position", "length", "height", "E P95", "E max", "class", "share", "cost"
    );
    for x in ranked.iter().take(sc.file.barrier_design.best) {
        println!(
            "{:>3}  {:<34} {:>6.0} m {:>7.1} m {:>7.0} kJ {:>7.0} kJ  {:<16} {:>7.1}% {:>8}",
            x.rank.unwrap_or(0),
            x.name,
            x.length_m,
            x.fence_height_m,
            x.energy_p95_kj,
            x.energy_max_kj,
            x.class_label,
            100.0 * x.share,
            x.cost.map_or("-".to_string(), |c| format!("{c:.0}"))
        );
    }
    if let (Some(r), Some(b)) = (&study.residual, &study.barrier) {
        println!(
            "with {} ({} m, {} kJ): rocks reaching the protected zone {} ({:.1} %) -> {} ({:.1} %); caught {}, through {}, over {}, around {}",
            b.name.as_deref().unwrap_or("the barrier"),
            b.height_m,
            b.capacity_kj,
            r.reaching_without,
            100.0 * r.probability_without(),
            r.reaching_with,
            100.0 * r.probability_with(),
            r.caught,
            r.through,
            r.over,
            r.around
        );
    }
    println!("wrote {}", a.out.join("index.html").display());
    Ok(())
}
